"""H1 frequency-response estimates from measured time histories (Welch-averaged cross spectra)."""

from __future__ import annotations

from typing import Sequence

import numpy as np
from scipy import signal

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.measured import MeasuredFrf, TimeHistory


def h1_estimate(history: TimeHistory, *, segment_length: int, window: str = "hann", overlap: float = 0.5,
                band_hz: tuple[float, float] | None = None, inputs_held: bool = False,
                lines_hz: Sequence[float] | None = None) -> MeasuredFrf:
    """H1 = S_yu S_uu^-1 [output unit / input unit] at the Welch frequencies [Hz], with multiple coherence.

    Cross spectra by ``scipy.signal.csd`` (``segment_length`` samples per segment, ``window``,
    ``overlap`` fraction of a segment, mean removed per segment). With several inputs the full
    matrix S_uu is inverted at each frequency, so simultaneous inputs must not be fully
    correlated. ``band_hz`` keeps [low, high] (inclusive); without it every frequency above 0 Hz.
    The settings are stated in the result's ``source``, the number of segments averaged in its
    ``averages`` (what the coherence's variance needs, :mod:`~mace_fmu.updating.engine.frf_noise`).
    ``lines_hz`` keeps only the bins of those frequencies: a periodic excitation's lines, where the inputs
    have power (between them S_uu holds nothing to invert).

    A record whose inputs were held over each sample (a simulation's: an FMU holds each input value
    for the step; a record that logs a DAC's commands rather than the measured signal) has the
    hold's response e^(-j pi f T) sinc(f T) in its H1: a half-sample delay and a droop, 21.6 deg and
    2.3 % at 60 Hz sampled at 500 Hz. An analyser's FRF of the continuous signals has neither, and the
    FMU updates compare with that (:mod:`~mace_fmu.updating.engine.multisine`): ``inputs_held``
    divides the hold out.

    Parameters
    ----------
    history : TimeHistory
        The measured inputs and outputs.
    segment_length : int
        Samples per Welch segment.
    window : str
        The segments' window (scipy name).
    overlap : float
        Overlap of the segments, a fraction of one.
    band_hz : tuple of float, optional
        [low, high] [Hz] to keep (inclusive).
    inputs_held : bool
        The inputs were held over each sample: divide the hold's response out (above).
    lines_hz : sequence of float, optional
        Keep only the bins nearest these frequencies [Hz] (each within half a bin of one).

    Returns
    -------
    MeasuredFrf
        H1 at the Welch frequencies [Hz], each output's multiple coherence, the settings in ``source``.
    """
    inputs, outputs = list(history.inputs), list(history.outputs)
    n = history.times_s.size
    if not inputs:
        raise MaceError(f"{history.source}: no input channels; H1 needs the measured inputs")
    if not (isinstance(segment_length, (int, np.integer)) and 2 <= segment_length <= n):
        raise MaceError(f"{history.source}: segment length {segment_length!r} samples, expected an integer in "
                        f"[2, {n}] (the record's length)")
    if not (0.0 <= overlap < 1.0):
        raise MaceError(f"H1 estimate: overlap {overlap!r}, expected a fraction in [0, 1)")
    u = np.stack([history.inputs[name] for name in inputs])  # (m, n)
    y = np.stack([history.outputs[name] for name in outputs])  # (p, n)
    fs = 1.0 / history.sample_time_s
    options = dict(fs=fs, window=window, nperseg=int(segment_length), noverlap=int(round(overlap * segment_length)),
                   detrend="constant", scaling="density")
    try:
        # scipy's csd(x, y) = E[conj(X) Y]: s_uu[a, b] = E[conj(U_a) U_b], s_uy[a, c] = E[conj(U_a) Y_c].
        f, s_uu = signal.csd(u[:, None, :], u[None, :, :], **options)
        _, s_uy = signal.csd(u[:, None, :], y[None, :, :], **options)
        _, s_yy = signal.welch(y, **options)
    except ValueError as exc:
        raise MaceError(f"H1 estimate of {history.source}: {exc}") from None
    keep = (f > 0) if band_hz is None else (f >= band_hz[0]) & (f <= band_hz[1])
    if lines_hz is not None:
        resolution = fs / segment_length
        keep &= np.isin(np.rint(f / resolution), np.rint(np.asarray(lines_hz, dtype=float) / resolution))
    if not np.any(keep):
        raise MaceError(f"H1 estimate of {history.source}: no Welch frequency in {band_hz} Hz (resolution "
                        f"{fs / segment_length:.6g} Hz up to {fs / 2:.6g} Hz)")
    s_uu = np.moveaxis(s_uu[..., keep], -1, 0)  # (k, m, m)
    s_uy = np.moveaxis(s_uy[..., keep], -1, 0)  # (k, m, p)
    s_yy = s_yy[:, keep].T.real  # (k, p)
    # S_uy = S_uu H^T (Y = H U), so H^T = S_uu^-1 S_uy; refuse a singular S_uu instead of returning noise.
    cond = np.linalg.cond(s_uu)
    if not np.all(np.isfinite(cond)) or np.any(cond > 1e12):
        k = int(np.argmax(np.where(np.isfinite(cond), cond, np.inf)))
        raise MaceError(f"H1 estimate of {history.source}: the input cross-spectral matrix is singular at "
                        f"{f[keep][k]:.6g} Hz (inputs {', '.join(inputs)} zero or fully correlated there)")
    h_t = np.linalg.solve(s_uu, s_uy)  # (k, m, p)
    response = np.transpose(h_t, (0, 2, 1))  # (k, p, m)
    if inputs_held:
        t = history.sample_time_s
        response = response / (np.exp(-1j * np.pi * f[keep] * t) * np.sinc(f[keep] * t))[:, None, None]
    # Multiple coherence of each output with all inputs: (S_yu S_uu^-1 S_uy)_cc / S_yy,cc.
    explained = np.einsum("kac,kac->kc", np.conj(s_uy), h_t).real
    # an output with no power there (all zeros) has nothing to explain: coherence 0, not 0/0
    ratio = np.divide(explained, s_yy, out=np.zeros_like(s_yy), where=s_yy > 0)
    coherence = np.clip(ratio, 0.0, 1.0)
    step = int(segment_length) - int(round(overlap * segment_length))
    averages = 1 + (n - int(segment_length)) // step  # scipy's Welch segments
    settings = (f"Welch: {segment_length}-sample segments ({segment_length * history.sample_time_s:.6g} s, "
                f"{fs / segment_length:.6g} Hz resolution), {window} window, {overlap:.0%} overlap, {averages} "
                f"averages" + (", the inputs' hold divided out" if inputs_held else ""))
    return MeasuredFrf(f[keep], tuple(inputs), tuple(outputs), response,
                                 source=f"H1 estimate of {history.source} ({settings})",
                                 units={name: history.unit(name) for name in inputs + outputs},
                                 coherence=coherence, averages=averages)
