"""The verdict on an update: converged or not, and whether the model then explains the data to their noise.

Two questions a test engineer asks before signing an updated parameter set, and three verdicts:

1. Did the update stop on a convergence test, or on its iteration cap? Each stage says so
   (:class:`~mace_fmu.updating.engine.solve.StageOutcome`). A stage that ended on its cap has **not
   converged** (exit 3), and that is the only way not to converge. A fit that meets its test with a
   parameter at a bound has converged, and says which: the data ask for a value outside the allowed
   range, so that parameter's interval is one-sided (``strict`` counts it as not converged).
2. Having converged, does the model **explain the data to their noise**, or is there a **model error**?
   At the true parameters of a right model the residual is the measurement noise: its sum of squares
   is chi-square about the noise's (for the time cost: each output's noise variance sigma_o^2, normalised
   by the output's RMS as the cost is, mean sum_o N_o sigma_o^2, standard deviation
   sqrt(2 sum_o N_o sigma_o^4)), and it is uncorrelated with the inputs. A converged fit whose residual is
   far above the noise, or correlated with the inputs (:mod:`~mace_fmu.updating.engine.residuals`, the
   ``resid`` tests), is a finding about the model, not a failure of the fit: the model (a missing element,
   mode or sensor dynamics; or a local minimum of the cost: start elsewhere to tell them apart) cannot
   reproduce the data, by how much and where is said. Its intervals then come from the residuals
   themselves (:mod:`~mace_fmu.updating.engine.uncertainty`). ``strict`` makes a model error exit 3.

The noise is estimated from the data when the inputs are band-limited: above the inputs' band
a linear structure's outputs hold only noise, so the mean of each output's Welch spectrum there,
times the Nyquist frequency, is its (white) noise variance. Or it is given, as a fraction of each
output's RMS.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.signal

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.costs import TimeResponseCost
from mace_fmu.updating.engine.residual_blocks import ResidualBlock
from mace_fmu.updating.engine.residuals import RATIO_LIMIT, ResidualAnalysis, analyse_residuals
from mace_fmu.updating.engine.solve import UpdateResult

#: a final cost more than this many standard deviations above the noise floor is not explained by the noise
SIGMA_LIMIT = 3.0
Verdict = Literal["explained", "model error", "not converged", "untested"]
#: the inputs' band ends where their summed spectrum falls below this fraction of its peak
BAND_EDGE = 1e-6


@dataclass(frozen=True)
class NoiseFloor:
    """The time cost expected at the true parameters, from the measurement noise alone."""

    expected_cost: float  #: mean of j^T j at the truth
    standard_deviation: float  #: of j^T j at the truth (chi-square)
    noise_rms_percent: dict  #: output -> noise RMS [% of the output's RMS]
    source: str  #: how the noise was found

    def sigmas_above(self, cost: float) -> float:
        """How many standard deviations ``cost`` lies above the expected cost."""
        return (cost - self.expected_cost) / self.standard_deviation if self.standard_deviation > 0 else math.inf


def time_noise_floor(cost: TimeResponseCost, *, noise_rms_fraction: float | None = None,
                     band_hz: tuple[float, float] | None = None) -> NoiseFloor | None:
    """The noise floor of a time cost: from ``noise_rms_fraction`` (noise RMS / output RMS, every output)
    when given, else estimated above the inputs' band; None when the inputs fill the band (no quiet
    part of the spectrum to measure the noise in). With a band-pass, ``band_hz`` (default: the cost's own,
    ``cost.band_hz``), the noise is that of the filtered error, read outside the band
    (:func:`~mace_fmu.updating.engine.band.band_noise_floor`)."""
    band = band_hz if band_hz is not None else cost.band_hz
    if band is not None:
        from mace_fmu.updating.engine.band import band_noise_floor

        found = band_noise_floor(cost, band_hz=band, noise_rms_fraction=noise_rms_fraction)
        return None if found is None else NoiseFloor(**found)
    data = cost.compared
    outputs = list(data.outputs)
    n = len(data.times_s)
    if noise_rms_fraction is not None:
        if not (math.isfinite(noise_rms_fraction) and noise_rms_fraction > 0):
            raise MaceError(f"noise RMS must be a positive fraction of the output RMS, got {noise_rms_fraction!r}")
        ratio = {o: noise_rms_fraction**2 for o in outputs}
        source = f"given: {100 * noise_rms_fraction:g} % of each output's RMS"
    else:
        f, edge, fs = _input_band(cost)
        if _no_quiet_band(f, edge, fs):
            return None
        segment = min(n, 1024)
        quiet = (f > 1.25 * edge) & (f < 0.95 * fs / 2)
        ratio = {}
        for o in outputs:
            y = np.asarray(data.outputs[o], dtype=float)
            _, p = scipy.signal.welch(y, fs=fs, nperseg=segment)
            variance = float(np.mean(p[quiet])) * fs / 2  # white noise: flat density over [0, fs/2]
            ratio[o] = variance / float(np.mean(y**2))
        source = (f"estimated from the outputs' spectra above the inputs' band ({edge:.4g} Hz; "
                  f"{1.25 * edge:.4g}-{0.95 * fs / 2:.4g} Hz)")
    if not cost.normalise:
        raise MaceError("the noise floor is defined for the normalised time cost")
    expected = sum(n * r for r in ratio.values())
    std = math.sqrt(sum(2 * n * r**2 for r in ratio.values()))
    return NoiseFloor(expected_cost=expected, standard_deviation=std,
                      noise_rms_percent={o: 100 * math.sqrt(r) for o, r in ratio.items()}, source=source)


def _no_quiet_band(f: np.ndarray, edge: float, fs: float) -> bool:
    quiet = (f > 1.25 * edge) & (f < 0.95 * fs / 2)
    return bool(edge > 0.7 * fs / 2 or quiet.sum() < 5)


def _input_band(cost: TimeResponseCost) -> tuple[np.ndarray, float, float]:
    """(Welch frequencies [Hz], the inputs' band edge [Hz], the sample rate [Hz]) of a time cost's data."""
    data = cost.compared
    fs = 1.0 / float(np.median(np.diff(data.times_s)))
    f, p_in = scipy.signal.welch(np.array(list(data.inputs.values())), fs=fs, nperseg=min(len(data.times_s), 1024),
                                 axis=-1)
    total = p_in.sum(axis=0)
    return f, float(f[np.flatnonzero(total > BAND_EDGE * total.max())].max()), fs


def missing_noise_floor(cost, *, noise_rms_fraction: float | None = None) -> str:
    """Why a time cost has no noise floor, with what to give instead ("" when it has one or is no time cost):
    the test that a fit ended at the noise is then not made, and a verdict without it is not a convergence."""
    from mace_fmu.updating.engine.costs import SeveralTests, WithPriors

    if noise_rms_fraction is not None:
        return ""
    inner = cost.cost if isinstance(cost, WithPriors) else cost
    given = inner.tests if isinstance(inner, SeveralTests) else (inner,)
    tests = [c for c in given if isinstance(c, TimeResponseCost)]
    if len(tests) != len(given):
        return ""
    for c in tests:
        if time_noise_floor(c) is None and c.band_hz is not None:
            return (f"noise-floor test not made: outside the band {c.band_hz[0]:g}-{c.band_hz[1]:g} Hz the record "
                    "leaves too few frequencies to read the outputs' noise in; give the noise (--noise-rms-percent "
                    "P: its RMS as P % of each output's RMS) so that the fit can be held to it")
        if time_noise_floor(c) is None:
            _, edge, fs = _input_band(c)
            nyquist = fs / 2
            return (f"noise-floor test not made: the inputs fill the band up to {edge:.4g} Hz (Nyquist "
                    f"{nyquist:.4g} Hz), which leaves the outputs no quiet band to measure their noise in; give "
                    "the noise (--noise-rms-percent P: its RMS as P % of each output's RMS) so that the fit can be "
                    "held to it")
    return ""


def noise_floor(cost, *, noise_rms_fraction: float | None = None) -> NoiseFloor | None:
    """The noise floor of a time cost, or of several tests' time costs summed with their weights
    (:class:`~mace_fmu.updating.engine.costs.SeveralTests`), priors included (each adds one residual of the
    noise's variance, :class:`~mace_fmu.updating.engine.costs.WithPriors`); None for other costs or when the
    noise is unknown."""
    from mace_fmu.updating.engine.costs import SeveralTests, WithPriors

    if isinstance(cost, WithPriors):
        inner = noise_floor(cost.cost, noise_rms_fraction=noise_rms_fraction)
        if inner is None:
            return None
        k, s2 = len(cost.priors), cost.noise_sd**2
        return NoiseFloor(expected_cost=inner.expected_cost + k * s2,
                          standard_deviation=math.sqrt(inner.standard_deviation**2 + 2 * k * s2**2),
                          noise_rms_percent=inner.noise_rms_percent,
                          source=f"{inner.source}; {k} prior(s)")
    if isinstance(cost, TimeResponseCost):
        return time_noise_floor(cost, noise_rms_fraction=noise_rms_fraction)
    if not isinstance(cost, SeveralTests):
        return None
    tests = [c for c in cost.tests if isinstance(c, TimeResponseCost)]
    if len(tests) != len(cost.tests):
        return None
    floors = [time_noise_floor(c, noise_rms_fraction=noise_rms_fraction) for c in tests]
    if any(f is None for f in floors):
        return None
    percent = {f"{label}: {o}": v for f, label in zip(floors, cost.labels) for o, v in f.noise_rms_percent.items()}
    return NoiseFloor(expected_cost=sum(w**2 * f.expected_cost for f, w in zip(floors, cost.weights)),
                      standard_deviation=math.sqrt(sum(w**4 * f.standard_deviation**2
                                                       for f, w in zip(floors, cost.weights))),
                      noise_rms_percent=percent, source="; ".join(f"{label}: {f.source}"
                                                                  for f, label in zip(floors, cost.labels)))


@dataclass(frozen=True)
class ConvergenceReport:
    """Whether an update converged, and whether the model explains the data to their noise."""

    converged: bool  #: every stage ended on a convergence test (and, ``strict``, no parameter at a bound)
    reasons: tuple[str, ...]  #: the stages' stopping tests, and the noise-floor comparison when there is one
    final_cost: float  #: j^T j at the end
    noise_floor: NoiseFloor | None  #: the time cost's expected value from the data's noise (None: not a time cost)
    at_bounds: tuple[tuple[str, str], ...] = ()  #: (parameter, "lower" or "upper") the fit ended at
    residuals: ResidualAnalysis | None = None  #: the residual's channels: noise or misfit (None: no channels)
    sigma_limit: float = SIGMA_LIMIT  #: a final cost this many standard deviations above the noise floor is a misfit
    strict: bool = False  #: a model error counts as a failure (exit 3)
    untested_because: str = ""  #: why the residual could not be held to the noise ("" when it could)

    @property
    def above_noise_floor(self) -> bool:
        """The final cost lies more than ``sigma_limit`` standard deviations above the noise floor, and its RMS
        more than :data:`~mace_fmu.updating.engine.residuals.RATIO_LIMIT` times the floor's."""
        nf = self.noise_floor
        return (nf is not None and nf.sigmas_above(self.final_cost) > self.sigma_limit
                and self.final_cost > RATIO_LIMIT**2 * nf.expected_cost)

    @property
    def verdict(self) -> Verdict:
        """"not converged", "model error" (converged, the model does not explain the data to their noise),
        "explained" (converged, it does) or "untested" (converged; no noise and no input to test against)."""
        if not self.converged:
            return "not converged"
        if self.above_noise_floor or (self.residuals is not None and self.residuals.misfits()):
            return "model error"
        tested = self.noise_floor is not None or (self.residuals is not None and self.residuals.tested)
        return "explained" if tested else "untested"

    @property
    def failed(self) -> bool:
        """The exit status of the update is 3: not converged, or (``strict``) a model error."""
        return self.verdict == "not converged" or (self.strict and self.verdict == "model error")

    def bound_note(self) -> str:
        """What ending at a bound means, naming the parameters ("" without any)."""
        if not self.at_bounds:
            return ""
        which = ", ".join(f"{n} at its {side} bound" for n, side in self.at_bounds)
        return (f"{which}: the data ask for a value outside the allowed range, so the value is the bound and its "
                "interval is one-sided (no two-sided confidence interval); widen the bound or fix the parameter if "
                "that value is not plausible")

    def misfit_lines(self) -> list[str]:
        """One line per channel the model does not explain, worst first (the residual analysis's)."""
        return [c.text() for c in self.residuals.misfits()] if self.residuals is not None else []

    def headline(self) -> str:
        """The verdict in words, without the reasons."""
        bound = f" (with {self.bound_note()})" if self.at_bounds else ""
        if self.verdict == "not converged":
            return "NOT CONVERGED" + bound
        if self.verdict == "explained":
            return f"converged{bound}: the model explains the data to their noise"
        if self.verdict == "untested":
            return (f"converged{bound}; whether the model explains the data was not tested"
                    + (f" ({self.untested_because})" if self.untested_because else ""))
        ratio = self._worst_ratio()
        how = f" (residual RMS up to {ratio:.3g} x the noise's)" if ratio is not None else ""
        estimate = any(c.domain == "frequency" for c in (self.residuals.misfits() if self.residuals else ()))
        causes = ("a model error (an element, mode or sensor dynamics the model lacks), a local minimum of the cost "
                  "(start elsewhere to tell)" + (", or errors of the frequency-response estimate its coherence does "
                                                 "not show (leakage: longer segments)" if estimate else ""))
        return (f"converged{bound}, but the model does not explain the data to their noise{how}: {causes}; the "
                "intervals come from the residuals")

    def _worst_ratio(self) -> float | None:
        ratios = [c.rms_over_noise for c in (self.residuals.channels if self.residuals else ())
                  if c.rms_over_noise is not None]
        if self.noise_floor is not None and self.noise_floor.expected_cost > 0:
            ratios.append(math.sqrt(self.final_cost / self.noise_floor.expected_cost))
        return max(ratios) if ratios else None

    def summary(self) -> str:
        """One line for the terminal: the verdict and the stopping tests."""
        return f"{self.headline()}: " + "; ".join(self.reasons)

    def to_toml(self) -> str:
        """The report as TOML (``convergence.toml`` beside the parameters)."""
        def q(text: str) -> str:
            return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'

        def num(x: float | None) -> str:
            return "nan" if x is None or x != x else (repr(float(x)) if math.isfinite(x) else
                                                      ("inf" if x > 0 else "-inf"))

        lines = ["# mace-fmu: did the update converge, and does the model explain the data to their noise?", "",
                 f"verdict = {q(self.verdict)}", f"converged = {'true' if self.converged else 'false'}",
                 f"explained = {'true' if self.verdict == 'explained' else 'false'}",
                 f"model_error = {'true' if self.verdict == 'model error' else 'false'}",
                 f"headline = {q(self.headline())}",
                 "reasons = [" + ", ".join(q(r) for r in self.reasons) + "]", f"final_cost = {self.final_cost!r}"]
        if self.at_bounds:
            lines += ["", "[at_bounds]", *(f"{q(n)} = {q(side)}" for n, side in self.at_bounds),
                      "", "[at_bounds_note]", f"text = {q(self.bound_note())}"]
        if self.noise_floor is not None:
            nf = self.noise_floor
            lines += ["", "[noise_floor]", f"expected_cost = {nf.expected_cost!r}",
                      f"standard_deviation = {nf.standard_deviation!r}",
                      f"sigmas_above = {nf.sigmas_above(self.final_cost)!r}", f"source = {q(nf.source)}",
                      "noise_rms_percent = { " + ", ".join(f"{q(o)} = {v!r}" for o, v in nf.noise_rms_percent.items())
                      + " }"]
        for c in (self.residuals.channels if self.residuals is not None else ()):
            lines += ["", "[[channel]]", f"name = {q(c.name)}", f"domain = {q(c.domain)}",
                      f"explained = {'true' if c.explained else 'false'}", f"rms = {num(c.rms)}",
                      f"noise_rms = {num(c.noise_rms)}", f"rms_over_noise = {num(c.rms_over_noise)}",
                      f"sigmas_above = {num(c.sigmas_above)}", f"whiteness_p = {num(c.whiteness_p)}",
                      "correlated_inputs = [" + ", ".join(q(i) for i in c.correlated_inputs) + "]",
                      "input_correlation_p = { " + ", ".join(f"{q(i)} = {num(p)}"
                                                             for i, p in c.input_correlation_p.items()) + " }",
                      "band_hz = [" + (", ".join(num(x) for x in c.band_hz) if c.band_hz else "") + "]",
                      f"delay_s = {num(c.delay_s)}", f"text = {q(c.text())}"]
        return "\n".join(lines) + "\n"

    def to_json(self) -> dict:
        """The verdict's fields for ``summary.json``."""
        channels = [] if self.residuals is None else [
            {"name": c.name, "explained": c.explained, "rms_over_noise": c.rms_over_noise,
             "sigmas_above": c.sigmas_above, "white": c.white, "correlated_inputs": list(c.correlated_inputs),
             "band_hz": list(c.band_hz) if c.band_hz else None, "delay_s": c.delay_s, "text": c.text()}
            for c in self.residuals.channels]
        return {"verdict": self.verdict, "converged": self.converged, "explained": self.verdict == "explained",
                "model_error": self.verdict == "model error", "headline": self.headline(),
                "reasons": list(self.reasons), "final_cost": self.final_cost,
                "at_bounds": {n: side for n, side in self.at_bounds},
                "noise_floor_sigmas_above": (self.noise_floor.sigmas_above(self.final_cost)
                                             if self.noise_floor is not None else None),
                "channels": channels}


def blocks_with_noise(cost, noise: NoiseFloor | None) -> tuple[ResidualBlock, ...]:
    """The cost's measured channels (:func:`~mace_fmu.updating.engine.costs.residual_blocks`), each time channel
    with its noise from ``noise`` (by the floor's channel names; a frequency channel knows its own)."""
    from mace_fmu.updating.engine.costs import residual_blocks

    blocks = residual_blocks(cost)
    if noise is None:
        return blocks
    return tuple(b.with_noise(noise.noise_rms_percent[b.name] / 100.0)
                 if b.domain == "time" and b.name in noise.noise_rms_percent else b for b in blocks)


def convergence_report(result: UpdateResult, *, noise_floor: NoiseFloor | None = None,
                       sigma_limit: float = SIGMA_LIMIT, strict: bool = False, missing_floor: str = "",
                       cost=None) -> ConvergenceReport:
    """The verdict on ``result``: its stages' tests, the final cost against the noise floor, and (given the
    ``cost``) the residual analysis of every measured channel.

    Parameters
    ----------
    result : UpdateResult
        The update to judge.
    noise_floor : NoiseFloor, optional
        The time cost expected at the truth (:func:`noise_floor`).
    sigma_limit : float
        A final cost (or a channel's) more than this many standard deviations above its noise is a misfit.
    strict : bool
        Count a parameter ending at a bound as not converged and a model error as a failure (exit 3).
    missing_floor : str
        Why a time cost's noise floor could not be found (:func:`missing_noise_floor`): the residual's level
        is then not held to the noise, which is said; the correlation tests are still made.
    cost : Cost, optional
        The update's cost: its measured channels (``residual_blocks``) are analysed
        (:func:`~mace_fmu.updating.engine.residuals.analyse_residuals`); without it only the stopping tests,
        bounds and noise floor decide.

    Returns
    -------
    ConvergenceReport
        The verdict and its reasons, for the terminal, ``convergence.toml`` and ``summary.json``.
    """
    reasons = list(result.reasons)
    converged = result.converged and not (strict and result.at_bounds)
    if strict and result.at_bounds:
        reasons.append("--strict: a parameter at a bound counts as not converged")
    if noise_floor is not None:
        k = noise_floor.sigmas_above(result.final_cost)
        reasons.append(f"final cost {result.final_cost:.6g} is {k:+.1f} standard deviations from the noise floor "
                       f"{noise_floor.expected_cost:.6g} +- {noise_floor.standard_deviation:.3g}")
    elif missing_floor:
        reasons.append(missing_floor)
    blocks = blocks_with_noise(cost, noise_floor) if cost is not None else ()
    residuals = analyse_residuals(result.final_residual, blocks, sigma_limit=sigma_limit) if blocks else None
    why = missing_floor
    if not why and noise_floor is None and residuals is not None and not residuals.tested:
        why = "the data carry no noise (no coherence) and no inputs to correlate the residual with"
    return ConvergenceReport(converged=converged, reasons=tuple(reasons), final_cost=result.final_cost,
                             noise_floor=noise_floor, at_bounds=result.at_bounds, residuals=residuals,
                             sigma_limit=sigma_limit, strict=strict, untested_because=why if not noise_floor else "")
