"""SSP 1.0 packages: FMUs, their wiring by signal name and their parameter values in one archive.

An ``.ssp`` file is a zip with ``SystemStructure.ssd`` (the system: components, their connectors,
the connections between them, parameter bindings) and the files it names under ``resources/``
(the FMUs and one SSV file of start values per component that has any). SSP 1.0 is the version
ecos, OMSimulator and ``fmpy.simulate_ssp`` read.

Importers differ (checked with ecospy 0.7 and fmpy 0.3.32): fmpy simulates FMI 2.0 FMUs only,
ignores the parameter bindings (pass the values as ``parameter_set=``) and fails on a system
without connections; ecos applies a parameter set only when it is named at initialisation and
rejects connections to the system's own boundary. So the packages written here wire components
to each other only, and every SSV binds to one component by its FMU variable names.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

from mace_fmu.errors import MaceError
from mace_fmu.ssp.ssv import SSC, units_element, values_ssv
from mace_fmu.util.atomic import atomic_zip

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
ET.register_namespace("ssd", SSD)

#: FMI causality -> SSP connector kind (the variables an SSP shows of a component)
_KINDS = {"input": "input", "output": "output", "parameter": "parameter"}


@dataclass(frozen=True)
class SspComponent:
    """One FMU in a system, with the start values an SSV binds to it (FMU variable names, SI units)."""

    name: str  #: instance name in the system, e.g. "plant"
    fmu: Path  #: the FMU file (copied into the archive's resources/)
    #: parameter name -> start value written to the component's SSV file (SI)
    start_values: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class SspConnection:
    """A signal from one component's output to another's input, by names."""

    from_component: str  #: component whose output is connected
    from_signal: str  #: that output's name
    to_component: str  #: component whose input it feeds
    to_signal: str  #: that input's name


@dataclass(frozen=True)
class _Variable:
    name: str
    causality: str
    unit: str | None
    minimum: float | None = None  #: declared min, None when the FMU declares none
    maximum: float | None = None


def _variables(fmu: Path) -> dict[str, _Variable]:
    import fmpy

    try:
        md = fmpy.read_model_description(str(fmu), validate=False)
    except Exception as exc:  # fmpy raises bare Exceptions for damaged archives
        raise MaceError(f"{fmu}: cannot read the FMU's model description: {exc}") from None
    if md.fmiVersion != "2.0":
        raise MaceError(f"{fmu}: FMI {md.fmiVersion}; SSP 1.0 importers (fmpy, ecos) take FMI 2.0 FMUs: export with "
                        "--fmi-version 2")
    out = {}
    for v in md.modelVariables:
        if v.causality in _KINDS and v.type == "Real":
            unit = v.declaredType.unit if v.unit is None and v.declaredType is not None else v.unit
            out[v.name] = _Variable(v.name, v.causality, unit, None if v.min is None else float(v.min),
                                    None if v.max is None else float(v.max))
    return out


def _checked(components: Sequence[SspComponent], connections: Sequence[SspConnection]) -> dict[str, dict]:
    """Each component's variables; MaceError naming the component, signal and what was expected."""
    names = [c.name for c in components]
    if not components:
        raise MaceError("SSP: no components")
    if len(set(names)) != len(names):
        raise MaceError(f"SSP: component names must be unique, got {names}")
    variables = {c.name: _variables(Path(c.fmu)) for c in components}
    for c in components:
        for key, value in c.start_values.items():
            v = variables[c.name].get(key)
            if v is None or v.causality != "parameter":
                raise MaceError(f"SSP component {c.name!r} ({Path(c.fmu).name}): no tunable parameter {key!r}")
            if (v.minimum is not None and value < v.minimum) or (v.maximum is not None and value > v.maximum):
                raise MaceError(f"SSP component {c.name!r} ({Path(c.fmu).name}): {key} = {value!r} is outside the "
                                f"declared range [{v.minimum}, {v.maximum}]")
    fed: dict[tuple[str, str], SspConnection] = {}
    for k in connections:
        for comp, sig, causality in ((k.from_component, k.from_signal, "output"),
                                     (k.to_component, k.to_signal, "input")):
            if comp not in variables:
                raise MaceError(f"SSP connection {k.from_component}.{k.from_signal} -> {k.to_component}.{k.to_signal}: "
                                f"no component {comp!r} (components: {', '.join(names)})")
            v = variables[comp].get(sig)
            if v is None or v.causality != causality:
                raise MaceError(f"SSP connection {k.from_component}.{k.from_signal} -> {k.to_component}.{k.to_signal}: "
                                f"component {comp!r} has no {causality} {sig!r}")
        if (k.to_component, k.to_signal) in fed:
            raise MaceError(f"SSP: input {k.to_component}.{k.to_signal} is connected twice")
        fed[(k.to_component, k.to_signal)] = k
    return variables


def system_structure(components: Sequence[SspComponent], connections: Sequence[SspConnection], *,
                     system_name: str, stop_time_s: float | None = None, step_size_s: float | None = None) -> str:
    """``SystemStructure.ssd`` text (SSP 1.0) of ``components`` wired by ``connections``.

    Every component lists its connected inputs, its outputs and its tunable parameters as
    connectors with their units (an unconnected input is left out, so that a host keeps the start
    value it was given: fmpy sets every declared input connector at each step); a component with
    start values binds ``resources/<name>.ssv``.

    Parameters
    ----------
    components : sequence of SspComponent
        The FMUs, their instance names and start values.
    connections : sequence of SspConnection
        Output -> input, by component and signal names.
    system_name : str
        The system's name.
    stop_time_s, step_size_s : float, optional
        The default experiment [s].

    Returns
    -------
    str
        The SSD XML text.

    Raises
    ------
    MaceError
        A connection naming a component or signal that does not exist.
    """
    variables = _checked(components, connections)
    root = ET.Element(f"{{{SSD}}}SystemStructureDescription", version="1.0", name=system_name,
                      generationTool="mace-fmu")
    system = ET.SubElement(root, f"{{{SSD}}}System", name=system_name)
    elements = ET.SubElement(system, f"{{{SSD}}}Elements")
    units: set[str] = set()
    for c in components:
        comp = ET.SubElement(elements, f"{{{SSD}}}Component", name=c.name,
                             type="application/x-fmu-sharedlibrary", source=f"resources/{c.name}.fmu")
        connectors = ET.SubElement(comp, f"{{{SSD}}}Connectors")
        fed = {k.to_signal for k in connections if k.to_component == c.name}
        for v in variables[c.name].values():
            if v.causality == "input" and v.name not in fed:
                continue  # fmpy sets every declared input each step (0 when unconnected): keep start values
            conn = ET.SubElement(connectors, f"{{{SSD}}}Connector", name=v.name, kind=_KINDS[v.causality])
            real = ET.SubElement(conn, f"{{{SSC}}}Real")
            if v.unit:
                real.set("unit", v.unit)
                units.add(v.unit)
        if c.start_values:
            bindings = ET.SubElement(comp, f"{{{SSD}}}ParameterBindings")
            ET.SubElement(bindings, f"{{{SSD}}}ParameterBinding", type="application/x-ssp-parameter-set",
                          source=f"resources/{c.name}.ssv")
    if connections:
        wires = ET.SubElement(system, f"{{{SSD}}}Connections")
        for k in connections:
            ET.SubElement(wires, f"{{{SSD}}}Connection", startElement=k.from_component, startConnector=k.from_signal,
                          endElement=k.to_component, endConnector=k.to_signal)
    if units:
        declared = units_element(units)
        declared.tag = f"{{{SSD}}}Units"
        root.append(declared)
    if stop_time_s is not None:
        ET.SubElement(root, f"{{{SSD}}}DefaultExperiment", startTime="0.0", stopTime=repr(float(stop_time_s)))
    del step_size_s  # SSP 1.0 has no step size in DefaultExperiment; the importer's own setting decides
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def component_ssv(component: SspComponent) -> str:
    """The SSV text binding ``component.start_values`` to its FMU (FMU variable names and units)."""
    variables = _variables(Path(component.fmu))
    return values_ssv(dict(component.start_values), name=f"{component.name} parameters",
                      units={k: variables[k].unit for k in component.start_values})


def write_ssp(path: str | os.PathLike, *, components: Sequence[SspComponent],
              connections: Sequence[SspConnection] = (), system_name: str = "system",
              stop_time_s: float | None = None) -> Path:
    """Write an SSP 1.0 archive of ``components`` wired by ``connections`` (atomically).

    Parameters
    ----------
    path
        The ``.ssp`` file to write.
    components
        The FMUs (FMI 2.0) with the start values to bind to each (FMU variable names, SI units).
    connections
        Output-to-input wiring by component and signal names.
    system_name
        Name of the system (and of the SSD).
    stop_time_s
        Default experiment stop time [s], if any.

    Returns
    -------
    Path
        ``path``. Nothing is written when a component, signal or parameter is unknown (MaceError).
    """
    ssd = system_structure(components, connections, system_name=system_name, stop_time_s=stop_time_s)
    ssvs = {c.name: component_ssv(c) for c in components if c.start_values}
    with atomic_zip(path) as z:
        z.writestr("SystemStructure.ssd", ssd)
        for c in components:
            z.write(c.fmu, f"resources/{c.name}.fmu")
            if c.name in ssvs:
                z.writestr(f"resources/{c.name}.ssv", ssvs[c.name])
    return Path(path)


def _schema_dir() -> Path:
    import fmpy

    return Path(fmpy.__file__).parent / "ssp" / "schema"


def schema_problems(text: str | bytes, *, kind: str) -> list[str]:
    """Problems of an SSD (``kind="ssd"``) or SSV (``kind="ssv"``) text against the SSP 1.0 schemas.

    The XSDs are the Modelica Association's, as fmpy ships them (BSD 2-clause, the licence text is in
    each file). An empty list means the file is valid.

    Parameters
    ----------
    text : str or bytes
        The XML document.
    kind : {"ssd", "ssv"}
        Which schema applies.

    Returns
    -------
    list of str
        One line per problem; empty when the document is valid.
    """
    from lxml import etree

    schema_file = {"ssd": "SystemStructureDescription.xsd", "ssv": "SystemStructureParameterValues.xsd"}[kind]
    schema = etree.XMLSchema(etree.parse(str(_schema_dir() / schema_file)))
    document = etree.fromstring(text.encode() if isinstance(text, str) else text)
    if schema.validate(document):
        return []
    return [f"line {e.line}: {e.message}" for e in schema.error_log]


def _default_step(fmu: Path) -> float | None:
    import fmpy

    md = fmpy.read_model_description(str(fmu), validate=False)
    step = md.defaultExperiment.stepSize if md.defaultExperiment is not None else None
    return float(step) if step is not None else None


def wiring_by_name(*, plant: SspComponent, controller: SspComponent) -> list[SspConnection]:
    """Connections of a controller to a plant by signal names: each controller input reads the plant
    output of that name, each controller output drives the plant input of that name.

    A MaceError names the controller's file and signal that has no counterpart, and a controller
    whose sample time (its default experiment's step) is not the plant's communication step.
    """
    pv, cv = _variables(Path(plant.fmu)), _variables(Path(controller.fmu))
    wires = []
    for v in cv.values():
        if v.causality == "input":
            if pv.get(v.name) is None or pv[v.name].causality != "output":
                raise MaceError(f"{Path(controller.fmu).name}: controller input {v.name!r} is not an output of the plant "
                                f"{Path(plant.fmu).name}")
            wires.append(SspConnection(plant.name, v.name, controller.name, v.name))
        elif v.causality == "output":
            if pv.get(v.name) is None or pv[v.name].causality != "input":
                raise MaceError(f"{Path(controller.fmu).name}: controller output {v.name!r} is not an input of the plant "
                                f"{Path(plant.fmu).name}")
            wires.append(SspConnection(controller.name, v.name, plant.name, v.name))
    plant_step, controller_step = _default_step(Path(plant.fmu)), _default_step(Path(controller.fmu))
    if plant_step is None or controller_step is None or abs(plant_step - controller_step) > 1e-12 * plant_step:
        raise MaceError(f"{Path(controller.fmu).name}: <DefaultExperiment stepSize> (the sample time) {controller_step} s "
                        f"is not the plant's communication step {plant_step} s ({Path(plant.fmu).name})")
    return wires
