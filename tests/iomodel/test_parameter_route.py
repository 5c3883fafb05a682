"""The FMUs' physical parameters move every channel as a full re-solve does, never graded against the FMU itself.

The reference of every test here is a full re-solve: the deck with the parameter built in, the FE model,
preload and modes solved again (tests/support/resolves.py), each mode keeping its nominal damping. The
route under test is the one both FMU kinds run: :class:`~mace_fmu.iomodel.parametric.ParametricSystem`
(the pythonfmu FMU runs it verbatim; tests/fmu/test_native_fmu.py holds the native runtime to it to 1e-9),
and the FMUs themselves in the last tests.

Before the static corrections (mace_fmu/iomodel/stiffness_route.py) the nominal modes alone moved the
strain gauge on the active strut 31-85 % wrong: ``test_each_channel_follows_the_resolve_at_the_nominal_point``
failed for every strut modulus on strain_strut2_z (0.82 of the re-solve's change off, 0-g center), and
``test_an_fmu_with_a_modulus_set_equals_the_fmu_exported_with_it`` by 7 to 12 % of strain_strut2_z's range.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from support.resolves import band_limited_inputs, resolved_system, zoh_response

from mace_fmu.deck.reader import read_deck
from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.parametric import ParametricSystem
from mace_fmu.iomodel.parametric_data import parametric_arrays
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.parameters.sets import deck_values
from mace_fmu.structure.file import bundled_deck_path

pytestmark = pytest.mark.slow  # each test compares against full re-solves of the 1-g structure

#: (configuration, parameter, outputs it moves by 2 % at least): each physical kind (moduli, springs), the
#: elements the instruments sit on (strut sections: gauges, piezo), the 1-g preload's redistribution (a
#: cable) and a bus material. A suspension spring acts on the 0.2-0.4 Hz suspension modes, which 10 s of
#: gimbal commands barely move: one output changes by 2 %, and the +-20 % check carries the rest.
CASES = [("1g", "E_active_strut_center", 20), ("1g", "E_active_strut_piezo", 20), ("1g", "E_cable_2", 4),
         ("1g", "k_suspension_device_3", 1), ("0g", "E_active_strut_end", 20), ("0g", "E_lexan_center", 20)]
#: the two experiments: gimbal commands alone, piezo patches alone (every input: an error in one input's
#: route is not hidden by another's response)
DRIVEN = (("gimbal",), ("active_strut",))
STEP = 0.02  #: +-2 %, the relative step of the derivatives
LARGE = 0.2  #: +-20 %


@pytest.fixture(scope="module")
def nominal():
    """Per configuration: the nominal model, its ParametricSystem with every physical parameter, the deck's
    moduli and springs."""
    values = deck_values(read_deck(bundled_deck_path()))
    out = {}
    for configuration in ("1g", "0g"):
        model = volts_model(compute_modes(configuration=configuration))
        out[configuration] = (model, ParametricSystem(parametric_arrays(model)), values)
    return out


@pytest.mark.parametrize("configuration, name, moved", CASES, ids=[f"{c}-{n}" for c, n, _ in CASES])
def test_each_channel_follows_the_resolve_at_the_nominal_point_and_at_20_percent(nominal, configuration, name,
                                                                                  moved):
    """d y / d ln p within 2 % of the re-solve's on every output whose change is at least 2 % of its response
    (norm of the difference over the norm of the re-solve's change, 10 s at 2 ms, each experiment), and at
    +-20 % every output within 1 % of its range of the re-solve's."""
    model, system, values = nominal[configuration]
    u_sets = [band_limited_inputs(system.inputs, driven) for driven in DRIVEN]
    y0 = [zoh_response(system.build(system.nominal), u) for u in u_sets]

    def route(rel):
        params = system.nominal.copy()
        params[system.index(name)] *= 1.0 + rel
        built = system.build(params)
        return [zoh_response(built, u) for u in u_sets]

    def resolve(rel):
        built = resolved_system(configuration, {**values, name: values[name] * (1.0 + rel)}, model)
        return [zoh_response(built, u) for u in u_sets]

    checked = 0
    for k, (rp, rm, ep, em) in enumerate(zip(route(STEP), route(-STEP), resolve(STEP), resolve(-STEP))):
        d_route, d_resolve = (rp - rm) / (2 * STEP), (ep - em) / (2 * STEP)
        for j, output in enumerate(system.outputs):
            change = np.linalg.norm(d_resolve[:, j])
            if change < 0.02 * np.linalg.norm(y0[k][:, j]):
                continue
            checked += 1
            error = np.linalg.norm(d_route[:, j] - d_resolve[:, j]) / change
            assert error <= 0.02, f"{name}, {DRIVEN[k][0]} inputs: d {output} / d ln p {error:.1%} off the re-solve's"
    assert checked >= moved, "the parameter must move these channels, or this proves nothing"
    for rel in (LARGE, -LARGE):
        for k, (yr, ye) in enumerate(zip(route(rel), resolve(rel))):
            span = np.ptp(y0[k], axis=0)
            worst = np.max(np.abs(yr - ye), axis=0) / span
            j = int(np.argmax(worst))
            assert worst[j] <= 0.01, (f"{name} x {1 + rel:g}, {DRIVEN[k][0]} inputs: {system.outputs[j]} "
                                      f"{worst[j]:.2%} of its range off the re-solve")


#: two physical parameters at once, at the edges the route must hold: the strut section under the gauges and
#: a suspension cable (the 1-g preload's redistribution)
BUILT_IN = {"E_active_strut_center": 1.2, "E_cable_2": 0.8}


@pytest.fixture(scope="module")
def reexported(nominal, tmp_path_factory):
    """(nominal 1-g model, re-solved model with BUILT_IN, folders of: its native FMU and the nominal native
    and pythonfmu FMUs), extracted."""
    import fmpy

    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.parameters.sets import ParameterSet

    model, _, values = nominal["1g"]
    resolved = volts_model(compute_modes(configuration="1g", parameters=ParameterSet({n: values[n] * f for n,
                                                                                      f in BUILT_IN.items()})))
    folder = tmp_path_factory.mktemp("route_fmus")
    fmus = {"resolved": export_fmu(resolved, out_dir=folder, name="MACE_1g_resolved", runtime="native"),
            "native": export_fmu(model, out_dir=folder, name="MACE_1g_native", runtime="native"),
            "pythonfmu": export_fmu(model, out_dir=folder, name="MACE_1g_python", runtime="pythonfmu")}
    return model, resolved, {k: fmpy.extract(str(v), unzipdir=str(folder / k)) for k, v in fmus.items()}


@pytest.mark.parametrize("kind", ["native", "pythonfmu"])
def test_an_fmu_with_moduli_set_equals_the_fmu_exported_with_them(reexported, kind):
    """The nominal FMU with E_active_strut_center x 1.2 and E_cable_2 x 0.8 set through FMI against the FMU
    exported from the re-solve with them built in (each mode's nominal damping set through FMI too), 10 s at
    2 ms, gimbal commands and piezo patches driven at once: every output within 1 % of its range."""
    from support.fmu_checks import initialised_slave, run_steps
    from support.resolves import SAMPLES, STEP_S, held_damping

    model, resolved, folders = reexported
    t = np.arange(SAMPLES) * STEP_S
    u = band_limited_inputs(list(model.system.input_labels), ("gimbal", "active_strut")).T
    values = deck_values(read_deck(bundled_deck_path()))
    route = initialised_slave(model, folders[kind], {n: values[n] * f for n, f in BUILT_IN.items()})
    reference = initialised_slave(resolved, folders["resolved"], held_damping(model, resolved))
    y_route, y_ref = run_steps(model, route, folders[kind], t, u), run_steps(resolved, reference, folders["resolved"], t, u)
    for fmu in (route, reference):
        fmu.terminate()
        fmu.freeInstance()
    nominal_fmu = initialised_slave(model, folders["native"], {})
    y_nominal = run_steps(model, nominal_fmu, folders["native"], t, u)
    nominal_fmu.freeInstance()
    span = np.ptp(y_ref, axis=1)
    worst = np.max(np.abs(y_route - y_ref), axis=1) / span
    outputs = list(model.system.output_labels)
    assert np.max(worst) <= 0.01, f"{outputs[int(np.argmax(worst))]}: {np.max(worst):.2%} of its range"
    # the change is seen: strain_strut2_z moves by far more than the tolerance
    moved = np.max(np.abs(y_ref - y_nominal), axis=1) / span
    assert moved[outputs.index("strain_strut2_z")] > 0.1 and np.max(moved) > 10 * np.max(worst)


GYROS = ("gyro_payload_x", "gyro_payload_z", "gyro_bus_x", "gyro_bus_y", "gyro_bus_z")


@pytest.mark.parametrize("outputs", [GYROS, GYROS + ("strain_strut2_y", "strain_strut2_z")],
                         ids=["gyros", "gyros and strut-2 gauges"])
def test_an_update_on_data_of_the_fmu_exported_with_the_truth_finds_every_modulus_in_its_interval(reexported,
                                                                                                  tmp_path, outputs):
    """The issue's check, from a full re-solve: the 8 kept moduli 2-6 % away from the nominal FMU's, built into
    a re-exported FMU (each mode's nominal damping set through FMI), a 20 s gimbal test at 2 ms with 2 % output
    noise; the nominal FMU updated on those data converges on the noise floor and every modulus's truth lies
    inside its reported 95 % interval (gyros alone: the strut's sections with wide intervals; with the
    gauges: all within 0.2 %). Before the static corrections, gyros alone put lexan and cables 1 and 3 outside
    intervals of about +-0.05 % (cable 3 6.0 % off): the FMU's model error was larger than the precision it
    reported."""
    from support.resolves import held_damping

    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.parameters.sets import ParameterSet
    from mace_fmu.updating.engine.convergence import convergence_report, noise_floor
    from mace_fmu.updating.engine.costs import TimeResponseCost
    from mace_fmu.updating.engine.measured import TimeHistory
    from mace_fmu.updating.engine.uncertainty import stage_uncertainty
    from mace_fmu.updating.fmu.model import fmu_family
    from mace_fmu.updating.fmu.truth import band_limited_noise
    from mace_fmu.updating.fmu.update import update_fmu
    from mace_fmu.updating.mace.update import THESIS_KEPT

    model, _, folders = reexported
    values = deck_values(read_deck(bundled_deck_path()))
    offsets = (0.04, -0.03, 0.06, -0.02, 0.05, -0.04, 0.03, 0.02)
    truth = {n: values[n] * (1 + d) for n, d in zip(THESIS_KEPT, offsets)}
    resolved = volts_model(compute_modes(configuration="1g", parameters=ParameterSet(truth)))
    truth_fmu = fmu_family(export_fmu(resolved, out_dir=tmp_path, name="MACE_1g_truth", runtime="native"),
                           fixed=held_damping(model, resolved))
    nominal_fmu = fmu_family(Path(folders["native"]).parent / "MACE_1g_native.fmu")
    gimbals = [i for i in model.system.input_labels if i.startswith("gimbal")]
    outputs = list(outputs)
    t = np.arange(10001) * 2e-3
    u = {g: band_limited_noise(samples=t.size, step_s=2e-3, band_hz=(0.5, 60.0), seed=j) for j, g in enumerate(gimbals)}
    y = truth_fmu.full({}).time_response(t, u, outputs=outputs)
    y = y + 0.02 * np.sqrt(np.mean(y**2, axis=0)) * np.random.default_rng(4).standard_normal(y.shape)
    cost = TimeResponseCost(TimeHistory(t, u, {o: y[:, j] for j, o in enumerate(outputs)}))
    result = update_fmu(family=nominal_fmu, cost=cost, start={n: values[n] for n in THESIS_KEPT},
                        stages=[list(THESIS_KEPT)])
    floor = noise_floor(cost)
    report = convergence_report(result, noise_floor=floor)
    assert report.converged and abs(floor.sigmas_above(result.final_cost)) < 3.0, report.reasons
    (stage,) = stage_uncertainty(result, noise_variance=floor.expected_cost / result.final_residual.size)
    for name in THESIS_KEPT:
        error = 100 * (result.values[name] / truth[name] - 1)
        sd = stage.standard_deviation_percent[name]
        assert abs(error) <= 1.96 * sd, f"{name}: {error:+.3f} % off the truth, reported sd {sd:.3f} %"
