"""Several tests in one FMU update: a gimbal test and an active-strut test with strain gauges.

The truth is the 1-g native FMU of the bundled deck (Table 4.4's moduli); the "lab" records 8 s
of band-limited (0.5-60 Hz) noise on the inputs and 2 % output noise. The three active-strut
moduli act in series: from the gimbals to the rate gyros the data see one combination of them,
which the update must flag as not identifiable. The strut test (its piezo inputs to strut 2's
strain gauges and a gyro) adds information, but measured here it leaves the same combination
weak (-0.10 end - 0.43 piezo + 0.91 center, sd about 18 % over 8 s): the update says so, and the
truth lies inside the intervals it reports.
"""

from __future__ import annotations

import numpy as np
import pytest

from mace_fmu.cli import main
from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.files import write_time_history

pytestmark = pytest.mark.slow  # each test is a full update of two FMU tests

STEP = 0.002
SECONDS = 8.0
STRUT = ("E_active_strut_end", "E_active_strut_piezo", "E_active_strut_center")
GIMBAL_TEST = (("gimbal_primary_x", "gimbal_primary_z", "gimbal_secondary_x", "gimbal_secondary_z"),
               ("gyro_payload_x", "gyro_payload_z", "gyro_bus_x", "gyro_bus_y", "gyro_bus_z"))
STRUT_TEST = (("active_strut_y", "active_strut_z"), ("strain_strut2_y", "strain_strut2_z", "gyro_payload_x"))


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """(the model's FMU: the strut moduli 3 % off built in, truth values, gimbal test file, strut test file, the
    deck's own FMU); the tests' data come from the deck's own FMU (another full re-solve)."""
    from support.reexported import fmu_with

    from mace_fmu.updating.fmu.model import fmu_family

    folder = tmp_path_factory.mktemp("several")
    deck_fmu = fmu_with(folder, factors={}, name="MACE_1g_truth")
    family = fmu_family(deck_fmu)
    fmu = fmu_with(folder, factors=dict(zip(STRUT, (1.03, 0.97, 1.03))), name="MACE_1g_native")
    t = np.arange(int(round(SECONDS / STEP)) + 1) * STEP
    f = np.fft.rfftfreq(t.size, STEP)
    files = []
    for k, (inputs, outputs) in enumerate((GIMBAL_TEST, STRUT_TEST)):
        rng = np.random.default_rng(10 + k)
        u = {}
        for name in inputs:
            spectrum = np.fft.rfft(rng.standard_normal(t.size))
            spectrum[(f < 0.5) | (f > 60.0)] = 0.0
            u[name] = np.fft.irfft(spectrum, t.size)
        y = family.full({}).time_response(t, u, outputs=list(outputs))
        y = y + 0.02 * np.sqrt(np.mean(y**2, axis=0)) * rng.standard_normal(y.shape)
        files.append(write_time_history(TimeHistory(t, u, {o: y[:, j] for j, o in enumerate(outputs)},
                                                    source=f"test {k}"), folder / f"test_{k}.csv"))
    truth = {n: family.interface.parameters[n] for n in STRUT}
    return fmu, truth, files[0], files[1], deck_fmu


def _update(lab, tmp_path, data_files, capsys):
    import tomllib

    fmu, truth = lab[0], lab[1]
    tmp_path.mkdir(parents=True, exist_ok=True)
    args = ["update", "fmu", str(fmu), "--update", ",".join(STRUT), "--cost", "time",
            "--hold-input", "rwa_x=0,rwa_y=0,rwa_z=0", "--workers", "1", "-o", str(tmp_path / "out")]
    for path in data_files:
        args += ["--data", str(path)]
    held = ",".join(f"{i}=0" for i in ("gimbal_primary_x", "gimbal_primary_z", "gimbal_secondary_x",
                                         "gimbal_secondary_z", "active_strut_y", "active_strut_z"))
    args += ["--hold-input", held]  # every test holds the inputs it does not drive at 0 V
    code = main(args)
    out = capsys.readouterr()
    assert code in (0, 3), out.err
    values = tomllib.loads((tmp_path / "out" / "parameters.toml").read_text())["values"]
    uncertainty = tomllib.loads((tmp_path / "out" / "uncertainty.toml").read_text())["stage"][0]
    sd = dict(zip(uncertainty["parameters"], uncertainty["standard_deviation_percent"]))
    return {n: 100 * (values[n] / truth[n] - 1) for n in STRUT}, sd, uncertainty, out.out


@pytest.fixture(scope="module")
def both(lab, tmp_path_factory):
    """The update on both tests (the gimbal test and the strut test), run once for the tests that read it:
    (errors, sd, uncertainty, stdout, its folder)."""
    import contextlib
    import io
    from types import SimpleNamespace

    folder = tmp_path_factory.mktemp("both")
    out, err = io.StringIO(), io.StringIO()

    class Captured:  # capsys's readouterr over the redirected streams
        @staticmethod
        def readouterr():
            return SimpleNamespace(out=out.getvalue(), err=err.getvalue())

    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        return (*_update(lab, folder, [lab[2], lab[3]], Captured), folder)


def test_the_gimbal_test_alone_flags_the_strut_combination(lab, tmp_path, capsys):
    _, sd, uncertainty, out = _update(lab, tmp_path, [lab[2]], capsys)
    assert max(sd.values()) > 5.0 and uncertainty["weak_directions"]
    assert "not identifiable from these data" in out


def test_two_tests_converge_to_the_noise_floor_with_the_truth_inside_the_reported_intervals(both):
    import tomllib

    errors, sd, uncertainty, out, folder = both
    report = tomllib.loads((folder / "out" / "convergence.toml").read_text())
    assert report["verdict"] == "explained" and abs(report["noise_floor"]["sigmas_above"]) < 3.0, report
    for n, e in errors.items():  # the truth inside the reported 95 % interval
        assert abs(e) <= 1.96 * sd[n], (n, e, sd[n])
    # the strut test's gauges sit on the sections: each is fixed on its own (plan-test predicts the same
    # from full re-solves, tests/updating/fmu/test_test_planning.py), no combination is weak
    assert max(sd[n] for n in STRUT) < 0.2 and not uncertainty["weak_directions"]


def test_a_second_test_adds_information(lab, both, tmp_path, capsys):
    _, alone, _, _ = _update(lab, tmp_path / "alone", [lab[3]], capsys)
    both = both[1]  # the update on both tests, as in the test above
    assert all(both[n] < alone[n] for n in STRUT), (both, alone)


def test_tests_with_different_sample_times_are_refused(lab, tmp_path, capsys):
    from mace_fmu.updating.files import read_time_history

    coarse = read_time_history(lab[3])
    other = write_time_history(TimeHistory(coarse.times_s[::2], {k: v[::2] for k, v in coarse.inputs.items()},
                                           {k: v[::2] for k, v in coarse.outputs.items()}), tmp_path / "coarse.csv")
    code = main(["update", "fmu", str(lab[0]), "--update", STRUT[0], "--data", str(lab[2]), "--data", str(other),
                 "-o", str(tmp_path / "out")])
    assert code == 2 and "sample time 0.004 s, but" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_from_the_pre_update_moduli_bounded_first_steps_reach_the_floor(lab, tmp_path):
    """Regression of the first step: the 8 kept moduli a few percent off the bundled ones, built into the FMU the
    data come from (a full re-solve); two 8 s tests (the gimbals to the gyros and gauges; the strut test); the
    deck's FMU updated from the pre-update moduli (up to 12 % off). Unbounded (before the FMU declared its
    validated range), the first linearised step threw cable 3 to +44 % and the fit into another minimum, 190
    standard deviations above the noise floor; bounded to 10 % and growing, the update ends explained to the
    noise with lexan and cables within 0.5 %."""
    from support.reexported import fmu_with

    from mace_fmu.updating.engine.convergence import convergence_report, noise_floor
    from mace_fmu.updating.fmu.model import fmu_family
    from mace_fmu.updating.fmu.problem import fmu_problem
    from mace_fmu.updating.fmu.truth import band_limited_noise
    from mace_fmu.updating.fmu.update import FMU_SETTINGS, update_fmu
    from mace_fmu.updating.mace.update import THESIS_KEPT, pre_update_parameters

    fmu = lab[4]
    offsets = (0.02, -0.03, 0.04, -0.02, 0.03, -0.02, 0.03, 0.02)
    source = fmu_family(fmu_with(tmp_path, factors={n: 1 + d for n, d in zip(THESIS_KEPT, offsets)}, name="truth"))
    truth = {n: source.interface.parameters[n] for n in THESIS_KEPT}
    t = np.arange(int(round(SECONDS / STEP)) + 1) * STEP
    files = []
    for k, (inputs, outputs) in enumerate(((GIMBAL_TEST[0], GIMBAL_TEST[1] + STRUT_TEST[1][:2]), STRUT_TEST)):
        u = {i: band_limited_noise(samples=t.size, step_s=STEP, band_hz=(0.5, 60.0), seed=10 * k + j)
             for j, i in enumerate(inputs)}
        y = source.full({}).time_response(t, u, outputs=list(outputs))
        y = y + 0.02 * np.sqrt(np.mean(y**2, axis=0)) * np.random.default_rng(10 * k + 50).standard_normal(y.shape)
        files.append(write_time_history(TimeHistory(t, u, {o: y[:, j] for j, o in enumerate(outputs)}),
                                        tmp_path / f"test_{k}.csv"))
    pre = pre_update_parameters()
    problem = fmu_problem(fmu=fmu, data=files, names=THESIS_KEPT, cost="time", start={n: pre[n] for n in THESIS_KEPT},
                          held_inputs=fmu_family(fmu).interface.inputs)
    assert FMU_SETTINGS.initial_radius == 0.1
    result = update_fmu(family=problem.family, cost=problem.cost, start=problem.start, stages=[problem.names])
    report = convergence_report(result, noise_floor=noise_floor(problem.cost), cost=problem.cost)
    errors = {n: result.values[n] / truth[n] - 1 for n in THESIS_KEPT}
    assert report.verdict == "explained", report.summary()
    assert all(abs(errors[n]) < 0.005 for n in THESIS_KEPT if "lexan" in n or "cable" in n), errors


def test_seeded_starts_ten_percent_off_all_converge_to_one_answer(lab, tmp_path):
    """Six starts, each of the lexan and cable moduli drawn within +-5 % of the truth (seeded), on a 4 s
    gimbal-to-gyro test of the deck's FMU; the model an FMU with those moduli 2-4 % off built in (the starts
    then within +-9 % of its own values, where its route is exact: tests/iomodel/test_parameter_route.py):
    every update converges, explained to the noise, and all end at one answer, their spread under 5 % of the
    reported standard deviation."""
    from support.reexported import fmu_with

    from mace_fmu.updating.engine.convergence import convergence_report, noise_floor
    from mace_fmu.updating.engine.costs import TimeResponseCost
    from mace_fmu.updating.engine.uncertainty import stage_uncertainty
    from mace_fmu.updating.fmu.model import fmu_family
    from mace_fmu.updating.fmu.truth import band_limited_noise
    from mace_fmu.updating.fmu.update import update_fmu

    names = ["E_lexan_end", "E_lexan_center", "E_cable_1", "E_cable_2", "E_cable_3"]
    source = fmu_family(lab[4])
    family = fmu_family(fmu_with(tmp_path, factors=dict(zip(names, (1.03, 0.98, 1.04, 0.97, 1.02))), name="model"))
    t = np.arange(2001) * STEP
    u = {g: band_limited_noise(samples=t.size, step_s=STEP, band_hz=(0.5, 60.0), seed=j)
         for j, g in enumerate(GIMBAL_TEST[0])}
    y = source.full({}).time_response(t, u, outputs=list(GIMBAL_TEST[1]))
    y = y + 0.02 * np.sqrt(np.mean(y**2, axis=0)) * np.random.default_rng(9).standard_normal(y.shape)
    cost = TimeResponseCost(TimeHistory(t, u, {o: y[:, j] for j, o in enumerate(GIMBAL_TEST[1])}))
    floor = noise_floor(cost)
    truth = {n: source.interface.parameters[n] for n in names}
    rng = np.random.default_rng(2026)
    answers, sds = [], []
    for _ in range(6):
        start = {n: v * (1 + rng.uniform(-0.05, 0.05)) for n, v in truth.items()}
        result = update_fmu(family=family, cost=cost, start=start, stages=[names])
        report = convergence_report(result, noise_floor=floor, cost=cost)
        assert report.verdict == "explained", report.summary()
        (stage,) = stage_uncertainty(result, noise_variance=floor.expected_cost / result.final_residual.size)
        answers.append([100 * (result.values[n] / truth[n] - 1) for n in names])
        sds.append([stage.standard_deviation_percent[n] for n in names])
    spread = np.ptp(np.array(answers), axis=0)
    assert np.all(spread < 0.05 * np.min(sds, axis=0)), (spread, np.min(sds, axis=0))
