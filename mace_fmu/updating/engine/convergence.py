"""Whether an update converged, and how far its cost ended above the measurement noise.

Two questions a test engineer asks before signing an updated parameter set:

1. Did the update stop on a convergence test, or on its iteration cap? Each stage says so
   (:class:`~mace_fmu.updating.engine.solve.StageOutcome`). A fit that meets its test with a parameter at a
   bound has converged, and says which: the data ask for a value outside the allowed range, so that
   parameter has no two-sided interval (``strict`` counts it as not converged).
2. For the time-domain cost, is the fit as good as the noise allows? At the true parameters the
   cost j^T j is a sum of squared noise samples: with each output's noise variance sigma_o^2
   (normalised by the output's RMS, as the cost is), its mean is sum_o N_o sigma_o^2 and its
   standard deviation sqrt(2 sum_o N_o sigma_o^4) (chi-square). A final cost several standard
   deviations above that mean is a fit that stopped short, whatever the tests said.

The noise is estimated from the data when the inputs are band-limited: above the inputs' band
a linear structure's outputs hold only noise, so the mean of each output's Welch spectrum there,
times the Nyquist frequency, is its (white) noise variance. Or it is given, as a fraction of each
output's RMS.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.signal

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.costs import TimeResponseCost
from mace_fmu.updating.engine.solve import UpdateResult

#: a final cost more than this many standard deviations above the noise floor has not converged
SIGMA_LIMIT = 3.0
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


def time_noise_floor(cost: TimeResponseCost, *, noise_rms_fraction: float | None = None) -> NoiseFloor | None:
    """The noise floor of a time cost: from ``noise_rms_fraction`` (noise RMS / output RMS, every output)
    when given, else estimated above the inputs' band; None when the inputs fill the band (no quiet
    part of the spectrum to measure the noise in)."""
    data = cost.data
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
    data = cost.data
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
    tests = inner.tests if isinstance(inner, SeveralTests) else (inner,)
    if not all(isinstance(c, TimeResponseCost) for c in tests):
        return ""
    for c in tests:
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
    if not isinstance(cost, SeveralTests) or not all(isinstance(c, TimeResponseCost) for c in cost.tests):
        return None
    floors = [time_noise_floor(c, noise_rms_fraction=noise_rms_fraction) for c in cost.tests]
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
    """Whether an update may be trusted as an optimum, and why."""

    converged: bool  #: every stage ended on a convergence test (and, ``strict``, no parameter at a bound)
    reasons: tuple[str, ...]  #: the stages' stopping tests, and the noise-floor verdict when there is one
    final_cost: float  #: j^T j at the end
    noise_floor: NoiseFloor | None  #: the time cost's expected value from the data's noise (None: not a time cost)
    at_bounds: tuple[tuple[str, str], ...] = ()  #: (parameter, "lower" or "upper") the fit ended at

    def bound_note(self) -> str:
        """What ending at a bound means, naming the parameters ("" without any)."""
        if not self.at_bounds:
            return ""
        which = ", ".join(f"{n} at its {side} bound" for n, side in self.at_bounds)
        return (f"{which}: the data ask for a value outside the allowed range, so the value is the bound and its "
                "interval is one-sided (no two-sided confidence interval); widen the bound or fix the parameter if "
                "that value is not plausible")

    def summary(self) -> str:
        """One line for the terminal."""
        head = "converged" if self.converged else "NOT CONVERGED"
        note = f" (with {self.bound_note()})" if self.at_bounds else ""
        return f"{head}{note}: " + "; ".join(self.reasons)

    def to_toml(self) -> str:
        """The report as TOML (``convergence.toml`` beside the parameters)."""
        def q(text: str) -> str:
            return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'

        lines = ["# mace-fmu: did the update converge, and how far above the noise did it end?", "",
                 f"converged = {'true' if self.converged else 'false'}",
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
        return "\n".join(lines) + "\n"


def convergence_report(result: UpdateResult, *, noise_floor: NoiseFloor | None = None,
                       sigma_limit: float = SIGMA_LIMIT, strict: bool = False,
                       missing_floor: str = "") -> ConvergenceReport:
    """The verdict on ``result``: its stages' tests, and (with a noise floor) the final cost against it.

    Parameters
    ----------
    result : UpdateResult
        The update to judge.
    noise_floor : NoiseFloor, optional
        The time cost expected at the truth (:func:`noise_floor`); without one only the stopping
        tests and bounds decide.
    sigma_limit : float
        A final cost more than this many standard deviations above the floor has not converged.
    strict : bool
        Count a parameter ending at a bound as not converged (by default it is named, not failed).
    missing_floor : str
        Why a time cost's noise floor could not be found (:func:`missing_noise_floor`): the fit is then not
        held to the noise, which is said, and the update does not count as converged.

    Returns
    -------
    ConvergenceReport
        ``converged`` and the reasons, for the terminal line and ``convergence.toml``.
    """
    reasons = list(result.reasons)
    converged = result.converged and not (strict and result.at_bounds)
    if strict and result.at_bounds:
        reasons.append("--strict: a parameter at a bound counts as not converged")
    if noise_floor is not None:
        k = noise_floor.sigmas_above(result.final_cost)
        verdict = (f"final cost {result.final_cost:.6g} is {k:+.1f} standard deviations from the noise floor "
                   f"{noise_floor.expected_cost:.6g} +- {noise_floor.standard_deviation:.3g}")
        if k > sigma_limit:
            converged = False
            verdict += f" (more than {sigma_limit:g} above: the fit stopped short of the optimum)"
        reasons.append(verdict)
    elif missing_floor:
        converged = False
        reasons.append(missing_floor)
    return ConvergenceReport(converged=converged, reasons=tuple(reasons), final_cost=result.final_cost,
                             noise_floor=noise_floor, at_bounds=result.at_bounds)
