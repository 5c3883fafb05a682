"""Transfer functions of Figures A.6-A.8 (plant, loop G K, compensator K), their crossover, poles and zeros."""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np

from mace_fmu.control_studies.reduced_order import THESIS_COSTS, ReducedOrderStudy
from mace_fmu.errors import MaceError
from mace_fmu.iomodel.frf import frequency_response

MODELS = ("full", "balanced", "updated")


def siso_response(system: ct.StateSpace, frequencies_hz: np.ndarray) -> np.ndarray:
    """Complex response of a single-input single-output system at ``frequencies_hz`` [Hz]."""
    return frequency_response(system, frequencies_hz)[:, 0, 0]


@dataclass(frozen=True)
class LoopShapes:
    """Responses at ``frequencies_hz`` of each model (full, balanced, updated)."""

    frequencies_hz: np.ndarray
    plants: dict[str, np.ndarray]  #: open-loop tip force -> tip displacement [m/N] (Fig. A.6)
    loops: dict[str, np.ndarray]  #: G_full(jw) K(jw) of each model's compensator (Fig. A.7)
    compensators: dict[str, np.ndarray]  #: K(jw), displacement -> force [N/m] (Fig. A.8)


def loop_shapes(study: ReducedOrderStudy, *, frequencies_hz: np.ndarray) -> LoopShapes:
    """The three figures' responses; the loop is -G K (u = K y, negative feedback), plotted as G K."""
    f = np.asarray(frequencies_hz, dtype=float)
    models = {"full": study.full, "balanced": study.balanced, "updated": study.updated}
    plants = {k: siso_response(m, f) for k, m in models.items()}
    comps = {k: siso_response(study.designs[k].compensator, f) for k in MODELS}
    loops = {k: -plants["full"] * comps[k] for k in MODELS}
    return LoopShapes(frequencies_hz=f, plants=plants, loops=loops, compensators=comps)


def dereverberated_crossover_hz(response: np.ndarray, frequencies_hz: np.ndarray, *,
                                window_decades: float = 0.5) -> float:
    """Highest frequency [Hz] where |response|, log-averaged over ``window_decades``, crosses 1.

    The moving average of log|L| over half a decade takes out the resonance-antiresonance
    excursions of a lightly damped loop and keeps its backbone (the dereverberated loop).
    ``frequencies_hz`` must be log-spaced.
    """
    f = np.asarray(frequencies_hz, dtype=float)
    steps = np.diff(np.log10(f))
    if not np.allclose(steps, steps[0], rtol=1e-6):
        raise MaceError("dereverberated crossover: frequencies must be log-spaced")
    half = max(1, int(round(0.5 * window_decades / steps[0])))
    log_mag = np.log10(np.abs(response))
    kernel = np.ones(2 * half + 1) / (2 * half + 1)
    smooth = np.convolve(np.pad(log_mag, half, mode="edge"), kernel, mode="valid")
    above = np.flatnonzero(smooth > 0.0)
    if not len(above) or above[-1] == len(f) - 1:
        return float("nan")
    k = above[-1]  # log-linear interpolation between k and k + 1
    t = smooth[k] / (smooth[k] - smooth[k + 1])
    return float(10.0 ** (np.log10(f[k]) + t * steps[0]))


@dataclass(frozen=True)
class Root:
    """A pole or zero: frequency [Hz], damping ratio (negative: right half-plane), real or a pair."""

    frequency_hz: float
    damping: float
    real: bool


def roots(values: np.ndarray) -> list[Root]:
    """Poles or zeros [rad/s] as Roots, one per pair, by frequency."""
    out = []
    for s in sorted(np.asarray(values), key=abs):
        if s.imag < 0:
            continue
        mag = abs(s)
        out.append(Root(frequency_hz=mag / (2 * np.pi), damping=-s.real / mag if mag else 1.0,
                        real=abs(s.imag) <= 1e-9 * max(mag, 1.0)))
    return out


def format_table(study: ReducedOrderStudy, *, crossover_hz: float, mode_frequencies_hz: np.ndarray,
                 length_m: float) -> str:
    """Table A.1 beside the thesis's, with the choices and the models' poles and zeros."""
    c, w = study.costs, study.weights
    lines = ["Reduced-order LQG (thesis A.2, Table A.1): cantilever, tip force -> tip displacement",
             f"  beam length {length_m:.4f} m ({length_m / 0.0254:.2f} in); modes [Hz]: "
             + ", ".join(f"{f:.1f}" for f in mode_frequencies_hz),
             f"  rho = theta = {w.rho:.4g}; dereverberated loop crossover {crossover_hz:.0f} Hz "
             f"(third mode {mode_frequencies_hz[2]:.0f} Hz)",
             "  Hankel singular values: " + ", ".join(f"{h:.3g}" for h in study.hankel_singular_values),
             f"  update: {study.iterations} BFGS iterations, {study.evaluations} cost evaluations ({_stop_reason(study)})",
             "",
             f"  {'':10s} {'J thesis':>10s} {'J ours':>11s} {'J/J_full thesis':>16s} {'J/J_full ours':>14s}"]
    for k in ("full", "balanced", "updated"):
        lines.append(f"  {k:10s} {THESIS_COSTS[k]:10.3g} {c[k]:11.4g} {THESIS_COSTS[k] / THESIS_COSTS['full']:16.3f} "
                     f"{c[k] / c['full']:14.3f}")
    lines.append("")
    for k, model in (("full", study.full), ("balanced", study.balanced), ("updated", study.updated)):
        for kind, values in (("poles", ct.poles(model)), ("zeros", ct.zeros(model))):
            text = ", ".join(f"{r.frequency_hz:.1f}{' real' if r.real else ''} ({r.damping:+.4f})"
                             for r in roots(values))
            lines.append(f"  {k:9s} {kind} [Hz (damping)]: {text or 'none'}")
    return "\n".join(lines) + "\n"


def _stop_reason(study) -> str:
    """Why the BFGS update stopped, in the study's terms rather than scipy's."""
    if "precision loss" in study.message:
        # the cost is accurate to ~1e-8 and its forward-difference gradient no better: BFGS stops where a
        # line search can no longer tell a descent; the cost has settled (2e-4 over the last 20
        # iterations), the parameters have not (a flat valley: README, A.2)
        return "stopped: the forward-difference gradient lost precision; the cost has settled, not the poles"
    if "Maximum number of iterations" in study.message:
        return "stopped at --max-iterations: not converged"
    return study.message
