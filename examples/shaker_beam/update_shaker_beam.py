"""Updating from a shaker record: a public steel cantilever's LabVIEW file, from the raw file to the verdict.
==============================================================================================================

    python examples/shaker_beam/update_shaker_beam.py [OUT_DIR]

The record is the High-Rate SHM Working Group's Dataset-4 (``data/README.md``: provenance, CC BY-SA 4.0 and
what the files say about themselves): a 759 x 50.66 x 5.14 mm steel cantilever driven through a load cell by
a shaker with 100, 120 and 150 Hz sines, its force in pounds and an accelerometer's acceleration in g, every
128th sample of the 51200 Hz original kept. ``shaker_beam.bdf`` is the project's deck of the beam from the
stated dimensions (steel's handbook values, the instruments placed from the bench's photograph),
``shaker_beam.toml`` its instruments: the shaker's force [N] and the accelerometer [m/s^2].
``data/channels.csv`` maps the record's channels to them and converts the units. The same from the command
line (the how-to "Update from a shaker record" walks through it)::

    mace-fmu data check data/data_set_1_downsampled_by_128.lvm --map data/channels.csv
    mace-fmu export 0g --deck shaker_beam.bdf --structure shaker_beam.toml -o fmus
    mace-fmu update fmu fmus/shaker_beam_0g_native.fmu --data data/data_set_1_downsampled_by_128.lvm \\
        --map data/channels.csv --update E_beam,m_shaker,damping_mode_3 --cost time --window 4 11.8 \\
        --band-hz 90 160 -o first_half
    mace-fmu update fmu fmus/shaker_beam_0g_native.fmu --data data/data_set_1_downsampled_by_128.lvm \\
        --map data/channels.csv --update E_beam,m_shaker,damping_mode_3 --cost time --window 11.9 19.7 \\
        --band-hz 90 160 -o second_half
    mace-fmu update fmu fmus/shaker_beam_0g_native.fmu --data data/data_set_2_downsampled_by_128.lvm \\
        --map data/channels_test_2.csv --update E_beam,m_shaker,damping_mode_3 --cost time --window 4 19.7 \\
        --band-hz 90 160 -o test_2
    mace-fmu modes 0g --deck shaker_beam.bdf --structure shaker_beam.toml --parameters first_half/parameters.toml

What it shows: the model cannot explain this record. Its accelerance at the three lines is 7 to 180 times the
measured one, at another phase; the update ends with the verdict "model error", the residual about 30 times
the record's own RMS in the band against a noise of about 1 %, the shaker's mass and the damping ratio at
their upper bounds (the fit making the model respond less, the one thing it can do) and the modulus 19 %
above steel's. The intervals come from the residuals and are wide; the other half of the record, and the
owners' second test, land inside them, as they must when all three see the same misfit. The updated
frequencies are further from the owners' measured ones (6.62, 41.4, 117.5 Hz) than the stated beam's:
parameters fitted through a model error are not measurements. What to look at, and what to change, is the
how-to's last section.
"""

# sphinx_gallery_thumbnail_number = 1

from __future__ import annotations

import sys
import tempfile
import tomllib
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from mace_fmu.cli import main as mace_fmu

# the folder of this script (sphinx-gallery runs it there, without __file__, when the site is built)
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
DECK, STRUCTURE, DATA = HERE / "shaker_beam.bdf", HERE / "shaker_beam.toml", HERE / "data"
RECORD, MAP = DATA / "data_set_1_downsampled_by_128.lvm", DATA / "channels.csv"
LINES_HZ = (100.0, 120.0, 150.0)  #: the multisine's lines (data/README.md)
PUBLISHED_HZ = (6.62, 41.4, 117.5)  #: the owners' impact test (modal_analysis/README.md of the dataset)
UPDATE = "E_beam,m_shaker,damping_mode_3"
#: (record, channel map, window): the record's two halves and, for a second test, test 2's record
RUNS = {"first_half": (RECORD, MAP, ("4", "11.8")), "second_half": (RECORD, MAP, ("11.9", "19.7")),
        "test_2": (DATA / "data_set_2_downsampled_by_128.lvm", DATA / "channels_test_2.csv", ("4", "19.7"))}


def accelerance_at_lines(times_s: np.ndarray, force: np.ndarray, acc: np.ndarray) -> np.ndarray:
    """The record's acceleration over force at each line of :data:`LINES_HZ`: the ratio of their Fourier
    coefficients at the line over the whole record (the lines are far apart, so the record's length resolves them).

    Parameters
    ----------
    times_s : ndarray
        Sample times [s].
    force, acc : ndarray
        The force [N] and the acceleration [m/s^2] at those times.

    Returns
    -------
    ndarray
        Complex accelerance [(m/s^2)/N], one per line.
    """
    out = []
    for hz in LINES_HZ:
        w = np.exp(-2j * np.pi * hz * times_s)
        out.append(np.mean((acc - acc.mean()) * w) / np.mean((force - force.mean()) * w))
    return np.array(out)


def main(out: Path) -> dict:
    """Every step of the module docstring, its files written into ``out``.

    Parameters
    ----------
    out : Path
        The folder for the FMU, the two updates' files and their figures.

    Returns
    -------
    dict
        ``measured`` and ``model``: the accelerance at the lines [(m/s^2)/N], complex; per half of the record
        (``first_half``, ``second_half``): ``code`` (the exit status), ``verdict`` (convergence.toml) and
        ``stage`` (uncertainty.toml's first stage).
    """
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.updating.files import read_channel_map, read_time_history

    out.mkdir(parents=True, exist_ok=True)
    # 1. The raw file: three channels, the header's units (pounds, g) converted by the channel map
    history = read_time_history(RECORD, channel_map=read_channel_map(MAP))
    t, force, acc = history.times_s, history.inputs["force_shaker"], history.outputs["acc_beam"]
    print(f"{RECORD.name}: {t.size} samples, {t[1] - t[0]:.4g} s apart, {t[-1]:.4g} s; force mean "
          f"{force.mean():.3g} N, RMS about it {force.std():.3g} N; acceleration RMS {acc.std():.3g} m/s^2")
    # 2. The beam's FMU, and its accelerance at the lines beside the record's
    assert mace_fmu(["export", "0g", "--deck", str(DECK), "--structure", str(STRUCTURE), "-o", str(out / "fmus")]) == 0
    fmu = out / "fmus" / "shaker_beam_0g_native.fmu"
    measured = accelerance_at_lines(t, force, acc)
    model = volts_model(compute_modes(read_deck(DECK), configuration="0g", structure_file=STRUCTURE)
                        ).frequency_response(np.array(LINES_HZ))[:, 0, 0]  # the FMU's model: one input, one output
    for hz, m, h in zip(LINES_HZ, measured, model):
        print(f"{hz:5.0f} Hz: record {abs(m):.3f} (m/s^2)/N at {np.angle(m, deg=True):6.1f} deg, "
              f"model {abs(h):.3f} at {np.angle(h, deg=True):6.1f} deg")
    fig, (ax_t, ax_h) = plt.subplots(1, 2, figsize=(10, 3.2))
    keep = (t >= 10) & (t <= 10.2)
    ax_t.plot(t[keep], force[keep], label="force [N]")
    ax_t.plot(t[keep], 10 * acc[keep], label="acceleration x 10 [m/s^2]")
    ax_t.set_xlabel("time [s]")
    ax_t.legend(fontsize=8)
    ax_h.semilogy(LINES_HZ, np.abs(measured), "o-", label="record")
    ax_h.semilogy(LINES_HZ, np.abs(model), "s--", label="stated beam")
    ax_h.set_xlabel("frequency [Hz]")
    ax_h.set_ylabel("|acceleration / force| [(m/s^2)/N]")
    ax_h.legend(fontsize=8)
    fig.tight_layout()
    # 3. The update on the record's first half and, for the intervals, on its second half and on test 2
    numbers = {"measured": measured, "model": model}
    for name, (record, channel_map, (start, end)) in RUNS.items():
        code = mace_fmu(["update", "fmu", str(fmu), "--data", str(record), "--map", str(channel_map),
                         "--update", UPDATE, "--cost", "time", "--window", start, end, "--band-hz", "90", "160",
                         "--workers", "1", "-o", str(out / name)])
        verdict = tomllib.loads((out / name / "convergence.toml").read_text())
        stage = tomllib.loads((out / name / "uncertainty.toml").read_text())["stage"][0]
        numbers[name] = {"code": code, "verdict": verdict, "stage": stage}
        (channel,) = verdict["channel"]
        print(f"{name}: exit {code}, verdict {verdict['verdict']!r}; residual RMS {channel['rms']:.3g} x the "
              f"record's in the band, noise {100 * channel['noise_rms']:.2g} %")
    first = numbers["first_half"]["stage"]
    for other in ("second_half", "test_2"):
        for k, p in enumerate(first["parameters"]):
            value = numbers[other]["stage"]["values"][k]
            inside = first["interval_95_low"][k] <= value <= first["interval_95_high"][k]
            print(f"{p}: first half {first['values'][k]:.4g} [{first['interval_95_low'][k]:.4g}, "
                  f"{first['interval_95_high'][k]:.4g}], {other.replace('_', ' ')} {value:.4g}: "
                  f"{'inside' if inside else 'OUTSIDE'}")
    # 4. The residual figure of the first half
    image = plt.imread(out / "first_half" / "residuals.png")
    fig = plt.figure(figsize=(10, 2.6))
    plt.imshow(image)
    plt.axis("off")
    # 5. The updated frequencies against the owners' impact test
    assert mace_fmu(["modes", "0g", "--deck", str(DECK), "--structure", str(STRUCTURE)]) == 0
    assert mace_fmu(["modes", "0g", "--deck", str(DECK), "--structure", str(STRUCTURE), "--parameters",
                     str(out / "first_half" / "parameters.toml")]) == 0
    return numbers


if __name__ == "__main__" or "__file__" not in globals():
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="shaker_beam_")))
    plt.show()
