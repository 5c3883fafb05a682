"""Rational approximations of a time delay (Pade) and of an analog Bessel low-pass filter.

Both are realised in well-scaled state-space forms instead of the companion form of their
polynomial coefficients: those coefficients span many decades (an 8-pole filter at 200 Hz has
a constant term of about 1e27), which would cost digits in every later computation.
"""

from __future__ import annotations

from collections.abc import Sequence

import control as ct
import numpy as np
import scipy.linalg
import scipy.signal
from numpy.typing import NDArray

from .blocks import Block, channel_states, channels, owner_label
from .connectors import Connector
from .errors import ModelError

__all__ = ["PadeDelay", "BesselFilter"]

Matrices = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]


def _check_order(owner: str, order: object) -> int:
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 1:
        raise ModelError(f"{owner}: order must be an integer >= 1, got {order!r}")
    return int(order)


def _number(owner: str, what: str, value: object, expected: str, *, minimum: float,
            strict: bool = False) -> float:
    """``value`` as a finite float ``>= minimum`` (``> minimum`` if strict), else ModelError."""
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        x = float("nan")
    if not np.isfinite(x) or x < minimum or (strict and x == minimum):
        raise ModelError(f"{owner}: {what} must be {expected}, got {value!r}")
    return x


def _copies(siso: Matrices, size: int) -> Matrices:
    """``size`` independent copies of a SISO realisation (block diagonal, channel-major states)."""
    eye = np.eye(size)
    return tuple(np.kron(eye, m) for m in siso)  # type: ignore[return-value]


def _series(first: Matrices, second: Matrices) -> Matrices:
    """Realisation of ``second`` driven by ``first`` (states of ``first`` come first)."""
    A1, B1, C1, D1 = first
    A2, B2, C2, D2 = second
    A = np.block([[A1, np.zeros((A1.shape[0], A2.shape[1]))], [B2 @ C1, A2]])
    return A, np.vstack([B1, B2 @ D1]), np.hstack([D2 @ C1, C2]), D2 @ D1


def pade_realization(delay: float, order: int) -> Matrices:
    """Balanced SISO realisation of ``control.pade(delay, order)`` (``delay > 0``)."""
    num, den = ct.pade(delay, order)
    # H(s) = H1(s*T) where H1 has the O(1) coefficients of the unit delay; realise H1 and scale
    # time (A, B by 1/T), then balance so no entry dwarfs the others.
    n = len(den) - 1
    num1 = np.asarray(num, dtype=float) * delay ** np.arange(n + 1)
    den1 = np.asarray(den, dtype=float) * delay ** np.arange(n + 1)
    A1, B1, C1, D1 = scipy.signal.tf2ss(num1 / den1[0], den1 / den1[0])
    A, B = A1 / delay, B1 / delay
    _, (scale, _perm) = scipy.linalg.matrix_balance(A, permute=False, separate=True)
    return A * (1.0 / scale)[:, None] * scale[None, :], B / scale[:, None], C1 * scale[None, :], D1


#: analog low-pass families: the scipy.signal design of each, |H| = -3.01 dB at the cutoff
LOWPASS_KINDS = ("bessel", "butterworth")


def lowpass_realization(kind: str, order: int, cutoff_hz: float) -> Matrices:
    """Cascade realisation of an analog low-pass, ``scipy.signal.bessel(..., norm="mag")`` or
    ``scipy.signal.butter``, unit DC gain per section.

    Each complex pole pair ``wn, zeta`` is a section with states (y, y'/wn); each real pole
    ``p`` a first-order lag ``-p/(s-p)``. Sections run from the most to the least damped.
    """
    wc = 2 * np.pi * cutoff_hz
    if kind == "bessel":
        zeros, poles, k = scipy.signal.bessel(order, wc, btype="low", analog=True, norm="mag", output="zpk")
    elif kind == "butterworth":
        zeros, poles, k = scipy.signal.butter(order, wc, btype="low", analog=True, output="zpk")
    else:
        raise ValueError(f"low-pass kind must be one of {', '.join(LOWPASS_KINDS)}, got {kind!r}")
    assert len(zeros) == 0, "an analog all-pole low-pass has no finite zeros"
    sections: list[Matrices] = []
    for p in sorted(poles[poles.imag >= 0], key=lambda p: -abs(p.real) / abs(p)):
        if abs(p.imag) <= 1e-12 * abs(p):
            sections.append((np.array([[p.real]]), np.array([[-p.real]]), np.eye(1),
                             np.zeros((1, 1))))
        else:
            wn, zeta = abs(p), -p.real / abs(p)
            sections.append((np.array([[0.0, wn], [-wn, -2 * zeta * wn]]), np.array([[0.0], [wn]]),
                             np.array([[1.0, 0.0]]), np.zeros((1, 1))))
    A, B, C, D = sections[0]
    for section in sections[1:]:
        A, B, C, D = _series((A, B, C, D), section)
    # The sections have unit DC gain; scipy's k is prod|p| up to rounding: keep its exact value.
    return A, B, C * (np.real(k) / np.prod(np.abs(poles))), D


def bessel_realization(order: int, cutoff_hz: float) -> Matrices:
    """:func:`lowpass_realization` of the Bessel design."""
    return lowpass_realization("bessel", order, cutoff_hz)


class PadeDelay(Block):
    """Time delay ``exp(-s*delay)`` by its Pade approximation ``control.pade(delay, order)``.

    Ports ``u`` and ``y`` (``size`` independent copies, element names ``signals``). ``delay == 0``
    is a unit feedthrough without states. The approximation is biproper (D = (-1)**order), so a
    delay does not break an algebraic loop.
    """

    kind = "PadeDelay"

    def __init__(self, name: str, delay: float, order: int = 3, size: int = 1,
                 signals: Sequence[str] | None = None) -> None:
        owner = owner_label("PadeDelay", name)
        size, signals = channels(owner, size, signals)
        order = _check_order(owner, order)
        delay = _number(owner, "delay", delay, "a finite number of seconds >= 0", minimum=0.0)
        self._delay, self._order = delay, order
        if delay == 0:
            siso: Matrices = (np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.eye(1))
            states: list[str] = []
        else:
            siso = pade_realization(delay, order)
            states = channel_states(size, order)
        u = Connector.make("u", "input", size, signals, owner=owner)
        y = Connector.make("y", "output", size, signals, owner=owner)
        super().__init__(name, [u], [y], *_copies(siso, size), states)

    @property
    def delay(self) -> float:
        """The approximated delay in seconds."""
        return self._delay

    @property
    def order(self) -> int:
        """Pade order (numerator and denominator degree)."""
        return self._order


class LowPassFilter(Block):
    """Analog low-pass (``family`` "bessel" or "butterworth") of ``order`` poles with |H| = -3.01 dB at
    ``cutoff_hz``.

    The design is ``scipy.signal.bessel(order, 2*pi*cutoff_hz, btype="low", analog=True,
    norm="mag")`` or ``scipy.signal.butter(order, 2*pi*cutoff_hz, analog=True)``; ports ``u`` and
    ``y`` (``size`` independent copies, element names ``signals``); ``order`` states per copy,
    strictly proper (D = 0).
    """

    kind = "LowPassFilter"

    def __init__(self, name: str, order: int, cutoff_hz: float, size: int = 1,
                 signals: Sequence[str] | None = None, *, family: str = "bessel") -> None:
        owner = owner_label(self.kind, name)
        if family not in LOWPASS_KINDS:
            raise ModelError(f"{owner}: family must be one of {', '.join(LOWPASS_KINDS)}, got {family!r}")
        self._family = family
        size, signals = channels(owner, size, signals)
        order = _check_order(owner, order)
        cutoff_hz = _number(owner, "cutoff_hz", cutoff_hz, "a finite frequency in Hz > 0",
                            minimum=0.0, strict=True)
        self._order, self._cutoff_hz = order, cutoff_hz
        u = Connector.make("u", "input", size, signals, owner=owner)
        y = Connector.make("y", "output", size, signals, owner=owner)
        super().__init__(name, [u], [y], *_copies(lowpass_realization(family, order, cutoff_hz), size),
                         channel_states(size, order))

    @property
    def family(self) -> str:
        """"bessel" or "butterworth"."""
        return self._family

    @property
    def order(self) -> int:
        """Number of poles per copy."""
        return self._order

    @property
    def cutoff_hz(self) -> float:
        """The -3.01 dB frequency in Hz."""
        return self._cutoff_hz


class BesselFilter(LowPassFilter):
    """Analog Bessel low-pass: :class:`LowPassFilter` of the Bessel family."""

    kind = "BesselFilter"

    def __init__(self, name: str, order: int, cutoff_hz: float, size: int = 1,
                 signals: Sequence[str] | None = None) -> None:
        super().__init__(name, order, cutoff_hz, size, signals, family="bessel")
