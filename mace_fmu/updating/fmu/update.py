"""Updating an FMU's parameters against measured time histories: the engine's update with the FMU in the cost.

The cost is the time-domain output error (eq. 4.3) or the log-FRF error (eq. 4.5/4.17) of the
FMU's simulated response; the update is the engine's cost-sensitivity method (N + 1 FMU
simulations per linearisation, handed to the ``runner``: ``map`` serially, a
:class:`~mace_fmu.util.runner.DaskRunner` on local processes or a cluster). The perturbed models are
the FMU itself with one parameter changed ("full" perturbations): the FMU re-analyses its own
physical parameters at initialisation.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Literal, Mapping, Sequence

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.parameters.sets import Provenance, now_utc, toml_key, toml_value, tool_version
from mace_fmu.updating.engine.bounds import default_bounds
from mace_fmu.updating.engine.costs import Cost, TimeResponseCost
from mace_fmu.updating.engine.measured import MeasuredFrf, TimeHistory
from mace_fmu.updating.engine.models import SimulatedModel
from mace_fmu.updating.engine.simulated_frf import H1Estimator, SimulatedFrequencyResponseCost, log_h1_weights, principal_pairs
from mace_fmu.updating.engine.solve import Bounds, Stage, UpdateResult, UpdateSettings, update
from mace_fmu.updating.fmu.model import FmuFamily, ship_fmu
from mace_fmu.util.atomic import write_text_atomic
from mace_fmu.util.progress import ProgressCallback

CostKind = Literal["time", "log-frf"]
COST_KINDS: tuple[str, ...] = ("time", "log-frf")
Weighting = Literal["noise", "none"]
WEIGHTINGS: tuple[str, ...] = ("noise", "none")
#: the FMU is the model: perturbed models are FMU runs, and the truth needs no penalty to hold it near the start.
#: Central differences with a 1e-3 step: forward differences at 1e-2 misjudged the weak strut directions by
#: an order of magnitude and let a run stop at its cap far above the noise. The cap is a safety net only.
#: The first step is bounded to 10 % per parameter (a trust region that doubles while the linearisation holds):
#: a time cost over a long record is far from quadratic, and an unbounded first step from the pre-update moduli
#: threw a cable modulus to its bound and the fit into another minimum.
FMU_SETTINGS = UpdateSettings(method="cost-sensitivity", perturbation="full", penalty=False, max_outer=30,
                              relative_step=1e-3, difference="central", initial_radius=0.1)


def fmu_cost(kind: CostKind, *, history: TimeHistory, frequency_data: MeasuredFrf | None = None,
             estimator: H1Estimator | None = None, pairs: Sequence[tuple[str, str]] = (),
             weighting: Weighting = "noise", compare_from_s: float | None = None,
             band_hz: tuple[float, float] | None = None) -> Cost[SimulatedModel]:
    """The cost ``kind`` of an FMU against ``history`` (measured inputs and outputs).

    ``time``: outputs normalised by their RMS (eq. 4.3), through the zero-phase band-pass ``band_hz`` where
    given (:class:`~mace_fmu.updating.engine.costs.TimeResponseCost`). ``log-frf``: :func:`log_frf_cost`, which
    documents ``frequency_data``, ``estimator``, ``pairs`` and ``weighting``. The FMU is driven from the record's
    first sample; the errors (time) or the estimates (log-frf) are taken from ``compare_from_s`` [s] on (default:
    the first sample).
    """
    start_s = float(history.times_s[0]) if compare_from_s is None else float(compare_from_s)
    if kind == "time":
        return TimeResponseCost(history, compare_from_s=start_s, band_hz=band_hz)
    if kind != "log-frf":
        raise MaceError(f"cost must be one of {', '.join(COST_KINDS)}, got {kind!r}")
    if band_hz is not None:
        raise MaceError("a band-pass is the time cost's; the log-FRF cost compares the estimator's band")
    if estimator is None:
        raise MaceError("the log-FRF cost needs an H1 estimator (segment length, window, band)")
    return log_frf_cost(history=history, frequency_data=frequency_data, estimator=estimator, pairs=pairs,
                        weighting=weighting, compare_from_s=start_s)


def log_frf_cost(*, history: TimeHistory, estimator: H1Estimator, frequency_data: MeasuredFrf | None = None,
                 pairs: Sequence[tuple[str, str]] = (), weighting: Weighting = "noise",
                 compare_from_s: float | None = None) -> SimulatedFrequencyResponseCost:
    """The log-FRF cost (eq. 4.5/4.17) of an FMU driven by ``history``'s measured inputs.

    Parameters
    ----------
    history : TimeHistory
        The measured inputs (and outputs) of one test; the FMU is driven from its first sample.
    estimator : H1Estimator
        The H1 estimator of the FMU's response (and of ``history``'s, without ``frequency_data``).
    frequency_data : MeasuredFrf, optional
        The measured frequency response compared (default: the ``estimator``'s H1 of ``history``).
    pairs : sequence of (str, str), optional
        (input, output) pairs compared (default: the principal pairs, same axis and X to Y, where the names say
        the axis; else every pair).
    weighting : {"noise", "none"}
        "noise" divides each log error by its standard deviation estimated from ``history`` (bins where the
        measurement noise buries the response weigh little), "none" is eq. 4.17 as printed.
    compare_from_s : float, optional
        The estimates are taken from this time [s] on (default: the record's first sample).

    Returns
    -------
    SimulatedFrequencyResponseCost
        The cost, of any :class:`~mace_fmu.updating.engine.models.SimulatedModel`.

    Raises
    ------
    MaceError
        An unknown ``weighting``, or data the estimator cannot weigh.
    """
    start_s = float(history.times_s[0]) if compare_from_s is None else float(compare_from_s)
    whole, history = history, record_from(history, start_s)
    data = frequency_data if frequency_data is not None else estimator(history)
    chosen = tuple(pairs) or principal_pairs(data.inputs, data.outputs) or \
        tuple((i, o) for i in data.inputs for o in data.outputs)
    if weighting not in WEIGHTINGS:
        raise MaceError(f"weighting must be one of {', '.join(WEIGHTINGS)}, got {weighting!r}")
    weights = None
    if weighting == "noise":
        weights = log_h1_weights(history, data, segment_length=estimator.segment_length, window=estimator.window,
                                 overlap=estimator.overlap)
    return SimulatedFrequencyResponseCost(data=data, excitation=whole, estimator=estimator, pairs=chosen,
                                          weights=weights, compare_from_s=start_s)


def record_from(history: TimeHistory, start_s: float) -> TimeHistory:
    """The samples of ``history`` from ``start_s`` [s] on (itself when that is its first)."""
    first = int(np.searchsorted(history.times_s, start_s - 1e-9 * history.sample_time_s))
    if first == 0:
        return history
    return TimeHistory(history.times_s[first:], {k: v[first:] for k, v in history.inputs.items()},
                       {k: v[first:] for k, v in history.outputs.items()},
                       source=f"{history.source} (from {start_s:g} s)", units=history.units)


def update_fmu(*, family: FmuFamily, cost: Cost[SimulatedModel], start: Mapping[str, float], stages: Sequence[Sequence[str]],
               settings: UpdateSettings = FMU_SETTINGS, runner: Callable = map,
               progress: ProgressCallback | None = None, bounds: Mapping[str, Bounds] | None = None) -> UpdateResult:
    """Update the FMU parameters of ``stages`` from ``start`` to lower ``cost``, stage after stage.

    Parameters
    ----------
    family : FmuFamily
        The FMU as a model family: which parameters it has and how to simulate it.
    cost : Cost
        The residual vector to lower (time or log-FRF, one or several tests).
    start : mapping of str to float
        Start values [FMU units: Pa, s, 1] of every parameter named in ``stages``.
    stages : sequence of sequences of str
        One tuple of parameter names per stage, in order.
    settings : UpdateSettings
        Stopping tests, difference steps and rounds.
    runner : callable
        A ``map``-like function that runs the simulations (``map``, or a
        :class:`~mace_fmu.util.runner.DaskRunner`).
    progress : callable, optional
        Called with a progress step after each outer iteration.
    bounds : mapping of str to Bounds, optional
        The range of each parameter (default, and for any name it leaves out: :func:`declared_bounds`).

    Returns
    -------
    UpdateResult
        Values, cost history, why each stage stopped (and whether it converged) and the final Jacobian
        the uncertainty report is computed from.

    Notes
    -----
    Default bounds by kind of name (:func:`~mace_fmu.updating.engine.bounds.default_bounds`, relative to the
    start value): moduli and masses x0.5-1.5, springs x0.2-5, delays x0.2-3, damping ratios x0.1-4 (at most
    0.95), others x0.2-5, each within the range the FMU declares for the parameter.
    """
    names = [n for s in stages for n in s]
    if not names:
        raise MaceError("name at least one FMU parameter to update")
    family.check_parameters(names)
    missing = [n for n in names if n not in start]
    if missing:
        raise MaceError(f"no start value for {', '.join(missing)}")
    bad = [n for n in names if not start[n] > 0]
    if bad:
        raise MaceError("update parameters must start positive (they move in relative terms): "
                        + ", ".join(f"{n} = {start[n]:g}" for n in bad))
    if family.interface.written_by_pythonfmu:
        if runner is map:
            raise MaceError(f"{family.interface.path}: FMUs written by pythonfmu run in worker processes only (their "
                            "wrapper releases a slave's Python objects twice after an error in it): pass a Dask runner "
                            "(runner=DaskRunner(...); the CLI always uses one), or export a native FMU")
        family = dataclasses.replace(family, runner=runner)  # every run of it, the base point's too, goes there
    outside = [f"{n} = {start[n]:.6g} (declared [{lo:.6g}, {hi:.6g}])" for n in names
               for lo, hi in [family.interface.ranges.get(n, (-math.inf, math.inf))] if not lo <= start[n] <= hi]
    if outside:
        raise MaceError(f"{family.interface.path}: start values outside the FMU's declared ranges: "
                        + "; ".join(outside))
    ship_fmu(family.interface, runner)  # the workers read the FMU's bytes, not the client's path
    plan = [Stage(name=f"stage {k + 1}", parameters=tuple(s)) for k, s in enumerate(stages)]
    chosen = {**declared_bounds(family, names, start), **{n: b for n, b in (bounds or {}).items() if n in names}}
    return update(family, cost, start=dict(start), stages=plan, bounds=chosen, settings=settings, runner=runner,
                  progress=progress)


def declared_bounds(family: FmuFamily, names: Sequence[str], start: Mapping[str, float],
                    given: Mapping[str, tuple[float | None, float | None]] | None = None,
                    where: Mapping[str, str] | None = None) -> dict[str, Bounds]:
    """:func:`~mace_fmu.updating.engine.bounds.default_bounds` within the FMU's declared ranges: a step never
    asks the FMU for a value it refuses (a MACE FMU's moduli and springs: 0.7 to 1.5 x nominal, where its
    parameter route was validated against full re-solves).

    ``given``: name -> (low, high) [FMU units] a user states instead (None keeps that side's default); each
    must hold the start value strictly inside and lie within the FMU's declared range, else a MaceError naming
    ``where[name]`` (the option or file that gave it)."""
    out = {}
    for name, bound in default_bounds(names, start).items():
        low, high = family.interface.ranges.get(name, (-math.inf, math.inf))
        out[name] = dataclasses.replace(bound, lower=max(bound.lower, low), upper=min(bound.upper, high))
    for name, (lower, upper) in (given or {}).items():
        at = (where or {}).get(name, "bounds")
        if name not in out:
            raise MaceError(f"{at}: {name!r} is not updated (the parameters updated: {', '.join(names)})")
        low, high = family.interface.ranges.get(name, (-math.inf, math.inf))
        lower = out[name].lower if lower is None else float(lower)
        upper = out[name].upper if upper is None else float(upper)
        unit = family.interface.units.get(name, "")
        if not lower < start[name] < upper:
            raise MaceError(f"{at}: {name} bounds [{lower:.6g}, {upper:.6g}] {unit} do not hold its start value "
                            f"{start[name]:.6g} strictly inside")
        if lower < low or upper > high:
            raise MaceError(f"{at}: {name} bounds [{lower:.6g}, {upper:.6g}] {unit} leave the range "
                            f"[{low:.6g}, {high:.6g}] {family.interface.path} declares for it (the FMU refuses "
                            "values outside)")
        out[name] = dataclasses.replace(out[name], lower=lower, upper=upper)
    return out


@dataclass(frozen=True)
class FmuParameters:
    """Updated values of an FMU's parameters by its own names, and where they come from."""

    values: Mapping[str, float]
    units: Mapping[str, str]
    provenance: Provenance
    sensor_gains: Mapping[str, float] = dataclasses.field(default_factory=dict)  #: output -> estimated gain

    def to_toml(self) -> str:
        """[provenance] and [values] tables as in :class:`~mace_fmu.parameters.sets.ParameterSet` files."""
        lines = ["# mace-fmu: FMU parameters after an update (names and units as the FMU declares them)", "",
                 "[provenance]"]
        for key in ("created", "tool", "configuration", "fitted_to", "data", "cost", "method", "initial_cost",
                    "final_cost", "notes"):
            value = getattr(self.provenance, key)
            if value is not None and value != "":
                lines.append(f"{key} = {toml_value(value)}")
        lines += ["", "[values]"]
        lines += [f"{toml_key(n)} = {toml_value(v)}" + (f"  # [{self.units[n]}]" if self.units.get(n) else "")
                  for n, v in self.values.items()]
        if self.sensor_gains:
            lines += ["", "# sensor gains estimated with the parameters (the data are gain x the model's output);",
                      "# not FMU parameters: a channel calibrated by them is its measured value divided by its gain",
                      "[sensor_gains]"]
            lines += [f"{toml_key(o)} = {toml_value(g)}" for o, g in self.sensor_gains.items()]
        return "\n".join(lines) + "\n"

    def write(self, path: str | os.PathLike) -> Path:
        """Write the TOML atomically."""
        return write_text_atomic(path, self.to_toml())


def fmu_parameters(result: UpdateResult, *, family: FmuFamily, data: str, cost: Cost,
                   convergence=None) -> FmuParameters:
    """The updated values of ``result`` with their provenance (FMU file, data files, cost, method) and, given a
    :class:`~mace_fmu.updating.engine.convergence.ConvergenceReport`, its verdict in the notes.

    Parameters
    ----------
    result : UpdateResult
        The FMU update.
    family : FmuFamily
        The FMU it updated (its file names the provenance; its sensor gains go to ``[sensor_gains]``).
    data : str
        The data files, for the provenance.
    cost : Cost
        The cost it lowered.
    convergence : ConvergenceReport, optional
        Its verdict, written into the notes.

    Returns
    -------
    FmuParameters
        Values by the FMU's names and units, estimated sensor gains, provenance; ``write`` makes the TOML.
    """
    s = result.settings
    notes = convergence.summary() if convergence is not None else ""
    prov = Provenance(created=now_utc(), tool=tool_version(), data=data,
                      cost=f"{cost.name} of the simulated response of {Path(family.interface.path).name}",
                      method=f"{s.method} ({s.perturbation} FMU runs, {s.difference} differences, step "
                             f"{s.relative_step}), penalty "
                             f"{'on' if s.penalty else 'off'}, {len(result.history)} outer iterations",
                      initial_cost=result.initial_cost, final_cost=result.final_cost, notes=notes,
                      configuration=family.interface.configuration, fitted_to=Path(family.interface.path).name)
    gains = {o: result.values[g] for o, g in zip(family.gain_outputs, family.gain_parameters) if g in result.values}
    values = {n: v for n, v in result.values.items() if n not in family.gain_parameters}
    return FmuParameters(values=values, units={n: family.interface.units.get(n, "") for n in values},
                         provenance=prov, sensor_gains=gains)
