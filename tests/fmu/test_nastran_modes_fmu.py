"""FMUs of a model built from NASTRAN's modes (a structure file's [modes] table): both kinds, modal parameters only.

The native (C runtime) and pythonfmu FMUs of a cantilever's modes, with a residual flexibility, run a step
in fmpy and must give the exact zero-order hold of the model's state space (1e-8 of each output's
range, the bound every FMU here is held to; the output after a step reads the input held over it); their
parameters are the modal ones, and a changed frequency scale moves the FMU as it moves the state-space model.
"""

from __future__ import annotations

from types import SimpleNamespace

import fmpy
import numpy as np
import pytest
import scipy.linalg
from support.cantilever import beam_deck
from support.fmu_checks import check_close, initialised_slave, make_inputs, nominal_slave, run_steps
from support.modes_file import read_modes_of

from mace_fmu.deck.reader import read_deck_text
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.fmu.export import export_fmu
from mace_fmu.fmu.naming import model_fmu_name
from mace_fmu.iomodel.modal_source import modal_structure
from mace_fmu.iomodel.parametric_data import parametric_arrays
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.parameters.sets import ParameterSet

pytestmark = pytest.mark.slow  # builds and runs a native and a pythonfmu FMU

STRUCTURE = """
[modes]
file = "cantilever.op2"
residual_flexibility = "residual.csv"

[[actuators]]
name = "shaker"
description = "force at mid-span along Y"
sensitivity = 0.0112

[[sensors]]
name = "disp_tip"
description = "tip displacement along Y"
kind = "displacement"
dofs = [[21, 2, 1.0]]

[[sensors]]
name = "acc_mid"
description = "accelerometer at the shaker"
kind = "acceleration"
dofs = [[11, 2, 1.0]]
sensitivity = 0.0102

[electronics]
actuator_delays_s = { shaker = 0.001 }

[damping]
default = 0.02
"""


def _held_reference(model, t: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Exact zero-order hold of the model's (A, B, C, D) as an FMU reports it: the output after the step from
    t_k to t_k+1 is C x(t_k+1) + D u_k, the input u_k still set (the accelerometer's feedthrough D reads it)."""
    a, b, c, d = (np.asarray(getattr(model.system, m)) for m in "ABCD")
    n, m = b.shape
    aug = np.zeros((n + m, n + m))
    aug[:n, :n], aug[:n, n:] = a, b
    e = scipy.linalg.expm(aug * (t[1] - t[0]))
    x, y = np.zeros(n), [np.zeros(c.shape[0])]  # at t_0 every input is 0
    for k in range(len(t) - 1):
        x = e[:n, :n] @ x + e[:n, n:] @ u[:, k]
        y.append(c @ x + d @ u[:, k])
    return np.array(y).T


def _setup(tmp_path):
    fe = compute_modes(read_deck_text(beam_deck(eigrl="EIGRL,1,,400.0"), name="cantilever.bdf"), configuration="0g")
    (tmp_path / "cantilever.op2").write_bytes(b"")
    (tmp_path / "residual.csv").write_text("grid_a,component_a,grid_b,component_b,flexibility\n21,2,11,2,2.0e-6\n")
    path = tmp_path / "cantilever.toml"
    path.write_text(STRUCTURE.replace('description = "force at mid-span along Y"',
                                      'description = "force at mid-span along Y"\ndofs = [[11, 2, 1.0]]'))
    return fe, modal_structure(path, nastran_modes=read_modes_of(fe, tmp_path / "cantilever.op2"))


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("nastran_modes_fmu")
    fe, structure = _setup(tmp)
    model = volts_model(structure)
    native = export_fmu(model, out_dir=tmp, runtime="native", name=model_fmu_name(model, runtime="native"))
    python = export_fmu(model, out_dir=tmp, runtime="pythonfmu", name=model_fmu_name(model, runtime="pythonfmu"))
    extract = lambda f: fmpy.extract(str(f), unzipdir=str(tmp_path_factory.mktemp(f.stem)))  # noqa: E731
    return SimpleNamespace(fe=fe, structure=structure, model=model, native=native, python=python,
                           dir_native=extract(native), dir_python=extract(python))


def test_both_fmu_kinds_step_as_the_state_space_model(built):
    assert built.native.name == "cantilever_modes_native.fmu" and built.python.name == "cantilever_modes_pythonfmu.fmu"
    t = np.arange(0.0, 1.0, 0.002)
    u = make_inputs("step", t, built.model.system.ninputs)
    reference = _held_reference(built.model, t, u)
    for unzipped in (built.dir_native, built.dir_python):
        fmu = nominal_slave(built.model, unzipped)
        try:
            check_close(built.model, run_steps(built.model, fmu, unzipped, t, u), reference)
        finally:
            fmu.terminate()
            fmu.freeInstance()


def test_the_fmus_have_modal_parameters_only_and_a_frequency_scale_moves_them_as_the_model(built):
    md = fmpy.read_model_description(built.dir_native)
    names = {v.name for v in md.modelVariables if v.causality == "parameter"}
    assert "frequency_scale_mode_1" in names and "damping_mode_1" in names
    assert not any(n.startswith(("E_", "k_", "m_")) for n in names)
    assert "NASTRAN's modes of cantilever.op2; modal parameters only" in md.description
    changed = volts_model(built.structure, parameters=ParameterSet({"frequency_scale:mode 1": 1.05}))
    t = np.arange(0.0, 1.0, 0.002)
    u = make_inputs("step", t, built.model.system.ninputs)
    reference = _held_reference(changed, t, u)
    for unzipped in (built.dir_native, built.dir_python):
        fmu = initialised_slave(built.model, unzipped, {"frequency_scale_mode_1": 1.05})
        try:
            check_close(changed, run_steps(built.model, fmu, unzipped, t, u), reference)
        finally:
            fmu.terminate()
            fmu.freeInstance()
    with pytest.raises(MaceError, match="NASTRAN's modes, not an FE model"):
        parametric_arrays(built.model, physical=["E_steel"])
