"""Parameter selection (thesis 4.2.2): orthogonality (eq. 4.15) and strength (eq. 4.16) tests, a rule, figures."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

import numpy as np

from mace_fmu.updating.engine.sensitivity import CostSensitivities


@dataclass(frozen=True)
class SelectionRule:
    """Which candidates to keep: strong enough, and not a near copy of a stronger one.

    A parameter is weak when its strength is below ``min_relative_strength`` times the largest;
    two parameters are aligned when |cos| of their sensitivities is at least ``max_alignment``,
    and then only the stronger is kept. ``groups`` are kept or dropped together (the thesis keeps
    the three active-strut moduli as one part): a group stays when any member passes.
    """

    min_relative_strength: float = 0.1
    max_alignment: float = 0.99
    groups: tuple[tuple[str, ...], ...] = ()


@dataclass(frozen=True)
class Selection:
    """The two tests, what the rule keeps and why."""

    names: tuple[str, ...]
    orthogonality: np.ndarray  #: |DJbar^T DJbar| (eq. 4.15), 1 on the diagonal
    strength: np.ndarray  #: |j0^T DJ_i| (eq. 4.16), scaled by the allowed perturbations when given
    keep: tuple[str, ...]
    reasons: Mapping[str, str]  #: name -> why it is kept or dropped

    def table(self) -> str:
        """One line per candidate: strength (relative to the largest), strongest alignment, verdict."""
        top = max(float(self.strength.max()), 1e-300)
        lines = [f"{'#':>2s} {'parameter':28s} {'strength':>9s} {'rel.':>6s}  {'most aligned with':28s} {'|cos|':>5s}  "
                 "verdict"]
        for k, name in enumerate(self.names):
            other = self.orthogonality[k].copy()
            other[k] = -1.0
            j = int(np.argmax(other)) if len(self.names) > 1 else k
            verdict = "keep" if name in self.keep else "drop"
            lines.append(f"{k + 1:2d} {name:28s} {self.strength[k]:9.3g} {self.strength[k] / top:6.3f}  "
                         f"{self.names[j]:28s} {other[j]:5.2f}  {verdict}: {self.reasons[name]}")
        return "\n".join(lines)


def select_parameters(sensitivities: CostSensitivities, *, rule: SelectionRule = SelectionRule(),
                      allowed_perturbation: Mapping[str, float] | None = None) -> Selection:
    """Run both tests on the cost sensitivities and apply ``rule``.

    ``allowed_perturbation`` (relative, e.g. 0.1 for +-10 %) scales each sensitivity before the
    strength test, so a parameter that may move far counts for more (thesis 4.2.2, last paragraph).
    """
    names = sensitivities.names
    dj = sensitivities.matrix
    norms = np.linalg.norm(dj, axis=0)
    unit = dj / np.where(norms > 0, norms, 1.0)
    ortho = np.abs(unit.T @ unit)
    scale = np.array([(allowed_perturbation or {}).get(n, 1.0) for n in names])
    strength = np.abs(sensitivities.j0 @ dj) * scale
    top = max(float(strength.max(initial=0.0)), 1e-300)
    reasons: dict[str, str] = {}
    passed = set()
    for k, n in enumerate(names):
        rel = strength[k] / top
        if norms[k] == 0.0:
            reasons[n] = "no effect on the cost at all"
        elif rel < rule.min_relative_strength:
            reasons[n] = f"weak: {rel:.3f} of the strongest (< {rule.min_relative_strength})"
        else:
            passed.add(n)
            reasons[n] = f"strong: {rel:.3f} of the strongest"
    for group in rule.groups:  # all or none
        members = [n for n in group if n in names]
        if any(n in passed for n in members):
            for n in members:
                if n not in passed:
                    passed.add(n)
                    reasons[n] += f"; kept with its group ({', '.join(members)})"
    order = sorted(passed, key=lambda n: -strength[names.index(n)])
    keep: list[str] = []
    for n in order:
        k = names.index(n)
        twin = next((m for m in keep if ortho[k, names.index(m)] >= rule.max_alignment), None)
        grouped = any(n in g and twin in g for g in rule.groups)
        if twin is not None and not grouped:
            reasons[n] = f"aligned with the stronger {twin} (|cos| {ortho[k, names.index(twin)]:.3f} >= " \
                         f"{rule.max_alignment}): not separately identifiable"
            continue
        keep.append(n)
    return Selection(names=tuple(names), orthogonality=ortho, strength=strength,
                     keep=tuple(n for n in names if n in keep), reasons=reasons)


def plot_selection(selection: Selection, *, orthogonality_png: str | Path, strength_png: str | Path,
                   title: str = "") -> tuple[Path, Path]:
    """Figures like thesis Figs. 4.11 (orthogonality, as a 3-D bar chart) and 4.12 (strength bars)."""
    from matplotlib.figure import Figure

    from mace_fmu.util.atomic import save_figure_atomic

    n = len(selection.names)
    ticks = np.arange(1, n + 1)
    fig = Figure(figsize=(7.5, 6.0))
    ax = fig.add_subplot(projection="3d")
    xx, yy = np.meshgrid(ticks, ticks)
    ax.bar3d(xx.ravel() - 0.4, yy.ravel() - 0.4, np.zeros(n * n), 0.8, 0.8, selection.orthogonality.ravel(),
             color="tab:blue", shade=True)
    ax.set_xticks(ticks)
    ax.set_yticks(ticks)
    ax.set_zlim(0, 1)
    ax.set_xlabel("parameter")
    ax.set_ylabel("parameter")
    ax.set_zlabel("|cos|")
    ax.set_title(f"Orthogonality test (eq. 4.15){' - ' + title if title else ''}")
    legend = "\n".join(f"{k}: {name}" for k, name in zip(ticks, selection.names))
    fig.text(0.01, 0.01, legend, fontsize=7, family="monospace", va="bottom")
    save_figure_atomic(fig, orthogonality_png, dpi=110)
    fig = Figure(figsize=(7.5, 4.5))
    ax = fig.add_subplot()
    colours = ["tab:green" if nm in selection.keep else "tab:gray" for nm in selection.names]
    ax.bar(ticks, selection.strength / max(selection.strength.max(), 1e-300), color=colours)
    ax.set_xticks(ticks, [f"{k}\n{nm}" for k, nm in zip(ticks, selection.names)], rotation=90, fontsize=7)
    ax.set_ylabel("|j0^T dJ_i| / max")
    ax.set_title(f"Strength test (eq. 4.16): green kept{' - ' + title if title else ''}")
    fig.tight_layout()
    save_figure_atomic(fig, strength_png, dpi=110)
    return Path(orthogonality_png), Path(strength_png)
