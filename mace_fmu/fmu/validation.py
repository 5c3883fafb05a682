"""An FMU's model description checked beyond what fmpy's validation checks: every start value within the
min and max its variable declares.

FMI 2.0 (section 2.2.7) and FMI 3.0 (section 2.4.7) require min <= start <= max, and a host checks it
when it instantiates the FMU (fmpy, FMI Check, OMSimulator refuse such an FMU), but
``fmpy.validation.validate_fmu`` does not: an FMU whose damping ratio started at 1.5 on a declared [0, 1]
passed it and failed in every host. :func:`validate_fmu` adds that check to fmpy's, and
:func:`mace_fmu.fmu.archive.check_fmu` refuses such an FMU before it is run.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from xml.etree import ElementTree as ET

#: FMI 3.0 numeric variable elements (FMI 2.0 puts the start in a <Real> or <Integer> child of <ScalarVariable>)
_FMI3_NUMERIC = ("Float32", "Float64", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64")
_FMI2_NUMERIC = ("Real", "Integer")


def _number(text: str | None) -> float | None:
    if text is None:
        return None
    try:
        return float(text)
    except ValueError:
        return math.nan


def start_value_problems(description: bytes | str) -> list[str]:
    """Each variable of a model description (FMI 2.0 or 3.0) whose start value lies outside its declared min/max.

    Parameters
    ----------
    description : bytes or str
        The text of a modelDescription.xml.

    Returns
    -------
    list of str
        One line per such variable: its name, start, and the declared range (empty: none).
    """
    root = ET.fromstring(description)
    problems = []
    variables = root.find("ModelVariables")
    for var in variables if variables is not None else ():
        typed = var
        if var.tag == "ScalarVariable":  # FMI 2.0: the type element holds start, min and max
            typed = next((child for child in var if child.tag in _FMI2_NUMERIC), None)
        elif var.tag not in _FMI3_NUMERIC:
            continue
        if typed is None:
            continue
        start, low, high = (_number(typed.get(a)) for a in ("start", "min", "max"))
        if start is None:
            continue
        below = low is not None and not start >= low  # a NaN anywhere fails as well
        above = high is not None and not start <= high
        if below or above or math.isnan(start):
            declared = f"[{typed.get('min', '-inf')}, {typed.get('max', 'inf')}]"
            problems.append(f'The start value {typed.get("start")} of variable "{var.get("name")}" lies outside its '
                            f"declared range {declared} (FMI: min <= start <= max).")
    return problems


def validate_fmu(path: str | os.PathLike) -> list[str]:
    """The problems of an FMU: fmpy's validation (schema, names, model structure, units) and every start value
    outside its declared min/max.

    Parameters
    ----------
    path : path
        An .fmu file or the folder of an unpacked one.

    Returns
    -------
    list of str
        The problems found (empty: none).
    """
    import zipfile

    from fmpy.validation import validate_fmu as fmpy_validate

    path = Path(path)
    problems = list(fmpy_validate(os.fspath(path)))
    try:
        if path.is_dir():
            description = (path / "modelDescription.xml").read_bytes()
        else:
            with zipfile.ZipFile(path) as archive:
                description = archive.read("modelDescription.xml")
        problems += start_value_problems(description)
    except (OSError, KeyError, zipfile.BadZipFile, ET.ParseError) as exc:
        if not problems:
            problems.append(f"the model description cannot be read ({exc})")
    return problems
