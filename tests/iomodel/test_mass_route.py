"""Concentrated masses as FMU parameters (``m_<name>``) move every channel as a full re-solve does.

The structure is the three-storey frame of examples/three_storey_frame (its floors are CONM2 cards named
``floor_1..3`` in frame.toml's ``[parameters] masses``; 1-g: gravity compresses the legs). The reference of
every test is a full re-solve: the deck with the mass (and its inertias) built in, the FE model, the 1-g
preload under the changed weight and the modes solved again (each mode keeping its nominal damping,
tests/support/resolves.py). The route under test is the one both FMU kinds run: the reanalysis with the
mass change and mass-correction vectors (mace_fmu/iomodel/reanalysis.py, stiffness_route.py) in
:class:`~mace_fmu.iomodel.parametric.ParametricSystem` (the pythonfmu FMU runs it verbatim) and in the native C
runtime (mace_model.c), and the FMUs themselves in the last test.

The accelerometers read the feedthrough D = a Phi^T b, which a mass moves directly (about 1/m at the driven
floor): D is compared on its own as well as through the responses.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.signal import butter, lfilter

from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.parametric import ParametricSystem
from mace_fmu.iomodel.parametric_data import parametric_arrays
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.parameters.sets import ParameterSet, deck_values, parameter_names
from mace_fmu.structure.file import load_structure_file

pytestmark = pytest.mark.slow  # each test compares against full re-solves of the 1-g frame

FRAME = Path(__file__).resolve().parents[2] / "examples" / "three_storey_frame"
MASSES = ("m_floor_1", "m_floor_2", "m_floor_3")
ENDS = (0.7, 1.5)  #: the declared range of a mass parameter, x nominal (mace_fmu/parameters/kinds.py)
TOLERANCE = 0.004  #: of each output's range: the bound the moduli and springs are held to
#: what the reanalysis reaches on this frame (docs/guide/fmus.md states it): 7.4e-6 at worst, m_floor_3 x 1.5
REACHED = 1e-5
STEP_S = 1e-3  #: 1 kHz, well above the 28 Hz third mode
SAMPLES = 4000


def _inputs(n_inputs: int, driven: int, *, seed: int = 3) -> np.ndarray:
    """(SAMPLES, n_inputs) forces [N]: noise below 40 Hz (all three sway modes) on input ``driven``, zero elsewhere."""
    b, a = butter(4, 40.0 * 2 * STEP_S)
    u = np.zeros((SAMPLES, n_inputs))
    u[:, driven] = lfilter(b, a, np.random.default_rng(seed + driven).standard_normal(SAMPLES))
    return u


def _zoh(system: tuple[np.ndarray, ...], u: np.ndarray, *, held_before: bool = False) -> np.ndarray:
    """(len(u), n_outputs) exact zero-order-hold response from rest. ``held_before``: the output at sample k reads
    the input held over the step before it (an FMU's output after doStep), else the input at k."""
    a, b, c, d = system
    n, m = b.shape
    block = expm(np.block([[a, b], [np.zeros((m, n + m))]]) * STEP_S)
    ad, bd = block[:n, :n], block[:n, n:]
    x, y = np.zeros(n), np.empty((len(u), c.shape[0]))
    for k, uk in enumerate(u):
        feed = (u[k - 1] if k else np.zeros(m)) if held_before else uk
        y[k] = c @ x + d @ feed
        x = ad @ x + bd @ uk
    return y


@pytest.fixture(scope="module")
def frame():
    """(deck, nominal 1-g model, its ParametricSystem with every physical parameter, the deck's m_ and E_ values)."""
    deck = read_deck(FRAME / "frame.bdf")
    model = volts_model(compute_modes(deck, configuration="1g", structure_file=FRAME / "frame.toml"))
    values = deck_values(deck, parameter_names(deck, load_structure_file(FRAME / "frame.toml")))
    return deck, model, ParametricSystem(parametric_arrays(model)), values


def _resolved(frame, values: dict[str, float]):
    """(re-solved model continuing the nominal modes, its (A, B, C, D)) with ``values`` built in."""
    deck, model, _, _ = frame
    resolved = volts_model(compute_modes(deck, configuration="1g", structure_file=FRAME / "frame.toml",
                                         parameters=ParameterSet(values), continue_from=model.structure_modes))
    system = ParametricSystem(parametric_arrays(resolved, physical=False))
    return resolved, system.build(system.nominal)


def test_the_frame_names_its_floor_masses_as_parameters_with_their_declared_range(frame):
    _, _, system, values = frame
    assert {n: values[n] for n in MASSES} == dict.fromkeys(MASSES, 5.201)  # frame.bdf's CONM2 cards [kg]
    for name in MASSES:
        k = system.index(name)
        assert (system.minimum[k], system.maximum[k]) == pytest.approx((0.7 * 5.201, 1.5 * 5.201), rel=1e-15)


@pytest.mark.parametrize("name", MASSES)
@pytest.mark.parametrize("factor", ENDS)
def test_every_accelerometer_follows_the_resolve_at_either_end_of_a_floor_mass_range(frame, name, factor):
    """A floor mass at 0.7 x and 1.5 x: the reanalysed frequencies within 1e-5 of the re-solve's, D within 1e-6 of
    its largest entry, and each accelerometer's response (4 s at 1 ms, each floor's force driven alone) within
    0.4 % of its range of the re-solve's (the declared range's bound; reached: below 1e-5), where the change itself
    is more than 25 x that."""
    _, _, system, values = frame
    params = system.nominal.copy()
    params[system.index(name)] = values[name] * factor
    route = system.build(params)
    resolved, reference = _resolved(frame, {name: values[name] * factor})
    flexible = resolved.plant.frequencies_hz[:len(system.frequencies_hz)]
    assert np.max(np.abs(system.frequencies_hz / flexible - 1)) <= 1e-5
    assert np.max(np.abs(route[3] - reference[3])) <= 1e-6 * np.max(np.abs(reference[3]))
    nominal = system.build(system.nominal)
    for driven, force in enumerate(system.inputs):
        u = _inputs(len(system.inputs), driven)
        y_route, y_ref, y_nominal = _zoh(route, u), _zoh(reference, u), _zoh(nominal, u)
        span = np.ptp(y_ref, axis=0)
        worst = np.max(np.abs(y_route - y_ref), axis=0) / span
        moved = np.max(np.abs(y_nominal - y_ref), axis=0) / span
        j = int(np.argmax(worst))
        assert worst[j] <= TOLERANCE, f"{name} x {factor}, {force}: {system.outputs[j]} {worst[j]:.3%} of its range"
        assert worst[j] <= REACHED, f"{name} x {factor}, {force}: {system.outputs[j]} {worst[j]:.2e} of its range"
        assert np.min(moved) > 25 * TOLERANCE, f"{name} x {factor}, {force}: the change moves too little to prove it"


def test_without_the_mass_corrections_and_mass_change_the_floor_accelerometers_miss(frame):
    """What the route adds is needed: the same 1.5 x floor-1 mass with the modal mass change left out (the
    reanalysis then sees only the weight's preload stiffness) is off the re-solve by far more than 0.4 %."""
    _, _, system, values = frame
    stripped = {k: v for k, v in system.data.items() if k not in ("physical_dm", "correction_dm",
                                                                   "correction_mass_coupling")}
    blind = ParametricSystem(stripped)
    params = blind.nominal.copy()
    params[blind.index("m_floor_1")] = values["m_floor_1"] * 1.5
    _, reference = _resolved(frame, {"m_floor_1": values["m_floor_1"] * 1.5})
    u = _inputs(len(blind.inputs), 0)
    y_ref = _zoh(reference, u)
    worst = np.max(np.abs(_zoh(blind.build(params), u) - y_ref), axis=0) / np.ptp(y_ref, axis=0)
    assert np.min(worst) > 25 * TOLERANCE


#: a floor mass at each end of its range, and a storey modulus with them: a mass and a stiffness at once
BUILT_IN = {"m_floor_1": 1.5, "m_floor_3": 0.7, "E_storey_2": 1.2}


@pytest.fixture(scope="module")
def folders(frame, tmp_path_factory):
    """The nominal frame's native and pythonfmu FMUs, extracted."""
    import fmpy

    from mace_fmu.fmu.export import export_fmu

    out = tmp_path_factory.mktemp("frame_fmus")
    return {kind: fmpy.extract(str(export_fmu(frame[1], out_dir=out, name=f"frame_{kind}", runtime=kind)),
                               unzipdir=str(out / kind)) for kind in ("native", "pythonfmu")}


@pytest.mark.parametrize("kind", ["native", "pythonfmu"])
def test_an_fmu_with_floor_masses_set_equals_the_resolve_with_them(frame, folders, kind):
    """The nominal frame FMU with m_floor_1 x 1.5, m_floor_3 x 0.7 and E_storey_2 x 1.2 set through FMI against the exact zero-order hold of the re-solve with them built
    in, 4 s at 1 ms, each floor's force driven: every accelerometer within 0.4 % of its range."""
    from support.fmu_checks import initialised_slave, run_steps

    _, model, system, values = frame
    changed = {n: values[n] * f for n, f in BUILT_IN.items()}
    resolved, reference = _resolved(frame, changed)
    folder = folders[kind]
    start = dict(changed)
    t = np.arange(SAMPLES) * STEP_S
    for driven, force in enumerate(system.inputs):
        u = _inputs(len(system.inputs), driven)
        fmu = initialised_slave(model, folder, start)
        y_fmu = run_steps(model, fmu, folder, t, u.T).T
        fmu.terminate()
        fmu.freeInstance()
        y_ref = _zoh(reference, u, held_before=True)
        worst = np.max(np.abs(y_fmu - y_ref), axis=0) / np.ptp(y_ref, axis=0)
        j = int(np.argmax(worst))
        assert worst[j] <= TOLERANCE, f"{kind}, {force}: {system.outputs[j]} {worst[j]:.3%} of its range"


@pytest.mark.skipif(shutil.which("gcc") is None or shutil.which("valgrind") is None, reason="needs gcc and valgrind")
def test_the_native_reanalysis_with_a_mass_is_clean_under_valgrind(frame, folders, tmp_path):
    """The C host (tests/support/native_host.c) with m_floor_1 x 1.5 and E_storey_2 x 1.2 in memcheck, two
    instantiate/initialise/step/free cycles: the generalized eigen-solution reads and writes nothing outside its
    arrays and frees all it took."""
    import fmpy
    from support.paths import SUPPORT

    from mace_fmu.fmu.native import compile as runtime

    _, model, system, values = frame
    host = tmp_path / "native_host"
    subprocess.run(["gcc", "-std=c99", "-O2", "-Wall", "-Werror", f"-I{Path(runtime.__file__).with_name('c')}", "-o",
                    str(host), str(SUPPORT / "native_host.c"), "-ldl"], check=True)
    folder = folders["native"]
    md = fmpy.read_model_description(folder)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    u = _inputs(3, 0)[:50].T
    np.ascontiguousarray(u.T, dtype="<f8").tofile(tmp_path / "u.bin")
    done = subprocess.run(["valgrind", "--error-exitcode=9", "--leak-check=full", "--errors-for-leak-kinds=all",
                           str(host), folder, md.coSimulation.modelIdentifier, md.guid, repr(STEP_S), str(u.shape[1]),
                           str(tmp_path / "u.bin"), str(tmp_path / "y.bin"),
                           ",".join(str(vr[n]) for n in model.system.input_labels),
                           ",".join(str(vr[n]) for n in model.system.output_labels), "2",
                           f"{vr['m_floor_1']}={values['m_floor_1'] * 1.5!r}",
                           f"{vr['E_storey_2']}={values['E_storey_2'] * 1.2!r}"],
                          capture_output=True, text=True, timeout=900, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "ERROR SUMMARY: 0 errors" in done.stderr and "All heap blocks were freed" in done.stderr
    # and the run was the reanalysed one: the host's outputs are the ParametricSystem's with the same values
    params = system.nominal.copy()
    params[system.index("m_floor_1")] *= 1.5
    params[system.index("E_storey_2")] *= 1.2
    y = np.fromfile(tmp_path / "y.bin", dtype="<f8").reshape(u.shape[1] + 1, -1)
    solved_again = ParametricSystem(parametric_arrays(model, resolve=True))  # what the FMU does with its parameters
    expected = _zoh(solved_again.build(params), np.vstack([u.T, np.zeros((1, 3))]), held_before=True)
    assert np.max(np.abs(y - expected)) <= 1e-9 * np.max(np.abs(expected))


def test_a_mass_name_without_a_conm2_is_refused_naming_the_file_and_key(tmp_path):
    text = (FRAME / "frame.toml").read_text().replace('"300" = "floor_3"', '"301" = "floor_3"')
    path = tmp_path / "frame.toml"
    path.write_text(text)
    with pytest.raises(MaceError, match=r"frame\.toml: \[parameters\] masses: key '301' \('floor_3'\) is no CONM2"):
        compute_modes(read_deck(FRAME / "frame.bdf"), configuration="1g", structure_file=path,
                      parameters=ParameterSet({"m_floor_1": 6.0}))
