"""Local feedback loops of a structure file, each with gains of its own or the shared ones.

Four torsional oscillators on their own grids (inertia J on a grounded spring k, nothing else free):
two carry a speed loop (torque = g_a K_f (u - K_b g_t theta')), the third a position loop on an encoder
(torque = g_a (K_a (r - c theta) - K_r c theta'), c = 180/pi: the loop works in degrees), the fourth the
speed loop's law on a rotation sensor, a plain gain loop (torque = g_a K_f (u - K_b g_s theta)). Each closed
loop is then J s^2 + d s + k' = 0 with d and k' from its own gains, so every pole is known in closed
form. Checked: the poles; the FMU parameters a loop of its own gets (K_f_<actuator>, ...); a parameter
set that changes one loop's gain; the native FMU against the exact ZOH, also with one loop's gain
changed at initialisation; and a structure file that names a gain a loop does not have.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import control as ct
import fmpy
import numpy as np
import pytest
from support.decks import deck_text

from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.model_options import ModelledElectronics
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.parameters import ParameterSet

#: (grid, inertia J [kg m^2], torsional stiffness k [N m/rad]) of each oscillator
OSCILLATORS = ((1, 2.0, 800.0), (2, 1.0, 900.0), (3, 0.5, 450.0), (4, 1.5, 600.0))
LOOPS = ("wheel_1", "wheel_2", "gimbal_3", "push_4")
ACTUATOR_GAIN, SENSOR_GAIN = 0.5, 2.0  # [N m/V], [V/(rad/s)]
DEG = 180.0 / math.pi
SHARED = {"K_f": 3.0, "K_b": 1.0, "K_a": 0.02, "K_r": 0.004}
OWN = {"wheel_2": {"K_f": 6.0, "K_b": 0.5}, "gimbal_3": {"K_a": 0.05, "K_r": 0.01}, "push_4": {"K_f": 100.0}}


def _deck() -> str:
    bulk = ["EIGRL,1,,,10", "SPC1,1,12345,1,2,3,4"]
    for grid, inertia, stiffness in OSCILLATORS:
        bulk += [f"GRID,{grid},,{float(grid)},0.0,0.0", f"CONM2,{10 + grid},{grid},,1.0\n,,,,,,{inertia}",
                 f"CELAS2,{20 + grid},{stiffness},{grid},6"]
    return deck_text(bulk, case="METHOD = 1\nSPC = 1\n")


def _instrument(table: str, name: str, grid: int, gain: float, kind: str = "") -> str:
    kind_line = f'kind = "{kind}"\n' if kind else ""
    return (f'\n[[{table}]]\nname = "{name}"\ndescription = "{name}"\n{kind_line}'
            f"dofs = [[{grid}, 6, 1.0]]\ngain = {gain}\n")


def _structure(*, own: bool = True, wheel_2: str | None = None) -> str:
    text = "[damping]\ndefault = 0.0\n"
    for grid, name in enumerate(LOOPS, start=1):
        text += _instrument("actuators", name, grid, ACTUATOR_GAIN)
    for grid, name in ((1, "tach_1"), (2, "tach_2"), (3, "encoder_3")):
        text += _instrument("sensors", name, grid, SENSOR_GAIN, "rate")
    text += _instrument("sensors", "angle_4", 4, SENSOR_GAIN, "displacement")
    if wheel_2 is None:
        wheel_2 = ('{ sensor = "tach_2", forward_gain = 6.0, backward_gain = 0.5 }' if own else '"tach_2"')
    gimbal_3 = ('{ sensor = "encoder_3", angle_gain = 0.05, rate_gain = 0.01 }' if own else '"encoder_3"')
    push_4 = '{ sensor = "angle_4", forward_gain = 100.0 }' if own else '"angle_4"'
    return (text + f"\n[servos]\nwheel_forward_gain = {SHARED['K_f']}\nwheel_backward_gain = {SHARED['K_b']}\n"
            f"gimbal_angle_gain = {SHARED['K_a']}\ngimbal_rate_gain = {SHARED['K_r']}\n"
            f'wheels = {{ wheel_1 = "tach_1", wheel_2 = {wheel_2}, push_4 = {push_4} }}\n'
            f"gimbals = {{ gimbal_3 = {gimbal_3} }}\n")


def _model(tmp_path, *, parameters: ParameterSet | None = None, **structure):
    deck, spec = tmp_path / "oscillators.bdf", tmp_path / "oscillators.toml"
    deck.write_text(_deck())
    spec.write_text(_structure(**structure))
    return volts_model(compute_modes(read_deck(deck), configuration="0g", structure_file=spec, parameters=parameters),
                       electronics=ModelledElectronics(bessel="none", delays=False))


def _expected_poles(gains: dict[str, dict[str, float]]) -> np.ndarray:
    """Roots of J s^2 + d s + k' per oscillator, with the gains each loop has."""
    poles = []
    for (_, inertia, stiffness), loop in zip(OSCILLATORS, LOOPS):
        g = {**SHARED, **gains.get(loop, {})}
        if loop == "push_4":  # the gain loop on a rotation: a stiffness
            damping, extra = 0.0, ACTUATOR_GAIN * g["K_f"] * g["K_b"] * SENSOR_GAIN
        elif loop.startswith("wheel"):
            damping, extra = ACTUATOR_GAIN * g["K_f"] * g["K_b"] * SENSOR_GAIN, 0.0
        else:
            damping, extra = ACTUATOR_GAIN * g["K_r"] * DEG, ACTUATOR_GAIN * g["K_a"] * DEG
        poles += list(np.roots([inertia, damping, stiffness + extra]))
    return np.sort_complex(np.array(poles))


def _poles(model) -> np.ndarray:
    # the position loop's encoder angle is an integrated rate: the structure gets a state per loop that no
    # mode sets; remove the zero poles the open integrators of the speed loops' rate-only rows leave
    poles = np.linalg.eigvals(model.system.A)
    return np.sort_complex(poles[np.abs(poles) > 1e-9])


@pytest.mark.parametrize("own", [False, True], ids=["shared gains", "gains of their own"])
def test_each_loop_closes_with_its_own_gains(tmp_path, own):
    model = _model(tmp_path, own=own)
    np.testing.assert_allclose(_poles(model), _expected_poles(OWN if own else {}), rtol=1e-9)


def test_a_loop_of_its_own_gets_fmu_parameters_of_its_own_and_the_shared_ones_stay(tmp_path):
    from mace_fmu.iomodel.parametric import ParametricSystem
    from mace_fmu.iomodel.parametric_data import parametric_arrays

    system = ParametricSystem(parametric_arrays(_model(tmp_path)))
    values = dict(zip(system.parameter_names, np.asarray(system.nominal, dtype=float)))
    # wheel_1 uses the shared K_f, K_b; the position loop has both gains of its own, so no shared K_a, K_r
    assert {n: values[n] for n in values if n.startswith("K_")} == {
        "K_f": 3.0, "K_b": 1.0, "K_f_wheel_2": 6.0, "K_b_wheel_2": 0.5, "K_f_push_4": 100.0, "K_a_gimbal_3": 0.05,
        "K_r_gimbal_3": 0.01}


def test_a_parameter_set_changes_one_loops_gain(tmp_path):
    changed = ParameterSet({"K_f_wheel_2": 9.0, "K_f": 4.0})
    model = _model(tmp_path, parameters=changed)
    # the shared K_f acts on wheel_1 alone: wheel_2 and push_4 have their own
    expected = {**OWN, "wheel_1": {"K_f": 4.0}, "wheel_2": {**OWN["wheel_2"], "K_f": 9.0}}
    np.testing.assert_allclose(_poles(model), _expected_poles(expected), rtol=1e-9)
    with pytest.raises(MaceError, match="no position loop on an actuator 'wheel_1'"):
        _model(tmp_path, parameters=ParameterSet({"K_a_wheel_1": 0.1}))


def test_native_fmu_steps_as_the_exact_zoh_with_one_loops_gain_changed_at_initialisation(tmp_path):
    from support.fmu_checks import zoh_reference

    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.parametric import ParametricSystem
    from mace_fmu.iomodel.parametric_data import parametric_arrays

    model = _model(tmp_path)
    arrays = parametric_arrays(model)
    rebuilt = ParametricSystem(arrays)
    names, nominal = list(rebuilt.parameter_names), np.asarray(rebuilt.nominal, dtype=float)
    changed = nominal.copy()
    changed[names.index("K_r_gimbal_3")] = 0.02
    fmu = export_fmu(model, out_dir=tmp_path, name="oscillators", arrays=arrays)
    t = np.arange(0.0, 0.5 + 1e-12, 1e-3)
    inputs = np.zeros(len(t), dtype=[("time", float)] + [(n, float) for n in model.system.input_labels])
    inputs["time"], inputs["wheel_1"], inputs["wheel_2"], inputs["gimbal_3"], inputs["push_4"] = t, 0.5, 1.0, 2.0, 1.0
    u = np.stack([inputs[n] for n in model.system.input_labels])
    outputs = list(model.system.output_labels)
    for start, reference in (({}, model.system), ({"K_r_gimbal_3": 0.02}, ct.ss(*rebuilt.build(changed)))):
        run = fmpy.simulate_fmu(str(fmu), input=inputs, output=outputs, step_size=1e-3, output_interval=1e-3,
                                stop_time=t[-1], start_values=start)
        y = np.stack([run[o] for o in outputs])[:, :len(t)]
        ref = zoh_reference(SimpleNamespace(system=reference), t, u)[:, :y.shape[1]]
        assert np.max(np.abs(y - ref) / np.ptp(ref, axis=1, keepdims=True)) <= 1e-10, start
    # the changed rate gain is the gimbal loop's damping: its poles moved as the closed form says
    expected = _expected_poles({**OWN, "gimbal_3": {**OWN["gimbal_3"], "K_r": 0.02}})
    poles = np.linalg.eigvals(ct.ss(*rebuilt.build(changed)).A)
    np.testing.assert_allclose(np.sort_complex(poles[np.abs(poles) > 1e-9]), expected, rtol=1e-9)


@pytest.mark.parametrize("entry, message", [
    ('{ sensor = "tach_2", angle_gain = 1.0 }', r"unknown key\(s\) \['angle_gain'\]; a wheel loop takes 'sensor'"),
    ('{ forward_gain = 1.0 }', "expected a sensor name or a table with 'sensor'"),
    ('{ sensor = "tach_2", forward_gain = "fast" }', "forward_gain must be a finite number, got 'fast'"),
    ('{ sensor = "no_such_sensor" }', "no_such_sensor"),
])
def test_a_malformed_loop_is_refused_naming_the_file_and_the_loop(tmp_path, entry, message):
    with pytest.raises(MaceError, match=message) as caught:
        _model(tmp_path, wheel_2=entry)
    assert "oscillators.toml" in str(caught.value)
