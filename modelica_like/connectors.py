"""Connectors (typed vector ports of a block) and the ``"block.port[sel]"`` reference syntax.

Elements are numbered from 1 in everything the user sees (Modelica convention) and from 0
internally. A connector's elements carry signal names; when the user gives none, element ``i``
of port ``u`` is called ``"u[i]"``.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

from .errors import ModelError

Causality = Literal["input", "output"]

_IDENTIFIER = re.compile(r"[A-Za-z_]\w*\Z")
_REFERENCE = re.compile(r"\s*([A-Za-z_]\w*)\.([A-Za-z_]\w*)(?:\[(.*)\])?\s*\Z")
_SLICE = re.compile(r"\s*(\d*)\s*:\s*(\d*)\s*\Z")
REFERENCE_FORMS = "'block.port', 'block.port[3]', 'block.port[name]' or 'block.port[2:4]'"


def check_identifier(name: object, what: str) -> str:
    """Return ``name`` if it is a Python identifier, else raise ModelError naming ``what``."""
    if not isinstance(name, str) or not _IDENTIFIER.match(name):
        raise ModelError(f"{what} must be a Python identifier (letters, digits, _), got {name!r}")
    return name


def default_signals(port: str, size: int) -> tuple[str, ...]:
    """Default element names of a port: ``("u[1]", "u[2]", ...)``."""
    return tuple(f"{port}[{i}]" for i in range(1, size + 1))


@dataclass(frozen=True)
class Connector:
    """A named vector port of a block: its causality and one signal name per element."""

    name: str
    causality: Causality
    signals: tuple[str, ...]

    @classmethod
    def make(cls, name: str, causality: Causality, size: int | None = None,
             signals: Sequence[str] | None = None, *, owner: str = "block") -> Connector:
        """Build a connector from a size and/or signal names, validating both."""
        check_identifier(name, f"{owner}: connector name")
        if signals is None:
            if size is None or int(size) != size or size < 1:
                raise ModelError(f"{owner}: size of connector {name!r} must be an integer >= 1, "
                                 f"got {size!r}")
            return cls(name, causality, default_signals(name, int(size)))
        if isinstance(signals, str):
            signals = [signals]  # one name for a size-1 port, a common slip
        signals = tuple(signals)
        if size is not None and len(signals) != size:
            raise ModelError(f"{owner}: {len(signals)} signal names {list(signals)} given for "
                             f"connector {name!r} of size {size}")
        if not signals:
            raise ModelError(f"{owner}: connector {name!r} needs at least one signal name")
        for s in signals:
            # Digit-only names would be indistinguishable from 1-based indices in references.
            if not isinstance(s, str) or not s.strip() or s.strip().isdigit() or _SLICE.match(s):
                raise ModelError(f"{owner}: signal name {s!r} of connector {name!r} must be a "
                                 "non-empty string that is not a number or a slice")
        duplicates = sorted({s for s in signals if signals.count(s) > 1})
        if duplicates:
            raise ModelError(f"{owner}: connector {name!r} has duplicate signal names {duplicates}")
        return cls(name, causality, signals)

    @property
    def size(self) -> int:
        """Number of scalar elements."""
        return len(self.signals)

    def label(self, index: int) -> str:
        """Port-local label of element ``index`` (0-based): ``"u[2]"`` or ``"y[gyro_x]"``."""
        signal = self.signals[index]
        return signal if signal == f"{self.name}[{index + 1}]" else f"{self.name}[{signal}]"

    def describe(self) -> str:
        """Short description for error messages, e.g. ``"u (input, size 2)"``."""
        return f"{self.name} ({self.causality}, size {self.size})"

    def select(self, selector: str | None, where: str) -> tuple[int, ...]:
        """0-based element indices picked by a reference selector (``None`` = whole port).

        ``where`` is the block-qualified port name used in messages, e.g. ``"plant.y"``.
        """
        if selector is None:
            return tuple(range(self.size))
        text = selector.strip()
        valid = f"1..{self.size}" if self.size > 1 else "1"
        if text.isdigit():
            i = int(text)
            if not 1 <= i <= self.size:
                raise ModelError(f"'{where}[{selector}]': index {i} is out of range for {where} "
                                 f"(size {self.size}; valid indices {valid})")
            return (i - 1,)
        m = _SLICE.match(text)
        if m:
            start = int(m[1]) if m[1] else 1
            stop = int(m[2]) if m[2] else self.size
            if not 1 <= start <= stop <= self.size:
                raise ModelError(f"'{where}[{selector}]': slice {start}:{stop} is not within "
                                 f"{where} (size {self.size}); expected 1 <= start <= stop <= "
                                 f"{self.size} (1-based, inclusive)")
            return tuple(range(start - 1, stop))
        if text in self.signals:
            return (self.signals.index(text),)
        raise ModelError(f"'{where}[{selector}]': {where} has no element named {text!r}; its "
                         f"elements are {', '.join(self.signals)} (or indices {valid})")


@dataclass(frozen=True)
class Element:
    """One scalar element of one block connector (``index`` is 0-based)."""

    block: str
    port: str
    index: int
    label: str = field(compare=False)  #: user-facing label, e.g. ``"plant.y[gyro_x]"``

    def __str__(self) -> str:
        return self.label


@dataclass(frozen=True)
class Reference:
    """A parsed connector reference ``block.port[selector]``."""

    text: str
    block: str
    port: str
    selector: str | None


def parse_reference(text: object) -> Reference:
    """Parse ``"block.port"``, ``"block.port[3]"``, ``"block.port[name]"`` or ``"...[2:4]"``."""
    m = _REFERENCE.match(text) if isinstance(text, str) else None
    if m is None or not isinstance(text, str):
        raise ModelError(f"malformed connector reference {text!r}; expected {REFERENCE_FORMS}")
    return Reference(text.strip(), m[1], m[2], m[3])
