"""Model descriptions of native FMUs: FMI 2.0 (co-simulation and model exchange) and FMI 3.0 (co-simulation).

Value references follow the runtime's order (mace_model.h): inputs, outputs, parameters,
calculated frequencies, then (FMI 2, for model exchange) the continuous states and their
derivatives. Names, units and descriptions are those of the pythonfmu FMU.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal
from xml.etree import ElementTree as ET

import numpy as np

from mace_fmu.fmu.variables import DEFAULT_EXPERIMENT, variable_unit
from mace_fmu.parameters.kinds import frequency_output_name

if TYPE_CHECKING:  # the record imports this module's JacobianPattern
    from mace_fmu.fmu.parametric import ParametricModel

LOG_CATEGORIES = (("logStatusError", "errors (always logged)"), ("logEvents", "debug information"))

#: the largest input magnitude [V] the runtime takes (mace_instance.c, MACE_INPUT_LIMIT_V): a million volts is no
#: signal, and 1e308 overflowed model exchange's derivatives to NaN
INPUT_LIMIT_V = 1e6


#: what a variable is to the FMU's importer (FMI 2.0 2.2.7, FMI 3.0 2.4.7; FMPy's ModelVariable.causality)
Causality = Literal["parameter", "calculatedParameter", "structuralParameter", "input", "output", "local",
                    "independent"]
#: when a variable's value can change (FMPy's ModelVariable.variability)
Variability = Literal["constant", "fixed", "tunable", "discrete", "continuous"]
#: how a variable's start value is meant (FMPy's ModelVariable.initial)
Initial = Literal["exact", "approx", "calculated"]


@dataclass(frozen=True)
class FmuVariable:
    """One scalar Real/Float64 variable of a native FMU."""

    name: str  #: variable name in the model description
    value_reference: int  #: FMI value reference
    causality: Causality  #: input, output, parameter, calculatedParameter, local or independent
    variability: Variability  #: continuous or fixed
    description: str  #: what it is, with its unit
    initial: Initial | None = None  #: FMI initial attribute (None: not given)
    start: float | None = None  #: start value (SI; None for outputs)
    unit: str | None = None  #: unit (None: dimensionless)
    minimum: float | None = None  #: declared minimum (None: none)
    maximum: float | None = None  #: declared maximum (None: none)
    derivative_of: int | None = None  #: 1-based index (FMI 2) of the state this is the derivative of


def fmu_variables(model: ParametricModel) -> list[FmuVariable]:
    """All variables in value-reference order, from what the model's FMUs carry.

    Parameters
    ----------
    model : ParametricModel
        The record the FMU writers serialise (:func:`~mace_fmu.fmu.parametric.parametric_model`).

    Returns
    -------
    list of FmuVariable
        Inputs, outputs, parameters (with units and declared ranges), frequencies, states, derivatives and
        time, in value-reference order.
    """
    out: list[FmuVariable] = []
    units = model.signal_units

    def add(*, name: str, causality: Causality, variability: Variability, description: str,
            initial: Initial | None = None, start: float | None = None, minimum: float | None = None,
            maximum: float | None = None, derivative_of: int | None = None) -> None:
        out.append(FmuVariable(name=name, value_reference=len(out), causality=causality, variability=variability,
                               description=description, initial=initial, start=start,
                               unit=variable_unit(name, causality, signal_units=units), minimum=minimum,
                               maximum=maximum, derivative_of=derivative_of))

    for signal in model.inputs:
        add(name=signal.name, causality="input", variability="continuous", description=signal.description,
            start=0.0, minimum=-INPUT_LIMIT_V, maximum=INPUT_LIMIT_V)
    for signal in model.outputs:
        add(name=signal.name, causality="output", variability="continuous", description=signal.description)
    for p in model.parameters:
        add(name=p.name, causality="parameter", variability="fixed", description=p.description, initial="exact",
            start=p.nominal, minimum=p.minimum if np.isfinite(p.minimum) else None,
            maximum=p.maximum if np.isfinite(p.maximum) else None)
    for k, label in enumerate(model.mode_labels):
        add(name=frequency_output_name(k + 1), causality="calculatedParameter", variability="fixed",
            initial="calculated", description=f"natural frequency [Hz] of mode {k + 1} ({label}) after reanalysis and frequency scale (the "
                        "mode it continues into, not the k-th lowest)")
    first_state = len(out)
    for name in model.state_names:
        add(name=name, causality="local", variability="continuous", initial="calculated",
            description="continuous state (model exchange)")
    for k, name in enumerate(model.state_names):
        add(name=f"der({name})", causality="local", variability="continuous", initial="calculated",
            description=f"time derivative of {name}", derivative_of=first_state + k + 1)
    out.append(FmuVariable(name="time", value_reference=len(out), causality="independent", variability="continuous",
                           description="simulation time", unit="s"))
    return out


def _number(value: float) -> str:
    return repr(float(value))


def _root(fmi_version: str, *, model_name: str, token_attribute: str, token: str, description: str,
          version: str) -> ET.Element:
    return ET.Element("fmiModelDescription", {
        "fmiVersion": fmi_version, "modelName": model_name, token_attribute: token, "description": description,
        "author": "mace-fmu", "version": version, "generationTool": f"mace-fmu {version} (native runtime)",
        "variableNamingConvention": "flat"})


def _common_elements(root: ET.Element, variables: Sequence[FmuVariable], step_size_s: float | None) -> None:
    units = ET.SubElement(root, "UnitDefinitions")
    for unit in sorted({v.unit for v in variables if v.unit}):
        ET.SubElement(units, "Unit", name=unit)
    categories = ET.SubElement(root, "LogCategories")
    for name, text in LOG_CATEGORIES:
        ET.SubElement(categories, "Category", name=name, description=text)
    experiment = dict(DEFAULT_EXPERIMENT)
    if step_size_s is not None:
        experiment["stepSize"] = _number(step_size_s)
    ET.SubElement(root, "DefaultExperiment", experiment)


def _attributes(v: FmuVariable) -> tuple[dict[str, str], dict[str, str]]:
    """(variable attributes, attributes of its type element: unit, start, min, max, derivative)."""
    attrs = {"name": v.name, "valueReference": str(v.value_reference), "description": v.description,
             "causality": v.causality, "variability": v.variability}
    if v.initial and not (v.causality == "parameter" and v.initial == "exact"):
        attrs["initial"] = v.initial
    values = {"start": v.start, "min": v.minimum, "max": v.maximum}
    typed = {"unit": v.unit} if v.unit else {}
    typed.update({k: _number(x) for k, x in values.items() if x is not None})
    if v.derivative_of is not None:
        typed["derivative"] = str(v.derivative_of)
    return attrs, typed


@dataclass(frozen=True)
class JacobianPattern:
    """Where the Jacobian blocks of x' = A x + B u, y = C x + D u can be nonzero (boolean arrays)."""

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    d: np.ndarray


def _document(root: ET.Element) -> bytes:
    """The XML document of ``root``, indented, UTF-8 with its declaration."""
    ET.indent(root)
    text: bytes = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    return text


def _dependencies(element: ET.Element, states: Sequence[int], inputs: Sequence[int], on_states: np.ndarray,
                  on_inputs: np.ndarray) -> None:
    """The dependencies of one unknown (FMI 2.0.x section 2.2.8): the states and inputs it depends on,
    each with the factor's kind "fixed" (a linear model: a constant set at initialisation)."""
    known = sorted([states[j] for j in np.flatnonzero(on_states).tolist()]
                   + [inputs[j] for j in np.flatnonzero(on_inputs).tolist()])
    element.set("dependencies", " ".join(map(str, known)))
    element.set("dependenciesKind", " ".join(["fixed"] * len(known)))


def fmi2_model_description(variables: Sequence[FmuVariable], *, model_identifier: str, guid: str, description: str,
                           version: str, source_files: Sequence[str], model_exchange: bool = True,
                           step_size_s: float | None = None, jacobian: JacobianPattern | None = None,
                           state_order: Sequence[int] | None = None) -> bytes:
    """modelDescription.xml of an FMI 2.0 FMU with co-simulation and (``model_exchange``) model exchange;
    ``step_size_s``: the default experiment's step [s] (default: the plants' 2 ms); ``jacobian``: the
    sparsity of the linear model, declared as the dependencies of the derivatives and outputs, with
    directional derivatives provided in model exchange (the runtime computes them exactly);
    ``state_order``: the model-exchange state vector (position i: state ``state_order[i]`` of the
    variables' order), which the order of ``ModelStructure/Derivatives`` defines (FMI 2.0.x 2.2.8)."""
    variables = [v for v in variables if v.causality != "independent"]  # FMI 2: time is implicit
    root = _root("2.0", model_name=model_identifier, token_attribute="guid", token=guid, description=description,
                 version=version)
    root.set("numberOfEventIndicators", "0")
    capabilities = {"modelIdentifier": model_identifier, "canGetAndSetFMUstate": "true",
                    "canSerializeFMUstate": "true", "canNotUseMemoryManagementFunctions": "false"}
    interfaces = (("ModelExchange", {"completedIntegratorStepNotNeeded": "true"}),
                  ("CoSimulation", {"canHandleVariableCommunicationStepSize": "true", "canInterpolateInputs": "false",
                                    "maxOutputDerivativeOrder": "0"}))
    for tag, extra in interfaces:
        if tag == "ModelExchange" and not model_exchange:
            continue
        if tag == "ModelExchange" and jacobian is not None:
            extra = {**extra, "providesDirectionalDerivative": "true"}
        element = ET.SubElement(root, tag, {**capabilities, **extra})
        sources = ET.SubElement(element, "SourceFiles")
        for name in source_files:
            ET.SubElement(sources, "File", name=name)
    _common_elements(root, variables, step_size_s)
    model_variables = ET.SubElement(root, "ModelVariables")
    for v in variables:
        attrs, typed = _attributes(v)
        scalar = ET.SubElement(model_variables, "ScalarVariable", attrs)
        ET.SubElement(scalar, "Real", typed)
    structure = ET.SubElement(root, "ModelStructure")
    index = {v.value_reference: k + 1 for k, v in enumerate(variables)}
    states = [v.derivative_of for v in variables if v.derivative_of is not None]  # 1-based, in state order
    inputs = [index[v.value_reference] for v in variables if v.causality == "input"]
    outputs = ET.SubElement(structure, "Outputs")
    for k, v in enumerate(v for v in variables if v.causality == "output"):
        unknown = ET.SubElement(outputs, "Unknown", index=str(index[v.value_reference]))
        if jacobian is not None:
            _dependencies(unknown, states, inputs, jacobian.c[k], jacobian.d[k])
    if states:  # the schema refuses an empty <Derivatives>
        derivatives = ET.SubElement(structure, "Derivatives")
        der = [v for v in variables if v.derivative_of is not None]
        for k in (range(len(der)) if state_order is None else state_order):
            unknown = ET.SubElement(derivatives, "Unknown", index=str(index[der[k].value_reference]))
            if jacobian is not None:
                _dependencies(unknown, states, inputs, jacobian.a[k], jacobian.b[k])
    initial = ET.SubElement(structure, "InitialUnknowns")
    for v in variables:
        if v.causality in ("output", "calculatedParameter", "local"):
            ET.SubElement(initial, "Unknown", index=str(index[v.value_reference]))
    return _document(root)


def fmi3_model_description(variables: Sequence[FmuVariable], *, model_identifier: str, token: str, description: str,
                           version: str, step_size_s: float | None = None) -> bytes:
    """modelDescription.xml of an FMI 3.0 co-simulation FMU (no continuous states exposed);
    ``step_size_s``: the default experiment's step [s] (default: the plants' 2 ms)."""
    root = _root("3.0", model_name=model_identifier, token_attribute="instantiationToken", token=token,
                 description=description, version=version)
    ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": model_identifier, "canGetAndSetFMUState": "true", "canSerializeFMUState": "true",
        "canHandleVariableCommunicationStepSize": "true", "providesIntermediateUpdate": "false",
        "canReturnEarlyAfterIntermediateUpdate": "false", "hasEventMode": "false", "maxOutputDerivativeOrder": "0"})
    scalars = [v for v in variables if v.causality != "local"]  # FMI 3: time (independent) included
    _common_elements(root, scalars, step_size_s)
    model_variables = ET.SubElement(root, "ModelVariables")
    for v in scalars:
        attrs, typed = _attributes(v)
        ET.SubElement(model_variables, "Float64", {**attrs, **typed})
    structure = ET.SubElement(root, "ModelStructure")
    for v in scalars:
        if v.causality == "output":
            ET.SubElement(structure, "Output", valueReference=str(v.value_reference))
    for v in scalars:
        if v.causality in ("output", "calculatedParameter"):
            ET.SubElement(structure, "InitialUnknown", valueReference=str(v.value_reference))
    return _document(root)


def fmi3_build_description(*, model_identifier: str, source_files: Sequence[str]) -> bytes:
    """sources/buildDescription.xml of an FMI 3.0 FMU: how to compile its C sources."""
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    configuration = ET.SubElement(root, "BuildConfiguration", modelIdentifier=model_identifier)
    files = ET.SubElement(configuration, "SourceFileSet", language="C99")
    for name in source_files:
        ET.SubElement(files, "SourceFile", name=name)
    return _document(root)
