"""modelica_like: block diagrams compiled with control.interconnect, checked against hand-derived
python-control models, the Pade/Bessel blocks against their definitions, errors and Modelica."""

from __future__ import annotations

import doctest
import re

import control as ct
import numpy as np
import pytest

import modelica_like
from modelica_like import PD, PI, BesselFilter, Gain, Integrator, ModelError, PadeDelay, StateSpace, Sum, System

# python-control warns about unused signals, duplicate names, ...: none of that may leak out.
pytestmark = pytest.mark.filterwarnings("error")

W = np.logspace(-1, 3, 50)  # rad/s


def freqresp(sys: ct.StateSpace, w: np.ndarray) -> np.ndarray:
    """H(jw) as an array (len(w), p, m), evaluated from A, B, C, D directly."""
    A, B, C, D = (np.asarray(M, dtype=float) for M in (sys.A, sys.B, sys.C, sys.D))
    n = A.shape[0]
    return np.array([C @ np.linalg.solve(1j * wk * np.eye(n) - A, B) + D if n else D + 0j
                     for wk in w])


def assert_same_response(a: ct.StateSpace, b: ct.StateSpace, rtol: float) -> None:
    Ha, Hb = freqresp(a, W), freqresp(b, W)
    assert Ha.shape == Hb.shape
    err = np.abs(Ha - Hb) / np.maximum(np.abs(Hb), 1e-300)
    assert err.max() < rtol, err.max()


def oscillator(w0: float = 3.0, zeta: float = 0.05) -> tuple[np.ndarray, ...]:
    """A, B, C, D of w0^2 / (s^2 + 2 zeta w0 s + w0^2), D = 0."""
    return (np.array([[0.0, 1.0], [-w0**2, -2 * zeta * w0]]), np.array([[0.0], [w0**2]]),
            np.array([[1.0, 0.0]]), np.zeros((1, 1)))


# --- compiled diagrams against hand-derived python-control models --------------------------------
def test_series_plant_gain_delay_matches_control_series():
    A, B, C, D = oscillator()
    K, T = 2.5, 0.01
    s = System("chain")
    s.add(PadeDelay("delay", T, order=3))  # added first: state order must not matter
    s.add(StateSpace("plant", A, B, C, D))
    s.add(Gain("k", K))
    s.connect("plant.y", "k.u")
    s.connect("delay.u", "k.y")  # either argument order, as in Modelica
    s.expose_input("u", "plant.u")
    s.expose_output("y", "delay.y")
    lti = s.compile()

    reference = ct.series(ct.ss(A, B, C, D), ct.tf(K, 1), ct.tf(*ct.pade(T, 3)))
    assert isinstance(lti, ct.StateSpace) and lti.isctime(strict=True)
    assert lti.nstates == 5 and (lti.ninputs, lti.noutputs) == (1, 1)
    assert lti.state_labels == ["delay.x[1]", "delay.x[2]", "delay.x[3]",
                                "plant.x[1]", "plant.x[2]"]
    assert_same_response(lti, ct.ss(reference), rtol=1e-10)
    assert lti.D[0, 0] == 0.0 and np.isclose(lti.dcgain(), K, rtol=1e-12)


def test_pd_feedback_loop_matches_control_feedback():
    m, k, c, tau = 2.0, 50.0, 0.5, 0.02
    A = np.array([[0, 1, 0], [-k / m, -c / m, 1 / m], [0, 0, -1 / tau]])
    B = np.array([[0.0], [0.0], [1 / tau]])
    C = np.array([[1.0, 0, 0], [0, 1.0, 0]])  # position, velocity
    kp, kd = 100.0, 10.0

    s = System("loop")
    s.add(StateSpace("plant", A, B, C, 0, inputs=["force"], outputs=["pos", "vel"]))
    s.add(Sum("err"))  # cmd - pos
    s.add(Sum("rate_err", signs=(-1,)))  # 0 - vel
    s.add(PD("pd", kp=kp, kd=kd))
    s.expose_input("cmd", "err.u1")
    s.connect("plant.y[pos]", "err.u2")
    s.connect("plant.y[vel]", "rate_err.u1")
    s.connect("err.y", "pd.x")
    s.connect("rate_err.y", "pd.dx")
    s.connect("pd.y", "plant.u")
    s.expose_output(["pos", "vel"], "plant.y")
    lti = s.compile()

    # Hand-derived: u = kp*cmd - [kp, kd] @ y, so y/cmd = feedback(G, [kp, kd]) * kp.
    G = ct.ss(A, B, C, np.zeros((2, 1)))
    gain = ct.ss(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), [[kp, kd]])
    reference = ct.series(ct.ss([], [], [], [[kp]]), ct.feedback(G, gain))
    poles, ref_poles = np.sort_complex(lti.poles()), np.sort_complex(reference.poles())
    np.testing.assert_allclose(poles, ref_poles, rtol=1e-9)
    assert np.all(poles.real < 0)
    assert_same_response(lti, reference, rtol=1e-9)
    assert np.allclose(lti.dcgain().ravel(), [kp / (k + kp), 0.0])


def test_names_slices_and_fan_out():
    s = System("named")
    s.add(StateSpace("plant", -np.eye(2), np.eye(2), np.eye(2), 0, inputs=["fx", "fy"],
                     outputs=["gyro_x", "gyro_y"], states=["theta", "omega"]))
    s.add(BesselFilter("filt", 2, 100.0, signals=["gyro_x", "gyro_y"]))
    s.add(PI("ctrl", kp=1.0, ki=2.0, size=2))
    s.add(Integrator("acc"))
    s.connect("plant.y[1:2]", "filt.u")
    s.connect("filt.y", "ctrl.u")
    s.connect("plant.y[gyro_y]", "acc.u")
    s.expose_input(["fx_cmd", "fy_cmd"], "plant.u")
    s.expose_output("rate_x", "filt.y[gyro_x]")
    s.expose_output("ctrl_2", "ctrl.y[2]")
    s.expose_output("angle_y", "acc.y")
    lti = s.compile()
    assert lti.input_labels == ["fx_cmd", "fy_cmd"]
    assert lti.output_labels == ["rate_x", "ctrl_2", "angle_y"]
    assert lti.state_labels == ["plant.theta", "plant.omega", "filt.x[1,1]", "filt.x[1,2]",
                                "filt.x[2,1]", "filt.x[2,2]", "ctrl.x[1]", "ctrl.x[2]", "acc.x[1]"]
    assert s.inputs == ("fx_cmd", "fy_cmd") and s.outputs == ("rate_x", "ctrl_2", "angle_y")
    # At 1e-3 rad/s: plant 1/(s+1) ~ 1, filter ~ 1, PI ~ ki/s, integrator 1/s.
    H = freqresp(lti, [1e-3])[0]
    assert abs(H[0, 0] - 1) < 2e-3 and abs(H[0, 1]) < 1e-12
    assert abs(H[1, 1] - 2 / 1e-3j) / 2e3 < 2e-3 and abs(H[1, 0]) < 1e-12
    assert abs(H[2, 1] - 1 / 1e-3j) / 1e3 < 2e-3

    # One system input may drive several connectors.
    f = System("fan")
    f.add(Gain("a", 2.0))
    f.add(Gain("b", -3.0))
    f.add(Sum("sum", signs=(1, 1)))
    f.expose_input("cmd", "a.u")
    f.expose_input("cmd", "b.u")
    f.connect("a.y", "sum.u1")
    f.connect("b.y", "sum.u2")
    f.expose_output("y", "sum.y")
    g = f.compile()
    assert g.input_labels == ["cmd"] and g.nstates == 0 and g.isctime(strict=True)
    assert g.D[0, 0] == pytest.approx(2.0 - 3.0, rel=1e-15)


# --- the delay and filter blocks -----------------------------------------------------------------
def test_pade_delay_phase_and_zero_delay():
    T = 2.44e-3
    d = PadeDelay("d", T, order=3)
    f = np.linspace(0.0, 1 / (10 * T), 4001)[1:]
    H = freqresp(d.lti(), 2 * np.pi * f)[:, 0, 0]
    phase_err = np.degrees(np.unwrap(np.angle(H)) + 2 * np.pi * f * T)
    assert np.abs(phase_err).max() < 1.0
    assert np.abs(np.abs(H) - 1).max() < 1e-12  # all-pass
    assert d.A.shape == (3, 3) and d.D[0, 0] == -1.0  # biproper, D = (-1)**order

    zero = PadeDelay("z", 0.0)
    assert zero.A.shape == (0, 0) and zero.states == () and zero.D.tolist() == [[1.0]]
    s = System("pure")
    s.add(zero)
    s.expose_input("u", "z.u")
    s.expose_output("y", "z.y")
    lti = s.compile()
    assert lti.nstates == 0 and lti.D.tolist() == [[1.0]]

    two = PadeDelay("two", T, order=2, signals=["a", "b"])
    assert two.states == ("x[1,1]", "x[1,2]", "x[2,1]", "x[2,2]")
    assert two.D.tolist() == [[1.0, 0.0], [0.0, 1.0]]


def test_bessel_8_pole_200_hz():
    b = BesselFilter("mace", 8, 200.0)
    assert b.A.shape == (8, 8) and len(b.states) == 8 and not b.D.any()

    def H(f_hz: float) -> complex:
        return complex(freqresp(b.lti(), [2 * np.pi * f_hz])[0, 0, 0])

    assert abs(20 * np.log10(abs(H(200.0))) + 3.0103) < 0.01
    assert abs(abs(H(0.0)) - 1) < 1e-12
    df = 1e-3  # group delay -dphi/dw from the phase slope at 1 Hz
    delay = -(np.angle(H(1 + df)) - np.angle(H(1 - df))) / (2 * np.pi * 2 * df)
    assert abs(delay / 2.44e-3 - 1) < 0.05, delay  # thesis Fig. 3.18: "a 2.44 ms delay"
    assert np.all(np.linalg.eigvals(b.A).real < 0)


# --- errors --------------------------------------------------------------------------------------
def servo_parts() -> System:
    s = System("servo")
    A, B, C, D = oscillator()
    s.add(StateSpace("plant", A, B, np.vstack([C, [0, 1]]), 0, inputs=["torque"],
                     outputs=["angle", "rate"]))
    s.add(Gain("k", 2.0))
    s.add(Sum("sum"))
    return s


def test_unconnected_inputs_are_all_named():
    s = servo_parts()
    s.connect("plant.y[angle]", "sum.u2")
    s.connect("sum.y", "k.u")
    s.expose_output("angle", "plant.y[angle]")
    with pytest.raises(ModelError, match="2 block input element") as e:
        s.compile()
    assert "plant.u[torque]" in str(e.value) and "sum.u1[1]" in str(e.value)


def test_double_connection_names_both_sources():
    s = servo_parts()
    s.connect("k.y", "plant.u")
    with pytest.raises(ModelError, match=r"plant\.u\[torque\] is already driven by k\.y\[1\]") as e:
        s.connect("sum.y", "plant.u[torque]")
    assert "sum.y[1]" in str(e.value)
    with pytest.raises(ModelError, match=r"already driven by k\.y\[1\].*system input 'cmd'"):
        s.expose_input("cmd", "plant.u")
    s.expose_input("cmd", "sum.u1")
    with pytest.raises(ModelError, match=r"sum\.u1\[1\] is already driven by system input 'cmd'"):
        s.connect("plant.y[rate]", "sum.u1")


def test_size_mismatch_names_both_sizes():
    s = servo_parts()
    with pytest.raises(ModelError, match=r"plant\.y has size 2 but k\.u has size 1"):
        s.connect("plant.y", "k.u")
    with pytest.raises(ModelError, match=r"2 name\(s\) for plant\.u of size 1"):
        s.expose_input(["a", "b"], "plant.u")


def test_unknown_block_port_element_and_wrong_direction():
    s = servo_parts()
    with pytest.raises(ModelError, match=r"no block 'motor'; its blocks are plant, k, sum"):
        s.connect("motor.y", "k.u")
    with pytest.raises(ModelError,
                       match=r"no connector 'z'.*u \(input, size 1\), y \(output, size 2\)"):
        s.connect("plant.z", "k.u")
    with pytest.raises(ModelError, match=r"plant\.y has no element named 'gyro_q'; its elements "
                                         r"are angle, rate"):
        s.connect("plant.y[gyro_q]", "k.u")
    with pytest.raises(ModelError, match=r"index 3 is out of range for plant\.y \(size 2"):
        s.connect("plant.y[3]", "k.u")
    with pytest.raises(ModelError, match=r"plant\.y and sum\.y are both outputs"):
        s.connect("plant.y[1]", "sum.y")
    with pytest.raises(ModelError, match=r"malformed connector reference 'plant'"):
        s.connect("plant", "k.u")
    with pytest.raises(ModelError, match=r"block named 'k'"):
        s.add(Gain("k", 1.0))


def test_algebraic_loop_is_named_and_a_state_breaks_it():
    s = System("loop")
    s.add(Gain("g1", 0.5))
    s.add(Gain("g2", 0.25))
    s.add(Sum("sum", signs=(1, 1)))
    s.expose_input("r", "sum.u1")
    s.connect("sum.y", "g1.u")
    s.connect("g1.y", "g2.u")
    s.connect("g2.y", "sum.u2")
    s.expose_output("y", "g1.y")
    with pytest.raises(ModelError, match="algebraic loop") as e:
        s.compile()
    msg = str(e.value)
    cycle = re.search(r": ((?:\S+ -> )+\S+);", msg)[1].split(" -> ")
    assert cycle[0] == cycle[-1] and len(cycle) == 7
    assert set(cycle) == {"g1.u[1]", "g1.y[1]", "g2.u[1]", "g2.y[1]", "sum.u2[1]", "sum.y[1]"}

    ok = System("loop_ok")  # the same loop through an integrator is fine: y = 0.5 r / (s - 0.125)
    ok.add(Gain("g1", 0.5))
    ok.add(Integrator("int"))
    ok.add(Gain("g2", 0.25))
    ok.add(Sum("sum", signs=(1, 1)))
    ok.expose_input("r", "sum.u1")
    ok.connect("sum.y", "int.u")
    ok.connect("int.y", "g1.u")
    ok.connect("g1.y", "g2.u")
    ok.connect("g2.y", "sum.u2")
    ok.expose_output("y", "g1.y")
    lti = ok.compile()
    np.testing.assert_allclose(lti.A, [[0.125]], rtol=1e-15)
    assert lti.B[0, 0] * lti.C[0, 0] == 0.5


def test_no_exposed_outputs_or_inputs():
    s = System("mute")
    s.add(Gain("k", 1.0))
    s.expose_input("u", "k.u")
    with pytest.raises(ModelError, match="system 'mute' has no exposed outputs"):
        s.compile()
    osc = System("osc")  # an autonomous oscillator: not an input-output model
    osc.add(Integrator("i1"))
    osc.add(Integrator("i2"))
    osc.add(Gain("g", -4.0))
    osc.connect("i1.y", "i2.u")
    osc.connect("i2.y", "g.u")
    osc.connect("g.y", "i1.u")
    osc.expose_output("x", "i2.y")
    with pytest.raises(ModelError, match="system 'osc' has no exposed inputs"):
        osc.compile()


@pytest.mark.parametrize("make, pattern", [
    (lambda: PadeDelay("d", -1e-3), r"PadeDelay 'd': delay must be a finite number of seconds "
                                    r">= 0, got -0\.001"),
    (lambda: PadeDelay("d", 1e-3, order=0), r"PadeDelay 'd': order must be an integer >= 1, got 0"),
    (lambda: BesselFilter("f", 0, 200.0), r"BesselFilter 'f': order must be an integer >= 1"),
    (lambda: BesselFilter("f", 8, -1.0), r"cutoff_hz must be a finite frequency in Hz > 0"),
    (lambda: StateSpace("p", np.eye(4), np.ones((3, 2)), np.ones((1, 4)), np.zeros((1, 2))),
     r"StateSpace 'p': B has shape \(3, 2\) but should be \(4, 2\)"),
    (lambda: StateSpace("p", np.ones((2, 3)), np.ones((2, 1)), np.ones((1, 2)), 0),
     r"A has shape \(2, 3\) but should be square"),
    (lambda: StateSpace("p", np.eye(2), np.ones((2, 1)), np.ones((1, 2)), np.ones((2, 1))),
     r"D has shape \(2, 1\) but should be \(1, 1\)"),
    (lambda: StateSpace("p", np.eye(2), np.ones((2, 1)), np.ones((1, 2)), 0, inputs=["a", "b"]),
     r"B has shape \(2, 1\) but should be \(2, 2\)"),
    (lambda: Gain("k", [1.0, 2.0]), r"K must be a scalar or a 2-D array"),
    (lambda: PD("pd", kp=[1.0, 2.0], kd=1.0), r"kp must be a scalar or a vector of length 1"),
    (lambda: Gain("2k", 1.0), r"Gain name must be a Python identifier"),
])
def test_bad_block_parameters(make, pattern):
    with pytest.raises(ModelError, match=pattern):
        make()


# --- Modelica export -----------------------------------------------------------------------------
def test_to_modelica_round_trips_the_matrices(tmp_path):
    s = servo_parts()
    s.add(PadeDelay("delay", 2.44e-3, order=3))
    s.expose_input("angle cmd", "sum.u1")
    s.connect("plant.y[angle]", "sum.u2")
    s.connect("sum.y", "k.u")
    s.connect("k.y", "delay.u")
    s.connect("delay.y", "plant.u")
    s.expose_output(["angle", "end"], "plant.y")
    lti = s.compile()
    text = s.to_modelica()

    assert text.startswith('model servo "') and text.endswith("end servo;\n")
    declaration = r'^  Modelica\.Blocks\.Interfaces\.Real{} {} "{}";$'
    assert re.search(declaration.format("Input", "angle_cmd", "angle cmd"), text, re.M)
    assert re.search(declaration.format("Output", "angle", "angle"), text, re.M)
    assert re.search(declaration.format("Output", "end_", "end"), text, re.M)
    assert "Modelica.Blocks.Continuous.StateSpace lti(" in text
    assert "connect(angle_cmd, lti.u[1]);" in text and "connect(lti.y[2], end_);" in text

    def matrix(label: str) -> np.ndarray:
        body = re.search(rf"\b{label} = \[(.*?)\],", text, re.S)[1]
        return np.array([[float(x) for x in row.split(",")] for row in body.split(";")])

    for label in "ABCD":
        M = np.asarray(getattr(lti, label))
        assert matrix(label).shape == M.shape
        np.testing.assert_allclose(matrix(label), M, rtol=1e-12, atol=0)
    assert lti.A.shape == (5, 5)

    path = s.write_modelica(tmp_path / "Servo.mo", model_name="Servo")
    assert path.read_text().splitlines()[0].startswith("model Servo ")
    assert path.read_text().endswith("end Servo;\n")


def test_package_docstring_example_runs():
    result = doctest.testmod(modelica_like, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 10 and result.failed == 0


def test_numpy_algebra_matches_control_and_compile():
    """modelica_like.algebra (numpy/scipy only, used inside FMUs): its Pade realisation equals
    control.pade, and interconnect() of connection_matrices() equals compile()."""
    import control as ct
    import numpy as np

    from modelica_like import Gain, PadeDelay, StateSpace, Sum, System
    from modelica_like.algebra import interconnect, pade

    for delay, order in ((2.44e-3, 3), (5e-3, 2), (1e-3, 5)):
        a, b, c, d = pade(delay, order)
        num, den = ct.pade(delay, order)
        w = 2 * np.pi * np.array([1.0, 10.0, 100.0, 300.0])
        ours = np.array([(c @ np.linalg.solve(1j * x * np.eye(order) - a, b) + d)[0, 0] for x in w])
        np.testing.assert_allclose(ours, np.polyval(num, 1j * w) / np.polyval(den, 1j * w), atol=1e-14)
    s = System("loop")
    s.add(StateSpace("plant", [[0, 1], [-4, -0.4]], [[0], [1]], np.eye(2), 0, inputs=["f"], outputs=["x", "v"]))
    s.add(Sum("err"))
    s.add(Gain("k", [[20.0, 3.0]]))
    s.add(PadeDelay("d", 1e-3, 2))
    s.expose_input("cmd", "err.u1")
    s.connect("plant.y[x]", "err.u2")
    s.connect("err.y", "d.u")
    s.connect("d.y", "k.u[1]")
    s.connect("plant.y[v]", "k.u[2]")
    s.connect("k.y", "plant.u")
    s.expose_output("x", "plant.y[x]")
    ic = s.connection_matrices()
    a, b, c, d = interconnect([(x.A, x.B, x.C, x.D) for x in ic.blocks], ic.wiring, ic.entry, ic.exit)
    ref = s.compile()
    for ours, theirs in ((a, ref.A), (b, ref.B), (c, ref.C), (d, ref.D)):
        np.testing.assert_allclose(ours, theirs, atol=1e-12)
