"""Parameter sets as SSP 1.0 parameter value files (SSV, ``SystemStructureParameterValues``).

An SSV file is how the co-simulation world hands parameter values to a model (SSP 1.0, Modelica
Association; read by ecos, OMSimulator and fmpy). :func:`parameter_set_to_ssv` writes a
:class:`~mace_fmu.parameters.sets.ParameterSet` as one: every value as an ``ssv:Real`` with its SI
unit (declared in the file's ``ssv:Units`` as SSP requires), the provenance and any frequency
bounds as a ``ssc:Annotation`` of type :data:`ANNOTATION_TYPE`, so that
:func:`parameter_set_from_ssv` gives back the same set, value for value and bit for bit
(``float`` repr is exact), and the same bounds.

The names are the set's own. An SSV that binds values to an FMU's variables inside an SSP
package holds the FMU's names instead (see :mod:`mace_fmu.ssp.package`).
"""

from __future__ import annotations

import dataclasses
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from mace_fmu.errors import MaceError
from mace_fmu.parameters.frequency_bounds import FrequencyBound
from mace_fmu.parameters.sets import ParameterSet, Provenance, parameter_unit
from mace_fmu.util.atomic import write_text_atomic
from mace_fmu.util.textfile import read_text

SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
MACE = "https://mace-fmu.invalid/ssp-annotation/1"  #: namespace of our annotation's content
ANNOTATION_TYPE = "org.mace-fmu.parameter-set"

#: SI base-unit exponents (and factor) of every unit a parameter, input or output can have, as SSP's ssc:Unit
#: wants them.
#: V = kg m^2 s^-3 A^-1; a degree is pi/180 rad.
BASE_UNITS: dict[str, dict[str, str]] = {
    "1": {},
    "Pa": {"kg": "1", "m": "-1", "s": "-2"},
    "kg": {"kg": "1"},  # a concentrated mass, m_<mass>
    "N/m": {"kg": "1", "s": "-2"},
    "s": {"s": "1"},
    "Hz": {"s": "-1"},
    "V": {"kg": "1", "m": "2", "s": "-3", "A": "-1"},
    # the physical inputs and outputs of a modal test's instruments (structure files without gains)
    "N": {"kg": "1", "m": "1", "s": "-2"},
    "N m": {"kg": "1", "m": "2", "s": "-2"},
    "m": {"m": "1"},
    "m/s": {"m": "1", "s": "-1"},
    "m/s^2": {"m": "1", "s": "-2"},
    "rad": {"rad": "1"},
    "rad/s": {"rad": "1", "s": "-1"},
    "rad/s^2": {"rad": "1", "s": "-2"},
    "strain": {},
    "V/deg": {"kg": "1", "m": "2", "s": "-3", "A": "-1", "rad": "-1", "factor": repr(180.0 / math.pi)},
    "V/(deg/s)": {"kg": "1", "m": "2", "s": "-2", "A": "-1", "rad": "-1", "factor": repr(180.0 / math.pi)},
}

ET.register_namespace("ssv", SSV)
ET.register_namespace("ssc", SSC)
ET.register_namespace("mace", MACE)


@dataclass(frozen=True)
class SsvContent:
    """What an SSV file of ours holds: a parameter set and, for the 0-g nominal model, its bounds."""

    parameters: ParameterSet  #: the parameter values the SSV file holds
    frequency_bounds: tuple[FrequencyBound, ...] = ()  #: Table 5.3's, by mode; empty if none


def units_element(units: set[str]) -> ET.Element:
    """``ssv:Units``/``ssd:Units``-style element (ssc:TUnits) declaring ``units`` by SI base exponents."""
    element = ET.Element(f"{{{SSV}}}Units")
    for unit in sorted(units):
        if unit not in BASE_UNITS:
            raise MaceError(f"SSP unit {unit!r}: no base-unit definition (known: {', '.join(BASE_UNITS)})")
        u = ET.SubElement(element, f"{{{SSC}}}Unit", name=unit)
        ET.SubElement(u, f"{{{SSC}}}BaseUnit", BASE_UNITS[unit])
    return element


def values_ssv(values: Mapping[str, float], *, name: str, units: Mapping[str, str | None],
               annotation: ET.Element | None = None) -> str:
    """SSV text of ``values`` (name -> value) with each value's unit (None: no unit attribute)."""
    root = ET.Element(f"{{{SSV}}}ParameterSet", version="1.0", name=name)
    params = ET.SubElement(root, f"{{{SSV}}}Parameters")
    for key, value in values.items():
        p = ET.SubElement(params, f"{{{SSV}}}Parameter", name=key)
        attrs = {"value": repr(float(value))}
        if units.get(key):
            attrs["unit"] = str(units[key])
        ET.SubElement(p, f"{{{SSV}}}Real", attrs)
    used = {u for u in units.values() if u}
    if used:
        root.append(units_element(used))
    if annotation is not None:
        annotations = ET.SubElement(root, f"{{{SSV}}}Annotations")
        wrapper = ET.SubElement(annotations, f"{{{SSC}}}Annotation", type=ANNOTATION_TYPE)
        wrapper.append(annotation)
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def parameter_set_to_ssv(content: SsvContent | ParameterSet, *, name: str = "parameters") -> str:
    """SSV text of a parameter set (and its frequency bounds), readable back by :func:`parameter_set_from_ssv`.

    Parameters
    ----------
    content
        The set, or an :class:`SsvContent` with the set and Table 5.3-style frequency bounds.
    name
        The SSV's ``name`` attribute.

    Returns
    -------
    str
        The XML text (SSP 1.0, UTF-8 declaration included).
    """
    content = content if isinstance(content, SsvContent) else SsvContent(parameters=content)
    ps = content.parameters
    extra = ET.Element(f"{{{MACE}}}ParameterSet")
    if ps.provenance is not None:
        prov = {f.name: getattr(ps.provenance, f.name) for f in dataclasses.fields(Provenance)}
        ET.SubElement(extra, f"{{{MACE}}}Provenance",
                      {k: (repr(float(v)) if isinstance(v, float) else str(v)) for k, v in prov.items()
                       if v is not None and v != ""})
    if content.frequency_bounds:
        bounds = ET.SubElement(extra, f"{{{MACE}}}FrequencyBounds")
        for b in sorted(content.frequency_bounds, key=lambda b: b.mode):
            ET.SubElement(bounds, f"{{{MACE}}}Mode", number=str(int(b.mode)), label=b.mode_label,
                          boundPercent=repr(float(b.bound_percent)))
    return values_ssv(dict(ps.values), name=name, units={n: parameter_unit(n) for n in ps.values},
                      annotation=extra if len(extra) else None)


def _where(source: str, element: ET.Element | None = None, detail: str = "") -> str:
    text = source
    if element is not None:
        tag = element.tag.split("}")[-1]
        text += f": <{tag}{' name=' + repr(element.get('name')) if element.get('name') is not None else ''}>"
    return text + (f": {detail}" if detail else "")


def read_ssv_values(text: str, *, source: str) -> tuple[dict[str, float], dict[str, str | None], ET.Element]:
    """(name -> value, name -> unit, root) of an SSV 1.0 file's Real parameters; MaceError naming the element."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise MaceError(f"{source}: not an XML file: {exc}") from None
    if root.tag != f"{{{SSV}}}ParameterSet":
        raise MaceError(_where(source, root, f"expected an SSP 1.0 ssv:ParameterSet ({SSV})"))
    if not str(root.get("version", "")).startswith("1."):
        raise MaceError(_where(source, root, f"version {root.get('version')!r}; this reader takes SSV 1.x"))
    params = root.find(f"{{{SSV}}}Parameters")
    if params is None:
        raise MaceError(_where(source, root, "no ssv:Parameters element"))
    declared = {u.get("name") for u in root.iterfind(f"{{{SSV}}}Units/{{{SSC}}}Unit")}
    values: dict[str, float] = {}
    units: dict[str, str | None] = {}
    for p in params.iterfind(f"{{{SSV}}}Parameter"):
        key = p.get("name")
        if not key:
            raise MaceError(_where(source, p, "a Parameter without a name"))
        if key in values:
            raise MaceError(_where(source, p, "parameter given twice"))
        real = p.find(f"{{{SSV}}}Real")
        if real is None:
            kinds = [c.tag.split("}")[-1] for c in p]
            raise MaceError(_where(source, p, f"expected an ssv:Real value, got {kinds or 'none'}"))
        try:
            value = float(real.get("value", ""))
        except ValueError:
            raise MaceError(_where(source, p, f"value {real.get('value')!r} is not a number")) from None
        if not math.isfinite(value):
            raise MaceError(_where(source, p, f"value {value!r} is not finite"))
        unit = real.get("unit")
        if unit is not None and unit not in declared:
            raise MaceError(_where(source, p, f"unit {unit!r} is not declared in the file's ssv:Units"))
        values[key], units[key] = value, unit
    return values, units, root


def parameter_set_from_ssv(text: str, *, source: str = "<string>") -> SsvContent:
    """The parameter set (and frequency bounds) of an SSV written by :func:`parameter_set_to_ssv`.

    Any SSV 1.0 file of Real parameters with our parameter names is read; a unit that is not the
    parameter's SI unit is refused (no silent conversion), naming the file and the element.

    Parameters
    ----------
    text : str
        The SSV (System Structure Parameter Values, SSP 1.0) document.
    source : str
        What error messages call it.

    Returns
    -------
    SsvContent
        The parameter set (with provenance) and, for the 0-g nominal model, its frequency bounds.

    Raises
    ------
    MaceError
        Not SSV 1.0, an unknown parameter, a non-Real value or a unit that is not the parameter's SI
        unit: the message names ``source`` and the element.
    """
    values, units, root = read_ssv_values(text, source=source)
    for key, unit in units.items():
        try:
            expected = parameter_unit(key)
        except MaceError as exc:
            raise MaceError(f"{source}: <Parameter name={key!r}>: {exc}") from None
        if unit is not None and unit != expected:
            raise MaceError(f"{source}: <Parameter name={key!r}>: unit {unit!r}, expected {expected!r}")
    provenance, bounds = None, []
    for ann in root.iterfind(f"{{{SSV}}}Annotations/{{{SSC}}}Annotation"):
        if ann.get("type") != ANNOTATION_TYPE:
            continue
        prov = ann.find(f"{{{MACE}}}ParameterSet/{{{MACE}}}Provenance")
        if prov is not None:
            kinds = {f.name: f.type for f in dataclasses.fields(Provenance)}
            unknown = set(prov.attrib) - set(kinds)
            if unknown:
                raise MaceError(f"{source}: provenance annotation: unknown attribute(s) {sorted(unknown)}")
            given: dict[str, Any] = {k: (float(v) if "float" in str(kinds[k]) else v) for k, v in prov.attrib.items()}
            provenance = Provenance(**given)
        for mode in ann.iterfind(f"{{{MACE}}}ParameterSet/{{{MACE}}}FrequencyBounds/{{{MACE}}}Mode"):
            try:
                bounds.append(FrequencyBound(mode=int(mode.get("number", "")), mode_label=mode.get("label", ""),
                                             bound_percent=float(mode.get("boundPercent", ""))))
            except ValueError:
                raise MaceError(f"{source}: frequency bound {mode.attrib}: expected number=<mode> label=<mode label> "
                                "boundPercent=<percent>") from None
    try:
        ps = ParameterSet(values, provenance)
    except MaceError as exc:
        raise MaceError(f"{source}: {exc}") from None
    return SsvContent(parameters=ps, frequency_bounds=tuple(bounds))


def write_parameter_ssv(content: SsvContent | ParameterSet, path: str | Path, *, name: str | None = None) -> Path:
    """Write :func:`parameter_set_to_ssv` atomically to ``path`` (its stem names the set by default).

    Parameters
    ----------
    content : SsvContent or ParameterSet
        The set (and bounds) to write.
    path : path
        The .ssv file.
    name : str, optional
        The set's name in the file (default: the file's stem).

    Returns
    -------
    Path
        ``path``.
    """
    return write_text_atomic(path, parameter_set_to_ssv(content, name=name or Path(path).stem))


def read_parameter_ssv(path: str | Path) -> SsvContent:
    """Read an SSV file written by :func:`write_parameter_ssv` (or by another tool with our names).

    Parameters
    ----------
    path : path
        The .ssv file.

    Returns
    -------
    SsvContent
        As :func:`parameter_set_from_ssv`.
    """
    return parameter_set_from_ssv(read_text(path, what="SSV parameter"), source=str(path))
