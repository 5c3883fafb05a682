"""Package a volts-volts model as an FMI 2.0 co-simulation FMU (pythonfmu), self-contained.

The FMU holds its blocks, wiring, modal data and stiffness sensitivities
(``resources/model.npz``) and a slave script that needs only numpy, scipy and pythonfmu (see
:mod:`mace_fmu.fmu.slave`), so it rebuilds itself when parameters change. pythonfmu cannot
declare units, a default experiment or a version, so those are written into the model
description after the build.
"""

from __future__ import annotations

import hashlib
import re
import sys
import tempfile
import zipfile
from importlib import metadata
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np
from pythonfmu.builder import FmuBuilder

from mace_fmu.datafile import data_file_path, read_data_file
from mace_fmu.fe.assembly import FEModel, assemble
from mace_fmu.fe.corotational import tangent
from mace_fmu.fe.preload import Preload
from mace_fmu.iomodel import modal_core
from mace_fmu.iomodel.modal_ss import modal_data
from mace_fmu.iomodel.motion import motion_unit, parse_motion_output
from mace_fmu.iomodel.volts import VoltsModel
from mace_fmu.structure import apply_overrides
from modelica_like import PD, Gain, PadeDelay, algebra

SLAVE_SOURCE = Path(__file__).with_name("slave.py")
DEFAULT_EXPERIMENT = {"startTime": "0.0", "stopTime": "10.0", "stepSize": "0.002"}
_UNITS = (("E_", "Pa"), ("k_", "N/m"), ("delay_", "s"), ("damping_mode_", "1"), ("K_a", "V/deg"),
          ("K_r", "V/(deg/s)"), ("K_f", "1"), ("K_b", "1"), ("frequency_mode_", "Hz"))
_RELATIVE_STEP = 1e-3  # the material stiffness is linear in E and k: the difference quotient is exact


def _descriptions(model: VoltsModel) -> tuple[list[str], list[str]]:
    """Variable descriptions that say which actuator or sensor, which axis and what a volt means."""
    inst = model.instruments
    gimbals = set(inst.servos.gimbals) if model.servos else set()
    wheels = set(inst.servos.wheels) if model.servos else set()
    ins = []
    for name in model.system.input_labels:
        a = inst.actuator(name)
        if name in gimbals:
            ins.append(f"{a.description}: commanded relative angle through the gimbal servo, 1 V = 1 deg")
        elif name in wheels:
            ins.append(f"{a.description}: speed-loop command [V]")
        else:
            ins.append(f"{a.description} [V], {a.gain} N m/V")
    outs = []
    for name in model.system.output_labels:
        motion = parse_motion_output(name)
        if motion is None:
            outs.append(f"{inst.sensor(name).description} [V], {inst.sensor(name).gain} V per physical unit")
        else:
            grid, comp = motion
            what = "translation along" if comp.startswith("t") else "rotation about"
            outs.append(f"grid {grid}: {what} basic {comp[1].upper()} [{motion_unit(comp)}], from the equilibrium "
                        "(animation output)")
    return ins, outs


def _blocks(model: VoltsModel) -> tuple[dict, list[tuple[str, float, str]]]:
    """Block arrays for the npz and the non-physical parameters (name, value, description)."""
    ic = model.diagram.connection_matrices()
    kinds, params, arrays, parameters = [], [], {}, []
    sv = model.instruments.servos
    for i, block in enumerate(ic.blocks):
        name = block.name
        # block kinds by class; which servo gain a Gain block carries, by the name volts.py gives it
        if name == "structure":
            kinds.append("structure"), params.append("")
        elif isinstance(block, PadeDelay):
            kinds.append("delay"), params.append(name)
            what = name.removeprefix("delay_")
            parameters.append((name, float(block.delay), f"time delay of {what} [s] (Pade order {model.pade_order})"))
        elif isinstance(block, Gain) and name.startswith(("kf_", "kb_")):
            gain = "K_f" if name.startswith("kf_") else "K_b"
            kinds.append("gain"), params.append(gain)
        elif isinstance(block, PD):
            kinds.append("pd"), params.append("K_a,K_r")
        else:
            kinds.append("const"), params.append("")
        for m in "ABCD":
            arrays[f"block{i}_{m}"] = np.asarray(getattr(block, m), dtype=float)
    if "K_f" in params:
        parameters += [("K_f", sv.wheel_forward_gain, "reaction wheel speed loop forward gain (eq. 3.18)"),
                       ("K_b", sv.wheel_backward_gain, "reaction wheel speed loop backward (tachometer) gain")]
    if "K_a,K_r" in params:
        parameters += [("K_a", sv.gimbal_angle_gain, "gimbal servo angle gain [V/deg] (eq. 3.20)"),
                       ("K_r", sv.gimbal_rate_gain, "gimbal servo rate gain [V/(deg/s)] (eq. 3.20)")]
    ins = [list(ic.inputs).index(n) for n in model.system.input_labels]
    outs = [list(ic.outputs).index(n) for n in model.system.output_labels]
    arrays.update(block_kinds=np.array(kinds), block_params=np.array(params), wiring=ic.wiring,
                  entry=ic.entry[:, ins], exit=ic.exit[outs], pade_order=np.array(model.pade_order))
    return arrays, parameters


def _material_stiffness(fe: FEModel, preload: Preload | None) -> np.ndarray:
    """Bar stiffness [N/m, N m/rad] about the configuration the modes are computed in.

    1-g: the preloaded (sagged) geometry with the preload's bar forces held, so a change of E
    changes only the material part, as at the new equilibrium, where gravity sets the forces.
    Taking the undeformed geometry instead puts spurious strain into the near-rigid suspension
    modes: Z tilt, X twist and 1st Y bending then came out 1.9e-3 to 2.9e-3 off after E of the
    Lexan center +5 %, against 7.8e-4 at most this way.
    """
    if preload is None:
        return fe.stiffness
    return tangent(fe.bars, preload.state, fe.dofs.size, natural_forces=preload.bar_forces)[1].toarray()


def _physical(model: VoltsModel, shapes: np.ndarray) -> tuple[list[tuple[str, float, str]], np.ndarray]:
    """Physical parameters and their projected stiffness sensitivities Phi0^T dK/d(ln p) Phi0."""
    names = read_data_file(data_file_path(), what="parameter names").get("parameters", {})
    deck, fe = model.structure_modes.structure.deck, model.structure_modes.model
    used = sorted({deck.pbars[b.pid].mid for b in deck.bars.values()})
    pre = model.structure_modes.preload
    nominal = _material_stiffness(fe, pre)
    parameters, sensitivities = [], []
    for mid in used:
        e = deck.mat1s[mid].youngs_modulus
        label = names.get("materials", {}).get(str(mid), f"mat{mid}")
        plus = assemble(apply_overrides(deck, {("MAT1", mid): {"e": e * (1 + _RELATIVE_STEP)}}))
        dk = (_material_stiffness(plus, pre) - nominal) / _RELATIVE_STEP  # linear in E: the quotient is exact
        parameters.append((f"E_{label}", e, f"Young's modulus of {label} (MAT1 {mid}) [Pa]; takes effect by "
                                            "reanalysis on the retained modes"))
        sensitivities.append(shapes.T @ dk @ shapes)
    for row, (sid, k) in enumerate(zip(fe.spring_ids, fe.spring_constants)):
        label = names.get("springs", {}).get(str(sid), f"spring{sid}")
        v = fe.spring_vectors[row] @ shapes
        parameters.append((f"k_{label}", float(k), f"stiffness of {label} (CELAS2 {sid}) [N/m]; reanalysis"))
        sensitivities.append(k * np.outer(v, v))
    n = shapes.shape[1]
    return parameters, np.array(sensitivities).reshape(len(parameters), n, n)


def _patch_model_description(fmu: Path, *, description: str, version: str) -> None:
    """Add units, a default experiment, initial unknowns, description and version."""
    with zipfile.ZipFile(fmu) as z:
        entries = {n: z.read(n) for n in z.namelist()}
    root = ET.fromstring(entries["modelDescription.xml"])
    root.set("description", description)
    root.set("version", version)
    root.set("author", "mace-fmu")
    root.set("generationTool", f"mace-fmu {version} ({root.get('generationTool', 'PythonFMU')})")
    used = set()
    for var in root.iter("ScalarVariable"):
        name = var.get("name")
        motion = parse_motion_output(name)
        if motion is not None:
            unit = motion_unit(motion[1])
        elif var.get("causality") in ("input", "output"):
            unit = "V"
        else:
            unit = next((u for prefix, u in _UNITS if name.startswith(prefix)), None)
        if unit is not None:
            var.find("Real").set("unit", unit)
            used.add(unit)
    units = ET.Element("UnitDefinitions")
    for unit in sorted(used):
        ET.SubElement(units, "Unit", name=unit)
    root.insert(list(root).index(root.find("CoSimulation")) + 1, units)
    for old in root.findall("DefaultExperiment"):
        root.remove(old)
    root.insert(list(root).index(root.find("ModelVariables")), ET.Element("DefaultExperiment", DEFAULT_EXPERIMENT))
    # FMI 2.0: outputs and calculated parameters are initial unknowns (pythonfmu omits them)
    structure = root.find("ModelStructure")
    outputs = structure.find("Outputs")
    if structure.find("InitialUnknowns") is None:
        initial = ET.Element("InitialUnknowns")
        variables = list(root.find("ModelVariables"))
        for k, var in enumerate(variables, start=1):
            if var.get("causality") in ("output", "calculatedParameter"):
                ET.SubElement(initial, "Unknown", index=str(k))
        position = list(structure).index(outputs) + 1 if outputs is not None else 0
        structure.insert(position, initial)
    entries["modelDescription.xml"] = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    with zipfile.ZipFile(fmu, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in entries.items():
            z.writestr(name, data)


_CACHE_PREFIX = "_mace_fmu_slave_"  #: sys.modules key of an FMU's cached implementation
_ENTRY_TEMPLATE = '''"""Entry script of a mace-fmu FMU (generated by mace-fmu export; the implementation is below).

pythonfmu 0.7's native wrapper, on every fmi2Instantiate, re-executes this script (globals: this
module's dict, locals: a fresh dict), keeps the MRO of every class it finds there alive for good,
and calls Py_DECREF on the module dict, a borrowed reference. A script that defines its class
here survives that only because each execution leaves a new class alive whose methods hold the
dict: about 52 kB per instance (NTNU-IHB/PythonFMU#229). Here the implementation and the model
class are created once per process and cached in sys.modules; each execution only binds that
same class again and adds back the one reference to the dict that the wrapper takes.
"""

import sys
import types

_KEY = "{prefix}{digest}"
if _KEY not in sys.modules:
    _impl = types.ModuleType(_KEY)
    exec(compile({source!r}, _KEY, "exec"), _impl.__dict__)
    _impl.model_class = type("{name}", (_impl.MaceSlave,), {{"description": {description!r}, "__module__": __name__}})
    _impl.wrapper_references = []
    sys.modules[_KEY] = _impl
sys.modules[_KEY].wrapper_references.append(globals())  # the reference the wrapper will take
{name} = sys.modules[_KEY].model_class
'''


def _entry_script(name: str, description: str) -> str:
    """The entry script: the numpy cores and the slave as one cached implementation, and a thin class."""
    parts = []
    for path in (Path(algebra.__file__), Path(modal_core.__file__), SLAVE_SOURCE):
        lines = [ln for ln in path.read_text().splitlines()
                 if ln.strip() != "from __future__ import annotations" and not ln.rstrip().endswith("# fmu: inlined")]
        parts.append("\n".join(lines))
    source = "from __future__ import annotations\n\n" + "\n\n".join(parts) + "\n"
    # one cache entry per distinct FMU: a process may load several (the 1-g and the 0-g model)
    digest = hashlib.sha256("\0".join((source, name, description)).encode()).hexdigest()[:16]
    return _ENTRY_TEMPLATE.format(name=name, description=description, source=source, digest=digest,
                                  prefix=_CACHE_PREFIX)


def export_fmu(model: VoltsModel, *, out_dir: str | Path = ".", name: str | None = None) -> Path:
    """Write ``out_dir/<name>.fmu`` (default name MACE_1g / MACE_0g) and return its path."""
    kind = model.structure_modes.structure.kind
    name = name or f"MACE_{kind}"
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise ValueError(f"FMU name must be a Python/C identifier (it names the model class), got {name!r}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    sys_ = model.system
    ins, outs = _descriptions(model)
    description = (f"MACE {kind} volts-volts model: {sys_.nstates} states; servos {'closed' if model.servos else 'open'}, "
                   f"Bessel filters {model.bessel}, delays {'on' if model.delays else 'off'}")
    max_hz = float(np.max(model.plant.frequencies_hz))
    data = modal_data(model.structure_modes.modes, model.instruments, max_hz=max_hz,
                      motion_grids=list(model.plant.motion_grids))
    arrays, parameters = _blocks(model)
    physical, dk = _physical(model, data.shapes)
    damping = [(f"damping_mode_{k + 1}", float(z), f"open-loop damping ratio of mode {k + 1}: {label}")
               for k, (z, label) in enumerate(zip(model.plant.damping, data.labels))]
    parameters = damping + parameters + physical
    arrays.update(
        inputs=np.array(sys_.input_labels), outputs=np.array(sys_.output_labels), input_descriptions=np.array(ins),
        output_descriptions=np.array(outs), param_names=np.array([p[0] for p in parameters]),
        param_values=np.array([p[1] for p in parameters], dtype=float),
        param_descriptions=np.array([p[2] for p in parameters]), physical_names=np.array([p[0] for p in physical]),
        physical_dk=dk, frequencies_hz=data.frequencies_hz, mode_labels=np.array(data.labels), modal_b=data.modal_b,
        disp_names=np.array(list(data.disp_out)), disp_rows=np.array(list(data.disp_out.values())),
        rate_names=np.array(list(data.rate_out)), rate_rows=np.array(list(data.rate_out.values())),
        motion_names=np.array(list(data.motion_out), dtype=str),
        motion_rows=np.array(list(data.motion_out.values())).reshape(len(data.motion_out), len(data.labels)),
        structure_outputs=np.array(data.output_order))
    with tempfile.TemporaryDirectory(prefix="mace_fmu_") as tmp:
        tmp = Path(tmp)
        script = tmp / f"{name.lower()}_fmu.py"
        script.write_text(_entry_script(name, description))
        np.savez(tmp / "model.npz", **arrays)
        cached = {k for k in sys.modules if k.startswith(_CACHE_PREFIX)}
        path = FmuBuilder.build_FMU(script, dest=out / f"{name}.fmu", project_files=[tmp / "model.npz"],
                                    canGetAndSetFMUstate=True, canSerializeFMUstate=True)
        for key in {k for k in sys.modules if k.startswith(_CACHE_PREFIX)} - cached:
            del sys.modules[key]  # the builder ran the entry script here; loading the FMU rebuilds it
    _patch_model_description(Path(path), description=description, version=metadata.version("mace-fmu"))
    return Path(path)
