"""A real record as it comes: a LabVIEW file of a shaker test that starts mid-stream, its force a
periodic multisine with broadband noise to Nyquist, updated through the command a user runs: --window, --band-hz
for the time cost, --cost log-frf on the lines, --bounds, and an analyser's lines that are not neighbours.

The data come from an independent route: the three-storey frame's FE model re-solved with other moduli and 2 %
damping, exported as its own FMU and run from 10 s before the record starts (the structure already moving at
its first sample, as a real test's structure is); the FMU updated is the nominal one, started at 2 % damping. The
record is written as LabVIEW writes it (tests/support/lvm_files.py): channels ai0-ai3, units Newtons and m/s^2,
a channel map to the FMU's signals.
"""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from support.cli import run_cli
from support.lvm_files import write_lvm
from support.paths import EXAMPLES

pytestmark = pytest.mark.slow  # two FMU exports, a 50 s run of the truth, updates of 15-30 s

FRAME = EXAMPLES / "three_storey_frame"
TRUTH = {"E_storey_1": 0.85 * 7.0e10, "E_storey_2": 0.95 * 7.0e10, "E_storey_3": 0.90 * 7.0e10}
DAMPING = {f"damping_mode_{k}": 0.02 for k in (1, 2, 3)}
OUTPUTS = ("acc_floor_1", "acc_floor_2", "acc_floor_3")
STEP_S, BEFORE_S, RECORD_S = 2e-3, 10.0, 40.0
F0 = 0.3  #: the multisine's fundamental [Hz]: its period, 3.33 s, is no whole number of samples


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """(folder, nominal FMU, the record's .lvm, its channel map, a start file at 2 % damping, the multisine's lines,
    the re-solved truth's volts model)."""
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.parameters.sets import ParameterSet
    from mace_fmu.updating.fmu.model import fmu_family

    folder = tmp_path_factory.mktemp("real_record")
    deck = read_deck(FRAME / "frame.bdf")
    fmu = export_fmu(volts_model(compute_modes(deck, configuration="1g", structure_file=FRAME / "frame.toml")),
                     out_dir=folder, name="frame_1g")
    truth = volts_model(compute_modes(deck, configuration="1g", structure_file=FRAME / "frame.toml",
                                      parameters=ParameterSet({**TRUTH, **DAMPING})))
    run = fmu_family(export_fmu(truth, out_dir=folder / "truth", name="frame_truth")).full({})
    t = np.arange(int(round((BEFORE_S + RECORD_S) / STEP_S))) * STEP_S
    rng = np.random.default_rng(48)
    lines = np.array([k for k in range(10, 134) if rng.uniform() < 0.35]) * F0  # 3-40 Hz, not neighbours
    force = sum(np.cos(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi)) for f in lines)
    force = 5.0 * force / np.sqrt(np.mean(force**2)) + 0.3 * rng.standard_normal(t.size)  # noise to Nyquist
    y = run.time_response(t, {"force_floor_1": force}, outputs=list(OUTPUTS))
    kept = t >= BEFORE_S - 1e-9  # the record starts mid-stream
    channels = {"Dev1/ai0": ("Newtons", force[kept])}
    for k in range(len(OUTPUTS)):
        clean = y[kept, k]
        noise = 0.02 * np.sqrt(np.mean(clean**2)) * rng.standard_normal(clean.size)
        channels[f"Dev1/ai{k + 1}"] = ("m/s^2", clean + noise)
    record = write_lvm(folder / "shaker.lvm", t[kept] - BEFORE_S, channels, segments=2)
    channel_map = folder / "channels.csv"
    channel_map.write_text("channel,signal,role,unit\nDev1/ai0,force_floor_1,input,N\n"
                           + "".join(f"Dev1/ai{k + 1},{o},output,m/s^2\n" for k, o in enumerate(OUTPUTS)))
    start = folder / "start.toml"
    start.write_text("[values]\n" + "".join(f"{n} = 0.02\n" for n in DAMPING))
    return folder, fmu, record, channel_map, start, lines, truth


def _update(capsys, rig, *options: str, out: str, names: str = "E_storey_1,E_storey_2,E_storey_3",
            start=None) -> tuple[int, str, str]:
    folder, fmu, record, channel_map, start_file, _, _ = rig
    return run_cli(capsys, ["update", "fmu", str(fmu), "--data", str(record), "--map", str(channel_map),
                            "--update", names, "--hold-input", "force_floor_2=0,force_floor_3=0",
                            "--start", str(start or start_file), "--workers", "2", *options, "-o", str(folder / out)])


def _within_intervals(folder, out: str) -> dict:
    stage = tomllib.loads((folder / out / "uncertainty.toml").read_text())["stage"][0]
    for name, low, high in zip(stage["parameters"], stage["interval_95_low"], stage["interval_95_high"]):
        assert low <= TRUTH[name] <= high, (name, low, high)
    return stage


def test_a_record_that_starts_mid_stream_is_compared_in_a_window_and_a_band_and_held_to_its_noise(rig, capsys):
    """--window 8 39 skips the first seconds (the FMU at rest, the structure not: 1.2 s to decay by e at 2 %
    damping), --band-hz 3 40 leaves out the broadband force noise above the lines (the FMU still driven by the
    whole measured force). The noise, unmeasurable without the band (the force fills the record to Nyquist), is
    read outside it: the fit ends on its floor and the re-solve's moduli lie inside the intervals. The whole record
    from its first sample is a model error: the mid-stream start."""
    folder = rig[0]
    code, _, err = _update(capsys, rig, "--cost", "time", "--window", "8", "39", "--band-hz", "3", "40", out="time")
    assert code == 0, err
    verdict = tomllib.loads((folder / "time" / "convergence.toml").read_text())
    assert verdict["verdict"] == "explained", verdict["headline"]
    assert verdict["noise_floor"]["source"].startswith("estimated outside the band 3-40 Hz")
    assert abs(verdict["noise_floor"]["sigmas_above"]) < 3
    _within_intervals(folder, "time")
    code, _, err = _update(capsys, rig, "--cost", "time", "--band-hz", "3", "40", out="whole")
    assert code == 0, err
    assert tomllib.loads((folder / "whole" / "convergence.toml").read_text())["verdict"] == "model error"


def test_log_frf_of_a_periodic_record_is_estimated_at_its_lines_with_segments_of_whole_periods(rig, capsys):
    """The multisine's 0.3 Hz fundamental is found (its lines are not neighbours), the H1 taken at its lines over
    one-period segments (1667 samples: every line within 0.05 of a bin), and the moduli come back inside their
    intervals."""
    folder, lines = rig[0], rig[5]
    code, _, err = _update(capsys, rig, "--cost", "log-frf", "--window", "8", "39", out="frf")
    assert code == 0, err
    assert (f"periodic inputs, {lines.size} lines from {lines[0]:.6g} to {lines[-1]:.6g} Hz, multiples of 0.3 Hz "
            "(period 3.33333 s, 1666.67 samples): H1 at the lines, 1667-sample segments") in err, err
    stage = _within_intervals(folder, "frf")
    assert stage["residuals"] == 2 * lines.size  # one pair (floor 1's force to its acceleration), each line once


def test_a_damping_ratio_held_at_a_bound_is_one_sided_in_the_table_and_the_file_as_in_the_verdict(rig, capsys,
                                                                                                   tmp_path):
    """--bounds damping_mode_1=0.022: (truth 0.02; the upper side the default) and a [bounds] table in the start
    file: the fit ends at 0.022, and the verdict, the terminal table and uncertainty.toml all say one-sided."""
    folder = rig[0]
    start = tmp_path / "start.toml"
    start.write_text("[values]\n" + "".join(f"{n} = {v!r}\n" for n, v in TRUTH.items())
                     + "damping_mode_1 = 0.025\ndamping_mode_2 = 0.02\ndamping_mode_3 = 0.02\n\n"
                     + '[bounds]\ndamping_mode_2 = [0.01, ""]\n')
    code, out, err = _update(capsys, rig, "--cost", "log-frf", "--window", "8", "39", "--bounds",
                             "damping_mode_1=0.022:", names="damping_mode_1,damping_mode_2", start=start, out="bound")
    assert code == 0, err
    assert "damping_mode_1 at its lower bound" in err and "interval is one-sided" in err
    line = next(text for text in out.splitlines() if text.strip().startswith("damping_mode_1") and "[" in text
                and "%" not in text)
    assert "[0.022, " in line and "one-sided: at its lower bound" in line, out
    stage = tomllib.loads((folder / "bound" / "uncertainty.toml").read_text())["stage"][0]
    assert stage["interval_95_at_bound"] == ["lower", ""] and stage["interval_95_low"][0] == pytest.approx(0.022)
    values = tomllib.loads((folder / "bound" / "parameters.toml").read_text())["values"]
    assert values["damping_mode_2"] == pytest.approx(0.02, rel=0.01)


def test_an_analyser_s_lines_that_are_no_neighbours_are_one_multisine(rig, capsys, tmp_path):
    """An FRF file at lines of 0.1 Hz steps whose smallest gap is 0.2 Hz (6.0, 6.3, 6.5, ...): the old code took
    0.2 Hz for the step and refused 6.3 Hz; the lines are one multisine of 0.1 Hz, and the moduli come back."""
    from mace_fmu.updating.engine.measured import FrequencyResponseData
    from mace_fmu.updating.files import write_frequency_response

    truth = rig[6]
    f = np.array([6.0, 6.3, 6.5, 6.7, 7.0, 18.0, 18.3, 18.5, 18.7, 19.0, 26.8, 27.1, 27.3, 27.5, 27.8])
    data = FrequencyResponseData(f, ("force_floor_1",), OUTPUTS, truth.frequency_response(f)[:, :3, :1],
                                 units={"force_floor_1": "N", **{o: "m/s^2" for o in OUTPUTS}})
    path = write_frequency_response(data, tmp_path / "lines.csv")
    code, _, err = run_cli(capsys, ["update", "fmu", str(rig[1]), "--data", str(path), "--cost", "log-frf",
                                    "--start", str(rig[4]), "--update", "E_storey_1,E_storey_2,E_storey_3",
                                    "--workers", "2", "-o", str(tmp_path / "out")])
    assert code == 0, err
    values = tomllib.loads((tmp_path / "out" / "parameters.toml").read_text())["values"]
    for name, value in TRUTH.items():
        assert values[name] == pytest.approx(value, rel=1e-3), name


@pytest.mark.parametrize("options, message", [
    (["--cost", "time", "--window", "8", "45"],
     "--window 8 45: {record}: the record runs from 0 to 39.998 s; the window must lie within it"),
    (["--cost", "time", "--window", "20", "10"], "--window 20 10: expected START < END [s] on the record's time axis"),
    (["--cost", "log-frf", "--window", "8", "39", "--segment-s", "2"],
     "--segment-s 2: the inputs are periodic ({lines} lines from {low:.6g} to {high:.6g} Hz, multiples of 0.3 Hz "
     "(period 3.33333 s, 1666.67 samples)), and the 16.8 Hz line falls 0.40 bins from the segments' bins; segments "
     "of whole periods put every line on a bin: 3.334 s, 6.666 s ... (or leave --segment-s out"),
    (["--cost", "time", "--band-hz", "3", "40", "--band-hz", "50", "60"],
     "--band-hz given 2 times: with time histories one band"),
    (["--cost", "time", "--band-hz", "3", "300"],
     "--band-hz 3 300: HIGH is above the record's Nyquist frequency 250 Hz"),
    (["--cost", "time", "--bounds", "damping_mode_1=0.01:0.05"],
     "--bounds: 'damping_mode_1' is not updated (the parameters updated: E_storey_1, E_storey_2, E_storey_3)"),
    (["--cost", "time", "--bounds", "E_storey_1=8e10:9e10"],
     "--bounds: E_storey_1 bounds [8e+10, 9e+10] Pa do not hold its start value 7e+10 strictly inside"),
    (["--cost", "time", "--bounds", "E_storey_1=1e10:"],
     "--bounds: E_storey_1 bounds [1e+10, 1.05e+11] Pa leave the range [4.9e+10, 1.05e+11]"),
    (["--cost", "time", "--bounds", "E_storey_1=1:2:3"], "expected NAME=LOW:HIGH"),
])
def test_bad_requests_stop_before_any_run_naming_the_option(rig, capsys, options, message):
    folder, lines = rig[0], rig[5]
    code, _, err = _update(capsys, rig, *options, out="refused")
    assert code == 2 and message.format(record=rig[2], lines=lines.size, low=lines[0], high=lines[-1]) in err, err
    assert not (folder / "refused").exists()
