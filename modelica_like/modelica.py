"""Modelica source text for a compiled LTI model (one ``Modelica.Blocks.Continuous.StateSpace``).

The model has a ``RealInput``/``RealOutput`` connector per exposed signal (names sanitised to
Modelica identifiers, the original name kept as description string) wired to one StateSpace
component that holds the compiled A, B, C, D. Numbers are written with ``repr`` so they read
back bit-for-bit.
"""

from __future__ import annotations

import re
import textwrap
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from .errors import ModelError

__all__ = ["modelica_identifier", "modelica_source"]

# Modelica 3.6 keywords (section 2.3.3): none of them may name a component.
_KEYWORDS = frozenset("""
    algorithm and annotation block break class connect connector constant constrainedby der
    discrete each else elseif elsewhen encapsulated end enumeration equation expandable extends
    external false final flow for function if import impure in initial inner input loop model
    not operator or outer output package parameter partial protected public pure record
    redeclare replaceable return stream then true type when while within""".split())


def modelica_identifier(name: str) -> str:
    """A valid Modelica identifier resembling ``name`` (``"y[gyro x]"`` -> ``"y_gyro_x"``).

    Runs of other characters become ``_``; a name not starting with a letter gets ``id_`` in
    front; keywords get a trailing ``_`` (``"end"`` -> ``"end_"``).
    """
    ident = re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_") or "signal"
    if not ident[0].isalpha():  # a letter first: leading underscores are best left to tools
        ident = "id_" + ident
    return ident + "_" if ident in _KEYWORDS else ident


def _unique(names: Sequence[str], taken: set[str]) -> list[str]:
    """Sanitise names, unique (``x``, ``x_2``, ...) against ``taken`` and each other."""
    out = []
    for name in names:
        base = modelica_identifier(name)
        ident, k = base, 2
        while ident in taken:
            ident, k = f"{base}_{k}", k + 1
        taken.add(ident)
        out.append(ident)
    return out


def _string(text: str) -> str:
    """A Modelica string literal."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _number(x: float) -> str:
    if not np.isfinite(x):
        raise ModelError(f"cannot write the non-finite number {x!r} to Modelica")
    return repr(float(x))  # shortest round-trip form; '1e-05' is a valid Modelica literal


def _matrix(M: NDArray[np.float64], indent: str) -> str:
    """``[a, b; c, d]`` with one row per line, or ``fill(0.0, r, c)`` for an empty matrix."""
    rows, cols = M.shape
    if rows == 0 or cols == 0:
        return f"fill(0.0, {rows}, {cols})"
    body = (";\n" + indent).join(", ".join(_number(x) for x in row) for row in M)
    return f"[{body}]"


def modelica_source(A: NDArray[np.float64], B: NDArray[np.float64], C: NDArray[np.float64],
                    D: NDArray[np.float64], *, model_name: str, inputs: Sequence[str],
                    outputs: Sequence[str], states: Sequence[str], description: str = "") -> str:
    """Modelica text of ``model model_name`` realising ``(A, B, C, D)`` between named signals.

    The StateSpace component starts at rest (``initType = InitialState``, ``x_start`` = 0).
    """
    model = modelica_identifier(model_name)
    taken = {model}
    in_ids, out_ids = _unique(inputs, taken), _unique(outputs, taken)
    comp = _unique(["lti"], taken)[0]
    lines = [f"model {model}" + (f" {_string(description)}" if description else "")]
    lines += [f"  Modelica.Blocks.Interfaces.RealInput {i} {_string(n)};"
              for i, n in zip(in_ids, inputs)]
    lines += [f"  Modelica.Blocks.Interfaces.RealOutput {i} {_string(n)};"
              for i, n in zip(out_ids, outputs)]
    order = textwrap.wrap(", ".join(states) or "(no states)", 96, break_on_hyphens=False)
    lines += [f"  // State order of {comp}.x:"] + [f"  //   {line}" for line in order]
    lines.append(f"  Modelica.Blocks.Continuous.StateSpace {comp}(")
    for label, M in (("A", A), ("B", B), ("C", C), ("D", D)):
        head = f"    {label} = "
        lines.append(head + _matrix(np.asarray(M, dtype=float), " " * (len(head) + 1)) + ",")
    lines.append("    initType = Modelica.Blocks.Types.Init.InitialState)"
                 f" {_string(f'nx={len(states)}, nu={len(inputs)}, ny={len(outputs)}')};")
    lines.append("equation")
    lines += [f"  connect({i}, {comp}.u[{k}]);" for k, i in enumerate(in_ids, 1)]
    lines += [f"  connect({comp}.y[{k}], {i});" for k, i in enumerate(out_ids, 1)]
    lines.append(f"end {model};")
    return "\n".join(lines) + "\n"
