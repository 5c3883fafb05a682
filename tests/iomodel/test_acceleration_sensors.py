"""Acceleration sensors: a structure file's ``kind = "acceleration"`` reads the second derivative of its DOFs.

An acceleration output a reads eta'' = -Omega^2 eta - 2 zeta Omega eta' + Phi^T b u, so the structure block gets
a feedthrough D = a Phi Phi^T b (iomodel/modal_core.py; the C runtime's structure block repeats it). Checked
against independent computations on the beam of tests/structure/test_own_deck.py:
* the identity H_acc(j w) = -w^2 H_disp(j w) of the same DOF, zero-frequency cluster included;
* a free-free beam's low-frequency acceleration per force: the rigid-body value 1/M + (L/2)^2 / I_cm from
  its lumped masses;
* D against the sum over the retained modes of phi_tip^2;
* the native FMU against the exact ZOH of the model, with a damping ratio changed at initialisation against
  the Python rebuild (ParametricSystem) of the same parameters.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import control as ct
import fmpy
import numpy as np
import pytest
from support.cantilever import AREA, RHO, L, N, beam_deck

from mace_fmu.deck.reader import read_deck
from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.frf import frequency_response
from mace_fmu.iomodel.model_options import ModelledElectronics
from mace_fmu.iomodel.volts import volts_model


def _instrument(table: str, name: str, description: str, grid: int, gain: float, kind: str = "") -> str:
    """One [[actuators]] or [[sensors]] table of a structure file, reading component 2 (Y) of ``grid``."""
    kind_line = f'kind = "{kind}"\n' if kind else ""
    return (f'\n[[{table}]]\nname = "{name}"\ndescription = "{description}"\n{kind_line}'
            f"dofs = [[{grid}, 2, 1.0]]\ngain = {gain}\n")


STRUCTURE = ('[components]\nbeam = ["1-21"]\n'
             + _instrument("actuators", "tip_force_y", "force along Y at the beam's tip", 21, 1.0)
             + _instrument("sensors", "tip_y", "tip displacement along Y", 21, 1.0, "displacement")
             + _instrument("sensors", "tip_acc_y", "tip acceleration along Y", 21, 1.0, "acceleration")
             + _instrument("sensors", "mid_acc_y", "mid-span acceleration along Y", 11, 2.0, "acceleration"))
BARE = ModelledElectronics(servos=False, bessel="none", delays=False)


def _model(tmp_path: Path, *, free: bool, max_hz: float = 2000.0):
    text = beam_deck()
    if free:  # no clamp: three rigid-body modes in the x-y plane
        text = text.replace("SPC1,7,123456,1\n", "").replace("SPC = 7\n", "")
    deck, spec = tmp_path / "beam.bdf", tmp_path / "beam.toml"
    deck.write_text(text)
    spec.write_text(STRUCTURE)
    return volts_model(compute_modes(read_deck(deck), configuration="0g", structure_file=spec, max_hz=max_hz),
                       electronics=BARE)


@pytest.mark.parametrize("free", [False, True], ids=["cantilever", "free-free"])
def test_acceleration_is_minus_omega_squared_times_displacement(tmp_path, free):
    model = _model(tmp_path, free=free)
    outs = list(model.system.output_labels)
    f = np.logspace(-1, 3, 25)
    h = frequency_response(model.system, f)[:, :, 0]
    disp, acc = h[:, outs.index("tip_y")], h[:, outs.index("tip_acc_y")]
    np.testing.assert_allclose(acc, -(2 * np.pi * f) ** 2 * disp, rtol=1e-8)
    # the unit the structure file did not give is derived from the DOFs
    assert model.instruments.sensor("tip_acc_y").unit == "m/s^2"


def test_feedthrough_is_the_retained_modes_sum_of_phi_squared(tmp_path):
    model = _model(tmp_path, free=False)
    modes = model.structure_modes.modes
    keep = modes.frequencies_hz <= 2000.0
    tip, mid = modes.dofs.index(21, 2), modes.dofs.index(11, 2)
    phi = modes.shapes[:, keep]
    outs = list(model.system.output_labels)
    d = model.system.D[:, 0]
    assert d[outs.index("tip_y")] == 0.0
    np.testing.assert_allclose(d[outs.index("tip_acc_y")], np.sum(phi[tip] ** 2), rtol=1e-10)
    np.testing.assert_allclose(d[outs.index("mid_acc_y")], 2.0 * np.sum(phi[mid] * phi[tip]), rtol=1e-10)


def test_free_free_beam_accelerates_as_a_rigid_body_below_its_first_mode(tmp_path):
    """Force F at the tip of a free beam: a_tip = F (1/M + (L/2)^2 / I_cm) at low frequency, from the deck's
    lumped masses (half of each bar's mass at each end; rotations massless) and the tip mass CONM2."""
    from support.cantilever import TIP_MASS

    model = _model(tmp_path, free=True)
    x = np.linspace(0.0, L, N + 1)
    m = np.full(N + 1, RHO * AREA * L / N)
    m[[0, -1]] /= 2.0
    m[-1] += TIP_MASS
    total = m.sum()
    centre = (m * x).sum() / total
    inertia = (m * (x - centre) ** 2).sum()
    rigid = 1.0 / total + (L - centre) ** 2 / inertia
    outs = list(model.system.output_labels)
    h = frequency_response(model.system, np.array([1e-3]))[0, outs.index("tip_acc_y"), 0]
    assert abs(h.imag) < 1e-6 * abs(h.real)
    np.testing.assert_allclose(h.real, rigid, rtol=1e-6)


def test_native_fmu_steps_as_the_exact_zoh_and_rebuilds_changed_damping_and_modulus_as_python_does(tmp_path):
    from support.fmu_checks import zoh_reference

    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.parametric import ParametricSystem
    from mace_fmu.iomodel.parametric_data import parametric_arrays

    model = _model(tmp_path, free=True, max_hz=200.0)
    arrays = parametric_arrays(model)  # with the modulus: its reanalysis turns the acceleration rows too
    system = ParametricSystem(arrays)
    nominal = np.asarray(system.nominal, dtype=float)
    for matrix, built in zip((model.system.A, model.system.B, model.system.C, model.system.D), system.build(nominal)):
        np.testing.assert_allclose(built, matrix, rtol=0, atol=1e-12 * max(np.abs(matrix).max(), 1.0))
    names = list(system.parameter_names)
    damping = next(name for name in names if name.startswith("damping_mode_")
                   and abs(system.frequencies_hz[int(name.rsplit("_", 1)[1]) - 1]) > 1.0)
    modulus = next(name for name in names if name.startswith("E_"))
    starts = {damping: 0.2, modulus: 1.1 * nominal[names.index(modulus)]}
    changed = nominal.copy()
    for name, value in starts.items():
        changed[names.index(name)] = value
    rebuilt = ct.ss(*system.build(changed))
    fmu = export_fmu(model, out_dir=tmp_path, name="beam_acc", arrays=arrays)
    t = np.arange(0.0, 0.4 + 1e-12, 1e-3)
    outputs = list(model.system.output_labels)
    inputs = np.zeros(len(t), dtype=[("time", float), ("tip_force_y", float)])
    inputs["time"], inputs["tip_force_y"] = t, 1.0
    for start, reference in (({}, model.system), (starts, rebuilt)):
        run = fmpy.simulate_fmu(str(fmu), input=inputs, output=outputs, step_size=1e-3, output_interval=1e-3,
                                stop_time=t[-1], start_values=start)
        y = np.stack([run[o] for o in outputs])[:, :len(t)]
        ref = zoh_reference(SimpleNamespace(system=reference), t, np.ones((1, len(t))))[:, :y.shape[1]]
        span = np.ptp(ref, axis=1, keepdims=True)
        assert np.all(span > 0)
        assert np.max(np.abs(y - ref) / span) <= 1e-10, start
    outs = list(model.system.output_labels)
    # the damping and the stiffer beam moved the acceleration rows; the feedthrough, a projection of the
    # inverse mass on the retained modes, stays: the reanalysis turns the modes within their span
    assert np.abs(rebuilt.C[outs.index("tip_acc_y")] - model.system.C[outs.index("tip_acc_y")]).max() > 1e-3
    np.testing.assert_allclose(rebuilt.D, model.system.D, rtol=1e-12, atol=1e-15)


def test_pythonfmu_fmu_gives_the_acceleration_with_its_feedthrough(tmp_path):
    """Run in a subprocess: loading a pythonfmu FMU has corrupted the heap of the process that did (see
    conftest.py), which would take an xdist worker down in a later test."""
    import subprocess
    import sys

    from support.fmu_checks import zoh_reference

    from mace_fmu.fmu.export import export_fmu

    model = _model(tmp_path, free=False, max_hz=200.0)
    fmu = export_fmu(model, runtime="pythonfmu", out_dir=tmp_path, name="beam_acc_py")
    t = np.arange(0.0, 0.2 + 1e-12, 1e-3)
    outputs = list(model.system.output_labels)
    host = tmp_path / "host.py"
    host.write_text(
        "import os, sys, fmpy, numpy as np\n"
        "t = np.arange(0.0, 0.2 + 1e-12, 1e-3)\n"
        "u = np.zeros(len(t), dtype=[('time', float), ('tip_force_y', float)])\n"
        "u['time'], u['tip_force_y'] = t, 1.0\n"
        f"outs = {outputs!r}\n"
        "run = fmpy.simulate_fmu(sys.argv[1], input=u, output=outs, step_size=1e-3, output_interval=1e-3,\n"
        "                        stop_time=t[-1])\n"
        "np.save(sys.argv[2], np.stack([run[o] for o in outs]))\n"
        "sys.stdout.flush(); os._exit(0)\n")
    saved = tmp_path / "y.npy"
    done = subprocess.run([sys.executable, str(host), str(fmu), str(saved)], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0 and saved.exists(), done.stderr
    y = np.load(saved)[:, :len(t)]
    ref = zoh_reference(model, t, np.ones((1, len(t))))[:, :y.shape[1]]
    assert y[1, 0] == pytest.approx(model.system.D[1, 0], rel=1e-12)  # at t = 0 the feedthrough alone
    assert np.max(np.abs(y - ref) / np.ptp(ref, axis=1, keepdims=True)) <= 1e-10


def test_a_structure_row_of_unknown_kind_in_the_model_data_is_refused_at_instantiation(tmp_path):
    """The runtime checks what each structure output reads (0 displacement, 1 rate, 2 acceleration) when it
    loads the data, rather than building a wrong model from a corrupted or foreign file."""
    import zipfile

    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.fmu.native.export import RESOURCE_NAME
    from mace_fmu.fmu.native.resource import resource_bytes, runtime_arrays
    from mace_fmu.fmu.parametric import parametric_model

    model = _model(tmp_path, free=False, max_hz=200.0)
    good = export_fmu(model, out_dir=tmp_path, name="beam_good")
    data = runtime_arrays(parametric_model(model))
    data["struct_row_kind"] = np.array([0, 7, 2], dtype=np.int64)
    bad = tmp_path / "beam_bad.fmu"
    with zipfile.ZipFile(good) as source, zipfile.ZipFile(bad, "w") as target:
        for item in source.infolist():
            body = source.read(item)
            target.writestr(item, resource_bytes(data) if item.filename.endswith(RESOURCE_NAME) else body)
    # in a subprocess: fmpy's logger proxy (fmpy/logging, addLoggerProxy) keeps the last logger given to
    # simulate_fmu(logger=...) in a global, and its default callbacks go through that proxy too; once the
    # Python callback is collected, the next FMU in the process that logs jumps into freed memory (measured:
    # a successful simulate_fmu with a logger, then the controller FMU's refused doStep: SIGSEGV/SIGILL)
    host = tmp_path / "host.py"
    host.write_text(
        "import os, sys, fmpy\n"
        "messages = []\n"
        "try:\n"
        "    fmpy.simulate_fmu(sys.argv[1], stop_time=0.01, step_size=1e-3, validate=False, debug_logging=True,\n"
        "                      logger=lambda c, i, s, k, m: messages.append(m))\n"
        "except Exception:\n"
        "    pass\n"
        "print(b'|'.join(messages).decode(), flush=True)\n"
        "os._exit(0)\n")
    import subprocess
    import sys

    done = subprocess.run([sys.executable, str(host), str(bad)], capture_output=True, text=True, timeout=120)
    assert "structure output 1 reads an unknown quantity" in done.stdout, done.stdout + done.stderr
