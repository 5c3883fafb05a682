"""Cost sensitivities (thesis eq. 4.12, 4.14) and the linearised cost of the cost-sensitivity method (eq. 4.13)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping, Sequence

import numpy as np

from mace_fmu.updating.costs import Cost
from mace_fmu.updating.inclusion import Evaluator
from mace_fmu.updating.model import LinearModel
from mace_fmu.util.progress import ProgressCallback, Step


@dataclass(frozen=True)
class CostSensitivities:
    """j0 and Delta J: column i is (j_i - j0) / dx_i, dx_i the relative change of parameter i (eq. 4.12)."""

    names: tuple[str, ...]
    base: Mapping[str, float]  #: parameter values [SI] at which they were computed
    j0: np.ndarray
    matrix: np.ndarray  #: (len(j0), len(names)): per unit relative change of each parameter
    relative_step: float
    perturbation: str  #: how the perturbed models were made ("full" or "reanalysis")

    def linearised(self, x: np.ndarray) -> np.ndarray:
        """Eq. 4.13: j = j0 + Delta J x, x the relative changes from ``base``."""
        return self.j0 + self.matrix @ x


def cost_sensitivities(cost: Cost, *, base_model: LinearModel, perturbed: Evaluator, base: Mapping[str, float],
                       names: Sequence[str], relative_step: float = 1e-2, perturbation: str = "",
                       runner: Callable = map, progress: ProgressCallback | None = None,
                       difference: str = "forward") -> CostSensitivities:
    """j0 of ``base_model`` and the perturbed models of each name: ``difference="forward"`` one per name
    (``base`` with that value times 1 + ``relative_step``; the N + 1 evaluations of the cost-sensitivity
    method), ``"central"`` two (times 1 +- ``relative_step``; 2N + 1 evaluations, error O(step^2) instead of
    O(step))."""
    if difference not in ("forward", "central"):
        raise ValueError(f"difference must be 'forward' or 'central', got {difference!r}")
    j0 = cost.residual(base_model)
    signs = (1.0,) if difference == "forward" else (1.0, -1.0)
    points = [{**base, n: base[n] * (1.0 + sign * relative_step)} for n in names for sign in signs]

    def residual(values: Mapping[str, float]) -> np.ndarray:
        return cost.residual(perturbed(values))

    results = []
    for k, j in enumerate(runner(residual, points)):
        results.append(j)
        if progress is not None:
            progress(Step("cost sensitivities", k + 1, len(points), detail=names[k // len(signs)]))
    if difference == "forward":
        columns = [(j - j0) / relative_step for j in results]
    else:
        columns = [(results[2 * i] - results[2 * i + 1]) / (2.0 * relative_step) for i in range(len(names))]
    matrix = np.column_stack(columns) if columns else np.zeros((len(j0), 0))
    return CostSensitivities(names=tuple(names), base=dict(base), j0=j0, matrix=matrix, relative_step=relative_step,
                             perturbation=perturbation if difference == "forward" else
                             f"{perturbation}, central differences".lstrip(", "))
