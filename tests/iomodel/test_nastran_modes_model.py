"""Volts-volts models from a structure file whose [modes] table points at NASTRAN's modes instead of a deck.

The modes here are a tip-mass cantilever's, given in the reader's form (``NastranModes``: Modes in basic,
mass-normalised, with grid positions). The model's FRF between two grids is checked against a direct
solve of the same structure's FE equations (K - w^2 M + i w C) u = f, which shares no code with the modal
route; the residual flexibility against the FE's static solution; the errors of a bad file are one line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from support.cantilever import beam_deck
from support.modes_file import read_modes_of

from mace_fmu.deck.reader import read_deck_text
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import StructureModes, compute_modes
from mace_fmu.iomodel.modal_source import modal_structure, read_residual_flexibility
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.parameters.sets import ParameterSet

ZETA = 0.02
FORCE = (11, 2)  #: the shaker: grid 11 (mid-span), along basic Y
TIP = (21, 2)  #: the tip grid, along basic Y


STRUCTURE = f"""
[modes]
file = "cantilever.op2"
{{extra}}

[[actuators]]
name = "shaker"
description = "force at mid-span along Y"
dofs = [[{FORCE[0]}, {FORCE[1]}, 1.0]]

[[sensors]]
name = "disp_tip"
description = "tip displacement along Y"
kind = "displacement"
dofs = [[{TIP[0]}, {TIP[1]}, 1.0]]

[[sensors]]
name = "vel_tip"
description = "tip velocity along Y"
kind = "rate"
dofs = [[{TIP[0]}, {TIP[1]}, 1.0]]

[[sensors]]
name = "acc_mid"
description = "accelerometer at the shaker"
kind = "acceleration"
dofs = [[{FORCE[0]}, {FORCE[1]}, 1.0]]

[damping]
default = {ZETA}
"""


@pytest.fixture(scope="module")
def fe() -> StructureModes:
    """The cantilever's every mode (40: the massive DOFs' count) from the FE core."""
    return compute_modes(read_deck_text(beam_deck(eigrl="EIGRL,1,,1.0E+9"), name="cantilever.bdf"), configuration="0g",
                         max_hz=1e9)


def _structure(tmp_path: Path, fe: StructureModes, *, extra: str = "", text: str | None = None,
               parameters: ParameterSet | None = None):
    (tmp_path / "cantilever.op2").write_bytes(b"")  # the [modes] file; its content is given as read
    path = tmp_path / "cantilever.toml"
    path.write_text(text if text is not None else STRUCTURE.replace("{extra}", extra))
    return modal_structure(path, nastran_modes=read_modes_of(fe, tmp_path / "cantilever.op2"), parameters=parameters)


def _direct_frf(fe: StructureModes, frequencies_hz: np.ndarray, *, zeta: float, out: tuple[int, int] = TIP
                ) -> np.ndarray:
    """Displacement of ``out`` per shaker force [m/N] from (K - w^2 M + i w C)^-1 on the independent DOFs, C the
    modal damping ``zeta`` written as a physical matrix, M Phi diag(2 zeta w) Phi^T M."""
    t = fe.constraints.transform
    t = t.toarray() if hasattr(t, "toarray") else np.asarray(t)
    dense = lambda a: a.toarray() if hasattr(a, "toarray") else np.asarray(a)  # noqa: E731
    k, m = t.T @ dense(fe.stiffness) @ t, t.T @ dense(fe.model.mass) @ t
    phi = np.linalg.lstsq(t, fe.modes.shapes, rcond=None)[0]
    omega = 2 * np.pi * fe.frequencies_hz
    c = m @ phi @ np.diag(2 * zeta * omega) @ phi.T @ m
    dofs = fe.modes.dofs
    b = t.T[:, dofs.index(*FORCE)]
    row = t[dofs.index(*out)]
    return np.array([row @ np.linalg.solve(k - w**2 * m + 1j * w * c, b) for w in 2 * np.pi * frequencies_hz])


def test_frf_between_two_grids_equals_the_direct_solve_of_the_fe_equations(tmp_path, fe):
    structure = _structure(tmp_path, fe)
    assert structure.labels[:2] == ("mode 1", "mode 2") and structure.configuration == "modes"
    model = volts_model(structure)
    f = np.geomspace(0.5, 400.0, 60)
    f = np.sort(np.concatenate([f, fe.frequencies_hz[fe.frequencies_hz < 400.0]]))  # at the resonances too
    h = model.frequency_response(f)
    outs, ins = list(model.system.output_labels), list(model.system.input_labels)
    w = 2 * np.pi * f
    # the modal superposition written out from the modes as read: sum phi_out phi_in / (w_k^2 - w^2 + 2 i z w_k w)
    shapes, omega = fe.modes.shapes, 2 * np.pi * fe.frequencies_hz
    dofs = fe.modes.dofs

    def superposition(out: tuple[int, int]) -> np.ndarray:
        terms = shapes[dofs.index(*out)] * shapes[dofs.index(*FORCE)]
        return np.array([np.sum(terms / (omega**2 - x**2 + 2j * ZETA * omega * x)) for x in w])

    direct, collocated = _direct_frf(fe, f, zeta=ZETA), _direct_frf(fe, f, zeta=ZETA, out=FORCE)
    for name, modal, fe_solve in (("disp_tip", superposition(TIP), direct),
                                  ("vel_tip", 1j * w * superposition(TIP), 1j * w * direct),
                                  ("acc_mid", -w**2 * superposition(FORCE), -w**2 * collocated)):
        got = h[:, outs.index(name), ins.index("shaker")]
        # relative to the FRF's peak: at the antiresonances both are round-off of the peak's size
        assert np.max(np.abs(got - modal)) < 1e-10 * np.max(np.abs(modal)), name
        # the direct solve: the lowest eigenvalue is known to eps (f_max / f_1)^2 ~ 1e-8 of itself (the axial
        # modes reach 1e5 Hz), which the resonance peaks carry
        assert np.max(np.abs(got - fe_solve)) < 3e-8 * np.max(np.abs(fe_solve)), name
    assert model.system.D[outs.index("acc_mid"), ins.index("shaker")] > 0  # the accelerometer's feedthrough


def test_modal_parameters_are_the_only_parameters(tmp_path, fe):
    structure = _structure(tmp_path, fe)
    nominal = volts_model(structure)
    changed = volts_model(structure, parameters=ParameterSet({"frequency_scale:mode 1": 1.1, "damping:mode 1": 0.05}))
    poles = lambda m: np.sort(np.abs(np.linalg.eigvals(m.system.A)))  # noqa: E731
    w1 = 2 * np.pi * fe.frequencies_hz[0]
    assert np.isclose(poles(nominal)[0], w1, rtol=1e-9) and np.isclose(poles(changed)[0], 1.1 * w1, rtol=1e-9)
    with pytest.raises(MaceError, match=r"E_steel.*NASTRAN's modes, not an FE model.*frequency_scale_mode"):
        volts_model(structure, parameters=ParameterSet({"E_steel": 2e11}))


def test_residual_flexibility_makes_the_truncated_model_meet_the_static_solution(tmp_path, fe):
    """One mode kept and the rest as a residual flexibility: the model's displacement FRF is the two modes'
    term plus that flexibility, and at 0 Hz it is the FE's static solution K^-1 f."""
    t = fe.constraints.transform
    t = t.toarray() if hasattr(t, "toarray") else np.asarray(t)
    dense = lambda a: a.toarray() if hasattr(a, "toarray") else np.asarray(a)  # noqa: E731
    k = t.T @ dense(fe.stiffness) @ t
    dofs = fe.modes.dofs
    static = t[dofs.index(*TIP)] @ np.linalg.solve(k, t.T[:, dofs.index(*FORCE)])  # [m/N], NASTRAN's SOL 101
    kept = 1
    phi_out, phi_in = fe.modes.shapes[dofs.index(*TIP), :kept], fe.modes.shapes[dofs.index(*FORCE), :kept]
    omega = 2 * np.pi * fe.frequencies_hz[:kept]
    residual = static - np.sum(phi_out * phi_in / omega**2)
    (tmp_path / "residual.csv").write_text("# static flexibility of the modes not kept [m/N]\n"
                                           "grid_a,component_a,grid_b,component_b,flexibility\n"
                                           f"{TIP[0]},{TIP[1]},{FORCE[0]},{FORCE[1]},{float(residual)!r}\n")
    structure = _structure(tmp_path, fe, extra='residual_flexibility = "residual.csv"')
    model = volts_model(structure, max_hz=float(fe.frequencies_hz[kept - 1]))
    f = np.array([1e-7, 1.0, 10.0, 60.0])
    w = 2 * np.pi * f
    h = model.frequency_response(f)[:, list(model.system.output_labels).index("disp_tip"), 0]
    superposition = np.array([np.sum(phi_out * phi_in / (omega**2 - x**2 + 2j * ZETA * omega * x)) for x in w])
    assert np.max(np.abs(h - (superposition + residual)) / np.abs(h)) < 1e-12
    assert abs(h[0] - static) / abs(static) < 1e-8  # at 1e-7 Hz the damping term 2 zeta w / w_1 is 1.4e-9
    assert abs(residual) > 1e-3 * abs(static)  # the correction is not negligible: without it 0 Hz would be off
    # the rate and acceleration sensors take no static correction (s R, s^2 R: no feedthrough)
    d = model.plant.static_correction
    names = [s.name for s in model.instruments.sensors]
    assert d[names.index("disp_tip"), 0] == residual and d[names.index("vel_tip"), 0] == 0.0


def test_an_instrument_on_a_grid_without_eigenvectors_names_the_grid_and_the_output_request(tmp_path, fe):
    text = STRUCTURE.replace("{extra}", "").replace(f"dofs = [[{TIP[0]}, {TIP[1]}, 1.0]]", "dofs = [[99, 2, 1.0]]", 1)
    with pytest.raises(MaceError) as info:
        _structure(tmp_path, fe, text=text)
    message = str(info.value)
    assert "\n" not in message
    assert "sensor 'disp_tip' sits on grid 99" in message and "DISPLACEMENT(PLOT) = ALL" in message
    assert "cantilever.op2" in message


@pytest.mark.parametrize("extra, expected", [
    ("subcase = 0", r"\[modes\]: subcase must be a positive integer"),
    ("shells = true", r"\[modes\]: unknown key 'shells'"),
    ('geometry = "missing.bdf"', r"geometry = 'missing.bdf': no such file"),
])
def test_a_bad_modes_table_is_one_line(tmp_path, fe, extra, expected):
    with pytest.raises(MaceError, match=expected) as info:
        _structure(tmp_path, fe, extra=extra)
    assert "\n" not in str(info.value) and "cantilever.toml:2" in str(info.value)


@pytest.mark.parametrize("text, expected", [
    ("grid,component,flexibility\n1,2,3.0\n", r"residual.csv:1: expected the header"),
    ("grid_a,component_a,grid_b,component_b,flexibility\n21,7,11,2,1e-6\n",
     r"residual.csv:2: expected .*components 1-6"),
    ("grid_a,component_a,grid_b,component_b,flexibility\n21,2,11,2,x\n", r"residual.csv:2: expected grid"),
    ("grid_a,component_a,grid_b,component_b,flexibility\n21,2,11,2,1e-6\n11,2,21,2,1e-6\n",
     r"residual.csv:3: grid 11 T2 to grid 21 T2 is given twice"),
])
def test_a_bad_residual_flexibility_file_is_one_line(tmp_path, text, expected):
    (tmp_path / "residual.csv").write_text(text)
    with pytest.raises(MaceError, match=expected):
        read_residual_flexibility(tmp_path / "residual.csv")


def test_a_residual_flexibility_lacking_a_pair_the_model_needs_names_it(tmp_path, fe):
    (tmp_path / "residual.csv").write_text("grid_a,component_a,grid_b,component_b,flexibility\n21,1,11,2,1e-6\n")
    structure = _structure(tmp_path, fe, extra='residual_flexibility = "residual.csv"')
    with pytest.raises(MaceError, match=r"no flexibility between grid 21 T2 \(sensor 'disp_tip'\) and grid 11 T2 "
                                        r"\(actuator 'shaker'\); add the row 21,2,11,2"):
        volts_model(structure)
