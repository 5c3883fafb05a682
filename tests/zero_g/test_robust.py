"""Robustness sweep: the box from the FMU's declared bounds, the LQG design against analytic properties,
the FMU co-simulation against the state-space closed loop, and Dask against a serial run."""

from __future__ import annotations

import re

import numpy as np
import pytest
from support.paths import EXAMPLES

from mace_fmu.errors import MaceError
from mace_fmu.zero_g.robust.box import corner_points, monte_carlo_points, read_box
from mace_fmu.zero_g.robust.loop import LoopSpec

#: 1-based mode -> relative bound: 1st Y, 2nd Z, 3rd Y bending with Table 5.3's +-1.1, 2.5, 1.8 %
BOUNDS = {15: 0.011, 17: 0.025, 22: 0.018}
SCALES = tuple(f"frequency_scale_mode_{k}" for k in BOUNDS)


@pytest.fixture(scope="module")
def model_0g():
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.iomodel.volts import volts_model

    return volts_model(compute_modes(configuration="0g"))


@pytest.fixture(scope="module")
def bounded_fmu(model_0g, tmp_path_factory):
    from mace_fmu.fmu.export import export_fmu

    return export_fmu(model_0g, out_dir=tmp_path_factory.mktemp("robust"), name="MACE_0g_native",
                             frequency_bounds=BOUNDS)


@pytest.fixture(scope="module")
def unzipped(bounded_fmu, tmp_path_factory):
    import fmpy

    return fmpy.extract(str(bounded_fmu), unzipdir=tmp_path_factory.mktemp("unzipped"))


@pytest.fixture(scope="module")
def design(model_0g):
    from mace_fmu.zero_g.robust.design import design_compensator

    return design_compensator(model_0g.system)


@pytest.fixture(scope="module")
def reference(model_0g):
    from mace_fmu.iomodel.parametric import ParametricSystem
    from mace_fmu.iomodel.parametric_data import parametric_arrays

    return ParametricSystem(parametric_arrays(model_0g, physical=False))


def test_box_is_the_fmus_declared_frequency_bounds(bounded_fmu):
    """Only the bounded frequency scales form the box (not the unbounded ones, not damping in [0, 1])."""
    box = read_box(bounded_fmu)
    assert box.names == SCALES
    np.testing.assert_array_equal(box.nominal, 1.0)
    np.testing.assert_allclose(box.low, [1 - b for b in BOUNDS.values()], rtol=0, atol=1e-15)
    np.testing.assert_allclose(box.high, [1 + b for b in BOUNDS.values()], rtol=0, atol=1e-15)
    assert [box.label(i) for i in range(3)] == ["1st Y bending", "2nd Z bending", "3rd Y bending"]
    # an FMU's other parameters join with explicit ranges, which must hold the start value
    more = read_box(bounded_fmu, ranges={"damping_mode_17": (0.001, 0.05)})
    k = more.names.index("damping_mode_17")  # in the model description's order
    assert set(more.names) == {*SCALES, "damping_mode_17"} and (more.low[k], more.high[k]) == (0.001, 0.05)
    with pytest.raises(MaceError, match="hold its start value"):
        read_box(bounded_fmu, ranges={"damping_mode_17": (0.5, 0.6)})
    with pytest.raises(MaceError, match=r"range \[0.9, 1.1\] leaves its declared \[0.975, 1.025\]"):
        read_box(bounded_fmu, ranges={"frequency_scale_mode_17": (0.9, 1.1)})
    with pytest.raises(MaceError, match="no real parameter matching 'K_\\*'"):
        read_box(bounded_fmu, pattern="K_*")


def test_corners_and_the_seeded_sample():
    from mace_fmu.zero_g.robust.box import ParameterBox

    box = ParameterBox(names=("a", "b", "c"), nominal=np.array([1.0, 2.0, 3.0]), low=np.array([0.5, 1.0, 2.0]),
                       high=np.array([1.5, 4.0, 3.5]))
    corners = corner_points(box, [0, 2])
    assert sorted(p.values for p in corners) == sorted((a, 2.0, c) for a in (0.5, 1.5) for c in (2.0, 3.5))
    assert corners[-1].note == "a high, c high"
    sample = monte_carlo_points(box, samples=4000, seed=7)
    values = np.array([p.values for p in sample])
    assert np.all(values >= box.low) and np.all(values <= box.high)
    assert values.tolist() == [list(p.values) for p in monte_carlo_points(box, samples=4000, seed=7)]
    assert values.tolist() != [list(p.values) for p in monte_carlo_points(box, samples=4000, seed=8)]
    # uniform: mean (low + high) / 2 within 4 standard errors (width / sqrt(12 n))
    np.testing.assert_allclose(values.mean(axis=0), 0.5 * (box.low + box.high),
                               atol=4 * np.max(box.high - box.low) / np.sqrt(12 * 4000))


def test_design_model_is_within_the_balanced_truncation_bound(design):
    """|G(jw) - G_r(jw)| <= 2 x (sum of the discarded Hankel singular values) at every frequency (Glover)."""
    full, reduced = design.channels, design.reduced
    assert reduced.nstates == 30 and full.nstates == 195
    bound = 2.0 * design.hankel_singular_values[30:].sum()
    f = np.logspace(-1, 2.5, 50)
    a_r = np.array(reduced.A)
    b_r = np.hstack([reduced.B, design.reduced_disturbance])
    for w in 2 * np.pi * f:
        g = full.C @ np.linalg.solve(1j * w * np.eye(full.nstates) - full.A, full.B)
        g_r = reduced.C @ np.linalg.solve(1j * w * np.eye(30) - a_r, b_r)
        assert np.linalg.norm(g - g_r, 2) <= bound * (1 + 1e-9)


def test_lqg_closed_loop_poles_are_regulator_and_estimator_poles(design):
    """Separation principle: the design model with its LQG compensator has the poles of A - BK and of A - LC."""
    plant, comp = design.reduced, design.lqg.compensator
    a = np.block([[plant.A, plant.B @ comp.C], [comp.B @ plant.C, comp.A]])
    k, ell = design.lqg.regulator_gain, design.lqg.kalman_gain
    expected = np.concatenate([np.linalg.eigvals(plant.A - plant.B @ k), np.linalg.eigvals(plant.A - ell @ plant.C)])
    got = np.linalg.eigvals(a)
    for pole in expected:
        assert np.min(np.abs(got - pole)) <= 1e-6 * max(1.0, abs(pole))
    assert expected.real.max() < 0
    assert design.compensator.dt == 0.002 and design.compensator.nstates == 30


def test_fmu_co_simulation_equals_the_state_space_closed_loop(unzipped, design, reference):
    """At a corner of the box: FMU (C runtime, fmpy) and Python model + control.feedback give the same samples."""
    from mace_fmu.zero_g.robust.cosim import SampledCompensator, run_fmu_loop
    from mace_fmu.zero_g.robust.statespace import simulate_state_space, state_space_loop

    loop = LoopSpec()
    corner = {name: 1 + b * s for (name, b), s in zip(zip(SCALES, BOUNDS.values()), (1, -1, 1))}
    run = run_fmu_loop(unzipped, loop=loop, compensator=SampledCompensator.of(design.compensator), parameters=corner)
    closed = state_space_loop(reference, loop=loop, compensator=design.compensator, parameters=corner)
    y, u, verdict = simulate_state_space(closed, loop)
    assert np.ptp(y) > 0.1 and np.ptp(u) > 0.01  # the loop is driven and acts
    np.testing.assert_allclose(run.measurement_v, y, rtol=0, atol=1e-9 * np.abs(y).max())
    np.testing.assert_allclose(run.control_v, u, rtol=0, atol=1e-9 * np.abs(u).max())
    assert run.verdict.cost_rms_v == pytest.approx(verdict.cost_rms_v, rel=1e-9)
    assert closed.spectral_radius < 1.0 and run.verdict.stable and verdict.stable
    # the frequency scale reached the FMU: the nominal run differs
    nominal = run_fmu_loop(unzipped, loop=loop, compensator=SampledCompensator.of(design.compensator), parameters={})
    assert abs(nominal.verdict.cost_rms_v / run.verdict.cost_rms_v - 1) > 1e-3


def test_a_refused_run_is_reported_not_printed(unzipped, design, capfd):
    """The FMU's own error (a value outside the declared bound) comes back in the run, not on the console."""
    from mace_fmu.zero_g.robust.cosim import SampledCompensator, run_fmu_loop

    run = run_fmu_loop(unzipped, loop=LoopSpec(), compensator=SampledCompensator.of(design.compensator),
                       parameters={"frequency_scale_mode_17": 0.5})
    assert "frequency_scale_mode_17 = 0.5 is outside its declared range [0.975, 1.025]" in run.failure
    assert not run.verdict.stable and run.verdict.cost_rms_v == float("inf")
    assert capfd.readouterr() == ("", "")


def test_growth_test_finds_the_unstable_loop_the_eigenvalues_find(unzipped, model_0g, reference, design):
    """A more aggressive design (rho = 0.001, theta = 0.01) destabilises the 0-g FMU: spectral radius > 1, and
    the growth test on the FMU run says unstable; the default design says stable both ways."""
    from mace_fmu.control_studies.lqg import LqgWeights
    from mace_fmu.zero_g.robust.cosim import SampledCompensator, run_fmu_loop
    from mace_fmu.zero_g.robust.design import design_compensator
    from mace_fmu.zero_g.robust.statespace import state_space_loop

    loop = LoopSpec()
    hot = design_compensator(model_0g.system, weights=LqgWeights(rho=1e-3, theta=1e-2))
    for d, stable in ((hot, False), (design, True)):
        closed = state_space_loop(reference, loop=loop, compensator=d.compensator, parameters={})
        run = run_fmu_loop(unzipped, loop=loop, compensator=SampledCompensator.of(d.compensator), parameters={})
        assert (closed.spectral_radius < 1.0) is stable and run.verdict.stable is stable
        if not stable:
            # the last two 1 s windows grow by the dominant eigenvalue's rate: |lambda|^(1 s / 2 ms)
            assert run.verdict.growth_ratio == pytest.approx(closed.spectral_radius ** 500, rel=0.05)


@pytest.mark.slow
def test_example_on_a_local_dask_cluster_equals_the_serial_sweep(model_0g, tmp_path):
    """examples/robust_lqg_0g.py on two Dask workers gives the serial sweep's numbers bit for bit; with
    three bounded modes and four critical ones every corner is run."""
    import importlib.util

    from mace_fmu.zero_g.robust.sweep import robust_sweep

    path = EXAMPLES / "robust_lqg_0g.py"
    spec = importlib.util.spec_from_file_location("robust_lqg_0g", path)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    study = example.study_on_dask(model_0g, frequency_bounds=BOUNDS, out_dir=tmp_path, samples=4, seed=3)
    parallel = study.sweep
    serial = robust_sweep(study.fmu, compensator=study.design.compensator, samples=4, seed=3)
    assert parallel.runs == serial.runs and parallel.open_loop == serial.open_loop  # dataclass ==: exact floats
    assert [p.kind for p in serial.points] == ["nominal"] + ["screen"] * 6 + ["corner"] * 8 + ["sample"] * 4
    assert serial.critical == SCALES
    corners = {p.values for p in serial.points if p.kind == "corner"}
    assert corners == {tuple(1 + s * b for s, b in zip(signs, BOUNDS.values()))
                       for signs in np.ndindex(2, 2, 2) for signs in [tuple(2 * np.array(signs) - 1)]}
    # the strongest driver is the mode whose bounds alone move the cost most
    screen = serial.costs("screen").reshape(3, 2)
    effect = np.abs(screen - serial.nominal.cost_rms_v).max(axis=1)
    assert serial.drivers[0].name == SCALES[int(np.argmax(effect))]
    assert all(r.stable for r in serial.runs) and serial.open_loop.cost_rms_v > serial.nominal.cost_rms_v
    # the two cross-checked points (nominal, worst): FMU and state space agree, and so do their verdicts
    assert [c.point for c in study.cross_checks] == sorted({0, serial.worst})
    for check in study.cross_checks:
        assert check.relative_difference < 1e-9 and check.fmu_stable == (check.spectral_radius < 1.0)


@pytest.mark.slow
def test_cli_robust_0g_writes_the_figure_runs_and_summary(tmp_path, capsys):
    from PIL import Image

    from mace_fmu.cli import main

    assert main(["study", "robust-0g", "--bound", "15=1.1", "--bound", "17=2.5", "--samples", "3", "--critical", "1",
                 "--serial", "--duration", "3", "-o", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    for name in ("MACE_0g_native_bounded.fmu", "robust_0g.png", "robust_0g_runs.csv", "robust_0g.txt"):
        assert f"wrote {tmp_path / name}" in printed
    rows = (tmp_path / "robust_0g_runs.csv").read_text().splitlines()
    assert rows[0] == "kind,note,frequency_scale_mode_15,frequency_scale_mode_17,cost_rms_v,growth_ratio,stable"
    assert len(rows) == 1 + 1 + 4 + 2 + 3  # header, nominal, one at a time, 2^1 corners, samples
    assert "samples 3/3; fraction 1.000" in printed and "runs: nominal, open loop, 4 one-at-a-time, 2 corners of mode" in printed
    diffs = [float(x) for x in re.findall(r"rel\. diff ([0-9.e+-]+)\)", printed)]
    assert len(diffs) == 2 and max(diffs) < 1e-9  # nominal and worst point, FMU against state space
    assert np.asarray(Image.open(tmp_path / "robust_0g.png").convert("L"), dtype=float).std() > 10.0
    # the same bounds from a predict-0g table (mode numbers checked against the model's labels)
    table = tmp_path / "table_5_3.toml"
    table.write_text('[[mode]]\nmode = 15\nmode_label = "1st Y bending"\nbound_percent = 1.1\n\n'
                     '[[mode]]\nmode = 17\nmode_label = "2nd Z bending"\nbound_percent = 2.5\n')
    again = tmp_path / "again"
    assert main(["study", "robust-0g", "--frequency-bounds", str(table), "--samples", "0", "--critical", "1",
                 "--serial", "--duration", "3", "-o", str(again)]) == 0
    capsys.readouterr()
    first = (tmp_path / "robust_0g_runs.csv").read_text().splitlines()
    assert (again / "robust_0g_runs.csv").read_text().splitlines() == first[:1 + 1 + 4 + 2]  # same runs, bit for bit
    assert main(["study", "robust-0g", "--frequency-bounds", str(table), "--bound", "15=1", "-o", str(again)]) == 2
    assert "either with --bound or with --frequency-bounds" in capsys.readouterr().err
    assert main(["study", "robust-0g", "--bound", "17", "-o", str(tmp_path)]) == 2
    assert "--bound takes MODE=PERCENT" in capsys.readouterr().err
    assert main(["study", "robust-0g", "--bound", "999=1.0", "--serial", "-o", str(tmp_path)]) == 2
    assert "the model has no frequency scale for mode 999" in capsys.readouterr().err


def test_loop_timing_is_checked():
    with pytest.raises(MaceError, match="whole periods per run"):
        LoopSpec(duration_s=2.5)
    with pytest.raises(MaceError, match="whole periods per run"):
        LoopSpec(duration_s=2.0)  # one period of disturbance leaves one to compare: two are needed
    w = LoopSpec().disturbance()
    assert w.size == 2000 and w[:250].tolist() == [0.5] * 250 and w[250:500].tolist() == [-0.5] * 250
    assert not w[500:].any()
