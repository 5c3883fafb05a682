"""An FMU updated against measured frequency responses given alone (an analyser's FRF file, no time history),
through the command a user with a shaker test runs.

The data are made by an independent route: the frame's FE model re-solved with other moduli
(``compute_modes(parameters=...)``) and its exact frequency response from the state space, written as a CSV
file of complex FRFs in (m/s^2)/N. The FMU, exported at the nominal moduli, only ever sees the file; the
update must bring its moduli to the re-solve's, the FMU's response coming from periodic runs
(mace_fmu/updating/engine/multisine.py) and its moduli from its own parameter route.
"""

from __future__ import annotations

import re
import tomllib

import numpy as np
import pytest
from support.cli import run_cli
from support.paths import EXAMPLES

from mace_fmu.updating.engine.measured import MeasuredFrf

pytestmark = pytest.mark.slow  # an FMU export and an update of six parameters (about 20 s)

FRAME = EXAMPLES / "three_storey_frame"
TRUTH = {"E_storey_1": 0.85 * 7.0e10, "E_storey_2": 0.95 * 7.0e10, "E_storey_3": 0.90 * 7.0e10}
UPDATE = "E_storey_1,E_storey_2,E_storey_3,damping_mode_1,damping_mode_2,damping_mode_3"


@pytest.fixture(scope="module")
def frame(tmp_path_factory):
    """(folder, nominal FMU, the re-solved model's FRF file) of the frame's 1-g configuration."""
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.parameters.sets import ParameterSet
    from mace_fmu.updating.files import write_frequency_response

    folder = tmp_path_factory.mktemp("frame_frf")
    deck = read_deck(FRAME / "frame.bdf")
    nominal = volts_model(compute_modes(deck, configuration="1g", structure_file=FRAME / "frame.toml"))
    fmu = export_fmu(nominal, out_dir=folder, name="frame_1g")
    resolved = volts_model(compute_modes(deck, configuration="1g", structure_file=FRAME / "frame.toml",
                                         parameters=ParameterSet(TRUTH)))
    f = np.arange(1, 1025) * 0.03125  # the analyser's grid of the real data, to 32 Hz
    h = resolved.frequency_response(f)[:, :3, :1]
    data = MeasuredFrf(f, ("force_floor_1",), ("acc_floor_1", "acc_floor_2", "acc_floor_3"), h,
                                 units={"force_floor_1": "N", **{f"acc_floor_{k}": "m/s^2" for k in (1, 2, 3)}})
    return folder, fmu, write_frequency_response(data, folder / "resolved.csv")


def test_an_frf_file_alone_brings_the_fmu_s_moduli_to_the_full_re_solve_s(frame, capsys):
    folder, fmu, data = frame
    code, out, err = run_cli(capsys, ["update", "fmu", str(fmu), "--data", str(data), "--cost", "log-frf",
                                      "--band-hz", "4", "32", "--update", UPDATE, "-o", str(folder / "out"),
                                      "--workers", "1"])
    assert code == 0, err
    values = tomllib.loads((folder / "out" / "parameters.toml").read_text())["values"]
    for name, truth in TRUTH.items():
        assert values[name] == pytest.approx(truth, rel=2e-3), name
    for k in (1, 2, 3):  # the data's damping is the structure file's, which the update must leave
        assert values[f"damping_mode_{k}"] == pytest.approx(0.002, rel=2e-3)


def test_the_same_data_in_a_uff_58_file_give_the_same_moduli(frame, capsys):
    """UFF 58 keeps six digits of each frequency (E13.5): the file's lines, up to 5e-6 off the analyser's grid,
    are put back on it (said on stderr, with the spacing of the grid the data were made on) and the update from
    the UFF file reaches the re-solve's moduli as the CSV file's does."""
    from mace_fmu.updating.files import (
        read_frequency_response,
        write_frequency_response,
    )

    folder, fmu, data = frame
    uff = write_frequency_response(read_frequency_response(data), folder / "resolved.uff")
    code, _, err = run_cli(capsys, ["update", "fmu", str(fmu), "--data", str(uff), "--cost", "log-frf",
                                    "--band-hz", "4", "32", "--update", UPDATE, "-o", str(folder / "out_uff"),
                                    "--workers", "1"])
    assert code == 0, err
    said = re.search(r"resolved\.uff: 897 lines from 4 to 32 Hz put on the grid k x (\S+) Hz", err)
    assert said and float(said.group(1)) == pytest.approx(0.03125, rel=1e-6), err
    values = tomllib.loads((folder / "out_uff" / "parameters.toml").read_text())["values"]
    for name, truth in TRUTH.items():
        assert values[name] == pytest.approx(truth, rel=2e-3), name


@pytest.mark.parametrize("extra, message", [
    (["--cost", "time"], "measured frequency responses are compared by the log-frf cost (--cost log-frf)"),
    (["--cost", "log-frf", "--band-hz", "40", "50"], "0 frequencies in 40-50 Hz (the file has 0.03125 to 32 Hz)"),
    (["--cost", "log-frf", "--band-hz", "9", "3"], "--band-hz 9 3: expected 0 <= LOW < HIGH"),
    # options of time histories are refused, not ignored, on frequency responses given alone
    (["--cost", "log-frf", "--segment-s", "4"], "segment_s (--segment-s): for time histories"),
    (["--cost", "log-frf", "--weighting", "none", "--noise-rms-percent", "2"],
     "noise_rms_fraction (--noise-rms-percent): for time histories"),
    (["--cost", "log-frf", "--weighting", "noise"], "resolved.csv: no coherence, so no noise to weigh the lines by"),
    (["--cost", "log-frf", "--averages", "8"], "--averages and --frf-floor-percent set the noise the lines are "
                                               "weighted by"),
    (["--cost", "log-frf", "--hold-input", "force_floor_2=0"], "held_inputs (--hold-input): for time histories"),
])
def test_bad_frf_requests_stop_before_any_run(frame, capsys, extra, message):
    folder, fmu, data = frame
    code, _, err = run_cli(capsys, ["update", "fmu", str(fmu), "--data", str(data), "--update", "E_storey_1",
                                    "-o", str(folder / "refused"), *extra])
    assert code == 2 and message in err, err
    assert not (folder / "refused").exists()


@pytest.fixture(scope="module")
def shaker_record(frame):
    """A shaker test of the re-solved frame as a data logger writes it: the load cell's force on floor 1 [N]
    and three accelerations [m/s^2] with 2 % noise, 1 kHz for 20 s (the re-solve's FMU made it)."""
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.parameters.sets import ParameterSet
    from mace_fmu.updating.engine.measured import TimeHistory
    from mace_fmu.updating.files import write_time_history
    from mace_fmu.updating.fmu.model import fmu_family
    from mace_fmu.updating.fmu.truth import band_limited_noise

    folder = frame[0]
    resolved = volts_model(compute_modes(read_deck(FRAME / "frame.bdf"), configuration="1g",
                                         structure_file=FRAME / "frame.toml", parameters=ParameterSet(TRUTH)))
    truth = fmu_family(export_fmu(resolved, out_dir=folder / "truth", name="frame_truth")).full({})
    t = np.arange(20000) * 1e-3
    force = 5.0 * band_limited_noise(samples=t.size, step_s=1e-3, band_hz=(1.0, 60.0), seed=34)
    outputs = ("acc_floor_1", "acc_floor_2", "acc_floor_3")
    y = truth.time_response(t, {"force_floor_1": force}, outputs=list(outputs))
    rng = np.random.default_rng(3434)
    noisy = {o: y[:, k] + 0.02 * np.sqrt(np.mean(y[:, k] ** 2)) * rng.standard_normal(t.size)
             for k, o in enumerate(outputs)}
    history = TimeHistory(t, {"force_floor_1": force}, noisy,
                          units={"force_floor_1": "N", **{o: "m/s^2" for o in outputs}}, source="shaker test")
    return write_time_history(history, folder / "shaker.csv")


def test_a_shaker_record_drives_the_fmu_s_force_input_and_the_truth_is_within_the_intervals(frame, shaker_record,
                                                                                           capsys):
    """The measured force drives the FMU's force input (the floors not driven held at 0 N). A time cost alone,
    from the nominal moduli 5-15 % off, stops in a local minimum of the lightly damped response and says so
    (exit 0: converged, but the verdict a model error or a local minimum, the residual far above the noise
    floor); the H1 log-FRF cost of the same record first, then the time cost from there (--start), brings the
    re-solve's moduli back within the 95 % intervals."""
    folder, fmu, _ = frame
    common = ["update", "fmu", str(fmu), "--data", str(shaker_record), "--update", "E_storey_1,E_storey_2,E_storey_3",
              "--hold-input", "force_floor_2=0,force_floor_3=0", "--workers", "1"]
    code, _, err = run_cli(capsys, [*common, "--cost", "time", "--noise-rms-percent", "2", "-o", str(folder / "cold")])
    assert code == 0 and "standard deviations from the noise floor" in err, err
    assert tomllib.loads((folder / "cold" / "convergence.toml").read_text())["verdict"] == "model error"
    code, _, err = run_cli(capsys, [*common, "--cost", "log-frf", "-o", str(folder / "frf")])
    assert code == 0, err
    code, _, err = run_cli(capsys, [*common, "--cost", "time", "--noise-rms-percent", "2", "--start",
                                    str(folder / "frf" / "parameters.toml"), "-o", str(folder / "time")])
    assert code == 0, err
    stage = tomllib.loads((folder / "time" / "uncertainty.toml").read_text())["stage"][0]
    for name, low, high, sd in zip(stage["parameters"], stage["interval_95_low"], stage["interval_95_high"],
                                   stage["standard_deviation_percent"]):
        assert low <= TRUTH[name] <= high, (name, low, high)
        assert sd < 0.01, (name, sd)  # 20 s of 2 % noise pin each storey's modulus to better than 0.01 %


def test_the_frame_example_updated_on_real_data_meets_the_resonances_of_every_driving_point(tmp_path_factory):
    """examples/three_storey_frame on the rig's measured FRFs: moduli, floor masses and damping fitted on the
    floor-1 file, the updated FMU's resonances within 0.3 % of those all three files show (the phase's 90 deg
    crossing of each driving point), the floor-2 and floor-3 files unseen by the fit. The magnitudes over the
    half-power bands reach 1.2 dB on the fitted file and 1.7 dB on the others, not the 1 dB goal (the example's
    text says why); the numbers the example's text states are held here. The figure and the animation are
    written. (The example's main runs once per process: test_frame_per_file_intervals.py reads its updates.)"""
    from support.frame_per_file import example_run

    tmp_path, summary, _ = example_run(tmp_path_factory.mktemp("frame_example"))
    for name, result in summary["files"].items():
        assert max(abs(e) for e in result["frequency_error_percent"]) < 0.3, (name, result)
    resonances = np.array([r["resonances_hz"] for r in summary["files"].values()])
    assert np.ptp(resonances, axis=0).max() < 0.005  # the three files' resonances agree to a fifth of a bin
    fitted, *others = summary["files"].values()
    assert max(fitted["half_power_error_db"]) < 1.25  # the text: 0.9-1.2 dB
    assert max(max(r["half_power_error_db"]) for r in others) < 1.75  # the text: 0.3-1.7 dB
    values = summary["values"]
    for k, stated in zip((1, 2, 3), (5.30, 4.45, 4.65)):  # the text's floor masses [kg]
        assert values[f"m_floor_{k}"] == pytest.approx(stated, abs=0.005)
    assert all(51.5e9 <= values[f"E_storey_{k}"] < 58.5e9 for k in (1, 2, 3))  # the text: 52-58 GPa
    per_file = summary["per_file"]  # the same fit on each driving point's file

    def spread(name: str) -> float:
        fits = [fit[name] for fit in per_file.values()]
        return max(fits) / min(fits) - 1

    # masses and moduli are not told apart between driving points, the total mass is (the text's 7 %, 8 %, 1 %)
    assert 0.05 < max(spread(f"m_floor_{k}") for k in (1, 2, 3)) < 0.075
    assert 0.06 < max(spread(f"E_storey_{k}") for k in (1, 2, 3)) < 0.085
    totals = [sum(fit[f"m_floor_{k}"] for k in (1, 2, 3)) for fit in per_file.values()]
    assert max(totals) / min(totals) - 1 < 0.015
    for k in (1, 2, 3):  # the fitted file's damping within the three files' scatter (4-7 %), near the owners' 0.2 %
        assert min(fit[f"damping_mode_{k}"] for fit in per_file.values()) <= values[f"damping_mode_{k}"] \
            <= max(fit[f"damping_mode_{k}"] for fit in per_file.values())
        assert 0.04 < spread(f"damping_mode_{k}") < 0.075
        assert 0.0013 < values[f"damping_mode_{k}"] < 0.003
    assert (tmp_path / "frame_frfs.png").stat().st_size > 50_000
    assert (tmp_path / "frame_modes.html").stat().st_size > 10_000
