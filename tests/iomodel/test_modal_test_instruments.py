"""A modal test's instruments: force inputs [N] and accelerometers [m/s^2], or either in volts through a stated
sensitivity, against closed forms.

* A spring-mass's driving-point accelerance, a(jw) / F(jw) = -w^2 / (k - m w^2 + j 2 zeta sqrt(k m) w), in the
  model and (its step response at the samples) in the native FMU, whose model description declares N and m/s^2.
* The tip accelerance of a uniform clamped-free Euler-Bernoulli beam, -w^2 (cosh bL sin bL - sinh bL cos bL) /
  (EI b^3 (1 + cos bL cosh bL)), b^4 = rho A w^2 / EI, over its first three modes.
* Bad entries: one line naming the file and the instrument.
"""

from __future__ import annotations

import math
from xml.etree import ElementTree as ET

import numpy as np
import pytest
from support.decks import deck_text, line_of_bars, r

from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.frf import frequency_response
from mace_fmu.iomodel.model_options import ModelledElectronics
from mace_fmu.iomodel.volts import volts_model

BARE = ModelledElectronics(servos=False, bessel="none", delays=False)
MASS, STIFFNESS, ZETA = 2.5, 4.0e4, 0.02  # kg, N/m, -


def _spring_mass(tmp_path, instruments: str):
    """A mass on a spring along X (every other DOF held): one mode at sqrt(k/m)."""
    deck = tmp_path / "spring_mass.bdf"
    deck.write_text(deck_text(["GRID,1,,0.0,0.0,0.0", f"CONM2,2,1,,{r(MASS)}", f"CELAS2,3,{r(STIFFNESS)},1,1",
                               "SPC1,7,23456,1", "EIGRL,1,,,2"], case="SPC = 7\nMETHOD = 1\n"))
    spec = tmp_path / "spring_mass.toml"
    spec.write_text(f"[components]\nmass = [1]\n{instruments}\n[damping]\ndefault = {ZETA}\n")
    return volts_model(compute_modes(read_deck(deck), configuration="0g", structure_file=spec), electronics=BARE)


FORCE_AND_ACCELEROMETER = '''
[[actuators]]
name = "force"
description = "shaker force on the mass along X"
dofs = [[1, 1, 1.0]]

[[sensors]]
name = "acc"
description = "accelerometer on the mass along X"
kind = "acceleration"
dofs = [[1, 1, 1.0]]
'''


def _accelerance(f_hz: np.ndarray) -> np.ndarray:
    w = 2 * np.pi * f_hz
    return -w**2 / (STIFFNESS - MASS * w**2 + 2j * ZETA * math.sqrt(STIFFNESS * MASS) * w)


def test_a_spring_mass_driven_in_newtons_reads_its_accelerance_in_m_per_s2(tmp_path):
    model = _spring_mass(tmp_path, FORCE_AND_ACCELEROMETER)
    assert model.signal_units == {"force": "N", "acc": "m/s^2"}
    f = np.array([0.5, 10.0, math.sqrt(STIFFNESS / MASS) / (2 * np.pi), 30.0, 500.0])
    np.testing.assert_allclose(frequency_response(model.system, f)[:, 0, 0], _accelerance(f), rtol=1e-9)
    np.testing.assert_allclose(model.system.D[0, 0], 1.0 / MASS, rtol=1e-12)  # the mass line


def test_sensitivities_put_volts_at_the_boundary(tmp_path):
    """A load cell of 11.2 mV/N on the input and an accelerometer of 10.15 mV/(m/s^2): volts per volt."""
    text = (FORCE_AND_ACCELEROMETER.replace('dofs = [[1, 1, 1.0]]\n\n[[sensors]]',
                                            'dofs = [[1, 1, 1.0]]\nsensitivity = 0.0112\n\n[[sensors]]')
            + "sensitivity = 0.01015\n")
    model = _spring_mass(tmp_path, text)
    assert model.signal_units == {"force": "V", "acc": "V"}
    f = np.array([3.0, 20.0, 80.0])
    np.testing.assert_allclose(frequency_response(model.system, f)[:, 0, 0], _accelerance(f) * 0.01015 / 0.0112,
                               rtol=1e-9)


def test_the_native_fmu_declares_newtons_and_m_per_s2_and_steps_as_the_closed_form(tmp_path):
    """A step of 1 N: a(t) = (1/m) e^(-zeta w t) (cos wd t - zeta / sqrt(1 - zeta^2) sin wd t); the input is held
    over each step, so the FMU's samples are exact."""
    import zipfile

    import fmpy

    from mace_fmu.fmu.export import export_fmu

    fmu = export_fmu(_spring_mass(tmp_path, FORCE_AND_ACCELEROMETER), out_dir=tmp_path, name="spring_mass")
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    units = {v.get("name"): v.find("Real").get("unit") for v in root.iter("ScalarVariable")}
    assert (units["force"], units["acc"]) == ("N", "m/s^2")
    assert {u.get("name") for u in root.iter("Unit")} >= {"N", "m/s^2"}
    t = np.arange(0.0, 0.5 + 1e-12, 1e-3)
    inputs = np.zeros(len(t), dtype=[("time", float), ("force", float)])
    inputs["time"], inputs["force"] = t, 1.0
    run = fmpy.simulate_fmu(str(fmu), input=inputs, output=["acc"], step_size=1e-3, output_interval=1e-3,
                            stop_time=t[-1])
    wn = math.sqrt(STIFFNESS / MASS)
    wd = wn * math.sqrt(1 - ZETA**2)
    exact = np.exp(-ZETA * wn * t) * (np.cos(wd * t) - ZETA / math.sqrt(1 - ZETA**2) * np.sin(wd * t)) / MASS
    np.testing.assert_allclose(run["acc"][:len(t)], exact, rtol=0, atol=1e-9 / MASS)


E, RHO, LENGTH, WIDTH, ELEMENTS = 7.0e10, 2700.0, 1.0, 0.02, 60
AREA, INERTIA = WIDTH**2, WIDTH**4 / 12


def _cantilever(tmp_path):
    bulk = line_of_bars(n=ELEMENTS, length=LENGTH, e=E, nu=0.33, rho=RHO, area=AREA, i=INERTIA, ps="345")
    bulk += ["SPC1,7,123456,1", "EIGRL,1,,,12"]
    deck = tmp_path / "beam.bdf"
    # the reader's consistent mass is what converges to the continuum: lumped masses would lag by O(h^2) more
    deck.write_text(deck_text(bulk + ["PARAM,COUPMASS,1"], case="SPC = 7\nMETHOD = 1\n"))
    spec = tmp_path / "beam.toml"
    tip = ELEMENTS + 1
    spec.write_text(f'[components]\nbeam = ["1-{tip}"]\n[[actuators]]\nname = "tip_force"\n'
                    f'description = "force at the tip along Y"\ndofs = [[{tip}, 2, 1.0]]\n[[sensors]]\n'
                    f'name = "tip_acc"\ndescription = "accelerometer at the tip along Y"\nkind = "acceleration"\n'
                    f'dofs = [[{tip}, 2, 1.0]]\n[damping]\ndefault = 0.0\n')
    return volts_model(compute_modes(read_deck(deck), configuration="0g", structure_file=spec, mass="consistent"),
                       electronics=BARE)


def _euler_bernoulli_tip_accelerance(f_hz: np.ndarray) -> np.ndarray:
    w = 2 * np.pi * f_hz
    beta = (RHO * AREA * w**2 / (E * INERTIA)) ** 0.25
    x = beta * LENGTH
    receptance = (np.cosh(x) * np.sin(x) - np.sinh(x) * np.cos(x)) / (E * INERTIA * beta**3 * (1 + np.cos(x) * np.cosh(x)))
    return -w**2 * receptance


def test_the_tip_accelerance_of_a_cantilever_is_euler_bernoulli_s_over_its_first_three_modes(tmp_path):
    model = _cantilever(tmp_path)
    roots = np.array([1.8751040687, 4.6940911330, 7.8547574382])  # 1 + cos x cosh x = 0
    exact_hz = roots**2 / (2 * np.pi * LENGTH**2) * math.sqrt(E * INERTIA / (RHO * AREA))
    bending = [f for f in model.structure_modes.frequencies_hz if f > 0][:3]
    np.testing.assert_allclose(bending, exact_hz, rtol=2e-4)
    # between and around the first three modes, away from the resonances (where a 2e-4 shift is a large relative
    # error) and the antiresonances, tan x = tanh x (where the accelerance passes through 0 and the modes above
    # the twelve retained ones decide its small value)
    zeros_hz = np.array([3.9266023120, 7.0685827500])**2 / (2 * np.pi * LENGTH**2) * math.sqrt(E * INERTIA / (RHO * AREA))
    f = np.geomspace(0.2 * exact_hz[0], 1.2 * exact_hz[2], 400)
    away = (np.all(np.abs(f[:, None] / exact_hz[None, :] - 1) > 0.03, axis=1)
            & np.all(np.abs(f[:, None] / zeros_hz[None, :] - 1) > 0.1, axis=1))
    model_h = frequency_response(model.system, f[away])[:, 0, 0]
    exact = _euler_bernoulli_tip_accelerance(f[away])
    assert np.max(np.abs(model_h / exact - 1)) < 0.01
    # the antiresonances (a sign change of the real accelerance) fall where Euler-Bernoulli's do
    assert np.array_equal(np.sign(model_h.real), np.sign(exact.real))


@pytest.mark.parametrize("entry, message", [
    ('dofs = [[1, 1, 1.0]]\nsensitivity = 0.0', "actuator force: sensitivity must be > 0 V per N, got 0"),
    ('dofs = [[1, 1, 1.0]]\nsensitivity = -0.01', "actuator force: sensitivity must be > 0 V per N, got -0.01"),
    ('dofs = [[1, 1, 1.0]]\ngain = 2.0\nsensitivity = 0.01', "actuator force: give gain or sensitivity, not both"),
    ('dofs = [[1, 1, 1.0], [1, 5, 1.0]]', "actuator force: its DOFs mix translations and rotations"),
    ('dofs = [[1, 7, 1.0]]', "actuator force: component 7 of grid 1 is not 1-6"),
    ('dofs = [[9, 1, 1.0]]', "grid 9"),
])
def test_bad_instrument_entries_name_the_file_and_the_instrument(tmp_path, entry, message):
    with pytest.raises(MaceError, match="spring_mass.toml") as raised:
        _spring_mass(tmp_path, FORCE_AND_ACCELEROMETER.replace("dofs = [[1, 1, 1.0]]\n\n[[sensors]]",
                                                               f"{entry}\n\n[[sensors]]"))
    assert message in str(raised.value)


K_MASS_SIDE, K_GROUND_SIDE = 3.0e4, 1.0e4  # N/m: the massless grid's springs to the mass and to the ground


def _mass_and_massless_grid(tmp_path, *, force_grid: int, accelerometer_grid: int):
    """The mass (grid 1, on a spring to the ground) and a massless grid 2 hung between it and the ground."""
    deck = tmp_path / "two_grids.bdf"
    deck.write_text(deck_text(["GRID,1,,0.0,0.0,0.0", "GRID,2,,1.0,0.0,0.0", f"CONM2,2,1,,{r(MASS)}",
                               f"CELAS2,3,{r(STIFFNESS)},1,1", f"CELAS2,4,{r(K_MASS_SIDE)},1,1,2,1",
                               f"CELAS2,5,{r(K_GROUND_SIDE)},2,1", "SPC1,7,23456,1,2", "EIGRL,1,,,2"],
                              case="SPC = 7\nMETHOD = 1\n"))
    spec = tmp_path / "two_grids.toml"
    spec.write_text(FORCE_AND_ACCELEROMETER.replace("dofs = [[1, 1, 1.0]]\n\n[[sensors]]",
                                                    f"dofs = [[{force_grid}, 1, 1.0]]\n\n[[sensors]]")
                    .replace("kind = \"acceleration\"\ndofs = [[1, 1, 1.0]]",
                             f"kind = \"acceleration\"\ndofs = [[{accelerometer_grid}, 1, 1.0]]")
                    + f"[damping]\ndefault = {ZETA}\n")
    return volts_model(compute_modes(read_deck(deck), configuration="0g", structure_file=spec), electronics=BARE)


def test_an_accelerometer_on_a_massless_grid_driven_through_the_mass_reads_the_static_share_of_its_motion(tmp_path):
    """Grid 2 has no mass: it moves as k_m / (k_m + k_g) of the mass, whose spring is k + k_m k_g / (k_m + k_g)."""
    model = _mass_and_massless_grid(tmp_path, force_grid=1, accelerometer_grid=2)
    share = K_MASS_SIDE / (K_MASS_SIDE + K_GROUND_SIDE)
    k = STIFFNESS + K_MASS_SIDE * K_GROUND_SIDE / (K_MASS_SIDE + K_GROUND_SIDE)
    f = np.array([0.5, 10.0, math.sqrt(k / MASS) / (2 * np.pi), 30.0, 500.0])
    w = 2 * np.pi * f
    exact = share * -w**2 / (k - MASS * w**2 + 2j * ZETA * math.sqrt(k * MASS) * w)
    np.testing.assert_allclose(frequency_response(model.system, f)[:, 0, 0], exact, rtol=1e-9)


def test_an_accelerometer_where_a_force_meets_no_mass_is_refused_naming_both(tmp_path):
    with pytest.raises(MaceError, match="two_grids.toml") as raised:
        _mass_and_massless_grid(tmp_path, force_grid=2, accelerometer_grid=2)
    assert "sensor 'acc' (kind = \"acceleration\") reads grid 2 where a DOF carries no mass, and actuator 'force'" \
        in str(raised.value)
