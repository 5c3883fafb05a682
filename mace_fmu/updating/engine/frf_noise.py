"""The noise of a measured frequency response's logarithm, from its coherence and number of averages.

An H1 estimate from ``n_d`` averages of a test with ``q`` inputs, whose output has multiple coherence
gamma^2 with them, has the random error (Bendat and Piersol, Random Data, 4th ed., eq. 9.90 and 11.30)

    var(H_ij) = (1 - gamma^2) S_yy [S_uu^-1]_jj / (n_d - q + 1),

and the real and imaginary parts of log H_ij (the log magnitude and the phase [rad], thesis eq. 4.17)
each have half of var(H_ij) / |H_ij|^2. A file gives H and gamma^2, not the spectra: with the inputs
uncorrelated and of one level s (the multi-input random test's design), S_yy = s sum_j |H_ij|^2 / gamma^2
and [S_uu^-1]_jj = 1 / s, so

    var(Re log H_ij) = var(Im log H_ij) = ((1 - gamma^2) / (2 nu gamma^2) + floor^2) sum_j' |H_ij'|^2 / |H_ij|^2
                                          + sum_j' |b_ij'|^2 / |H_ij|^2

with nu = n_d - q + 1 (n_d for one input: the single-input 1 / (2 n_d) (1 - gamma^2) / gamma^2). The
share sum_j' |H_ij'|^2 / |H_ij|^2 is what makes a weak path (a cross-axis response, an antiresonance)
weigh little: its estimate carries the strong paths' errors. ``floor`` is the part of the error the
coherence does not see, as a fraction of the output's whole response: the bias of a Welch estimate at a
lightly damped resonance (leakage, a few bins per half-power band), calibration. Without it a noise-free
record's coherence of 0.99999 is read as an error of 0.1 %, and its leakage bias becomes the target of
the fit: on the 1-g FMU (noise-free 64 s, 16 s segments, E_lexan_end x 1.03, E_lexan_center x 0.98) the
coherence weights of earlier versions, sqrt(gamma^2 / (1 - gamma^2)), gave +11.0 % / -5.9 %.

b is the leakage bias the coherence does not see either: a window smooths the spectra it estimates, so
E[H1](f) = H(f) + (m2 / 2) H''(f) to second order, m2 the second moment of the window's power kernel, 1/3
of a squared line spacing for a Hann window (m2 = int |w'|^2 / (4 pi^2 int w^2)). A lightly damped resonance
narrower than a few lines makes it the largest error of a Welch estimate. b_ij = (H_ij(f+) - 2 H_ij(f) +
H_ij(f-)) / 6 from the file's own neighbouring lines (a Hann window assumed, the analysers' default), taken
as an error of its size rather than corrected: on the file above, at the truth, the lines' squared errors
over their variance average 1.7 without b (the largest pair 4.7: a fit "not explained to the noise" of a
right model) and 0.48 with it (1.1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.measured import MeasuredFrf

#: the default floor: 1 % of an output's whole response (see the module docstring)
DEFAULT_FLOOR = 0.01


@dataclass(frozen=True)
class FrfNoise:
    """The standard deviation of log H at every line, output and input of one measured frequency response."""

    standard_deviation: np.ndarray  #: (k, output, input): of Re log H and of Im log H (each) [1, rad]
    averages: int  #: n_d, the averages behind the estimate
    floor: float  #: the error floor, a fraction of the output's whole response
    source: str  #: where the averages came from

    @property
    def weights(self) -> np.ndarray:
        """w = 1 / standard deviation: each log error in units of its own noise."""
        return 1.0 / self.standard_deviation


def frf_noise(data: MeasuredFrf, *, averages: int | None = None, floor: float = DEFAULT_FLOOR) -> FrfNoise:
    """The noise of log H of ``data`` from its coherence (module docstring).

    Parameters
    ----------
    data : MeasuredFrf
        A measured frequency response with its multiple coherence.
    averages : int, optional
        n_d, the averages behind the estimate, where the file does not say (``data.averages``); a number
        given here and a different one in the file is refused.
    floor : float
        The error floor, a fraction of each output's whole response (0.01: 1 %).

    Returns
    -------
    FrfNoise
        Standard deviations of log |H| and phase at every line, output and input, and the weights.

    Raises
    ------
    MaceError
        Without coherence, without a number of averages, with fewer averages than inputs, or a floor
        that is not a positive fraction.
    """
    if data.coherence is None:
        raise MaceError(f"{data.source}: no coherence, so no noise to weigh the lines by: give the coherence "
                        "columns, or compare unweighted (--weighting none)")
    if averages is not None and data.averages is not None and averages != data.averages:
        raise MaceError(f"{data.source}: the file states {data.averages} averages, --averages says {averages}")
    n_d = averages if averages is not None else data.averages
    if n_d is None:
        raise MaceError(f"{data.source}: the coherence's noise needs the number of averages behind the estimate, which "
                        "the file does not state: give the analyser's setting (--averages N), or compare unweighted "
                        "(--weighting none)")
    q = len(data.inputs)
    nu = n_d - q + 1
    if nu < 1:
        raise MaceError(f"{data.source}: {n_d} averages for {q} inputs: an H1 of {q} inputs needs at least {q}")
    if not (np.isfinite(floor) and 0 < floor < 1):
        raise MaceError(f"error floor {floor!r}, expected a fraction in (0, 1) of each output's response")
    gamma2 = np.clip(data.coherence, np.finfo(float).tiny, 1.0)[:, :, None]
    power = np.abs(data.response) ** 2
    with np.errstate(divide="ignore"):
        share = power.sum(axis=2, keepdims=True) / power  # inf where a path's response is exactly zero
    with np.errstate(divide="ignore"):
        leakage = (np.abs(_curvature(data.frequencies_hz, data.response) / 6.0) ** 2).sum(axis=2, keepdims=True) / power
    variance = ((1.0 - gamma2) / (2.0 * nu * gamma2) + floor**2) * share + leakage
    source = "the file" if data.averages is not None else "--averages"
    return FrfNoise(standard_deviation=np.sqrt(variance), averages=int(n_d), floor=float(floor),
                    source=f"{n_d} averages ({source}), {q} input(s), error floor {100 * floor:g} % of each "
                           "output's response")


def _curvature(f: np.ndarray, h: np.ndarray) -> np.ndarray:
    """H(f+) - 2 H(f) + H(f-) at every line whose neighbours are one line spacing away on both sides; the
    nearest such line's elsewhere (the ends, the edges of a band), 0 where no line has two neighbours."""
    out = np.zeros_like(h)
    if f.size < 3:
        return out
    spacing = float(np.min(np.diff(f)))
    inner = np.flatnonzero(np.isclose(f[2:] - f[1:-1], spacing, rtol=1e-6) &
                           np.isclose(f[1:-1] - f[:-2], spacing, rtol=1e-6)) + 1
    if inner.size == 0:
        return out
    out[inner] = h[inner + 1] - 2 * h[inner] + h[inner - 1]
    nearest = inner[np.clip(np.searchsorted(inner, np.arange(f.size)), 0, inner.size - 1)]
    other = inner[np.clip(np.searchsorted(inner, np.arange(f.size)) - 1, 0, inner.size - 1)]
    pick = np.where(np.abs(other - np.arange(f.size)) < np.abs(nearest - np.arange(f.size)), other, nearest)
    rest = np.setdiff1d(np.arange(f.size), inner)
    out[rest] = out[pick[rest]]
    return out
