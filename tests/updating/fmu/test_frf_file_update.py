"""An FMU updated against measured frequency responses given alone (an analyser's FRF file, no time history),
through the command a user with a shaker test runs.

The data are made by an independent route: the frame's FE model re-solved with other moduli
(``compute_modes(parameters=...)``) and its exact frequency response from the state space, written as a CSV
file of complex FRFs in (m/s^2)/N. The FMU, exported at the nominal moduli, only ever sees the file; the
update must bring its moduli to the re-solve's, the FMU's response coming from periodic runs
(mace_fmu/updating/engine/multisine.py) and its moduli from its own parameter route.
"""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from support.cli import run_cli
from support.paths import EXAMPLES

from mace_fmu.updating.engine.measured import FrequencyResponseData

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
    data = FrequencyResponseData(f, ("force_floor_1",), ("acc_floor_1", "acc_floor_2", "acc_floor_3"), h,
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


@pytest.mark.parametrize("extra, message", [
    (["--cost", "time"], "measured frequency responses are compared by the log-frf cost (--cost log-frf)"),
    (["--cost", "log-frf", "--band-hz", "40", "50"], "0 frequencies in 40-50 Hz (the file has 0.03125 to 32 Hz)"),
    (["--cost", "log-frf", "--band-hz", "9", "3"], "--band-hz 9 3: expected 0 <= LOW < HIGH"),
])
def test_bad_frf_requests_stop_before_any_run(frame, capsys, extra, message):
    folder, fmu, data = frame
    code, _, err = run_cli(capsys, ["update", "fmu", str(fmu), "--data", str(data), "--update", "E_storey_1",
                                    "-o", str(folder / "refused"), *extra])
    assert code == 2 and message in err, err
    assert not (folder / "refused").exists()
