"""Whether an update's residuals are noise or a misfit of the model, and where the misfit lies.

After a fit that converged, the residual either is measurement noise (the model explains the data to
their noise) or holds what the model cannot reproduce. The tests are the System Identification
Toolbox's ``resid`` (Ljung, System Identification, 2nd ed., sec. 16.6), made on every measured channel
of the cost (:mod:`~mace_fmu.updating.engine.residual_blocks`):

- **level**: the residual's RMS over the noise's, where the noise is known (a time record's noise floor,
  a frequency response's coherence); a channel whose sum of squares lies more than ``sigma_limit``
  standard deviations above its chi-square mean, and whose RMS is more than ``RATIO_LIMIT`` times the
  noise's, is not explained. The second condition is there because the noise's own level is known to a few
  per cent at best (a noise floor read from a spectrum, a coherence's variance formula): over tens of
  thousands of samples a residual 2 % above it is statistically certain and says nothing about the model;
- **correlation with the inputs** (time records): a part of the output that the input drives and the model
  misses is coherent with the input. ``resid`` tests the cross-correlation at lags -25..25; a lightly damped
  structure's misfit (a resonance a few per cent off) rings for hundreds of samples and shows at 25 lags
  hardly at all (on the two-mass record of the tests, a local minimum with a residual 20 times the noise
  gave p = 1.0 there). The test here is its frequency-domain counterpart: the multiple coherence of the
  residual with all inputs (Welch, n_d averages), which for a residual independent of q inputs is
  Beta(q, n_d - q) distributed at each bin (Bendat and Piersol, Random Data, sec. 9.3); the bins of the
  inputs' band where it is significant at 1 % are counted, and more of them than a binomial 1 % allows
  (Bonferroni ``alpha`` over the channels) is a model error, the bins giving its band. The cross-correlation
  at lags -M..M is still drawn, with its 99 % band, as ``resid`` draws it;
- **whiteness** (time records): the Ljung-Box statistic of the residual's autocorrelation over lags 1..M.
  A coloured residual with no input correlation is coloured noise (or a misfit the inputs do not reveal);
  it is reported, and makes the intervals come from the residuals
  (:mod:`~mace_fmu.updating.engine.uncertainty`);
- **where**: the band holding the misfit (a time residual's spectrum above the noise's; a frequency
  response's lines beyond their noise), and for a frequency response the phase's linear trend, a delay the
  model lacks (a record whose inputs were held over each sample carries half a sample).

``analyse_residuals`` gives the findings per channel, :func:`residual_figure` the ``resid`` figure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.signal
import scipy.stats

from mace_fmu.updating.engine.residual_blocks import ResidualBlock

#: lags of the correlation tests, in samples (``resid``'s default)
MAX_LAG = 25
#: significance of the correlation tests, over all channels and inputs together (Bonferroni)
ALPHA = 0.01
#: a channel's sum of squares this many chi-square standard deviations above its mean is not noise ...
SIGMA_LIMIT = 3.0
#: ... when its RMS is also more than this many times the noise's (the noise's level is known to some per cent)
RATIO_LIMIT = 1.1


@dataclass(frozen=True)
class ChannelFinding:
    """What one channel's residual is."""

    name: str  #: the block's name
    domain: str  #: "time" or "frequency"
    samples: int  #: residual entries (a frequency line counts once: its magnitude and phase together)
    rms: float  #: of the residual [the cost's units]; a frequency line's |log error| / sqrt(2)
    noise_rms: float | None  #: the noise's standard deviation per entry [the cost's units] (None: unknown)
    sigmas_above: float | None  #: the sum of squares' distance above its chi-square mean [standard deviations]
    whiteness_p: float | None = None  #: time: Ljung-Box p-value (small: not white)
    input_correlation_p: dict = field(default_factory=dict)  #: time: input -> p-value of the cross-correlation test
    band_hz: tuple[float, float] | None = None  #: where the misfit lies (None: nowhere in particular)
    delay_s: float | None = None  #: frequency: a delay the phase's linear trend says the model lacks [s]
    significance: float = ALPHA  #: the p-value below which an input correlation is a finding (Bonferroni)
    sigma_limit: float = SIGMA_LIMIT

    @property
    def rms_over_noise(self) -> float | None:
        """Residual RMS over noise RMS (1: noise; None: the noise is unknown)."""
        return None if self.noise_rms is None or self.noise_rms <= 0 else self.rms / self.noise_rms

    @property
    def above_noise(self) -> bool:
        """The residual is larger than the noise allows (statistically and by more than ``RATIO_LIMIT``)."""
        ratio = self.rms_over_noise
        return (self.sigmas_above is not None and self.sigmas_above > self.sigma_limit and ratio is not None
                and ratio > RATIO_LIMIT)

    @property
    def correlated_inputs(self) -> tuple[str, ...]:
        """The inputs the residual is correlated with (a part of the output the model misses)."""
        return tuple(i for i, p in self.input_correlation_p.items() if p < self.significance)

    @property
    def white(self) -> bool | None:
        """Whether the residual is white (None: not tested)."""
        return None if self.whiteness_p is None else self.whiteness_p >= self.significance

    @property
    def explained(self) -> bool:
        """The model explains this channel to its noise: not above it, not correlated with an input."""
        return not self.above_noise and not self.correlated_inputs

    def text(self) -> str:
        """One line: how far the channel's residual is from noise, and how."""
        parts = []
        ratio = self.rms_over_noise
        if ratio is not None:
            parts.append(f"residual RMS {ratio:.3g} x the noise's ({self.sigmas_above:+.1f} sd)")
        else:
            parts.append(f"residual RMS {self.rms:.3g} (noise unknown)")
        if self.whiteness_p is not None:
            parts.append("white" if self.white else f"not white (Ljung-Box p = {self.whiteness_p:.1e})")
        if self.correlated_inputs:
            parts.append("correlated with " + ", ".join(f"{i} (p = {self.input_correlation_p[i]:.1e})"
                                                          for i in self.correlated_inputs))
        if self.band_hz is not None:
            parts.append(f"misfit in {self.band_hz[0]:.3g}-{self.band_hz[1]:.3g} Hz")
        if self.delay_s is not None:
            parts.append(f"phase falls like a delay of {1e3 * self.delay_s:.3g} ms the model lacks")
        return f"{self.name}: " + ", ".join(parts)


@dataclass(frozen=True)
class CorrelationCurves:
    """The ``resid`` figure's curves of one time channel."""

    name: str
    lags_s: np.ndarray  #: lags [s], -M..M
    autocorrelation: np.ndarray  #: of the residual at lags 0..M (normalised: 1 at 0)
    cross_correlation: dict  #: input -> normalised cross-correlation at lags -M..M
    band: float  #: the 99 % band of a white residual's correlation, +-band


@dataclass(frozen=True)
class ResidualAnalysis:
    """The findings on every channel of an update's final residual."""

    channels: tuple[ChannelFinding, ...]
    max_lag: int  #: lags of the correlation tests [samples]
    curves: tuple[CorrelationCurves, ...] = ()  #: time channels' correlations, for the figure
    frequency_residuals: dict = field(default_factory=dict)  #: frequency channel -> (f [Hz], z complex or None)

    @property
    def noise_known(self) -> bool:
        """Every channel's noise is known (the level test is made on all)."""
        return bool(self.channels) and all(c.noise_rms is not None for c in self.channels)

    @property
    def tested(self) -> bool:
        """Some test could be made: a known noise level, or a time channel's correlation with its inputs."""
        return any(c.noise_rms is not None or c.input_correlation_p for c in self.channels)

    @property
    def explained(self) -> bool:
        """Every channel is explained to its noise (and something was tested)."""
        return self.tested and all(c.explained for c in self.channels)

    @property
    def white(self) -> bool:
        """No time channel's residual is found coloured."""
        return all(c.white is not False for c in self.channels)

    def misfits(self) -> tuple[ChannelFinding, ...]:
        """The channels the model does not explain, worst first."""
        bad = [c for c in self.channels if not c.explained]
        return tuple(sorted(bad, key=lambda c: -(c.sigmas_above if c.sigmas_above is not None else math.inf)))


def analyse_residuals(residual: np.ndarray, blocks: tuple[ResidualBlock, ...], *, max_lag: int = MAX_LAG,
                      alpha: float = ALPHA, sigma_limit: float = SIGMA_LIMIT) -> ResidualAnalysis:
    """The findings on each block of ``residual`` (module docstring).

    Parameters
    ----------
    residual : ndarray
        The update's final residual vector.
    blocks : tuple of ResidualBlock
        Its measured channels, with their noise where known.
    max_lag : int
        M, the lags of the correlation tests [samples].
    alpha : float
        Significance of the correlation tests over all channels and inputs together.
    sigma_limit : float
        A channel's sum of squares this many standard deviations above its chi-square mean is a misfit.

    Returns
    -------
    ResidualAnalysis
        One finding per block, the correlation curves of the time blocks.
    """
    tests = sum(max(len(b.inputs), 1) for b in blocks if b.domain == "time") or 1
    significance = alpha / tests
    findings, curves, spectra = [], [], {}
    for block in blocks:
        e = block.values(residual)
        if block.domain == "time":
            finding, curve = _time_channel(block, np.asarray(e, dtype=float), max_lag=max_lag,
                                           significance=significance, sigma_limit=sigma_limit)
            curves.append(curve)
        else:
            finding = _frequency_channel(block, np.asarray(e, dtype=complex), sigma_limit=sigma_limit)
            spectra[block.name] = (block.axis, None if block.noise_sd is None else e / block.noise_sd)
        findings.append(finding)
    return ResidualAnalysis(channels=tuple(findings), max_lag=max_lag, curves=tuple(curves),
                            frequency_residuals=spectra)


def _level(sum_squares: float, entries: int, noise_sd: float | None) -> float | None:
    """Standard deviations of a chi-square sum of ``entries`` squared noises above its mean (None: unknown)."""
    if noise_sd is None or noise_sd <= 0 or entries == 0:
        return None
    return (sum_squares / noise_sd**2 - entries) / math.sqrt(2.0 * entries)


def _time_channel(block: ResidualBlock, e: np.ndarray, *, max_lag: int, significance: float,
                  sigma_limit: float) -> tuple[ChannelFinding, CorrelationCurves]:
    n = e.size
    dt = float(block.axis[1] - block.axis[0]) if block.axis.size > 1 else 1.0
    m = int(min(max_lag, n // 4))
    centred = e - e.mean()
    var = float(centred @ centred) / n
    sd = math.sqrt(var) if var > 0 else 1.0
    auto = np.array([centred[k:] @ centred[:n - k] / (n * sd**2) for k in range(m + 1)])
    ljung_box = n * (n + 2) * float(np.sum(auto[1:] ** 2 / (n - np.arange(1, m + 1))))
    whiteness_p = float(scipy.stats.chi2.sf(ljung_box, m)) if m > 0 else None
    cross = {name: _cross_correlation(centred, np.asarray(u, dtype=float), m) for name, u in block.inputs.items()}
    p_value, coherent_band = _input_coherence(centred, block.inputs, fs=1.0 / dt)
    p_values = {name: p_value for name in block.inputs} if p_value is not None else {}
    band = 2.5758293035489004 / math.sqrt(n)  # two-sided 99 %
    lags = np.arange(-m, m + 1) * dt
    rms = float(np.sqrt(np.mean(e**2)))
    finding = ChannelFinding(name=block.name, domain="time", samples=n, rms=rms, noise_rms=block.noise_sd,
                             sigmas_above=_level(float(e @ e), n, block.noise_sd), whiteness_p=whiteness_p,
                             input_correlation_p=p_values,
                             band_hz=coherent_band if coherent_band is not None and p_value is not None
                             and p_value < significance else _time_band(e, dt, block.noise_sd),
                             significance=significance, sigma_limit=sigma_limit)
    return finding, CorrelationCurves(name=block.name, lags_s=lags, autocorrelation=auto, cross_correlation=cross,
                                      band=band)


def _cross_correlation(e: np.ndarray, u: np.ndarray, m: int) -> np.ndarray:
    """Normalised r_eu at lags -m..m: r(k) = sum_t e(t) u(t - k) / (N s_e s_u) (k > 0: the input before)."""
    n = e.size
    uc = u - u.mean()
    su, se = float(np.sqrt(uc @ uc / n)), float(np.sqrt(e @ e / n))
    if su == 0 or se == 0:
        return np.zeros(2 * m + 1)
    return np.array([(e[k:] @ uc[:n - k] if k >= 0 else e[:n + k] @ uc[-k:]) for k in range(-m, m + 1)]) / (n * se * su)


def _input_coherence(e: np.ndarray, inputs, *, fs: float) -> tuple[float | None, tuple[float, float] | None]:
    """(p-value of "the residual is independent of the inputs", the band [Hz] of the bins where it is not):
    the count of the inputs' band's bins whose multiple coherence with the inputs is significant at 1 %
    (module docstring). (None, None) without inputs or with too short a record."""
    names = [n for n, u in inputs.items() if np.ptp(np.asarray(u)) > 0]
    q, n = len(names), e.size
    if q == 0 or n < 64:
        return None, None
    segment = int(2 ** np.floor(np.log2(max(n / 8, 32))))
    segments = 1 + (n - segment) // (segment // 2)
    averages = segments / 1.06  # a Hann window's half-overlapping segments are not quite independent
    if averages <= q + 1:
        return None, None
    u = np.array([np.asarray(inputs[k], dtype=float) for k in names])
    opts = dict(fs=fs, nperseg=segment, noverlap=segment // 2, detrend="constant")
    f, s_uu = scipy.signal.csd(u[:, None, :], u[None, :, :], **opts)
    _, s_ue = scipy.signal.csd(u, e[None, :], **opts)
    _, s_ee = scipy.signal.welch(e, **opts)
    power = np.real(np.einsum("iif->f", s_uu))
    band = (power > 1e-6 * power.max()) & (f > 0)
    s_uu, s_ue, s_ee, f = np.moveaxis(s_uu[..., band], -1, 0), s_ue[:, band].T, s_ee[band], f[band]
    if f.size < 4:
        return None, None
    explained = np.real(np.einsum("ka,kab,kb->k", np.conj(s_ue), np.linalg.pinv(s_uu), s_ue))
    gamma2 = np.clip(explained / np.where(s_ee > 0, s_ee, np.inf), 0.0, 1.0)
    significant = scipy.stats.beta.sf(gamma2, q, averages - q) < 0.01
    # neighbouring bins of a Hann window are correlated: count them as half as many independent ones
    count, bins = int(significant.sum()) // 2, f.size // 2
    p = float(scipy.stats.binom.sf(count - 1, bins, 0.01)) if count > 0 else 1.0
    if not significant.any():
        return p, None
    # the band holding the middle 80 % of the residual's power that the inputs explain, at the significant bins
    # (a few bins significant by chance anywhere must not stretch it)
    share = np.where(significant, explained, 0.0)
    cumulative = np.cumsum(share) / np.sum(share)
    return p, (float(f[np.searchsorted(cumulative, 0.1)]), float(f[min(np.searchsorted(cumulative, 0.9), f.size - 1)]))


def _time_band(e: np.ndarray, dt: float, noise_sd: float | None) -> tuple[float, float] | None:
    """The band [Hz] holding the middle 80 % of the residual's power above the noise's (all of it without a
    known noise); None for a residual at the noise."""
    if e.size < 16:
        return None
    fs = 1.0 / dt
    f, p = scipy.signal.welch(e, fs=fs, nperseg=min(e.size, 1024))
    excess = p - (0.0 if noise_sd is None else noise_sd**2 / (fs / 2))
    excess = np.clip(excess, 0.0, None)
    if noise_sd is not None and np.sum(excess) <= 0.1 * np.sum(p):
        return None
    cumulative = np.cumsum(excess) / np.sum(excess)
    return float(f[np.searchsorted(cumulative, 0.1)]), float(f[np.searchsorted(cumulative, 0.9)])


def _frequency_channel(block: ResidualBlock, e: np.ndarray, *, sigma_limit: float) -> ChannelFinding:
    f = block.axis
    n = e.size
    rms = float(np.sqrt(np.mean(np.abs(e) ** 2) / 2))
    noise = block.noise_sd
    sigmas = _level(float(np.sum(np.abs(e) ** 2)), 2 * n, noise)
    band = None
    z2 = np.abs(e) ** 2 / (2 * (noise if noise else rms or 1.0) ** 2)
    excess = np.clip(z2 - (1.0 if noise else 0.0), 0.0, None)
    if np.sum(excess) > 0 and (noise is None or sigmas is not None and sigmas > sigma_limit):
        cumulative = np.cumsum(excess) / np.sum(excess)
        band = (float(f[np.searchsorted(cumulative, 0.1)]), float(f[min(np.searchsorted(cumulative, 0.9), n - 1)]))
    weights = np.ones(n) if block.line_weights is None else np.asarray(block.line_weights, dtype=float)
    return ChannelFinding(name=block.name, domain="frequency", samples=n, rms=rms, noise_rms=noise, sigmas_above=sigmas,
                          band_hz=band, delay_s=_delay(f, e.imag, weights), sigma_limit=sigma_limit)


def _delay(f: np.ndarray, weighted_phase: np.ndarray, weights: np.ndarray) -> float | None:
    """The delay tau [s] of phase = a - 2 pi f tau fitted (weighted least squares) to the phase error [rad] of
    each line (``weighted_phase`` / ``weights``: the cost's entries are weight x phase), where the trend is
    significant (t > 5) and explains at least a quarter of the phase error's weighted variance; else None."""
    ok = weights > 0
    if ok.sum() < 8 or np.ptp(f[ok]) <= 0:
        return None
    f, w, y = f[ok], weights[ok], weighted_phase[ok]
    x = np.column_stack([w, -2 * np.pi * f * w])  # the model a - 2 pi f tau, weighted like the entries
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    resid = y - x @ coef
    s2 = float(resid @ resid) / max(f.size - 2, 1)
    cov = s2 * np.linalg.pinv(x.T @ x)
    t = abs(coef[1]) / math.sqrt(cov[1, 1]) if cov[1, 1] > 0 else 0.0
    mean = float(w @ y) / float(w @ w)
    centred = y - w * mean
    explained = 1.0 - float(resid @ resid) / float(centred @ centred) if centred @ centred > 0 else 0.0
    return float(coef[1]) if t > 5 and explained > 0.25 else None


def residual_figure(analysis: ResidualAnalysis, path: str | Path, *, max_channels: int = 8) -> Path | None:
    """The ``resid`` figure (PNG): per time channel the residual's autocorrelation and its cross-correlation
    with each input, with the 99 % band of white noise; per frequency channel its log-magnitude and phase
    errors over their noise. The channels shown are the worst ``max_channels``. None when there is nothing
    to draw."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mace_fmu.util.atomic import atomic_path

    order = {c.name: k for k, c in enumerate(analysis.misfits())}
    time = sorted(analysis.curves, key=lambda c: order.get(c.name, len(order)))[:max_channels]
    freq = sorted(analysis.frequency_residuals.items(), key=lambda kv: order.get(kv[0], len(order)))
    freq = freq[:max(0, max_channels - len(time))]
    rows = len(time) + len(freq)
    if rows == 0:
        return None
    fig, axes = plt.subplots(rows, 2, figsize=(11, 2.3 * rows + 0.6), squeeze=False)
    for ax, c in zip(axes, time):
        m = c.autocorrelation.size - 1
        ax[0].bar(c.lags_s[m:], c.autocorrelation, width=0.6 * (c.lags_s[1] - c.lags_s[0]) if m else 1.0)
        ax[0].axhspan(-c.band, c.band, color="0.85")
        ax[0].set_title(f"{c.name}: autocorrelation of the residual", fontsize=9)
        for name, r in c.cross_correlation.items():
            ax[1].plot(c.lags_s, r, ".-", label=name, markersize=3)
        ax[1].axhspan(-c.band, c.band, color="0.85")
        ax[1].set_title(f"{c.name}: cross-correlation with the inputs", fontsize=9)
        if c.cross_correlation:
            ax[1].legend(fontsize=7)
        ax[1].set_xlabel("lag [s]", fontsize=8)
    for ax, (name, (f, z)) in zip(axes[len(time):], freq):
        if z is None:
            ax[0].text(0.5, 0.5, "noise unknown", ha="center", transform=ax[0].transAxes)
            continue
        for a, part, label in ((ax[0], z.real, "log magnitude"), (ax[1], z.imag, "phase")):
            a.plot(f, part, lw=0.7)
            a.axhspan(-2, 2, color="0.85")
            a.set_title(f"{name}: {label} error / its noise", fontsize=9)
            a.set_xlabel("frequency [Hz]", fontsize=8)
    fig.tight_layout()
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90, format="png")
    plt.close(fig)
    return path
