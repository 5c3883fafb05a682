"""PNG figures of the Appendix A studies: cost contours (Figs. A.2-A.4), transfer functions (A.6-A.8)."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import matplotlib

matplotlib.use("Agg")  # files only: no display on CI or servers
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from mace_fmu.control_studies.stiffness_sensitivity import CostMinimum, SensitivityMap  # noqa: E402
from mace_fmu.util.atomic import atomic_path  # noqa: E402

#: contour levels of the normalised cost (1.1 is the thesis's "tolerable" boundary)
COST_LEVELS = (1.01, 1.02, 1.05, 1.1, 1.2, 1.5, 2.0, 3.0, 5.0, 10.0)


def save_figure(fig: plt.Figure, path: str | Path) -> Path:
    """Write ``fig`` as PNG to ``path`` atomically and close it; returns the path."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
    return Path(path)


def sensitivity_contour(cost_map: SensitivityMap, *, minima: Sequence[CostMinimum], title: str,
                        path: str | Path) -> Path:
    """Contours of J / J_opt over the design stiffnesses, k2 across and k1 up (as Figs. A.2-A.4)."""
    c = cost_map.normalised_cost
    fig, ax = plt.subplots(figsize=(6.4, 5.6))
    k2, k1 = np.meshgrid(cost_map.k2, cost_map.k1)
    unstable = ~np.isfinite(c)
    if unstable.any():
        ax.contourf(k2, k1, unstable.astype(float), levels=[0.5, 1.5], colors=["0.85"], hatches=["//"])
    finite = np.where(unstable, np.nan, c)
    lines = ax.contour(k2, k1, finite, levels=list(COST_LEVELS), cmap="viridis", linewidths=0.9)
    ax.clabel(lines, fmt="%g", fontsize=7)
    ax.plot(cost_map.actual.k2, cost_map.actual.k1, "r*", ms=11, label="actual system (J/J_opt = 1)")
    for m in minima[1:]:
        ax.plot(m.k2, m.k1, "kx", ms=9, mew=2)
        ax.annotate(f"local min {m.normalised_cost:.2f}", (m.k2, m.k1), textcoords="offset points",
                    xytext=(6, 6), fontsize=8)
    ax.set_xlabel("design-model k2 [N/m]")
    ax.set_ylabel("design-model k1 [N/m]")
    w = cost_map.weights
    ax.set_title(f"{title}\nrho = {w.rho:g}, theta = {w.theta:g}; hatched: unstable", fontsize=10)
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path)


def bode_overlay(responses: Mapping[str, np.ndarray], *, frequencies_hz: np.ndarray, title: str, ylabel: str,
                 path: str | Path, unit_line: bool = False) -> Path:
    """Magnitude and phase of complex responses on one frequency axis [Hz]; ``unit_line`` marks |.| = 1."""
    fig, (ax_m, ax_p) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True)
    for (label, h), style in zip(responses.items(), ("-", "--", ":", "-.")):
        ax_m.loglog(frequencies_hz, np.abs(h), style, label=label)
        ax_p.semilogx(frequencies_hz, np.degrees(np.unwrap(np.angle(h))), style)
    if unit_line:
        ax_m.axhline(1.0, color="0.5", lw=0.8)
    ax_m.set_ylabel(ylabel)
    ax_m.set_title(title, fontsize=10)
    ax_m.legend(fontsize=8)
    ax_m.grid(True, which="both", alpha=0.3)
    ax_p.set_ylabel("phase [deg]")
    ax_p.set_xlabel("frequency [Hz]")
    ax_p.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path)
