"""Package a volts-volts model as an FMI 2.0 co-simulation FMU (pythonfmu), self-contained.

The FMU holds its matrices (``resources/model.npz``) and a slave script that needs only numpy,
scipy and pythonfmu (see :mod:`mace_fmu.fmu.slave`). pythonfmu cannot declare units, a default
experiment or a version, so those are written into the model description after the build.
"""

from __future__ import annotations

import re
import tempfile
import zipfile
from importlib import metadata
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np
from pythonfmu.builder import FmuBuilder

from mace_fmu.iomodel.volts import VoltsModel

SLAVE_SOURCE = Path(__file__).with_name("slave.py")
DEFAULT_EXPERIMENT = {"startTime": "0.0", "stopTime": "10.0", "stepSize": "0.002"}


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
    outs = [f"{inst.sensor(n).description} [V], {inst.sensor(n).gain} V per physical unit"
            for n in model.system.output_labels]
    return ins, outs


def _patch_model_description(fmu: Path, *, description: str, version: str) -> None:
    """Add unit "V", a default experiment, initial unknowns, description and version to modelDescription.xml."""
    with zipfile.ZipFile(fmu) as z:
        entries = {n: z.read(n) for n in z.namelist()}
    root = ET.fromstring(entries["modelDescription.xml"])
    root.set("description", description)
    root.set("version", version)
    root.set("author", "mace-fmu")
    root.set("generationTool", f"mace-fmu {version} ({root.get('generationTool', 'PythonFMU')})")
    units = ET.Element("UnitDefinitions")
    ET.SubElement(units, "Unit", name="V")
    root.insert(list(root).index(root.find("CoSimulation")) + 1, units)
    for old in root.findall("DefaultExperiment"):
        root.remove(old)
    position = list(root).index(root.find("ModelVariables"))
    root.insert(position, ET.Element("DefaultExperiment", DEFAULT_EXPERIMENT))
    for real in root.iter("Real"):
        real.set("unit", "V")
    # FMI 2.0: outputs with calculated initial values are initial unknowns (pythonfmu omits them)
    structure = root.find("ModelStructure")
    outputs = structure.find("Outputs")
    if outputs is not None and structure.find("InitialUnknowns") is None:
        initial = ET.Element("InitialUnknowns")
        for unknown in outputs.findall("Unknown"):
            ET.SubElement(initial, "Unknown", index=unknown.get("index"))
        structure.insert(list(structure).index(outputs) + 1, initial)
    entries["modelDescription.xml"] = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    with zipfile.ZipFile(fmu, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in entries.items():
            z.writestr(name, data)


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
    with tempfile.TemporaryDirectory(prefix="mace_fmu_") as tmp:
        tmp = Path(tmp)
        script = tmp / f"{name.lower()}_slave.py"
        source = SLAVE_SOURCE.read_text().replace("class MaceSlave(Fmi2Slave):", f"class {name}(Fmi2Slave):")
        script.write_text(source.replace('description = "MACE volts-volts model"', f"description = {description!r}"))
        np.savez(tmp / "model.npz", A=sys_.A, B=sys_.B, C=sys_.C, D=sys_.D, inputs=np.array(sys_.input_labels),
                 outputs=np.array(sys_.output_labels), input_descriptions=np.array(ins),
                 output_descriptions=np.array(outs))
        path = FmuBuilder.build_FMU(script, dest=out / f"{name}.fmu", project_files=[tmp / "model.npz"],
                                    canGetAndSetFMUstate=True, canSerializeFMUstate=True)
    version = metadata.version("mace-fmu")
    _patch_model_description(Path(path), description=description, version=version)
    return Path(path)
