"""How sure an update is of each parameter, and which combinations its data cannot see.

From the final linearisation of each stage (the cost sensitivities the update already has: no
extra model runs), J = d j / d delta with delta the parameters' changes relative to the point of
that linearisation (the end point, or its last base within the stopping tolerance), and the residual noise
variance sigma^2 (j^T j / (m - n) at the end, m residuals, n parameters), the linearised
covariance of x is sigma^2 (J^T J)^-1 = sigma^2 V S^-2 V^T (SVD J = U S V^T). Standard
deviations, correlations and 95 % intervals (value x (1 +- 1.96 sd), normal approximation)
follow; each right singular vector v_k whose standard deviation sigma / s_k exceeds the
tolerance is a combination the data do not fix, written in parameter names
("0.08 E_active_strut_end + 0.32 E_active_strut_piezo - 0.95 E_active_strut_center").
The penalty of eq. 4.18, when on, is a regularisation and is left out: the uncertainty is the data's.

That covariance assumes the residual is white noise of variance sigma^2. When it is not (the model does
not explain the data: :mod:`~mace_fmu.updating.engine.convergence`), the covariance comes from the
residuals themselves, the sandwich (J^T J)^-1 M (J^T J)^-1 of
:mod:`~mace_fmu.updating.engine.residual_covariance`, and the weak directions are the covariance's
eigenvectors. Every stage names the method it used (``method``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Mapping, Sequence

import numpy as np

from mace_fmu.updating.engine.residual_blocks import ResidualBlock
from mace_fmu.updating.engine.residual_covariance import residual_covariance
from mace_fmu.updating.engine.solve import UpdateResult

Z95 = 1.959963984540054  #: two-sided 95 % quantile of the normal distribution
Z95_ONE_SIDED = 1.6448536269514722  #: one-sided 95 % quantile: the interval of a parameter at a bound
#: a parameter (or a combination) whose standard deviation exceeds this [%] is "not fixed by these data"
DEFAULT_TOLERANCE_PERCENT = 5.0


@dataclass(frozen=True)
class WeakDirection:
    """A combination of relative parameter changes the data fix poorly."""

    standard_deviation_percent: float  #: of the combination (unit-norm coefficients)
    coefficients: dict  #: parameter -> coefficient of its relative change; the largest is positive

    def text(self) -> str:
        """'0.08 E_a + 0.32 E_b - 0.95 E_c' (terms below 0.05 left out)."""
        terms = [(c, n) for n, c in self.coefficients.items() if abs(c) >= 0.05]
        out = ""
        for k, (c, n) in enumerate(terms):
            sign = "-" if c < 0 else ("+" if k else "")
            out += f"{' ' if k else ''}{sign}{' ' if k else ''}{abs(c):.2f} {n}"
        return out


@dataclass(frozen=True)
class StageUncertainty:
    """The linearised uncertainty of one stage's parameters at the end of the update."""

    stage: str  #: stage name
    names: tuple[str, ...]  #: parameters of the stage
    values: dict  #: final values [SI]
    residuals: int  #: m
    noise_variance: float  #: sigma^2 per (normalised) residual
    standard_deviation_percent: dict  #: of each parameter, relative to its value
    correlation: np.ndarray  #: (n, n)
    interval_95: dict  #: name -> (low, high) [SI]
    singular_values: np.ndarray  #: of J (per unit relative change), largest first
    weak_directions: tuple[WeakDirection, ...]  #: combinations with sd above the tolerance, weakest first
    tolerance_percent: float  #: standard deviation below which a parameter counts as determined [%]
    method: str = "noise"  #: how the covariance was found: "noise" (sigma^2 (J^T J)^-1) or "residuals" (sandwich)
    method_text: str = ""  #: the method in words, for the report
    #: name -> "lower" or "upper": a parameter the fit ended at that bound, its interval one-sided
    #: (:func:`one_sided_at_bounds`)
    at_bound: dict = field(default_factory=dict)

    @property
    def not_fixed(self) -> tuple[str, ...]:
        """Parameters whose standard deviation exceeds the tolerance."""
        return tuple(n for n in self.names if self.standard_deviation_percent[n] > self.tolerance_percent)


def _stage_jacobians(result: UpdateResult) -> dict[str, tuple]:
    """stage -> (names, J per unit relative change) of the stage's last linearisation."""
    return {it.stage: (it.sensitivities.names, it.sensitivities.matrix) for it in result.history
            if it.sensitivities is not None}


def stage_uncertainty(result: UpdateResult, *, tolerance_percent: float = DEFAULT_TOLERANCE_PERCENT,
                      noise_variance: float | None = None, noise_source: str = "",
                      residual_blocks: tuple[ResidualBlock, ...] | None = None) -> tuple[StageUncertainty, ...]:
    """The uncertainty of every stage that has cost sensitivities (the cost-sensitivity method).

    Parameters
    ----------
    result : UpdateResult
        An update whose stages kept their final linearisation (no extra model runs are made).
    tolerance_percent : float
        A parameter or combination whose standard deviation exceeds this [%] is reported as not
        fixed by the data.
    noise_variance : float, optional
        sigma^2 per residual when known (e.g. the noise floor's expected cost / m); default: the
        final cost / (m - n).
    noise_source : str
        Where ``noise_variance`` came from, for the report.
    residual_blocks : tuple of ResidualBlock, optional
        Given, the covariance comes from the residuals themselves (the sandwich of
        :mod:`~mace_fmu.updating.engine.residual_covariance`): for a residual that is not white noise at
        the stated level.

    Returns
    -------
    tuple of StageUncertainty
        Per stage: standard deviations [% of the value], correlations, 95 % intervals [SI], singular
        values, the weak directions in parameter names, and the method.
    """
    out = []
    for stage, (names, jac) in _stage_jacobians(result).items():
        m, n = jac.shape
        sigma2 = noise_variance if noise_variance is not None else result.final_cost / max(m - n, 1)
        values = {k: float(result.values[k]) for k in names}
        if residual_blocks and m == result.final_residual.size:
            cov = residual_covariance(jac, result.final_residual, residual_blocks, other_variance=sigma2)
            out.append(linearised_uncertainty(
                stage=stage, names=names, values=values, jacobian=jac, noise_variance=sigma2,
                tolerance_percent=tolerance_percent, covariance=cov, method="residuals",
                method_text="from the residuals (the model does not explain the data to their noise): the sandwich "
                            "(J^T J)^-1 M (J^T J)^-1, M from the residual's spectra and cross-spectra (Huber 1967, "
                            "White 1982, Brillinger 1981)"))
        else:
            how = noise_source or ("the final cost / (m - n)" if noise_variance is None else "the stated noise")
            out.append(linearised_uncertainty(stage=stage, names=names, values=values, jacobian=jac,
                                              noise_variance=sigma2, tolerance_percent=tolerance_percent,
                                              method_text=f"from the noise: sigma^2 (J^T J)^-1, sigma^2 {how}"))
    return tuple(out)


def linearised_uncertainty(*, stage: str, names, values: dict, jacobian: np.ndarray, noise_variance: float,
                           tolerance_percent: float = DEFAULT_TOLERANCE_PERCENT, covariance: np.ndarray | None = None,
                           method: str = "noise", method_text: str = "") -> StageUncertainty:
    """The uncertainty of parameters ``names`` at ``values`` [SI] from J = d j / d delta (per unit relative
    change, one column per name, m rows) and the noise variance per residual: sigma^2 (J^T J)^-1, or the
    ``covariance`` (per unit relative change) given (``method`` "residuals")."""
    jac = np.asarray(jacobian, dtype=float)
    m, n = jac.shape
    sigma2 = float(noise_variance)
    u, s, vt = np.linalg.svd(jac, full_matrices=False)
    tiny = s <= s[0] * 1e-12 if len(s) else np.zeros(0, dtype=bool)
    if covariance is None:
        inv = np.where(tiny, np.inf, 1.0 / np.where(tiny, 1.0, s))
        cov = (vt.T * (sigma2 * inv**2)) @ vt if not tiny.any() else np.full((n, n), np.inf)
        directions = [(100 * math.sqrt(sigma2) * inv[k], vt[k]) for k in range(len(s))]
    else:
        cov = np.full((n, n), np.inf) if tiny.any() else np.asarray(covariance, dtype=float)
        w, v = np.linalg.eigh(cov) if not tiny.any() else (np.full(n, np.inf), np.eye(n))
        directions = [(100 * math.sqrt(max(w[k], 0.0)), v[:, k]) for k in range(n)]
    sd = np.sqrt(np.abs(np.diag(cov)))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(sd, sd)
    sd_percent = {k: float(100 * d) for k, d in zip(names, sd)}
    interval = {k: (values[k] * (1 - Z95 * sd_percent[k] / 100), values[k] * (1 + Z95 * sd_percent[k] / 100))
                for k in names}
    weak = []
    for sd_dir, vec in directions:
        if sd_dir > tolerance_percent:
            vec = vec * np.sign(vec[np.argmax(np.abs(vec))])
            weak.append(WeakDirection(standard_deviation_percent=float(sd_dir),
                                      coefficients={nm: float(c) for nm, c in zip(names, vec)}))
    weak.sort(key=lambda w: -w.standard_deviation_percent)
    return StageUncertainty(stage=stage, names=tuple(names), values=dict(values), residuals=m, noise_variance=sigma2,
                            standard_deviation_percent=sd_percent, correlation=corr, interval_95=interval,
                            singular_values=s, weak_directions=tuple(weak), tolerance_percent=tolerance_percent,
                            method=method, method_text=method_text)


def one_sided_at_bounds(stages: tuple[StageUncertainty, ...], at_bounds: Sequence[tuple[str, str]], *,
                        ranges: Mapping[str, tuple[float, float]] | None = None) -> tuple[StageUncertainty, ...]:
    """``stages`` with the interval of each parameter that ended at a bound made one-sided, as the verdict says.

    The data ask for a value beyond the bound, so the value is the bound and no two-sided interval about it
    holds: at a lower bound the 95 % interval runs from the bound to value x (1 + 1.645 sd), at an upper bound
    from value x (1 - 1.645 sd) to the bound (the one-sided 95 % quantile of the same standard deviation),
    the far end held within the parameter's declared range where one is given (a mass at its upper bound with
    a standard deviation of 160 % ran to -0.25 kg before; an FMU is not defined beyond its range, and the data
    say nothing there).

    Parameters
    ----------
    stages : tuple of StageUncertainty
        From :func:`stage_uncertainty`.
    at_bounds : sequence of (str, str)
        (parameter, "lower" or "upper"): :attr:`~mace_fmu.updating.engine.solve.UpdateResult.at_bounds`.
    ranges : mapping of str to (float, float), optional
        Each parameter's declared (min, max), e.g. an FMU's (:attr:`FmuInterface.ranges
        <mace_fmu.updating.fmu.model.FmuInterface.ranges>`): the interval's far end is kept within it.

    Returns
    -------
    tuple of StageUncertainty
        The same stages, each such parameter's ``interval_95`` one-sided and named in ``at_bound``.
    """
    sides = dict(at_bounds)
    out = []
    for st in stages:
        here = {n: side for n, side in sides.items() if n in st.names}
        if not here:
            out.append(st)
            continue
        interval = dict(st.interval_95)
        for n, side in here.items():
            v, reach = st.values[n], abs(st.values[n]) * Z95_ONE_SIDED * st.standard_deviation_percent[n] / 100
            low, high = (ranges or {}).get(n, (-np.inf, np.inf))
            interval[n] = (v, min(v + reach, max(high, v))) if side == "lower" else (max(v - reach, min(low, v)), v)
        out.append(replace(st, interval_95=interval, at_bound={**st.at_bound, **here}))
    return tuple(out)


def format_uncertainty(stages: tuple[StageUncertainty, ...]) -> str:
    """The terminal table: value, standard deviation, 95 % interval, and what the data do not fix."""
    lines = []
    for st in stages:
        if st.method == "residuals":
            lines.append(f"{st.stage}: uncertainty from {st.residuals} residuals, {st.method_text} (tolerance "
                         f"{st.tolerance_percent:g} %)")
        else:
            lines.append(f"{st.stage}: uncertainty from {st.residuals} residuals, noise sd "
                         f"{math.sqrt(st.noise_variance):.3g} per residual (tolerance {st.tolerance_percent:g} %)")
        width = max([28, *(len(n) for n in st.names)])
        lines.append(f"  {'parameter':<{width}} {'value':>13} {'sd %':>8}  95 % interval")
        for n in st.names:
            flag = "  not fixed by these data" if n in st.not_fixed else ""
            if n in st.at_bound:
                flag = f"  one-sided: at its {st.at_bound[n]} bound{flag}"
            lo, hi = st.interval_95[n]
            lines.append(f"  {n:<{width}} {st.values[n]:>13.6g} {st.standard_deviation_percent[n]:>8.3g}  "
                         f"[{lo:.6g}, {hi:.6g}]{flag}")
        for w in st.weak_directions:
            lines.append(f"  not identifiable from these data (sd {w.standard_deviation_percent:.3g} %): {w.text()}")
    return "\n".join(lines)


def uncertainty_toml(stages: tuple[StageUncertainty, ...]) -> str:
    """``uncertainty.toml``: per stage, standard deviations, 95 % intervals, correlations, singular values, weak
    directions in parameter names."""
    def q(text: str) -> str:
        return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'

    def num(x: float) -> str:
        return repr(float(x)) if math.isfinite(x) else ("inf" if x > 0 else "nan" if x != x else "-inf")

    lines = ["# mace-fmu: linearised uncertainty of an update (from its final cost sensitivities)", ""]
    for st in stages:
        lines += ["[[stage]]", f"name = {q(st.stage)}", f"residuals = {st.residuals}",
                  f"noise_variance = {num(st.noise_variance)}", f"tolerance_percent = {num(st.tolerance_percent)}",
                  f"method = {q(st.method)}", f"method_text = {q(st.method_text)}",
                  "parameters = [" + ", ".join(q(n) for n in st.names) + "]",
                  "values = [" + ", ".join(num(st.values[n]) for n in st.names) + "]",
                  "standard_deviation_percent = [" + ", ".join(num(st.standard_deviation_percent[n]) for n in st.names)
                  + "]",
                  "interval_95_low = [" + ", ".join(num(st.interval_95[n][0]) for n in st.names) + "]",
                  "interval_95_high = [" + ", ".join(num(st.interval_95[n][1]) for n in st.names) + "]",
                  # "" two-sided; "lower"/"upper": the parameter ended at that bound, its interval one-sided from it
                  "interval_95_at_bound = [" + ", ".join(q(st.at_bound.get(n, "")) for n in st.names) + "]",
                  "singular_values = [" + ", ".join(num(x) for x in st.singular_values) + "]",
                  "correlation = [" + ", ".join("[" + ", ".join(num(x) for x in row) + "]" for row in st.correlation)
                  + "]",
                  "not_fixed = [" + ", ".join(q(n) for n in st.not_fixed) + "]",
                  "weak_directions = [" + ", ".join(q(w.text()) for w in st.weak_directions) + "]",
                  "weak_direction_sd_percent = [" + ", ".join(num(w.standard_deviation_percent)
                                                             for w in st.weak_directions) + "]", ""]
    return "\n".join(lines)
