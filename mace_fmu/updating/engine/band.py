"""The time cost in a band: one zero-phase band-pass on the measured outputs and the model's, and what it does
to the noise.

A record whose inputs reach beyond the band the model is meant for (a shaker's broadband force noise above its
lines, a drift below them) is compared in the band by filtering the error, never the inputs that drive the
model: the model is driven by what the structure felt, and for a linear model filtering both outputs with the
same filter is the same as driving it with the filtered inputs. The filter runs forwards and backwards
(``scipy.signal.sosfiltfilt``): no phase, so no delay between the filtered outputs and the filtered inputs the
residual analysis correlates them with.

White measurement noise of one-sided density N through the filter has the variance N (fs / 2) g, g the mean of
|H(f)|^4 over [0, fs / 2] (|H|^2 of the one pass, twice); its samples are correlated, so a sum of n squares of it
spreads sqrt(kappa) times more than n independent ones, kappa = mean |H|^8 / (mean |H|^4)^2 (Parseval on the
autocorrelation: the record holds n / kappa independent samples of the band).

Where the band leaves part of the spectrum, the noise is read there: the outputs' spectrum outside the band less
the part the inputs explain (a broadband force drives the structure outside the band too; that response is not
noise), its median over the bins (a resonance there leaks past the regression in the bins about it), assumed
white across the band. What no input explains within a Welch segment (1024 samples) reads as noise: a strongly
driven structure whose free response outlasts the segment, outside the band, reads too much of it (the thesis's
two-mass record, its 0.09 Hz mode at 0.35 % damping driven below a 0.2 Hz band: 7 standard deviations
high); there the noise is to be given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np
import scipy.signal

from mace_fmu.errors import MaceError

#: order of the Butterworth band-pass (each pass; sosfiltfilt squares its magnitude)
ORDER = 4
#: the quiet part of the spectrum starts this factor beyond the band's edges (the filter's skirts) ...
MARGIN = 1.25
#: ... and stops short of the Nyquist frequency by this fraction of it (an anti-aliasing filter's roll-off)
NYQUIST_SHARE = 0.95
#: fewer Welch bins than this outside the band leave the noise unmeasured
MIN_QUIET_BINS = 5


def check_band(band_hz: tuple[float, float], *, sample_time_s: float, where: str) -> tuple[float, float]:
    """``band_hz`` as floats when 0 <= LOW < HIGH <= the Nyquist frequency and it leaves something out; a
    MaceError naming ``where`` otherwise."""
    low, high = (float(x) for x in band_hz)
    nyquist = 0.5 / sample_time_s
    if not (math.isfinite(low) and math.isfinite(high) and 0.0 <= low < high):
        raise MaceError(f"{where} {low:g} {high:g}: expected 0 <= LOW < HIGH [Hz]")
    if high > nyquist * (1 + 1e-9):
        raise MaceError(f"{where} {low:g} {high:g}: HIGH is above the record's Nyquist frequency {nyquist:g} Hz")
    if low == 0.0 and high >= nyquist * (1 - 1e-9):
        raise MaceError(f"{where} {low:g} {high:g}: the whole band to Nyquist ({nyquist:g} Hz) filters nothing; "
                        "leave the option out")
    return low, high


def band_sos(band_hz: tuple[float, float], sample_time_s: float) -> np.ndarray:
    """Second-order sections of the Butterworth filter of ``band_hz`` (a low-pass from 0 Hz, a high-pass to
    Nyquist, else a band-pass), order :data:`ORDER`."""
    low, high = band_hz
    fs = 1.0 / sample_time_s
    if low <= 0.0:
        return scipy.signal.butter(ORDER, high, btype="lowpass", fs=fs, output="sos")
    if high >= 0.5 * fs * (1 - 1e-9):
        return scipy.signal.butter(ORDER, low, btype="highpass", fs=fs, output="sos")
    return scipy.signal.butter(ORDER, [low, high], btype="bandpass", fs=fs, output="sos")


def band_filtered(values: np.ndarray, band_hz: tuple[float, float], sample_time_s: float, *,
                  axis: int = 0) -> np.ndarray:
    """``values`` through the zero-phase filter of ``band_hz`` (forwards and backwards) along ``axis``."""
    return scipy.signal.sosfiltfilt(band_sos(band_hz, sample_time_s), np.asarray(values, dtype=float), axis=axis)


@dataclass(frozen=True)
class NoiseGain:
    """What the zero-phase filter does to white noise: its variance gain ``g`` and its correlation ``kappa``."""

    g: float  #: mean of |H|^4 over [0, fs / 2]: the filtered white noise's variance over the raw one's
    kappa: float  #: mean |H|^8 / (mean |H|^4)^2: a sum of n filtered squares spreads sqrt(kappa) times more


def noise_gain(band_hz: tuple[float, float], sample_time_s: float) -> NoiseGain:
    """The filter's :class:`NoiseGain` (its response on 2^16 points of [0, fs / 2])."""
    _, h = scipy.signal.sosfreqz(band_sos(band_hz, sample_time_s), worN=1 << 16)
    p = np.abs(h) ** 4  # sosfiltfilt: |H|^2 on the amplitude, |H|^4 on the power
    g = float(np.mean(p))
    return NoiseGain(g=g, kappa=float(np.mean(p**2)) / g**2)


@dataclass(frozen=True)
class OutsideBand:
    """Each output's white-noise density as read outside the band, and where it was read."""

    density: Mapping[str, float]  #: output -> one-sided density [unit^2 / Hz] of its noise
    bins_hz: tuple[float, float, int]  #: (lowest, highest frequency [Hz], count) of the Welch bins read


def noise_outside_band(inputs: Mapping[str, np.ndarray], outputs: Mapping[str, np.ndarray], *,
                       sample_time_s: float, band_hz: tuple[float, float]) -> OutsideBand | None:
    """Each output's noise density read outside ``band_hz`` (module docstring): the Welch bins below LOW / 1.25
    and above 1.25 HIGH (up to 0.95 of Nyquist, above the first bins), where the outputs' spectrum less the part
    the inputs explain is the noise; None when fewer than :data:`MIN_QUIET_BINS` bins are left there."""
    n = len(next(iter(outputs.values())))
    fs = 1.0 / sample_time_s
    segment = min(n, 1024)
    opts = dict(fs=fs, nperseg=segment, noverlap=segment // 2, detrend="constant")
    names = [k for k, u in inputs.items() if np.ptp(np.asarray(u)) > 0]
    f, _ = scipy.signal.welch(np.asarray(next(iter(outputs.values())), dtype=float), **opts)
    low, high = band_hz
    quiet = ((f < low / MARGIN) | (f > MARGIN * high)) & (f < NYQUIST_SHARE * fs / 2) & (f > 2 * fs / segment)
    if quiet.sum() < MIN_QUIET_BINS:
        return None
    segments = 1 + (n - segment) // (segment - segment // 2)
    averages = segments / 1.06  # half-overlapping Hann segments are not quite independent
    q = len(names)
    if names:
        u = np.array([np.asarray(inputs[k], dtype=float) for k in names])
        _, s_uu = scipy.signal.csd(u[:, None, :], u[None, :, :], **opts)
        s_uu = np.moveaxis(s_uu[..., quiet], -1, 0)
        inverse = np.linalg.pinv(s_uu, rcond=1e-12)
    density = {}
    for name, y in outputs.items():
        y = np.asarray(y, dtype=float)
        _, s_yy = scipy.signal.welch(y, **opts)
        s_yy = s_yy[quiet]
        unexplained = s_yy
        if names and averages > q + 1:
            _, s_uy = scipy.signal.csd(u, y[None, :], **opts)
            s_uy = s_uy[:, quiet].T  # (k, input)
            explained = np.clip(np.real(np.einsum("ka,kab,kb->k", np.conj(s_uy), inverse, s_uy)), 0.0, s_yy)
            # the regression on q inputs takes q of the averages' degrees of freedom with it
            unexplained = (s_yy - explained) * averages / (averages - q)
        # the median over the bins, not the mean: a lightly damped resonance outside the band leaks past the
        # regression in the bins about it; the median of a chi-square of nu degrees of freedom is about
        # (1 - 2 / (9 nu))^3 of its mean (Wilson-Hilferty)
        nu = 2.0 * max(averages - q, 1.0)
        density[name] = float(np.median(unexplained)) / (1.0 - 2.0 / (9.0 * nu)) ** 3
    f = f[quiet]
    return OutsideBand(density=density, bins_hz=(float(f.min()), float(f.max()), int(f.size)))


def band_noise_floor(cost, *, band_hz: tuple[float, float], noise_rms_fraction: float | None = None) -> dict | None:
    """The fields of a :class:`~mace_fmu.updating.engine.convergence.NoiseFloor` of a band-passed time cost
    (:class:`~mace_fmu.updating.engine.costs.TimeResponseCost` with ``band_hz``): each output's white noise,
    given (``noise_rms_fraction`` of its RMS in the record) or read outside the band
    (:func:`noise_outside_band`), through the filter, over the filtered output's mean square; None when the
    record leaves too little outside the band to read it.

    Returns
    -------
    dict or None
        ``expected_cost`` (sum of n r_o), ``standard_deviation`` (sqrt(sum 2 n r_o^2 kappa)),
        ``noise_rms_percent`` (100 sqrt(r_o), the noise of each output's residual) and ``source``.
    """
    dt = cost.data.sample_time_s
    first = int(np.searchsorted(cost.data.times_s, cost.compare_from_s - 1e-9 * dt))
    raw_in = {k: np.asarray(v, dtype=float)[first:] for k, v in cost.data.inputs.items()}
    raw_out = {k: np.asarray(v, dtype=float)[first:] for k, v in cost.data.outputs.items()}
    n = len(cost.data.times_s) - first
    gain = noise_gain(band_hz, dt)
    band_text = f"{band_hz[0]:g}-{band_hz[1]:g} Hz"
    if noise_rms_fraction is not None:
        if not (math.isfinite(noise_rms_fraction) and noise_rms_fraction > 0):
            raise MaceError(f"noise RMS must be a positive fraction of the output RMS, got {noise_rms_fraction!r}")
        raw_variance = {o: noise_rms_fraction**2 * float(np.mean(y**2)) for o, y in raw_out.items()}
        source = (f"given: {100 * noise_rms_fraction:g} % of each output's RMS (white), through the {band_text} "
                  "band-pass")
    else:
        outside = noise_outside_band(raw_in, raw_out, sample_time_s=dt, band_hz=band_hz)
        if outside is None:
            return None
        raw_variance = {o: d * 0.5 / dt for o, d in outside.density.items()}
        low, high, count = outside.bins_hz
        source = (f"estimated outside the band {band_text} ({count} bins from {low:.4g} to {high:.4g} Hz: the "
                  "outputs' spectra less what the inputs explain), through the band-pass")
    if not cost.normalise:
        raise MaceError("the noise floor is defined for the normalised time cost")
    ratio = {}
    for o in raw_out:
        filtered = cost._measured(o)
        ratio[o] = raw_variance[o] * gain.g / float(np.mean(filtered**2))
    expected = sum(n * r for r in ratio.values())
    std = math.sqrt(sum(2 * n * r**2 * gain.kappa for r in ratio.values()))
    return {"expected_cost": expected, "standard_deviation": std,
            "noise_rms_percent": {o: 100 * math.sqrt(r) for o, r in ratio.items()}, "source": source}
