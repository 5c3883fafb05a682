"""Frequencies as every stage reads them: the edge of the zero-frequency cluster, the default highest mode,
and frequency text."""

from __future__ import annotations

#: modes below this frequency [Hz] form the zero cluster: rigid bodies and mechanisms, whose computed
#: frequencies are round-off (a few 1e-4 Hz)
ZERO_HZ = 0.01
#: highest mode [Hz] found when the deck has no EIGRL/EIGR range (thesis 3.4: the MACE models keep modes to
#: 250 Hz)
DEFAULT_MAX_HZ = 250.0


def hz_text(frequency_hz: float, *, decimals: int) -> str:
    """A frequency [Hz] to ``decimals`` places; the zero-frequency cluster (rigid-body motions and
    mechanisms, |f| < ZERO_HZ, whose computed values are round-off such as -4e-4 Hz) reads 0.000."""
    shown = 0.0 if abs(frequency_hz) < ZERO_HZ else round(float(frequency_hz), decimals)
    return f"{shown + 0.0:.{decimals}f}"
