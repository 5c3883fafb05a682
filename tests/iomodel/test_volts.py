"""Volts-volts models of the 1-g and 0-g structures against Tables 4.7 and 5.2 (thesis 3.5-3.7, 5.2)."""

from __future__ import annotations

import json

import control as ct
import numpy as np
import pytest

from mace_fmu.cli import main
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import DEFAULT_MAX_HZ, compute_modes
from mace_fmu.iomodel.frf import frequency_response
from mace_fmu.iomodel.modal_ss import modal_data
from mace_fmu.iomodel.model_options import ModelledElectronics, SignalSelection
from mace_fmu.iomodel.poles import closed_loop_poles
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.parameters.sets import ParameterSet, deck_values, parameter_names
from mace_fmu.thesis import table_4_7_comparison, table_5_2_comparison


@pytest.fixture(scope="module")
def v1():
    return volts_model(compute_modes(configuration="1g"))


@pytest.fixture(scope="module")
def v0():
    return volts_model(compute_modes(configuration="0g"))


def test_state_count_of_the_full_1g_model(v1):
    """Thesis 3.7: 160 modal + 104 Bessel + 36 delay = 300 states. Ours: the 3 wheel angles are
    unobservable (tachometers sense rate) and removed, so 157 + 104 + 36 = 297."""
    names = v1.system.state_labels
    assert v1.system.nstates == 297
    assert sum(n.startswith("structure.") for n in names) == 157
    assert sum(n.startswith("bessel.") for n in names) == 13 * 8
    assert sum(n.startswith("delay_") for n in names) == (7 + 5) * 3
    assert (v1.system.ninputs, v1.system.noutputs) == (9, 20)


def test_1g_closed_loop_poles_match_table_4_7(v1):
    rows = table_4_7_comparison(closed_loop_poles(v1))
    assert len(rows) == 29
    for row in rows:
        assert row.ours_hz is not None, row
        if not row.heavy:
            assert abs(row.error_percent) < 3.0, row
    # the servo-dominated modes land close too (reported, not required): gimbal pendula and delays
    heavy = [abs(r.error_percent) for r in rows if r.heavy]
    assert max(heavy) < 3.0


def test_0g_closed_loop_poles_match_table_5_2(v0):
    for row in table_5_2_comparison(closed_loop_poles(v0), column="g0"):
        assert row.ours_hz is not None, row
        if not row.heavy:
            assert abs(row.error_percent) < 3.0, row


def test_1g_model_also_matches_table_5_2_1g_column(v1):
    for row in table_5_2_comparison(closed_loop_poles(v1), column="g1"):
        if not row.heavy:
            assert abs(row.error_percent) < 3.0, row


def _encoder_angle_response(model, gimbal: str, encoder: str, f: np.ndarray) -> np.ndarray:
    """Encoder angle [deg] per commanded angle [deg]: the encoder output is a rate (1 V / (rad/s))."""
    h = model.frequency_response(f)
    i, o = model.system.input_labels.index(gimbal), model.system.output_labels.index(encoder)
    return h[:, o, i] / (2j * np.pi * f) * 180.0 / np.pi


@pytest.mark.parametrize("gimbal", ["primary_x", "primary_z", "secondary_x", "secondary_z"])
def test_gimbal_servo_tracks_its_command_with_a_few_hz_bandwidth(v0, v1, gimbal):
    """Thesis 3.6: 'below 3 Hz the input commands the relative angle'. 0-g: unit DC tracking; 1-g:
    gravity's pendulum stiffness competes with the proportional servo (DC 0.92-0.93)."""
    f = np.logspace(-2, np.log10(50.0), 2000)
    for model, dc in ((v0, 1.0), (v1, 0.927)):
        t = np.abs(_encoder_angle_response(model, f"gimbal_{gimbal}", f"encoder_{gimbal}", f))
        assert t[0] == pytest.approx(dc, abs=0.01)
        bandwidth = f[np.argmax(t < t[0] / np.sqrt(2))]
        assert 3.0 < bandwidth < 6.0
        # tracks below the first bending mode (1.94 Hz, where the Z servos see the bus bend)
        assert np.all(t[f < 1.0] > 0.9 * t[0])


def _peaks_below(model, f_max: float) -> list[float]:
    f = np.logspace(-1.5, np.log10(f_max), 4000)
    h = model.frequency_response(f)
    i, o = model.system.input_labels.index("gimbal_secondary_z"), model.system.output_labels.index("gyro_payload_z")
    mag = np.abs(h[:, o, i])
    return [f[k] for k in range(1, len(f) - 1) if mag[k] > mag[k - 1] and mag[k] > mag[k + 1]]


def test_0g_has_no_resonance_below_first_bending_while_1g_has_the_suspension(v0, v1):
    """Figs. 5.1/5.2: below the first bending mode the 0-g response is smooth; 1-g shows the
    suspension modes (0.23 Hz pendulum/twist/bounce, 0.44 Hz tilt)."""
    assert _peaks_below(v0, 1.8) == []
    peaks = _peaks_below(v1, 1.8)
    assert any(abs(p - 0.23) < 0.02 for p in peaks) and any(abs(p - 0.445) < 0.02 for p in peaks)


@pytest.mark.parametrize("route", ["model", "generic"])
def test_fast_frequency_response_equals_python_control(v1, route):
    """Both routes agree with control.frequency_response to 2e-9 of each channel's peak: the
    model's (core eigen-decomposition x exact output filters; 1.3e-9 on the weakest channel, whose
    matrices agree with a block-by-block evaluation to 1.7e-12, tests/iomodel/test_build_equivalence.py);
    the generic balanced one, which the 13 identical Bessel filters limit to ~1e-8, to 2e-8."""
    f = np.logspace(np.log10(0.5), np.log10(250.0), 60)
    ours = v1.frequency_response(f) if route == "model" else frequency_response(v1.system, f)
    ref = ct.frequency_response(v1.system, 2 * np.pi * f)
    theirs = np.moveaxis(np.asarray(ref.frdata), -1, 0)
    scale = np.abs(theirs).max(axis=0, keepdims=True)
    assert np.max(np.abs(ours - theirs) / scale) < (2e-9 if route == "model" else 2e-8)


def test_bessel_delay_variant_and_open_loop_variant():
    delay = volts_model(compute_modes(configuration="0g"), electronics=ModelledElectronics(bessel="delay"))
    # 13 analog channels x 3 Pade states (gyro extra delays merged) + 7 actuator delays x 3
    assert delay.system.nstates == 55 + 13 * 3 + 7 * 3
    bare = volts_model(compute_modes(configuration="0g"), electronics=ModelledElectronics(bessel="none", delays=False,
                                                                                          servos=False))
    assert bare.system.nstates == 55
    # open loop: the gimbal mechanisms are free, so A has zero eigenvalues (rigid gimbal rotation)
    assert np.min(np.abs(np.linalg.eigvals(bare.system.A))) < 1e-6


@pytest.mark.parametrize(("kwargs", "message"), [
    (lambda: dict(signals=SignalSelection(outputs=["gyro_payload_q"])),
     "unknown output signal 'gyro_payload_q'; allowed: encoder_primary_x"),
    (lambda: dict(signals=SignalSelection(inputs=["gimbal_tertiary"])),
     "unknown input signal 'gimbal_tertiary'; allowed: gimbal_primary_x"),
    (dict(parameters=ParameterSet({"delay_gimbal_primary_x": -1e-3})), "= -0.001 is outside \\[0, 1\\] s, the range of every delay parameter"),
    (dict(parameters=ParameterSet({"delay_gyro_payload_y": 1e-3})), "no delayed channel 'gyro_payload_y'"),
    (dict(parameters=ParameterSet({"E_unobtainium": 1e9})), "no such material; known: E_lexan_end"),
    (lambda: dict(electronics=ModelledElectronics(pade_order=0)), "pade_order must be an integer from 1 to 10"),
    (dict(max_hz=1.0), "below the first flexible mode"),
    (lambda: dict(electronics=ModelledElectronics(bessel="elliptic")), "bessel must be 'full', 'delay' or 'none'"),
    (dict(parameters=ParameterSet({"damping:1st W bending": 0.02})),
     "no mode labelled '1st W bending' in the 0g structure"),
    (dict(parameters=ParameterSet({"damping:1st Z bending": 1.5})), "= 1.5 is outside \\[0, 1\\], the range of every damping parameter"),
    (lambda: dict(signals=SignalSelection(motion_grids=[1, 999999])),
     "999999] are not in the 0g model; it has grids 1..112"),
    (lambda: dict(signals=SignalSelection(motion_grids="some")), "motion_grids must be grid IDs or 'all'"),
    (lambda: dict(signals=SignalSelection(motion_grids=1)), "motion_grids must be a list of grid IDs or 'all', got 1"),
    (lambda: dict(electronics=dict(servos=False)), "electronics must be a ModelledElectronics record, got dict"),
    # the modes fix the structure: a set that says otherwise is refused
    (dict(parameters=ParameterSet({"E_lexan_end": 1.0e9})), "parameters set MAT1 .* e = 1e\\+09 but the modes were "
                                                             "computed with"),
])
def test_bad_requests_are_value_errors_that_say_what_is_allowed(v0, kwargs, message):
    """Records refuse bad values when they are made (a callable here), volts_model what contradicts the modes."""
    pattern = message if "\\(" in message else message.replace("(", r"\(").replace(")", r"\)")
    with pytest.raises(ValueError, match=pattern):
        volts_model(v0.structure_modes, **(kwargs() if callable(kwargs) else kwargs))


def test_an_unknown_keyword_is_a_type_error(v0):
    with pytest.raises(TypeError, match="unexpected keyword argument 'servo'"):
        volts_model(v0.structure_modes, servo=False)


def test_signal_selection_keeps_names(v0):
    sub = volts_model(v0.structure_modes, signals=SignalSelection(inputs=["gimbal_secondary_z"],
                                                                  outputs=["gyro_payload_z"]))
    assert list(sub.system.input_labels) == ["gimbal_secondary_z"]
    assert list(sub.system.output_labels) == ["gyro_payload_z"]
    f = np.array([1.0, 10.0])
    full = frequency_response(v0.system, f)
    i, o = v0.system.input_labels.index("gimbal_secondary_z"), v0.system.output_labels.index("gyro_payload_z")
    np.testing.assert_allclose(frequency_response(sub.system, f)[:, 0, 0], full[:, o, i], rtol=1e-12)


def test_motion_outputs_add_grid_motion_and_leave_the_sensors_alone(v0):
    """Asking for grid motion keeps the states no sensor reads (the 3 wheel angles, in 0-g) and
    leaves the sensors' response as it was."""
    grids = v0.structure_modes.modes.dofs.grid_ids
    moving = volts_model(v0.structure_modes, signals=SignalSelection(motion_grids=[grids[0], grids[-1]]))
    assert list(moving.system.output_labels) == list(v0.system.output_labels) + [
        f"grid_{g}_{c}" for g in (grids[0], grids[-1]) for c in ("tx", "ty", "tz", "rx", "ry", "rz")]
    assert moving.system.nstates == v0.system.nstates + 3
    # asking only for sensors keeps the sensor model: no unread wheel-angle states
    quiet = volts_model(v0.structure_modes, signals=SignalSelection(motion_grids=[grids[0]], outputs=["gyro_bus_x"]))
    assert quiet.system.nstates == v0.system.nstates
    f = np.array([0.5, 2.0, 10.0, 40.0])
    h, hm = v0.frequency_response(f), moving.frequency_response(f)
    assert np.max(np.abs(hm[:, :20] - h) / np.abs(h).max(axis=0)) <= 1e-8  # of each channel's peak
    # open loop, no filters or delays: the motion is the plain modal sum over every retained mode,
    # zero-frequency ones included unreduced (1 / -w^2)
    bare = volts_model(v0.structure_modes, signals=SignalSelection(motion_grids=[grids[-1]]),
                       electronics=ModelledElectronics(servos=False, bessel="none", delays=False))
    data = modal_data(v0.structure_modes.modes, bare.instruments, max_hz=DEFAULT_MAX_HZ, motion_grids=[grids[-1]])
    w = 2 * np.pi * f
    wk = 2 * np.pi * np.where(np.abs(data.frequencies_hz) < 0.01, 0.0, data.frequencies_hz)
    for actuator in ("rwa_x", "active_strut_z", "gimbal_primary_x"):
        a = [x.name for x in bare.instruments.actuators].index(actuator)
        gain = bare.instruments.actuator(actuator).gain
        for c, component in enumerate(("tx", "ty", "tz", "rx", "ry", "rz")):
            row = data.motion_out[f"grid_{grids[-1]}_{component}"]
            modal = row * data.modal_b[:, a] * gain
            want = (modal[None, :] / (wk[None, :] ** 2 - w[:, None] ** 2
                                      + 2j * bare.plant.damping[None, :] * wk[None, :] * w[:, None])).sum(axis=1)
            got = bare.frequency_response(f)[:, 20 + c, list(bare.system.input_labels).index(actuator)]
            assert np.max(np.abs(want)) > 0
            assert np.max(np.abs(got - want)) <= 1e-9 * np.max(np.abs(want))


def test_cli_model_json_and_npz(capsys, tmp_path):
    npz, mo = tmp_path / "m.npz", tmp_path / "m.mo"
    assert main(["model", "0g", "--json", "--npz", str(npz), "--modelica", str(mo)]) == 0
    out, err = capsys.readouterr()
    data = json.loads(out)  # --json keeps stdout the JSON document; the confirmations go to stderr
    assert f"wrote {mo}" in err and f"wrote {npz}" in err
    assert data["states"] == 195 and len(data["inputs"]) == 9 and len(data["outputs"]) == 20
    first_z = next(p for p in data["poles"] if p["label"] == "1st Z bending")
    assert first_z["frequency_hz"] == pytest.approx(1.94, rel=0.03)
    saved = np.load(npz)
    assert saved["A"].shape == (195, 195) and list(saved["inputs"]) == data["inputs"]
    source = mo.read_text()
    assert source.startswith("model MACE_0g_volts") and source.rstrip().endswith("end MACE_0g_volts;")
    assert source.count("Modelica.Blocks.Interfaces.RealInput") == 9
    assert source.count("Modelica.Blocks.Interfaces.RealOutput") == 20


def test_cli_model_poles_prints_the_thesis_table(capsys):
    assert main(["model", "1g", "--poles", "--max-hz", "60"]) == 0
    out = capsys.readouterr().out
    assert "Table 4.7" in out and "time delay (gimbal_primary_x)" in out
    assert "removed: zero-frequency cluster" in out


def test_damping_override_moves_only_that_pole(v0):
    """Open-loop damping of the 0-g 5th Y bending mode from 1.6 % to 5 %: its closed-loop pole
    follows (the servos hardly touch it), the others stay."""
    base = {p.label: p for p in closed_loop_poles(v0) if "bending" in p.label}
    damped = volts_model(v0.structure_modes, parameters=ParameterSet({"damping:5th Y bending": 0.05}))
    new = {p.label: p for p in closed_loop_poles(damped) if "bending" in p.label}
    assert base["5th Y bending"].damping == pytest.approx(0.017, abs=0.002)
    assert new["5th Y bending"].damping == pytest.approx(0.05, abs=0.003)
    assert new["4th Z bending"].damping == pytest.approx(base["4th Z bending"].damping, rel=1e-6)


def test_the_model_takes_its_structure_from_the_modes_and_nothing_else():
    """The first argument is the modes (a configuration string is refused by name), whose configuration and
    parameter set the model takes: the 5th Y bending damping of the set given to compute_modes is the
    closed-loop pole's (the servos hardly touch it)."""
    with pytest.raises(MaceError, match="modes must be the StructureModes of compute_modes\\(...\\), got str"):
        volts_model("0g")
    modes = compute_modes(configuration="0g", parameters=ParameterSet({"damping:5th Y bending": 0.05}))
    model = volts_model(modes)
    assert model.parameters["damping:5th Y bending"] == 0.05
    assert model.structure_modes.structure.configuration == "0g"
    poles = {p.label: p for p in closed_loop_poles(model)}
    assert poles["5th Y bending"].damping == pytest.approx(0.05, abs=0.003)


def test_modes_agree_with_parameters_that_repeat_their_moduli(v0):
    """A set whose moduli are those the modes were computed with is no contradiction: same model."""
    deck = v0.structure_modes.structure.deck
    same = ParameterSet(deck_values(deck, parameter_names(deck, v0.structure_modes.structure.file)))
    again = volts_model(v0.structure_modes, parameters=same)
    assert np.array_equal(again.system.A, v0.system.A)
