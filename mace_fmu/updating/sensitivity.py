"""Cost sensitivities (thesis eq. 4.12, 4.14) and the linearised cost of the cost-sensitivity method (eq. 4.13)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping, Sequence

import numpy as np

from mace_fmu.progress import ProgressCallback, Step
from mace_fmu.updating.costs import Cost
from mace_fmu.updating.inclusion import Evaluator
from mace_fmu.updating.model import LinearModel



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
                       runner: Callable = map, progress: ProgressCallback | None = None) -> CostSensitivities:
    """j0 of ``base_model`` and one perturbed model per name (``base`` with that value times
    1 + ``relative_step``), the N + 1 evaluations of the cost-sensitivity method."""
    j0 = cost.residual(base_model)
    points = [{**base, n: base[n] * (1.0 + relative_step)} for n in names]

    def residual(values: Mapping[str, float]) -> np.ndarray:
        return cost.residual(perturbed(values))

    columns = []
    for k, j in enumerate(runner(residual, points)):
        columns.append((j - j0) / relative_step)
        if progress is not None:
            progress(Step("cost sensitivities", k + 1, len(points), detail=names[k]))
    matrix = np.column_stack(columns) if columns else np.zeros((len(j0), 0))
    return CostSensitivities(names=tuple(names), base=dict(base), j0=j0, matrix=matrix, relative_step=relative_step,
                             perturbation=perturbation)
