"""The uncertainty box: FMU parameters whose declared min/max bound them, and the points a sweep visits.

The box is read from the FMU's model description (fmpy): every real parameter whose name matches
``pattern`` (default the 0-g FMU's ``frequency_scale_mode_<k>``) and whose declared minimum and
maximum are narrower, on both sides, than the range of every parameter of its kind (the validity
limits of mace_fmu.parameters.kinds): a bound given at export. ``ranges`` names the range of other parameters explicitly (an
FMU without declared bounds, e.g. ``damping_mode_<k>`` over a chosen interval).
"""

from __future__ import annotations

import fnmatch
import itertools
import os
from dataclasses import dataclass
from typing import Literal, Mapping

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.parameters.kinds import FREQUENCY_SCALE, kind_of_fmu_name, mode_number

PointKind = Literal["nominal", "screen", "corner", "sample"]
#: The 0-g FMU's modal frequency scales; their min/max are Table 5.3's bounds.
DEFAULT_PATTERN = "frequency_scale_mode_*"


@dataclass(frozen=True)
class ParameterBox:
    """Named parameters, each with its nominal value and its interval [low, high]."""

    names: tuple[str, ...]  #: the parameters spanning the box
    nominal: np.ndarray  #: (n,) the FMU's start values
    low: np.ndarray  #: (n,)
    high: np.ndarray  #: (n,)
    descriptions: tuple[str, ...] = ()  #: the model description's text of each

    def label(self, index: int) -> str:
        """Short name of parameter ``index``: the mode label in its description's parentheses, else its name."""
        text = self.descriptions[index] if index < len(self.descriptions) else ""
        start, end = text.find("("), text.find(")")
        return text[start + 1:end] if 0 <= start < end else self.names[index]


@dataclass(frozen=True)
class SweepPoint:
    """One set of parameter values to run, and why it is in the sweep."""

    kind: PointKind
    values: tuple[float, ...]  #: in the order of ParameterBox.names
    note: str = ""  #: screen: "<name> low|high"; corner: the critical parameters' signs


def short_name(name: str) -> str:
    """"mode 14" for frequency_scale_mode_14, else the name itself (for notes and summaries)."""
    return f"mode {mode_number(name)}" if kind_of_fmu_name(name) is FREQUENCY_SCALE else name


def _is_uncertainty_bound(name: str, start: float, low: float, high: float) -> bool:
    """True when a declared range is narrower, on both sides, than the range every parameter of its kind
    has (mace_fmu.parameters.kinds): then it was given as a bound (Table 5.3's), not as a validity limit."""
    kind = kind_of_fmu_name(name)
    own_low, own_high = kind.range_for(start) if kind is not None else (-np.inf, np.inf)
    return bool(np.isfinite(low) and np.isfinite(high) and own_low < low < high < own_high)


def read_box(fmu: str | os.PathLike, *, pattern: str = DEFAULT_PATTERN,
             ranges: Mapping[str, tuple[float, float]] | None = None) -> ParameterBox:
    """The box of ``fmu`` (an .fmu file or its extracted folder): see the module docstring.

    Parameters
    ----------
    fmu : path
        An .fmu file or its extracted folder.
    pattern : str
        Which parameters span the box (fnmatch of their names).
    ranges : mapping, optional
        Name -> (low, high) replacing the declared min/max.

    Returns
    -------
    ParameterBox
        Names, nominal values and [low, high] of each parameter.

    Raises
    ------
    MaceError
        No parameter matches, or a range outside what the FMU declares.
    """
    import fmpy

    md = fmpy.read_model_description(os.fspath(fmu))
    ranges = dict(ranges or {})
    real = {v.name: v for v in md.modelVariables if v.causality == "parameter" and v.type == "Real"}
    unknown = [n for n in ranges if n not in real]
    if unknown:
        raise MaceError(f"{os.fspath(fmu)}: no real parameter(s) {', '.join(unknown)} to give a range")
    names, nominal, low, high, texts = [], [], [], [], []
    for name, var in real.items():
        start = float(var.start)
        if name in ranges:
            lo, hi = (float(x) for x in ranges[name])
            declared = (float(var.min) if var.min is not None else -np.inf, float(var.max) if var.max is not None else np.inf)
            if lo < declared[0] or hi > declared[1]:
                raise MaceError(f"{os.fspath(fmu)}: parameter {name}: range [{lo:g}, {hi:g}] leaves its declared "
                                f"[{declared[0]:g}, {declared[1]:g}], which the FMU enforces")
        elif fnmatch.fnmatchcase(name, pattern) and var.min is not None and var.max is not None:
            lo, hi = float(var.min), float(var.max)
            if not _is_uncertainty_bound(name, start, lo, hi):
                continue
        else:
            continue
        if not (np.isfinite(lo) and np.isfinite(hi) and lo <= start <= hi and lo < hi):
            raise MaceError(f"{os.fspath(fmu)}: parameter {name}: range [{lo:g}, {hi:g}] must be finite, "
                            f"increasing and hold its start value {start:g}")
        names.append(name)
        nominal.append(start)
        low.append(lo)
        high.append(hi)
        texts.append(var.description or "")
    if not names:
        raise MaceError(f"{os.fspath(fmu)} has no real parameter matching {pattern!r} with finite, distinct min and "
                        "max, and none was given a range: export the 0-g FMU with its frequency bounds")
    return ParameterBox(names=tuple(names), nominal=np.array(nominal), low=np.array(low), high=np.array(high),
                        descriptions=tuple(texts))


def nominal_point(box: ParameterBox) -> SweepPoint:
    """Every parameter at its start value."""
    return SweepPoint(kind="nominal", values=tuple(box.nominal.tolist()))


def screening_points(box: ParameterBox) -> list[SweepPoint]:
    """One parameter at a time at its low and at its high end, the others nominal (2 n points)."""
    points = []
    for i, name in enumerate(box.names):
        for end, value in (("low", box.low[i]), ("high", box.high[i])):
            v = box.nominal.copy()
            v[i] = value
            points.append(SweepPoint(kind="screen", values=tuple(v.tolist()), note=f"{short_name(name)} {end}"))
    return points


def corner_points(box: ParameterBox, critical: list[int]) -> list[SweepPoint]:
    """All 2^m corners of the ``critical`` parameters (indices into the box), the others nominal."""
    points = []
    for ends in itertools.product((0, 1), repeat=len(critical)):
        v = box.nominal.copy()
        for i, end in zip(critical, ends):
            v[i] = box.high[i] if end else box.low[i]
        note = ", ".join(f"{short_name(box.names[i])} {'high' if end else 'low'}" for i, end in zip(critical, ends))
        points.append(SweepPoint(kind="corner", values=tuple(v.tolist()), note=note))
    return points


def monte_carlo_points(box: ParameterBox, *, samples: int, seed: int) -> list[SweepPoint]:
    """``samples`` points drawn independently and uniformly in the box (numpy PCG64 from ``seed``)."""
    if samples < 0:
        raise MaceError(f"samples must be 0 or more, got {samples}")
    draws = np.random.default_rng(seed).uniform(box.low, box.high, size=(samples, len(box.names)))
    return [SweepPoint(kind="sample", values=tuple(row.tolist())) for row in draws]
