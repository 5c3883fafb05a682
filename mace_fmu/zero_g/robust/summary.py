"""The sweep on one screen (text) and in one picture (histogram of the costs, cost against the top driver)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from mace_fmu.util.atomic import save_figure_atomic
from mace_fmu.zero_g.robust.box import short_name
from mace_fmu.zero_g.robust.design import RobustDesign
from mace_fmu.zero_g.robust.sweep import SweepResult


def _db(ratio: float) -> str:
    return f"{20 * np.log10(ratio):+.1f} dB" if np.isfinite(ratio) and ratio > 0 else "-"


def format_summary(result: SweepResult, design: RobustDesign | None = None, *, drivers: int = 3) -> str:
    """The one-screen summary: loop, design, box, runs, fraction stable, worst cost, the modes that drive it.

    Parameters
    ----------
    result : SweepResult
        The sweep.
    design : RobustDesign, optional
        The compensator's design, to state it.
    drivers : int
        How many of the modes that drive the worst cost to name.

    Returns
    -------
    str
        The summary, a few lines.
    """
    loop, box = result.loop, result.box
    nominal, open_cost = result.nominal.cost_rms_v, result.open_loop.cost_rms_v
    lines = [f"loop: {loop.control_input} <- K <- {loop.measurement}; disturbance {loop.disturbance_amplitude_v:g} V "
             f"square wave on {loop.disturbance_input}, {loop.disturbance_periods} x {loop.disturbance_period_s:g} s, "
             f"then 0; {loop.duration_s:g} s at {1e3 * loop.step_s:g} ms"]
    if design is not None:
        lines.append(f"design: nominal model ({design.channels.nstates} states), balanced truncation to "
                     f"{design.reduced.nstates} states; LQG rho = {design.weights.rho:g}, theta = {design.weights.theta:g}"
                     f"; Tustin at {1e3 * loop.step_s:g} ms")
    span = ", ".join(f"{short_name(n)} {100 * (lo / nom - 1):+.1f}/{100 * (hi / nom - 1):+.1f} %"
                     for n, nom, lo, hi in zip(box.names, box.nominal, box.low, box.high))
    lines.append(f"box: {len(box.names)} parameters: {span}")
    corners, samples = result.stable("corner"), result.stable("sample")
    lines.append(f"runs: nominal, open loop, {2 * len(box.names)} one-at-a-time, {corners.size} corners of "
                 f"{', '.join(map(short_name, result.critical)) or '-'}, {samples.size} Monte Carlo samples (uniform, seed {result.seed})")
    lines.append(f"cost = RMS of {loop.measurement} [V]: open loop {open_cost:.4f}, nominal {nominal:.4f} "
                 f"({_db(nominal / open_cost)})")
    every = np.concatenate([corners, samples])
    lines.append(f"stable (growth test, last period RMS / previous <= {loop.growth_limit:g}): corners "
                 f"{int(corners.sum())}/{corners.size}, samples {int(samples.sum())}/{samples.size}; fraction "
                 f"{every.mean() if every.size else float('nan'):.3f}")
    sample_costs = result.costs("sample")
    finite = sample_costs[np.isfinite(sample_costs)]
    if finite.size:
        lines.append(f"sample costs: median {np.median(finite):.4f}, 95th percentile {np.percentile(finite, 95):.4f}, "
                     f"max {finite.max():.4f}")
    worst = result.worst
    run, point = result.runs[worst], result.points[worst]
    first_sample = next((i for i, p in enumerate(result.points) if p.kind == "sample"), worst)
    where = point.note if point.kind == "corner" else f"sample {worst - first_sample} (0-based)"
    lines.append(f"worst: {run.cost_rms_v:.4f} ({100 * (run.cost_rms_v / nominal - 1):+.1f} % on nominal, "
                 f"{_db(run.cost_rms_v / open_cost)} on open loop), {point.kind} {where}"
                 + ("" if run.stable else " - UNSTABLE"))
    lines.append("drivers (cost change with it alone at its low / high bound; Spearman rank correlation with the "
                 "cost over the samples):")
    for d in result.drivers[:drivers]:
        lines.append(f"  {d.name:26s} {d.label:24s} low {d.low_change_percent:+6.1f} %  high {d.high_change_percent:+6.1f} %"
                     f"  rho {d.rank_correlation:+.2f}")
    return "\n".join(lines)


def sweep_figure(result: SweepResult, *, path: str | Path, title: str = "") -> Path:
    """PNG: histogram of the sample costs with the corners, nominal and open loop marked; cost against the
    strongest driver's value."""
    fig = Figure(figsize=(11, 4.5))  # no pyplot: the caller's matplotlib backend stays as it is
    FigureCanvasAgg(fig)
    left, right = fig.subplots(1, 2)
    samples, corners = result.costs("sample"), result.costs("corner")
    finite = samples[np.isfinite(samples)]
    if finite.size:
        left.hist(finite, bins=max(5, min(30, finite.size // 4)), color="#4A7FC1", alpha=0.8,
                  label=f"{finite.size} samples")
    for c in corners[np.isfinite(corners)]:
        left.axvline(c, color="#D1495B", lw=0.8, alpha=0.6)
    left.axvline(np.nan, color="#D1495B", lw=0.8, label=f"{corners.size} corners")  # legend entry only
    left.axvline(result.nominal.cost_rms_v, color="k", lw=1.5, ls="--", label="nominal")
    left.axvline(result.open_loop.cost_rms_v, color="0.5", lw=1.5, ls=":", label="open loop")
    left.set_xlabel(f"cost: RMS {result.loop.measurement} [V]")
    left.set_ylabel("samples")
    left.legend(fontsize=8)
    top = result.drivers[0]
    k = result.box.names.index(top.name)
    rows = [i for i, p in enumerate(result.points) if p.kind == "sample"]
    x = np.array([result.points[i].values[k] for i in rows])
    stable = result.stable("sample")
    right.scatter(x[stable], samples[stable], s=12, color="#4A7FC1", label="stable")
    if (~stable).any():  # an unstable run's cost may be inf: drawn at the top of the stable ones
        top_cost = float(finite.max()) if finite.size else result.nominal.cost_rms_v
        shown = np.where(np.isfinite(samples[~stable]), samples[~stable], 1.05 * top_cost)
        right.scatter(x[~stable], shown, s=20, marker="x", color="#D1495B", label="unstable")
    right.axhline(result.nominal.cost_rms_v, color="k", lw=1.0, ls="--")
    right.set_xlabel(f"{top.name} ({top.label})")
    right.set_ylabel("cost [V]")
    right.set_title(f"strongest driver: Spearman rho {top.rank_correlation:+.2f}", fontsize=9)
    right.legend(fontsize=8)
    for ax in (left, right):
        ax.grid(True, alpha=0.3)
    fig.suptitle(title or "LQG compensator on the 0-g FMU over the parameter bounds")
    fig.tight_layout()
    return save_figure_atomic(fig, path, dpi=110)
