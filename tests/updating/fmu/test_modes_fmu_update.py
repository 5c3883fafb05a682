"""An FMU of NASTRAN's modes (no FE behind it) updated through FMI on a frequency-response file: its modal
parameters are what an update of such a model can move.

The data are the volts-volts state space of the same NASTRAN modes with mode 7's damping ratio raised from 2 % to
3 % (computed by python-control from the modal model's matrices, not by any FMU), written as an analyser's CSV
file; the nominal native FMU, updated through its FMI parameter ``damping_mode_7`` over a band about that mode,
must come back to 3 %.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
from support.cli import run_cli

pytestmark = pytest.mark.slow

PLATE = Path(__file__).resolve().parents[3] / "examples" / "nastran_plate" / "plate.toml"


def test_an_fmu_of_nastran_s_modes_gets_its_damping_ratio_back_from_an_frf_file(tmp_path, capsys):
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.modal_source import modal_structure
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.parameters.sets import ParameterSet
    from mace_fmu.updating.engine.measured import MeasuredFrf
    from mace_fmu.updating.files import write_frequency_response

    structure = modal_structure(PLATE)
    fmu = export_fmu(volts_model(structure), out_dir=tmp_path, name="plate")
    truth = volts_model(structure, parameters=ParameterSet({"damping:mode 7": 0.03}))
    f7 = float(structure.frequencies_hz[6])
    f = np.linspace(0.9 * f7, 1.1 * f7, 81)
    outputs = ("acc_corner", "acc_middle")
    h = truth.frequency_response(f)
    rows = [list(truth.system.output_labels).index(o) for o in outputs]
    data = write_frequency_response(
        MeasuredFrf(f, ("shaker",), outputs, h[:, rows, :], source="plate test",
                              units={"shaker": "V", "acc_corner": "V", "acc_middle": "V"}),
        tmp_path / "plate_frf.csv")
    code, _, err = run_cli(capsys, ["update", "fmu", str(fmu), "--data", str(data), "--cost", "log-frf",
                                    "--update", "damping_mode_7", "-o", str(tmp_path / "out"), "--workers", "1"])
    assert code == 0, err
    values = tomllib.loads((tmp_path / "out" / "parameters.toml").read_text())["values"]
    assert values["damping_mode_7"] == pytest.approx(0.03, rel=2e-3)


def test_a_probe_that_cannot_resolve_a_delayed_feedthrough_says_so(tmp_path):
    """The plate's accelerometer at the shaker reads the force through a 20 us delay: at 20 and 40 samples per
    cycle the probe's driving-point response differs by a third; allowed one doubling only, it refuses."""
    from dataclasses import replace

    from mace_fmu.errors import MaceError
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.modal_source import modal_structure
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.updating.engine.multisine import multisine_probe
    from mace_fmu.updating.fmu.model import fmu_family

    structure = modal_structure(PLATE)
    model = fmu_family(export_fmu(volts_model(structure), out_dir=tmp_path, name="plate")).full({})
    f7 = float(structure.frequencies_hz[6])
    probe = replace(multisine_probe(np.linspace(0.9 * f7, 1.1 * f7, 9)), max_rate_doublings=1)
    with pytest.raises(MaceError, match="response to shaker still changes by .* when the sample rate doubles"):
        probe.response(model, inputs=["shaker"], outputs=["acc_corner"])
