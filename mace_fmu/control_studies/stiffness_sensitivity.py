"""Thesis A.1: LQG designed on a two-mass model with wrong stiffnesses, evaluated on the actual system.

The design model differs from the actual system (k1 = 0.75, k2 = 1.2 N/m) only in k1 and k2; each
compensator is closed around the actual system and its cost normalised by that of the compensator
designed on the actual system (so 1 is the global minimum, inf an unstable loop).

Unstated in the thesis, chosen here (see README, "Modelling for control"):
- theta = 1 for all three authorities: the thesis varies rho only, and its second minimum is
  stable for every authority, which needs a slow estimator (theta = rho, the dual choice, makes
  it unstable for moderate and high authority);
- rho = 100, 1e-2, 1e-3 (low, moderate, high), placed by the regulator's poles against the modes
  at 0.56 and 1.68 rad/s: at rho = 100 they stay at the open-loop frequencies (within 0.5 %);
  at 1e-2 the slow pair (1.59 rad/s) lies between the modes; at 1e-3 both pairs (2.27, 2.72
  rad/s) lie above the upper mode. rho = 0.1 is also "moderate" by this rule; 1e-2 is the one of
  the two whose map shows the thesis's k2 range (README gives both). Below 1e-4 the second
  minimum of the high-authority map is gone (the valley falls to the global minimum).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.optimize as so

from mace_fmu.control_studies.lqg import LqgWeights, closed_loop_cost, design_lqg, optimal_cost, regulator_poles
from mace_fmu.errors import MaceError
from mace_fmu.updating.sample.two_mass import Mass, TwoMassSystem

#: the three control authorities of Figures A.2-A.4
AUTHORITIES: dict[str, LqgWeights] = {
    "low": LqgWeights(rho=100.0, theta=1.0),
    "moderate": LqgWeights(rho=1.0e-2, theta=1.0),
    "high": LqgWeights(rho=1.0e-3, theta=1.0),
}

#: Appendix A.1: force on mass 1, displacement of mass 2
FORCE_ON: Mass = 1
MEASURED: Mass = 2


@dataclass(frozen=True)
class SensitivityMap:
    """Normalised closed-loop cost over a grid of design-model stiffnesses."""

    k1: np.ndarray  #: design-model k1 [N/m], one per row
    k2: np.ndarray  #: design-model k2 [N/m], one per column
    normalised_cost: np.ndarray  #: (len(k1), len(k2)) J / J_optimal; inf where the loop is unstable
    optimal_cost: float  #: J of the compensator designed on the actual system [m^2 + rho N^2]
    actual: TwoMassSystem
    weights: LqgWeights


@dataclass(frozen=True)
class CostMinimum:
    """A local minimum of the normalised cost over the design stiffnesses."""

    k1: float  #: [N/m]
    k2: float  #: [N/m]
    normalised_cost: float


def normalised_cost(*, actual: TwoMassSystem, model_k1: float, model_k2: float, weights: LqgWeights,
                    optimal: float | None = None) -> float:
    """J / J_optimal of the compensator designed with stiffnesses (model_k1, model_k2) [N/m]; inf if unstable."""
    if model_k1 <= 0.0 or model_k2 <= 0.0:
        return float("inf")  # not a spring any more: outside the study
    plant = actual.state_space(force_on=FORCE_ON, measured=MEASURED)
    if optimal is None:
        optimal = optimal_cost(plant, weights)
    model = TwoMassSystem(k1=model_k1, k2=model_k2, m1=actual.m1, m2=actual.m2, c1=actual.c1, c2=actual.c2)
    design = design_lqg(model.state_space(force_on=FORCE_ON, measured=MEASURED), weights)
    return closed_loop_cost(plant, design) / optimal


def sensitivity_map(*, actual: TwoMassSystem, weights: LqgWeights, k1_values: np.ndarray, k2_values: np.ndarray,
                    progress: Callable[[int, int], None] | None = None) -> SensitivityMap:
    """Normalised cost on the grid k1_values x k2_values [N/m]; ``progress(done, total)`` per row.

    Parameters
    ----------
    actual : TwoMassSystem
        The plant the compensators are closed around.
    weights : LqgWeights
        The LQG weighting (rho, theta) of every design.
    k1_values, k2_values : numpy.ndarray
        The design models' spring stiffnesses [N/m].
    progress : callable, optional
        ``progress(done, total)`` after each row.

    Returns
    -------
    SensitivityMap
        The closed-loop cost of each design model's compensator on the actual system, over the
        optimal one's (inf where the loop is unstable).
    """
    k1 = np.asarray(k1_values, dtype=float)
    k2 = np.asarray(k2_values, dtype=float)
    if k1.ndim != 1 or k2.ndim != 1 or not len(k1) or not len(k2) or min(k1.min(), k2.min()) <= 0.0:
        raise MaceError("the stiffness grids must be non-empty 1-D arrays of positive stiffnesses [N/m]")
    optimal = optimal_cost(actual.state_space(force_on=FORCE_ON, measured=MEASURED), weights)
    cost = np.empty((len(k1), len(k2)))
    for i, a in enumerate(k1):
        for j, b in enumerate(k2):
            cost[i, j] = normalised_cost(actual=actual, model_k1=a, model_k2=b, weights=weights, optimal=optimal)
        if progress:
            progress(i + 1, len(k1))
    return SensitivityMap(k1=k1, k2=k2, normalised_cost=cost, optimal_cost=optimal, actual=actual, weights=weights)


def grid_local_minima(cost_map: SensitivityMap) -> list[tuple[int, int]]:
    """(row, column) of grid points not higher than any finite neighbour (8-neighbourhood), edges included."""
    c = cost_map.normalised_cost
    padded = np.pad(c, 1, constant_values=np.inf)
    found = []
    for i, j in zip(*np.nonzero(np.isfinite(c))):
        block = padded[i:i + 3, j:j + 3]
        if c[i, j] <= block.min():
            found.append((int(i), int(j)))
    return found


def refine_minimum(*, actual: TwoMassSystem, weights: LqgWeights, start_k1: float, start_k2: float) -> CostMinimum:
    """The local minimum of the normalised cost reached from (start_k1, start_k2) [N/m] by Nelder-Mead."""
    optimal = optimal_cost(actual.state_space(force_on=FORCE_ON, measured=MEASURED), weights)

    def cost(k: np.ndarray) -> float:
        return normalised_cost(actual=actual, model_k1=k[0], model_k2=k[1], weights=weights, optimal=optimal)

    # simplex of about one grid step; tolerances far below the grid step and the costs quoted
    start = np.array([start_k1, start_k2])
    if not np.isfinite(cost(start)):
        raise MaceError(f"the loop designed with k1 = {start_k1}, k2 = {start_k2} N/m is unstable: start elsewhere")
    simplex = np.array([start, start + [0.05, 0.0], start + [0.0, 0.05]])
    res = so.minimize(cost, start, method="Nelder-Mead",
                      options=dict(initial_simplex=simplex, xatol=1e-4, fatol=1e-6, maxiter=400))
    return CostMinimum(k1=float(res.x[0]), k2=float(res.x[1]), normalised_cost=float(res.fun))


def local_minima(cost_map: SensitivityMap) -> list[CostMinimum]:
    """The distinct local minima of the map, each refined from a grid minimum; lowest cost first.

    A grid minimum on the grid's edge is kept only if the refined point lies inside the grid
    (otherwise the cost goes on falling outside the searched region: not a minimum of it).
    """
    found: list[CostMinimum] = []
    k1, k2 = cost_map.k1, cost_map.k2
    step = min(np.diff(k1).min(initial=1.0), np.diff(k2).min(initial=1.0))
    for i, j in grid_local_minima(cost_map):
        m = refine_minimum(actual=cost_map.actual, weights=cost_map.weights, start_k1=k1[i], start_k2=k2[j])
        inside = k1[0] <= m.k1 <= k1[-1] and k2[0] <= m.k2 <= k2[-1]
        if inside and not any(abs(m.k1 - f.k1) < step and abs(m.k2 - f.k2) < step for f in found):
            found.append(m)
    return sorted(found, key=lambda m: m.normalised_cost)


def tolerable_ranges(cost_map: SensitivityMap, *, threshold: float = 1.1) -> tuple[tuple[float, float],
                                                                                      tuple[float, float]]:
    """((k1_min, k1_max), (k2_min, k2_max)) [N/m] spanned by the grid points with cost < ``threshold``."""
    inside = cost_map.normalised_cost < threshold
    rows, cols = np.nonzero(inside)
    return ((float(cost_map.k1[rows].min()), float(cost_map.k1[rows].max())),
            (float(cost_map.k2[cols].min()), float(cost_map.k2[cols].max())))


def cost_curvatures(*, actual: TwoMassSystem, weights: LqgWeights, step: float = 0.02) -> tuple[float, float]:
    """d^2(J/J_opt)/dk1^2 and d^2(J/J_opt)/dk2^2 [(N/m)^-2] at the actual stiffnesses (central differences)."""
    optimal = optimal_cost(actual.state_space(force_on=FORCE_ON, measured=MEASURED), weights)
    curv = []
    for d1, d2 in ((step, 0.0), (0.0, step)):
        plus, minus = (normalised_cost(actual=actual, model_k1=actual.k1 + s * d1, model_k2=actual.k2 + s * d2,
                                       weights=weights, optimal=optimal) for s in (1.0, -1.0))
        curv.append((plus + minus - 2.0) / step**2)  # the cost is exactly 1 at the actual stiffnesses
    return curv[0], curv[1]


@dataclass(frozen=True)
class AuthorityStudy:
    """One authority's map and what the thesis says about it, measured."""

    name: str  #: "low", "moderate" or "high"
    cost_map: SensitivityMap
    minima: list[CostMinimum]  #: local minima, lowest first (the first is the actual system)
    tolerable: tuple[tuple[float, float], tuple[float, float]]  #: k1 and k2 spans with J/J_opt < 1.1 [N/m]
    curvatures: tuple[float, float]  #: d^2(J/J_opt)/dk1^2, d^2(J/J_opt)/dk2^2 at the actual system
    regulator_poles: np.ndarray  #: of the compensator designed on the actual system [rad/s]


def study_authority(*, name: str, actual: TwoMassSystem, weights: LqgWeights, k1_values: np.ndarray,
                    k2_values: np.ndarray, progress: Callable[[int, int], None] | None = None) -> AuthorityStudy:
    """Map, local minima, tolerable spans and curvatures of one authority over a stiffness grid [N/m]."""
    cost_map = sensitivity_map(actual=actual, weights=weights, k1_values=k1_values, k2_values=k2_values,
                               progress=progress)
    plant = actual.state_space(force_on=FORCE_ON, measured=MEASURED)
    return AuthorityStudy(name=name, cost_map=cost_map, minima=local_minima(cost_map),
                          tolerable=tolerable_ranges(cost_map),
                          curvatures=cost_curvatures(actual=actual, weights=weights),
                          regulator_poles=regulator_poles(plant, design_lqg(plant, weights)))


def format_studies(studies: list[AuthorityStudy]) -> str:
    """A plain-text table of the studies (one block per authority) with the thesis's statements."""
    lines = ["LQG sensitivity to mismodelled stiffness (thesis A.1); actual k1 = 0.75, k2 = 1.2 N/m",
             "thesis: low flat, unstable lower-left; moderate J/J_opt < 1.1 only for k2 about 1.0-1.4,",
             "more sensitive to k2; high valley-shaped; second minimum for k1 in 2-3, J/J_opt about 1.6", ""]
    for s in studies:
        m, w = s.cost_map, s.cost_map.weights
        finite = np.isfinite(m.normalised_cost)
        (a1, b1), (a2, b2) = s.tolerable
        poles = ", ".join(f"{p:.2f}" for p in np.unique(np.round(np.abs(s.regulator_poles), 3)))
        lines += [f"{s.name} authority: rho = {w.rho:g}, theta = {w.theta:g}, J_opt = {m.optimal_cost:.4g}",
                  f"  regulator pole magnitudes [rad/s]: {poles}",
                  f"  grid k1 {m.k1[0]:g}-{m.k1[-1]:g}, k2 {m.k2[0]:g}-{m.k2[-1]:g} N/m, {m.k1.size} x {m.k2.size}; "
                  f"unstable {100 * (1 - finite.mean()):.0f} % of it",
                  f"  J/J_opt < 1.1 for k1 {a1:.2f}-{b1:.2f} and k2 {a2:.2f}-{b2:.2f} N/m",
                  f"  curvature at the actual system: d2/dk1^2 {s.curvatures[0]:.2f}, d2/dk2^2 {s.curvatures[1]:.2f}"]
        for k, mm in enumerate(s.minima):
            lines.append(f"  {'global' if k == 0 else 'local '} minimum: k1 = {mm.k1:.3f}, k2 = {mm.k2:.3f} N/m, "
                         f"J/J_opt = {mm.normalised_cost:.3f}")
        lines.append("")
    return "\n".join(lines)
