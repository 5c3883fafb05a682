"""Numbers as people read them, shared by the command line and the viewer."""

from __future__ import annotations

from mace_fmu.iomodel.modal_core import ZERO_HZ


def hz_text(frequency_hz: float, *, decimals: int) -> str:
    """A frequency [Hz] to ``decimals`` places; the zero-frequency cluster (rigid-body motions and
    mechanisms, |f| < ZERO_HZ, whose computed values are round-off such as -4e-4 Hz) reads 0.000."""
    shown = 0.0 if abs(frequency_hz) < ZERO_HZ else round(float(frequency_hz), decimals)
    return f"{shown + 0.0:.{decimals}f}"
