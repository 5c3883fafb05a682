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

The error is measured as a user meets it: each output's RMS difference over the output's RMS, every input
driven with band-limited noise at once, every physical parameter changed at once. Until the re-solve
continued the nominal modes (``compute_modes(..., continue_from="nominal")``) it labelled its modes afresh
and handed damping ratios to other modes where two crossed: the FMU exported with E_cable_1 x 1.1 was 2.7 %
off the nominal FMU with that value set, x 1.2 34 %; ``test_a_cable_modulus_up_10_percent_keeps_each_mode_s
_damping`` fails on that route.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from support.resolves import STEP_S, band_limited_inputs, resolved_system, zoh_response

from mace_fmu.deck.reader import read_deck
from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.parametric import ParametricSystem
from mace_fmu.iomodel.parametric_data import parametric_arrays
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.parameters.sets import ParameterSet, deck_values
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
#: the large change checked per configuration: the 1-g route's first-order preload holds to 0.1 % within +-10 %
LARGE = {"1g": 0.1, "0g": 0.2}


@pytest.fixture(scope="module")
def nominal():
    """Per configuration: the nominal model, its ParametricSystem with every physical parameter, the deck's
    moduli and springs."""
    values = deck_values(read_deck(bundled_deck_path()))
    out = {}
    for configuration in ("1g", "0g"):
        model = volts_model(compute_modes(configuration=configuration))
        arrays = parametric_arrays(model, resolve=True)
        out[configuration] = (model, ParametricSystem({k: v for k, v in arrays.items() if not k.startswith("resolve_")}),
                              values)
        out[f"{configuration}-resolve"] = (model, ParametricSystem(arrays), values)
    return out


@pytest.mark.parametrize("configuration, name, moved", CASES, ids=[f"{c}-{n}" for c, n, _ in CASES])
def test_each_channel_follows_the_resolve_at_the_nominal_point_and_at_20_percent(nominal, configuration, name,
                                                                                  moved):
    """d y / d ln p within 2 % of the re-solve's on every output whose change is at least 2 % of its response
    (norm of the difference over the norm of the re-solve's change, 10 s at 2 ms, each experiment), and at
    +-10 % (1-g) or +-20 % (0-g) every output's RMS difference from the re-solve within 0.1 % of its RMS."""
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
    for rel in (LARGE[configuration], -LARGE[configuration]):
        for k, (yr, ye) in enumerate(zip(route(rel), resolve(rel))):
            errors = _rms_error(yr, ye)
            j = int(np.argmax(errors))
            assert errors[j] <= 0.001, (f"{name} x {1 + rel:g}, {DRIVEN[k][0]} inputs: {system.outputs[j]} "
                                        f"{errors[j]:.3%} of its RMS off the re-solve")


def test_the_references_zero_order_hold_is_its_step_by_step_definition_and_a_closed_form():
    """The reference every route test compares with (tests/support/lifted.py: 20 samples per matrix product)
    against x[k+1] = Ad x[k] + Bd u[k], y[k] = C x[k] + D u[k] stepped one sample at a time on a random stable
    system with 7 inputs over 1003 samples (not a whole number of blocks), and a first-order lag's step response
    in closed form: y[k] = c b (1 - a^k) / (1 - a) + d."""
    from support.lifted import lifted_response

    rng = np.random.default_rng(3)
    n, m, p, samples = 12, 7, 5, 1003
    ad = rng.standard_normal((n, n))
    ad *= 0.97 / np.max(np.abs(np.linalg.eigvals(ad)))
    bd, c, d = rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m))
    u = rng.standard_normal((samples, m))
    x, stepped = np.zeros(n), np.empty((samples, p))
    for k in range(samples):
        stepped[k] = c @ x + d @ u[k]
        x = ad @ x + bd @ u[k]
    lifted = lifted_response(ad, bd, c, d, u)
    assert np.max(np.abs(lifted - stepped)) <= 1e-12 * np.max(np.abs(stepped))
    a, b, cc, dd = 0.99, 0.5, 2.0, 0.25
    k = np.arange(300)
    y = lifted_response(np.array([[a]]), np.array([[b]]), np.array([[cc]]), np.array([[dd]]), np.ones((300, 1)))
    np.testing.assert_allclose(y[:, 0], cc * b * (1 - a**k) / (1 - a) + dd, rtol=1e-13, atol=1e-13)


def _all_inputs(system, *, seed: int = 1) -> np.ndarray:
    """(SAMPLES, n_inputs) independent 0.5-60 Hz noise [V] on every input."""
    from mace_fmu.updating.fmu.truth import band_limited_noise
    from support.resolves import SAMPLES, STEP_S

    return np.column_stack([band_limited_noise(samples=SAMPLES, step_s=STEP_S, band_hz=(0.5, 60.0), seed=seed + k)
                            for k in range(len(system.inputs))])


def _rms_error(y: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Each output's RMS difference over the reference output's RMS."""
    rms = np.sqrt(np.mean(reference**2, axis=0))
    return np.sqrt(np.mean((y - reference) ** 2, axis=0)) / np.where(rms > 0, rms, 1.0)


def _random_point(system, rng, *, within: float | None) -> dict[str, float]:
    """Every physical parameter uniform over its declared range, or within +-``within`` of nominal."""
    point = {}
    for name in (str(n) for n in system.data["physical_names"]):
        k = system.index(name)
        nominal, low, high = system.nominal[k], system.minimum[k], system.maximum[k]
        if within is not None:
            low, high = max(low, nominal * (1 - within)), min(high, nominal * (1 + within))
        point[name] = float(rng.uniform(low, high))
    return point


def _route_and_resolve_systems(nominal_entry, configuration: str, point: dict[str, float]):
    """((A, B, C, D) of the route, of the re-solve) at ``point``, the re-solve continuing the nominal modes."""
    model, system, _ = nominal_entry
    params = system.nominal.copy()
    for name, value in point.items():
        params[system.index(name)] = value
    resolved = volts_model(compute_modes(configuration=configuration, parameters=ParameterSet(point),
                                         continue_from=model.structure_modes))
    reference = ParametricSystem(parametric_arrays(resolved, physical=False))
    return system.build(params), reference.build(reference.nominal)


def _route_and_resolve(nominal_entry, configuration: str, point: dict[str, float], u: np.ndarray):
    """(route's response, re-solve's response) to inputs u, the re-solve continuing the nominal modes."""
    route, reference = _route_and_resolve_systems(nominal_entry, configuration, point)
    return zoh_response(route, u), zoh_response(reference, u)


#: (configuration (``-resolve``: the structure solved again, mace_fmu.iomodel.resolve), half-width of the box
#: about nominal (None: the declared ranges), limit of every output's RMS difference over its RMS, measured worst
#: of the 20 points): the 1-g reanalysis carries the preload's redistribution to first order, within 0.1 % in
#: +-10 % of nominal; over the declared 0.7-1.5 it is not (up to 7.8 % of an output's RMS at these points,
#: benchmarks/bench_parameter_route.py and RESULTS.md). Solved again, the 1-g model is exact over them.
RANDOM = [("1g", 0.10, 0.001, "0.062 %"), ("1g-resolve", None, 0.001, "0.0015 %"), ("0g", None, 0.002, "0.132 %"),
          ("0g-resolve", None, 0.001, "0.0017 %")]


@pytest.mark.parametrize("configuration, within, limit, measured", RANDOM,
                         ids=["1g-within-10-percent", "1g-resolved-declared-range", "0g-declared-range",
                              "0g-resolved-declared-range"])
def test_the_route_follows_the_re_solve_at_20_random_points_all_parameters_at_once(nominal, configuration, within,
                                                                                    limit, measured, tmp_path):
    """20 seeded points, every physical parameter (10 moduli, 3 springs) drawn at once; every input driven by
    0.5-60 Hz noise for 10 s at 2 ms: every output's RMS difference from the full re-solve within ``limit`` of
    its RMS. The first five points also drive each input alone (every output that input moves by 1 % of its
    RMS under all inputs). Solved again, the native FMU (its own C re-solve) meets the same limit at every
    point; the ParametricSystem is what the pythonfmu FMU runs."""
    model, system, _ = nominal[configuration]
    solved = configuration.removesuffix("-resolve")
    u = _all_inputs(system)
    native = None
    if configuration.endswith("-resolve"):
        import fmpy

        from mace_fmu.fmu.export import export_fmu

        native = fmpy.extract(str(export_fmu(model, out_dir=tmp_path, name=f"MACE_{solved}_native")),
                              unzipdir=str(tmp_path / "native"))
    t = np.arange(len(u)) * STEP_S
    rng = np.random.default_rng(50)
    worst, moved_most = 0.0, 0.0
    y_nominal = zoh_response(system.build(system.nominal), u)
    for k in range(20):
        point = _random_point(system, rng, within=within)
        route, resolved = _route_and_resolve_systems(nominal[configuration], solved, point)
        y, reference = zoh_response(route, u), zoh_response(resolved, u)
        errors = _rms_error(y, reference)
        worst, moved_most = max(worst, float(errors.max())), max(moved_most, float(_rms_error(y_nominal, reference).max()))
        assert errors.max() <= limit, (f"point {k}: {system.outputs[int(errors.argmax())]} {errors.max():.3%} off "
                                       f"the re-solve (measured worst {measured})")
        if native is not None:  # the runtime's re-solve, through FMI (no feedthrough: its outputs are the ZOH's)
            fmu_errors = _rms_error(_fmu_response(model, native, point, t, u.T).T, reference)
            assert fmu_errors.max() <= limit, f"native FMU, point {k}: {fmu_errors.max():.3%} off the re-solve"
        if k < 5:
            everything = np.sqrt(np.mean(reference**2, axis=0))
            for j in range(len(system.inputs)):
                alone = np.zeros_like(u)
                alone[:, j] = u[:, j]
                y, reference = zoh_response(route, alone), zoh_response(resolved, alone)
                moved = np.sqrt(np.mean(reference**2, axis=0)) >= 0.1 * everything
                errors = _rms_error(y, reference)[moved]
                assert errors.max(initial=0.0) <= limit, (f"point {k}, {system.inputs[j]} alone: {errors.max():.3%}")
    assert moved_most > 30 * max(worst, limit / 10), "the points must move the outputs far more, or this proves nothing"


def test_a_cable_modulus_up_10_percent_keeps_each_mode_s_damping(nominal):
    """E_cable_1 x 1.1: the FMU's route keeps each physical mode's damping ratio; the re-solve, which labelled
    its modes afresh, gave the 3rd in-plane violins of cables 1 and 3 each other's (2.7 % of strain_strut1_y's
    RMS off). Continuing the nominal modes, within 0.1 %; the change itself moves the outputs by far more."""
    model, system, values = nominal["1g"]
    u = _all_inputs(system)
    point = {"E_cable_1": 1.1 * values["E_cable_1"]}
    y, reference = _route_and_resolve(nominal["1g"], "1g", point, u)
    assert _rms_error(y, reference).max() <= 0.001
    continued = volts_model(compute_modes(configuration="1g", parameters=ParameterSet(point)))
    assert continued.structure_modes.labels == model.structure_modes.labels
    assert dict(zip(continued.plant.labels, continued.plant.damping)) == dict(zip(model.plant.labels,
                                                                               model.plant.damping))
    fresh = ParametricSystem(parametric_arrays(volts_model(compute_modes(
        configuration="1g", parameters=ParameterSet(point), continue_from=None)), physical=False))
    assert _rms_error(y, zoh_response(fresh.build(fresh.nominal), u)).max() > 0.02  # the earlier re-export: 2.7 %
    y0 = zoh_response(system.build(system.nominal), u)
    assert _rms_error(y0, reference).max() > 0.01  # the change is seen


#: the route's hard case: the 8 kept moduli 2-6 % off nominal at once
POINT_A = {"E_lexan_center": 1.037, "E_lexan_end": 0.978, "E_active_strut_end": 1.051, "E_active_strut_piezo": 0.982,
           "E_active_strut_center": 1.029, "E_cable_1": 1.06, "E_cable_2": 0.96, "E_cable_3": 1.025}


@pytest.fixture(scope="module")
def reexported(nominal, tmp_path_factory):
    """(nominal 1-g model, the re-solve at POINT_A, folders of: its native FMU and the nominal native FMI 2,
    native FMI 3 and pythonfmu FMUs), extracted."""
    import fmpy

    from mace_fmu.fmu.export import export_fmu

    model, _, values = nominal["1g"]
    resolved = volts_model(compute_modes(configuration="1g", parameters=ParameterSet({n: values[n] * f for n,
                                                                                      f in POINT_A.items()})))
    folder = tmp_path_factory.mktemp("route_fmus")
    fmus = {"resolved": export_fmu(resolved, out_dir=folder, name="MACE_1g_resolved", runtime="native"),
            "native": export_fmu(model, out_dir=folder, name="MACE_1g_native", runtime="native"),
            "native-fmi3": export_fmu(model, out_dir=folder, name="MACE_1g_native3", runtime="native", fmi_version=3),
            "pythonfmu": export_fmu(model, out_dir=folder, name="MACE_1g_python", runtime="pythonfmu")}
    return model, resolved, {k: fmpy.extract(str(v), unzipdir=str(folder / k)) for k, v in fmus.items()}


def _run_fmi3(model, folder: str, start: dict[str, float], t: np.ndarray, u: np.ndarray) -> np.ndarray:
    """y[output, k] of an FMI 3 co-simulation FMU initialised with ``start``, u[input, k] held over each step."""
    import fmpy
    from fmpy.fmi3 import FMU3Slave
    from support.fmu_checks import run_steps

    md = fmpy.read_model_description(folder)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier)
    fmu.instantiate()
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setFloat64([vr[k] for k in start], list(start.values()))
    fmu.exitInitializationMode()
    y = run_steps(model, fmu, folder, t, u)
    fmu.terminate()
    fmu.freeInstance()
    return y


@pytest.mark.parametrize("kind", ["native", "native-fmi3", "pythonfmu"])
def test_an_fmu_with_moduli_set_equals_the_fmu_exported_with_them(reexported, kind):
    """The nominal FMU with the 8 moduli at POINT_A set through FMI against the FMU exported from the re-solve
    with them built in (``export 1g --parameters``: nothing set through FMI), 10 s at 2 ms, every input driven
    by 0.5-60 Hz noise at once: every output's RMS difference within 0.1 % of its RMS. Measured: 5.0e-6 of it,
    each kind solving its structure again (0.006 % when they re-analysed); the issue's 1.64 % was the re-export
    handing damping ratios to other modes."""
    from support.resolves import SAMPLES, STEP_S

    model, resolved, folders = reexported
    t = np.arange(SAMPLES) * STEP_S
    u = _all_inputs(ParametricSystem(parametric_arrays(model, physical=False))).T
    values = deck_values(read_deck(bundled_deck_path()))
    start = {n: values[n] * f for n, f in POINT_A.items()}
    if kind == "native-fmi3":
        y_route = _run_fmi3(model, folders[kind], start, t, u)
    else:
        y_route = _fmu_response(model, folders[kind], start, t, u)
    y_ref = _fmu_response(resolved, folders["resolved"], {}, t, u)
    y_nominal = _fmu_response(model, folders["native"], {}, t, u)
    errors = _rms_error(y_route.T, y_ref.T)
    outputs = list(model.system.output_labels)
    assert errors.max() <= 0.001, f"{outputs[int(errors.argmax())]}: {errors.max():.3%} of its RMS"
    moved = _rms_error(y_nominal.T, y_ref.T)  # the change is seen, far above the tolerance
    assert moved.max() > 30 * errors.max() and moved.max() > 0.01


#: the issue's second point, inside the declared ranges: the reanalysis was 36 % (of strain_strut2_y's RMS) off
POINT_B = {"E_lexan_center": 0.79, "E_lexan_end": 1.17, "E_active_strut_end": 0.88, "E_active_strut_piezo": 1.26,
           "E_active_strut_center": 0.82, "E_cable_1": 0.85, "E_cable_2": 1.22, "E_cable_3": 1.09}


def _fmu_response(model, folder: str, start: dict[str, float], t: np.ndarray, u: np.ndarray) -> np.ndarray:
    """y[output, k] of the FMI 2 co-simulation FMU extracted in ``folder``, initialised with ``start``."""
    from support.fmu_checks import initialised_slave, run_steps

    slave = initialised_slave(model, folder, start)
    y = run_steps(model, slave, folder, t, u)
    slave.terminate()
    slave.freeInstance()
    return y


@pytest.fixture(scope="module")
def far(nominal, tmp_path_factory):
    """(the moduli at POINT_B, the re-solve with them built in, folders of: the nominal native and pythonfmu
    FMUs, the re-solve's native FMU), extracted."""
    import fmpy

    from mace_fmu.fmu.export import export_fmu

    model, _, values = nominal["1g"]
    start = {n: values[n] * f for n, f in POINT_B.items()}
    resolved = volts_model(compute_modes(configuration="1g", parameters=ParameterSet(start)))
    out = tmp_path_factory.mktemp("far")
    folders = {name: fmpy.extract(str(export_fmu(m, out_dir=out, name=f"MACE_1g_{name}", runtime=runtime)),
                                  unzipdir=str(out / name))
               for name, m, runtime in (("native", model, "native"), ("pythonfmu", model, "pythonfmu"),
                                        ("resolved", resolved, "native"))}
    return start, resolved, folders


@pytest.mark.parametrize("kind", ["native", "pythonfmu"])
def test_an_fmu_far_from_nominal_solves_its_structure_again(nominal, far, kind):
    """The nominal FMU with the 8 moduli at POINT_B set through FMI (fmpy, 10 s at 2 ms, every input driven by
    0.5-60 Hz noise at once) against the FMU exported from the re-solve with them built in: every output's RMS
    difference within 0.1 % of its RMS (measured 4.1e-6 of it, both kinds). The FMU solves the preload and the
    modes again at initialisation (mace_fmu.iomodel.resolve, mace_resolve.c). On the reanalysis this test
    fails: the same model re-analysed is 0.81 % off (strain_strut4_y; the issue measured 36 % before the
    re-solve continued the nominal modes)."""
    from support.resolves import SAMPLES, STEP_S

    model, route_system, _ = nominal["1g"]
    start, resolved, folders = far
    t = np.arange(SAMPLES) * STEP_S
    u = _all_inputs(route_system).T
    y = _fmu_response(model, folders[kind], start, t, u)
    y_ref = _fmu_response(resolved, folders["resolved"], {}, t, u)
    errors = _rms_error(y.T, y_ref.T)
    outputs = list(model.system.output_labels)
    assert errors.max() <= 0.001, f"{outputs[int(errors.argmax())]}: {errors.max():.3%} of its RMS"
    params = route_system.nominal.copy()
    for name, value in start.items():
        params[route_system.index(name)] = value
    reanalysed = _rms_error(zoh_response(route_system.build(params), u.T), y_ref.T)
    assert reanalysed.max() > 0.005 and reanalysed.max() > 30 * errors.max(), f"{errors.max():.2e}, {reanalysed.max():.2e}"


GYROS = ("gyro_payload_x", "gyro_payload_z", "gyro_bus_x", "gyro_bus_y", "gyro_bus_z")


@pytest.mark.parametrize("outputs", [GYROS, GYROS + ("strain_strut2_y", "strain_strut2_z")],
                         ids=["gyros", "gyros and strut-2 gauges"])
def test_an_update_on_data_of_the_fmu_exported_with_the_truth_finds_every_modulus_in_its_interval(reexported,
                                                                                                  tmp_path, outputs):
    """The check, from a full re-solve: the 8 kept moduli 2-6 % away from the nominal FMU's, built into
    a re-exported FMU (nothing set through FMI), a 20 s gimbal test at 2 ms with 2 % output noise; the nominal
    FMU updated on those data converges and the model explains the data to their noise; every modulus's truth
    lies inside its reported 95 % interval; the strut's sections within 1.96 standard deviations of what the full
    re-solves' Fisher information about the estimate says; lexan and the cables within 1 % where that
    information fixes them (its standard deviation below 0.5 %); each reported standard deviation below 1 %
    within 10 % of the re-solves'. Measured with the FMU solving its structure again: gyros alone, -0.2
    standard deviations from the noise floor, lexan within 0.010 %, cables 1-3 within 0.13 / 1.12 / 0.29 %
    (cable 2's standard deviation is 0.85 %), every modulus within 1.55 reported standard deviations, each
    reported one below 1 % within 4.5 % of the re-solves'; the sections 6.8-71 % uncertain (the gyros hardly
    see them). With the strut-2 gauges: +0.3 standard deviations, every modulus within 0.12 %, the sections
    within 0.014 %, every reported standard deviation the re-solves' to its third digit. On the reanalysis,
    this was 35 % (the route's 3 % error in cable 2's derivative through an information matrix of condition
    number 1e4), and before the static corrections gyros alone put lexan and cables 1 and 3 outside intervals
    of about +-0.05 % (cable 3 6.0 % off): the FMU's model error was larger than the precision it reported."""
    from support.resolves import fisher_standard_deviations

    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.updating.engine.convergence import convergence_report, noise_floor
    from mace_fmu.updating.engine.costs import TimeResponseCost
    from mace_fmu.updating.engine.measured import TimeHistory
    from mace_fmu.updating.engine.uncertainty import stage_uncertainty
    from mace_fmu.updating.fmu.model import fmu_family
    from mace_fmu.updating.fmu.planning import TestDesign
    from mace_fmu.updating.fmu.truth import band_limited_noise
    from mace_fmu.updating.fmu.update import update_fmu
    from mace_fmu.updating.mace.update import THESIS_KEPT

    model, _, folders = reexported
    values = deck_values(read_deck(bundled_deck_path()))
    offsets = (0.04, -0.03, 0.06, -0.02, 0.05, -0.04, 0.03, 0.02)
    truth = {n: values[n] * (1 + d) for n, d in zip(THESIS_KEPT, offsets)}
    resolved = volts_model(compute_modes(configuration="1g", parameters=ParameterSet(truth)))
    truth_fmu = fmu_family(export_fmu(resolved, out_dir=tmp_path, name="MACE_1g_truth", runtime="native"))
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
    report = convergence_report(result, noise_floor=noise_floor(cost), cost=cost)
    assert report.verdict == "explained", report.summary()
    # the intervals from the noise the data were made with (2 % of each output's RMS): the route's information
    # against the re-solves', not the noise floor's estimate
    known = noise_floor(cost, noise_rms_fraction=0.02)
    (stage,) = stage_uncertainty(result, noise_variance=known.expected_cost / result.final_residual.size)
    fisher = fisher_standard_deviations("1g", list(THESIS_KEPT), [
        TestDesign(name="gimbal", seconds=20.0, inputs=tuple(gimbals), outputs=tuple(outputs))],
        about={n: float(v) for n, v in result.values.items()})
    for name in THESIS_KEPT:
        error = 100 * (result.values[name] / truth[name] - 1)
        sd, information = stage.standard_deviation_percent[name], fisher[name]
        assert abs(error) <= 1.96 * sd, f"{name}: {error:+.3f} % off the truth, reported sd {sd:.3f} %"
        if name.startswith("E_active_strut"):  # the sections: within what the re-solves' information allows
            assert abs(error) <= 1.96 * information, f"{name}: {error:+.3f} %, re-solves' sd {information:.3f} %"
        elif information < 0.5:  # lexan and the cables the test fixes: within 1 %
            assert abs(error) < 1.0, f"{name}: {error:+.3f} % off the truth"
        if information < 1.0:
            assert abs(sd / information - 1) < 0.10, f"{name}: reported sd {sd:.4f} %, the re-solves' {information:.4f} %"
