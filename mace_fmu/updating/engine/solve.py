"""The update: stages of parameters, each an outer loop around scipy.optimize.least_squares.

Parameters are moved in relative terms, x_i = p_i / p_i,start - 1. The cost vector is augmented
with a penalty on the changes from the start (thesis eq. 4.18), j~ = [j; W x], W diagonal, with
the thesis's own reading of its weighting: a change of gamma_i percent in parameter i costs 1 %
of the stage's initial cost j0^T j0, W_ii = sqrt(0.01 j0^T j0) / (gamma_i / 100). gamma_i is the
change one would call plausible (``Bounds.gamma_percent``: 10 % for a modulus, more for a
damping ratio).

Inclusion ``cost-sensitivity`` (the thesis's MACE update): about the current point, j0 from a
full model and Delta J from N perturbed models (``perturbation``: full re-solves or reanalysis),
then least squares on the linearised cost j0 + Delta J dx; the sensitivities are recomputed about
the new point until no parameter moves by more than ``tolerance`` (the thesis's outer loop).
The other inclusions give least squares the model itself (finite-difference Jacobian with step
``relative_step``), about a base point that is moved the same way until converged. The outer
loop is a trust region: it moves to the new point when the full model there costs less
(augmented cost), else it stays and halves the largest step it allows, reusing the
linearisation (with a finite ``initial_radius`` the first steps are bounded too, the bound doubling
while the linearisation predicts the fall well); a label flip or a mispairing far from the base cannot drag the update away.
Stages run in order and the whole sequence ``rounds`` times (thesis 4.5: physical parameters,
then delays, then damping, repeated).

Each stage's outer loop ends on a stated test, and says which (:class:`StageOutcome`): the
largest parameter step below ``tolerance``, the relative fall of the cost below
``cost_tolerance``, first-order optimality (the cost's gradient with respect to relative changes
below ``gradient_tolerance`` times the cost), or no better point within ``tolerance`` of the base
(the trust region shrank to nothing). Reaching ``max_outer`` is only a safety net, and it is
reported as not converged. A stage that meets its test with a parameter at a bound has converged:
the data ask for a value outside the allowed range, which the outcome names (``at_bounds``); that
parameter's interval is then one-sided.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Literal, Mapping, Sequence, TypeVar

import numpy as np
from scipy.optimize import least_squares

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.costs import Cost, scalar_cost
from mace_fmu.updating.engine.inclusion import ModelFamily, check_inclusion, evaluator
from mace_fmu.updating.engine.sensitivity import CostSensitivities, cost_sensitivities
from mace_fmu.util.progress import ProgressCallback, Step
from mace_fmu.util.threads import single_blas_thread

Method = Literal["cost-sensitivity", "full", "reanalysis", "modal-sensitivity"]
M = TypeVar("M")  #: the models the family makes and the cost reads


@dataclass(frozen=True)
class Bounds:
    """Allowed range [SI] of one update parameter, and its plausible change for the penalty."""

    lower: float  #: lowest allowed value [SI]
    upper: float  #: highest allowed value [SI]
    gamma_percent: float = 10.0  #: a change this large costs 1 % of the initial cost (eq. 4.18)


@dataclass(frozen=True)
class Stage:
    """One step of the sequence: which parameters move together, against which cost.

    ``cost`` (default: the update's cost) lets a stage see only what its parameters can fix,
    e.g. frequencies for stiffnesses (thesis 4.3: stiffness and damping updated separately).
    """

    name: str  #: stage name in reports
    parameters: tuple[str, ...]  #: parameters this stage updates
    cost: Cost[Any] | None = None  #: the cost of this stage (None: the update's)


@dataclass(frozen=True)
class UpdateSettings:
    """How the update runs (see the module docstring)."""

    #: the inclusion: "cost-sensitivity" (the thesis's), "full", "reanalysis" or "modal-sensitivity"
    method: Method = "cost-sensitivity"
    perturbation: Literal["full", "reanalysis"] = "reanalysis"  #: perturbed models of the cost-sensitivity method
    relative_step: float = 1e-2  #: finite-difference step, relative to each parameter
    difference: Literal["forward", "central"] = "forward"  #: of the cost-sensitivity method's sensitivities
    penalty: bool = True  #: augment the cost with eq. 4.18's penalty
    tolerance: float = 1e-3  #: largest relative parameter change that ends the outer loop
    cost_tolerance: float = 1e-6  #: relative fall of the (augmented) cost that ends it
    gradient_tolerance: float = 1e-6  #: ``|d cost / d relative change| / cost`` that ends it (first-order optimality)
    max_outer: int = 6  #: safety net only: a stage that reaches it has not converged
    rounds: int = 1  #: repeats of the stage sequence (fewer when a round moves nothing)
    loss: str = "linear"  #: least_squares loss ("soft_l1", "huber", "cauchy", "arctan": outliers count less)
    loss_scale: float = 1.0  #: residual size beyond which the loss treats an entry as an outlier (f_scale)
    #: trust region: the largest relative step of a stage's first outer iteration (inf: none until a step fails);
    #: a finite radius doubles after a step the linearisation predicted well and halves after one it did not
    initial_radius: float = math.inf


@dataclass(frozen=True)
class Iteration:
    """One outer iteration of one stage."""

    stage: str
    round: int
    outer: int
    cost_before: float  #: j^T j of the stage's cost, full model, at the base point
    cost_predicted: float  #: what the linearised / included model predicted for the new point
    cost_after: float  #: j^T j of the full model at the new point
    improved: bool  #: the new point is the best of the stage so far (augmented cost, eq. 4.18)
    values: Mapping[str, float]  #: the new point (the stage's parameters)
    largest_change: float  #: max |relative change| from the base point
    seconds: float
    sensitivities: CostSensitivities | None = None


@dataclass(frozen=True)
class StageOutcome:
    """How one stage's outer loop ended."""

    stage: str
    round: int
    outer_iterations: int
    converged: bool
    reason: str  #: the test that ended it, e.g. "largest step 2.1e-04 < tolerance 1e-03"
    at_bounds: tuple[tuple[str, str], ...] = ()  #: (parameter, "lower" or "upper") it ended at


@dataclass(frozen=True)
class UpdateResult:
    """Where the update ended and how it got there."""

    start: Mapping[str, float]  #: parameter values at the start
    values: Mapping[str, float]  #: every parameter the update touched, final
    initial_cost: float  #: j^T j of the full model at the start
    final_cost: float  #: j^T j of the full model at the end
    initial_residual: np.ndarray  #: residual vector j at the start
    final_residual: np.ndarray  #: residual vector j at the end
    history: tuple[Iteration, ...]  #: every outer iteration, in order
    settings: UpdateSettings  #: the settings the update ran with
    seconds: float  #: wall time of the whole update [s]
    stage_seconds: Mapping[str, float] = field(default_factory=dict)  #: wall time per stage [s]
    outcomes: tuple[StageOutcome, ...] = ()  #: how each stage of each round ended

    @property
    def converged(self) -> bool:
        """Whether the last round's stages all ended on a convergence test (not on the iteration cap)."""
        last = max((o.round for o in self.outcomes), default=0)
        return all(o.converged for o in self.outcomes if o.round == last)

    @property
    def at_bounds(self) -> tuple[tuple[str, str], ...]:
        """(parameter, "lower" or "upper") of each parameter the last round ended at a bound of."""
        last = max((o.round for o in self.outcomes), default=0)
        return tuple(b for o in self.outcomes if o.round == last for b in o.at_bounds)

    @property
    def reasons(self) -> tuple[str, ...]:
        """Why each stage of the last round ended, "stage: reason"."""
        last = max((o.round for o in self.outcomes), default=0)
        return tuple(f"{o.stage}: {o.reason}" for o in self.outcomes if o.round == last)

    @property
    def reduction(self) -> float:
        """Fraction of the initial cost removed (0.25: 25 % lower)."""
        return 1.0 - self.final_cost / self.initial_cost if self.initial_cost > 0 else 0.0


def _check(names: Sequence[str], start: Mapping[str, float], bounds: Mapping[str, Bounds]) -> None:
    for n in names:
        if n not in start:
            raise MaceError(f"update parameter {n!r} has no start value; known: {', '.join(sorted(start))}")
        if n not in bounds:
            raise MaceError(f"update parameter {n!r} has no bounds")
        b, v = bounds[n], start[n]
        if not (math.isfinite(v) and v != 0.0):
            raise MaceError(f"update parameter {n!r}: start value must be finite and nonzero (changes are relative), "
                            f"got {v}")
        if not b.lower < b.upper:
            raise MaceError(f"update parameter {n!r}: lower bound {b.lower} must be below upper bound {b.upper}")
        if not b.lower < v < b.upper:
            raise MaceError(f"update parameter {n!r}: bounds [{b.lower:g}, {b.upper:g}] exclude its start value {v:g}")


@single_blas_thread
def update(family: ModelFamily[M], cost: Cost[M], *, start: Mapping[str, float], stages: Sequence[Stage],
           bounds: Mapping[str, Bounds], settings: UpdateSettings = UpdateSettings(), runner: Callable = map,
           progress: ProgressCallback | None = None) -> UpdateResult:
    """Update ``start`` (every parameter value the family needs) stage by stage to lower ``cost``.

    Parameters
    ----------
    family : ModelFamily
        Parameter values -> model (the FE model, the sample problem, an FMU); the ``reanalysis`` perturbations
        and inclusion of a family without a modal basis (not a
        :class:`~mace_fmu.updating.engine.inclusion.ReanalysisFamily`) are full solves.
    cost : Cost
        The residual vector j whose j^T j is lowered (modal, frequency response, time response, ...), of the
        family's models.
    start : mapping of str to float
        Every parameter value the family needs [SI]; the stages' parameters move from these, in
        relative terms.
    stages : sequence of Stage
        Which parameters move together, in order (and, optionally, against which cost).
    bounds : mapping of str to Bounds
        Allowed range [SI] and plausible change of every stage parameter.
    settings : UpdateSettings
        Method, differences, stopping tests, trust region, rounds.
    runner : callable
        ``map``-like function the perturbed models' evaluations go to (``map`` or a Dask runner).
    progress : callable, optional
        Called with a :class:`~mace_fmu.util.progress.Step` as the work advances.

    Returns
    -------
    UpdateResult
        The final values, the cost before and after, every outer iteration with its sensitivities,
        and how each stage ended (:attr:`UpdateResult.converged`, :attr:`UpdateResult.reasons`).

    Raises
    ------
    MaceError
        A stage parameter without a start value or bounds, a start outside its bounds or zero, an
        unknown method, modal sensitivities of a family without modes.
    """
    t_start = time.perf_counter()
    names_all = sorted({n for s in stages for n in s.parameters})
    _check(names_all, start, bounds)
    if settings.method not in ("cost-sensitivity", "full", "reanalysis", "modal-sensitivity"):
        raise MaceError(f"method must be cost-sensitivity, full, reanalysis or modal-sensitivity, got {settings.method!r}")
    if settings.method != "cost-sensitivity":
        check_inclusion(family, settings.method)
    model = family.full(start)
    j_start = cost.residual(model)
    initial = scalar_cost(j_start)
    values = dict(start)
    history: list[Iteration] = []
    outcomes: list[StageOutcome] = []
    stage_seconds: dict[str, float] = {}
    for rnd in range(settings.rounds):
        before = dict(values)
        for stage in stages:
            t_stage = time.perf_counter()
            problem = _StageProblem.of(family=family, cost=stage.cost or cost, stage=stage, round=rnd, start=start,
                                       bounds=bounds, settings=settings, runner=runner, progress=progress)
            values, model, outcome = _run_stage(problem, values, model, history)
            outcomes.append(outcome)
            stage_seconds[stage.name] = stage_seconds.get(stage.name, 0.0) + time.perf_counter() - t_stage
        if max(abs(values[n] / before[n] - 1.0) for n in names_all) < settings.tolerance:
            break  # a whole round moved nothing: the sequence has converged
    touched = {n: values[n] for n in names_all}
    j_final = cost.residual(model)
    return UpdateResult(start=dict(start), values=touched, initial_cost=initial, final_cost=scalar_cost(j_final),
                        initial_residual=j_start, final_residual=j_final, history=tuple(history), settings=settings,
                        seconds=time.perf_counter() - t_start, stage_seconds=stage_seconds, outcomes=tuple(outcomes))


@dataclass(frozen=True)
class _StageProblem:
    """What stays fixed while one stage runs: the family, cost and settings, the stage's parameters and
    their box in relative changes x = value / start - 1."""

    family: ModelFamily[Any]
    cost: Cost[Any]
    stage: Stage
    round: int
    settings: UpdateSettings
    runner: Callable
    progress: ProgressCallback | None
    names: tuple[str, ...]
    start_values: np.ndarray  #: relative changes are measured from the update's start values
    lower: np.ndarray  #: bounds in relative change
    upper: np.ndarray
    gamma: np.ndarray  #: eq. 4.18's plausible relative change of each parameter

    @classmethod
    def of(cls, *, family: ModelFamily[Any], cost: Cost[Any], stage: Stage, round: int, start: Mapping[str, float],
           bounds: Mapping[str, Bounds], settings: UpdateSettings, runner: Callable,
           progress: ProgressCallback | None) -> _StageProblem:
        names = tuple(stage.parameters)
        s = np.array([start[n] for n in names])
        lo = np.array([bounds[n].lower for n in names]) / s - 1.0
        hi = np.array([bounds[n].upper for n in names]) / s - 1.0
        return cls(family=family, cost=cost, stage=stage, round=round, settings=settings, runner=runner,
                   progress=progress, names=names, start_values=s,
                   lower=np.minimum(lo, hi), upper=np.maximum(lo, hi),  # a negative start value flips the interval
                   gamma=np.array([bounds[n].gamma_percent for n in names]) / 100.0)

    def relative(self, values: Mapping[str, float]) -> np.ndarray:
        """x of ``values``: the stage's parameters as relative changes from the start."""
        return np.array([values[n] for n in self.names]) / self.start_values - 1.0

    def point(self, values: Mapping[str, float], x: np.ndarray) -> dict[str, float]:
        """``values`` with the stage's parameters set to relative changes ``x``."""
        return {**values, **{n: float(v) for n, v in zip(self.names, self.start_values * (1.0 + x))}}


def _run_stage(problem: _StageProblem, values: dict[str, float], model: Any, history: list[Iteration]
               ) -> tuple[dict[str, float], Any, StageOutcome]:
    """The outer loop of one stage from ``values`` (``model``: the full model there); returns the new
    values, the full model at them and how the loop ended."""
    family, cost, stage, settings = problem.family, problem.cost, problem.stage, problem.settings
    names, lo, hi, rnd = list(problem.names), problem.lower, problem.upper, problem.round
    j_base = cost.residual(model)
    w = np.sqrt(0.01 * scalar_cost(j_base)) / problem.gamma if settings.penalty else np.zeros(len(names))
    best = (_total(j_base, w, problem.relative(values), settings), values, model)

    def point(x: np.ndarray) -> dict[str, float]:
        return problem.point(values, x)

    radius = settings.initial_radius  # trust region: largest step in x from the base point
    linearisation = None  # (x_base, fun builder) kept while the base point does not move
    reason, converged, outer = f"iteration cap reached (max_outer = {settings.max_outer})", False, -1
    for outer in range(settings.max_outer):
        t0 = time.perf_counter()
        x_base = problem.relative(values)
        lo_t, hi_t = np.maximum(lo, x_base - radius), np.minimum(hi, x_base + radius)
        if linearisation is None:
            linearisation = _linearise(problem, values, model, x_base, w, point)
            optimality = _first_order_optimality(linearisation[2], x_base, lo, hi, best[0])
            if optimality is not None and optimality < settings.gradient_tolerance:
                reason, converged = (f"first-order optimality: |d cost / d relative change| = {optimality:.1e} x cost "
                                     f"< {settings.gradient_tolerance:g}"), True
                break
        sens, solve, _ = linearisation
        sol, predicted = solve(lo_t, hi_t)
        new = point(sol.x)
        new_model = family.full(new)
        j_new = cost.residual(new_model)
        change = float(np.max(np.abs((1.0 + sol.x) / (1.0 + x_base) - 1.0)))
        total = _total(j_new, w, sol.x, settings)
        improved = total < best[0]
        history.append(Iteration(stage=stage.name, round=rnd, outer=outer, cost_before=scalar_cost(j_base),
                                 cost_predicted=predicted, cost_after=scalar_cost(j_new), improved=improved,
                                 values={n: new[n] for n in names}, largest_change=change,
                                 seconds=time.perf_counter() - t0, sensitivities=sens))
        fall = (best[0] - total) / best[0] if best[0] > 0 else 0.0
        if change < settings.tolerance or settings.method == "full":
            if improved:
                best = (total, new, new_model)
            reason, converged = (f"largest step {change:.1e} < tolerance {settings.tolerance:g}" if change <
                                 settings.tolerance else "one least-squares solve on the full model"), True
            break
        if improved:
            radius = _next_radius(radius, step=float(np.max(np.abs(sol.x - x_base))), before=scalar_cost(j_base),
                                  predicted=predicted, after=scalar_cost(j_new))
            best = (total, new, new_model)
            values, model, j_base = new, new_model, j_new
            linearisation = None
            if fall < settings.cost_tolerance:
                reason, converged = f"cost fell by {fall:.1e} of itself < {settings.cost_tolerance:g}", True
                break
        else:  # the linearisation promised more than the model gives: shorter steps from the same point
            radius = 0.5 * float(np.max(np.abs(sol.x - x_base)))
            if radius < settings.tolerance:
                reason, converged = (f"no lower cost within a step of {radius:.1e} of the point (tolerance "
                                     f"{settings.tolerance:g})"), True
                break
    x_end = problem.relative(best[1])
    # least_squares keeps its answer strictly inside the box, and may stop short of it: within the update's
    # own precision (tolerance, as a relative change) is at the bound
    at_bounds = tuple((n, "lower" if abs(x - a) <= abs(x - b) else "upper")
                      for n, x, a, b in zip(names, x_end, lo, hi) if min(abs(x - a), abs(x - b)) <= settings.tolerance)
    if at_bounds:
        reason = f"{reason}; {', '.join(f'{n} at its {side} bound' for n, side in at_bounds)}"
    return best[1], best[2], StageOutcome(stage=stage.name, round=rnd, outer_iterations=outer + 1,
                                          converged=converged, reason=reason, at_bounds=at_bounds)


def _next_radius(radius: float, *, step: float, before: float, predicted: float, after: float) -> float:
    """The trust radius after an accepted step (unbounded stays unbounded): doubled when the step reached the
    radius and the model fell by more than 3/4 of the predicted fall, halved below the step when by less than 1/4."""
    if not math.isfinite(radius) or before <= predicted:
        return radius
    agreement = (before - after) / (before - predicted)
    if agreement > 0.75 and step >= 0.99 * radius:
        return 2.0 * radius
    if agreement < 0.25:
        return 0.5 * step
    return radius


def _first_order_optimality(gradient, x_base: np.ndarray, lo: np.ndarray, hi: np.ndarray, cost: float) -> float | None:
    """max |projected gradient| / cost at ``x_base``: the cost's first-order change per unit relative
    change of any one parameter, as a fraction of the cost (None when the method has no Jacobian)."""
    if gradient is None or cost <= 0:
        return None
    g = np.array(gradient(x_base), dtype=float)
    g[(x_base <= lo) & (g > 0)] = 0.0  # at a bound, a gradient pointing out of the box is no defect
    g[(x_base >= hi) & (g < 0)] = 0.0
    return float(np.max(np.abs(g))) / cost


def _linearise(problem: _StageProblem, values: dict[str, float], model, x_base: np.ndarray, w: np.ndarray,
               point: Callable[[np.ndarray], dict[str, float]]):
    """(sensitivities or None, solve(lo, hi) -> (least-squares solution, predicted j^T j), gradient or None)
    about ``values``."""
    family, cost, stage, settings = problem.family, problem.cost, problem.stage, problem.settings
    names, runner, progress = list(problem.names), problem.runner, problem.progress
    if settings.method == "cost-sensitivity":
        perturbed = evaluator(family, settings.perturbation, values, names)
        limits = {n: (float(s * (1.0 + a)), float(s * (1.0 + b)))
                  for n, s, a, b in zip(names, problem.start_values, problem.lower, problem.upper)}
        sens = cost_sensitivities(cost, base_model=model, perturbed=perturbed, base=values, names=names,
                                  relative_step=settings.relative_step, perturbation=settings.perturbation,
                                  runner=runner, progress=progress, difference=settings.difference, limits=limits)
        scale = 1.0 / (1.0 + x_base)  # the sensitivities are per unit relative change of the base value
        jac = np.vstack([sens.matrix * scale[None, :], np.diag(w)])

        def linearised(x):
            return np.concatenate([sens.linearised((x - x_base) * scale), w * x])

        def solve(lo, hi):
            sol = least_squares(linearised, np.clip(x_base, lo, hi), jac=lambda x: jac, bounds=(lo, hi), loss=settings.loss,
                                f_scale=settings.loss_scale, x_scale=1.0)
            return sol, scalar_cost(sens.linearised((sol.x - x_base) * scale))

        def gradient(x):  # of the augmented cost [j; W x]^T [j; W x]
            return 2.0 * jac.T @ linearised(x)

        return sens, solve, gradient
    model_at = evaluator(family, settings.method, values, names, relative_step=settings.relative_step, runner=runner)
    calls = [0]

    def fun(x):
        calls[0] += 1
        if progress is not None:
            progress(Step(f"{stage.name}: least squares on the {settings.method} model", calls[0], calls[0]))
        return np.concatenate([cost.residual(model_at(point(x))), w * x])

    def solve(lo, hi):
        sol = least_squares(fun, np.clip(x_base, lo, hi), bounds=(lo, hi), loss=settings.loss,
                            f_scale=settings.loss_scale, diff_step=settings.relative_step, x_scale="jac")
        return sol, scalar_cost(sol.fun[:-len(names)])

    return None, solve, None


def _total(j: np.ndarray, w: np.ndarray, x: np.ndarray, settings: UpdateSettings) -> float:
    """What least_squares minimises: the loss summed over the augmented cost [j; W x] (eq. 4.18)."""
    c = settings.loss_scale
    z = (np.concatenate([j, w * x]) / c) ** 2
    rho = {"linear": lambda z: z, "soft_l1": lambda z: 2.0 * (np.sqrt(1.0 + z) - 1.0),
           "huber": lambda z: np.where(z <= 1.0, z, 2.0 * np.sqrt(z) - 1.0), "cauchy": np.log1p,
           "arctan": np.arctan}[settings.loss]
    return float(c**2 * np.sum(rho(z)))
