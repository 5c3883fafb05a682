"""Cost sensitivities (thesis eq. 4.12, 4.14) and the linearised cost of the cost-sensitivity method (eq. 4.13)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping, Sequence

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.costs import Cost
from mace_fmu.updating.engine.inclusion import Evaluator
from mace_fmu.updating.engine.linear_model import LinearModel
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
                       difference: str = "forward",
                       limits: Mapping[str, tuple[float, float]] | None = None) -> CostSensitivities:
    """j0 of ``base_model`` and the perturbed models of each name: ``difference="forward"`` one per name
    (``base`` with that value times 1 + ``relative_step``; the N + 1 evaluations of the cost-sensitivity
    method), ``"central"`` two (times 1 +- ``relative_step``; 2N + 1 evaluations, error O(step^2) instead of
    O(step)). ``limits``: name -> [low, high] no model may be asked for (an FMU's declared range); a step that
    would leave it is taken on the other side of the base value (one-sided there)."""
    if difference not in ("forward", "central"):
        raise MaceError(f"difference must be 'forward' or 'central', got {difference!r}")
    j0 = cost.residual(base_model)
    wanted = (1.0,) if difference == "forward" else (1.0, -1.0)

    def inside(n: str, sign: float) -> bool:
        low, high = (limits or {}).get(n, (-np.inf, np.inf))
        return low <= base[n] * (1.0 + sign * relative_step) <= high

    # per name: the signs of its steps; 0 stands for the base point itself (j0, no run)
    signs = []
    for n in names:
        steps = tuple(s if inside(n, s) else (0.0 if difference == "central" and inside(n, -s) else -s)
                      for s in wanted)
        signs.append(steps)
    points = [({**base, n: base[n] * (1.0 + sign * relative_step)}, k) for k, n in enumerate(names)
              for sign in signs[k] if sign != 0.0]

    def residual(values: Mapping[str, float]) -> np.ndarray:
        return cost.residual(perturbed(values))

    results: list[list[np.ndarray]] = [[] for _ in names]
    for k, (j, (_, owner)) in enumerate(zip(runner(residual, [p for p, _ in points]), points)):
        results[owner].append(j)
        if progress is not None:
            progress(Step("cost sensitivities", k + 1, len(points), detail=names[owner]))
    columns = []
    for steps, runs in zip(signs, results):
        at = iter(runs)
        values = [j0 if sign == 0.0 else next(at) for sign in steps]
        if len(steps) == 1:
            columns.append(steps[0] * (values[0] - j0) / relative_step)
        else:
            columns.append((values[0] - values[1]) / ((steps[0] - steps[1]) * relative_step))
    matrix = np.column_stack(columns) if columns else np.zeros((len(j0), 0))
    return CostSensitivities(names=tuple(names), base=dict(base), j0=j0, matrix=matrix, relative_step=relative_step,
                             perturbation=perturbation if difference == "forward" else
                             f"{perturbation}, central differences".lstrip(", "))
