"""The updated nominal 0-g model and its frequency bounds (thesis 5.3, Table 5.3).

From a parameter set (the bundled deck's values by default) the physical parameters are carried
to 0-g by the FE model itself. The residual 1-g errors (our closed-loop 1-g model against a
measurement model, Table 4.7 by default) are then taken out of the 0-g model as the thesis does:
for each lightly damped mode the 0-g open-loop frequency and damping ratio of the structural
mode behind it are adjusted until its closed-loop 0-g pole is the unaltered one times the 1-g
ratio measured / model (frequency and damping alike). Heavily damped modes (servo-dominated,
zeta >= 10 %) are left as they are, as in the thesis: Table 5.3 keeps them at their Table 5.2
values. The adjustments are ordinary parameters (``frequency_scale:<label>``,
``damping:<label>``), so the nominal model is
``volts_model(compute_modes(configuration="0g", parameters=...))`` like any other.

Bounds (:class:`BoundRule`): lightly damped modes the larger of 1 % and half the absolute
residual 1-g frequency error; heavily damped modes +-2.5 %.
"""

from __future__ import annotations

import dataclasses
import csv
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from mace_fmu.deck.cards import Deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.model_options import ModelledElectronics
from mace_fmu.iomodel.parametric import ParametricSystem
from mace_fmu.iomodel.parametric_data import parametric_arrays
from mace_fmu.iomodel.pole_pairing import REAL_POLE_DAMPING, pair_poles
from mace_fmu.iomodel.poles import ClosedLoopPole, closed_loop_poles, label_poles
from mace_fmu.iomodel.volts import VoltsModel, volts_model
from mace_fmu.parameters.kinds import DAMPING, FREQUENCY_SCALE, kind_of_set_name, mode_label
from mace_fmu.parameters.per_mode import label_mode_names
from mace_fmu.parameters.sets import ParameterSet, Provenance, deck_fingerprint, now_utc, tool_version
from mace_fmu.structure.file import StructureFile, is_bundled_deck
from mace_fmu.thesis import thesis_data
from mace_fmu.updating.engine.measured import MeasuredMode, read_measured_modes
from mace_fmu.updating.mace.update import measured_modes
from mace_fmu.util.frequency import ZERO_HZ
from mace_fmu.util.progress import ProgressCallback, begin_stage
from mace_fmu.util.threads import single_blas_thread

_TOLERANCE = 1e-7  #: largest relative miss of an adjusted closed-loop frequency or damping ratio
_FREQUENCY_WEIGHT = 1e5  #: of the frequency residuals against the damping ones


@dataclass(frozen=True)
class BoundRule:
    """How the 0-g uncertainty is set (thesis 5.3); all numbers are fractions, not percent."""

    heavy_damping: float = 0.10  #: a mode with measured 1-g damping ratio >= this is heavily damped
    minimum_bound: float = 0.01  #: lightly damped modes: at least +-1 %
    error_fraction: float = 0.5  #: lightly damped modes: or this fraction of ``|residual 1-g error|``, if larger
    heavy_bound: float = 0.025  #: heavily damped modes: +-2.5 %
    correct_heavy: bool = False  #: also take the residual errors out of heavily damped modes (the thesis does not)

    def __post_init__(self) -> None:
        checks = (("heavy_damping", self.heavy_damping, 0.0, 1.0), ("minimum_bound", self.minimum_bound, 0.0, 1.0),
                  ("error_fraction", self.error_fraction, 0.0, 10.0), ("heavy_bound", self.heavy_bound, 0.0, 1.0))
        for name, value, low, high in checks:
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or not low <= value < high:
                raise MaceError(f"bound rule: {name} = {value!r} must be a number in [{low:g}, {high:g}) "
                                "(fractions: 0.01 is 1 %)")

    def bound(self, *, heavy: bool, frequency_error: float) -> float:
        """Relative frequency bound of a mode (0.011: +-1.1 %) from its residual 1-g error (a fraction)."""
        if heavy:
            return self.heavy_bound
        return max(self.minimum_bound, self.error_fraction * abs(frequency_error))


@dataclass(frozen=True)
class ZeroGRow:
    """One mode of the updated nominal 0-g model (a row of Table 5.3) and how it was made."""

    label: str  #: the measurement model's label, e.g. "1st Y bending"
    heavy: bool  #: heavily damped (measured 1-g damping ratio >= the rule's threshold)
    measured_1g_hz: float  #: measured 1-g frequency (Table 4.7) [Hz]
    measured_1g_damping: float  #: measured 1-g damping ratio
    model_1g_hz: float  #: our closed-loop 1-g pole paired with the measured mode
    model_1g_damping: float  #: damping ratio of that model pole
    unaltered_hz: float  #: our closed-loop 0-g pole before the adjustments (Table 5.2's 0-g column)
    unaltered_damping: float  #: its damping ratio
    nominal_hz: float  #: the updated nominal model's closed-loop pole
    nominal_damping: float  #: its damping ratio
    bound: float  #: relative frequency bound (0.011: +-1.1 %)
    pole_label: str  #: label of the nominal model's pole
    mode: int | None  #: 1-based open-loop mode (the FMU's frequency_scale_mode_<k>) carrying the bound, if flexible
    mode_label: str  #: label of that open-loop mode
    frequency_scale: float  #: factor applied to that mode's open-loop frequency (1: not adjusted)
    open_loop_damping: float  #: that mode's open-loop damping ratio in the nominal model
    adjusted: bool  #: the residual 1-g errors were taken out (lightly damped modes, as in the thesis)
    damping_reached: bool = True  #: False: servo damping alone exceeds the damping target (open-loop damping 0)
    #: relative change of the closed-loop frequency with the mode's frequency scale at 1 - bound and 1 + bound
    closed_loop_shift: tuple[float, float] | None = None

    @property
    def frequency_error(self) -> float:
        """Residual 1-g frequency error (model - measured) / measured, a fraction."""
        return self.model_1g_hz / self.measured_1g_hz - 1.0

    @property
    def damping_error(self) -> float:
        """Residual 1-g damping error (model - measured) / measured, a fraction."""
        return self.model_1g_damping / self.measured_1g_damping - 1.0 if self.measured_1g_damping > 0 else 0.0


@dataclass(frozen=True)
class ZeroGPrediction:
    """The updated nominal 0-g model with its bounds, and the parameter set that builds it."""

    rows: tuple[ZeroGRow, ...]  #: one row per mode of Table 5.3
    parameters: ParameterSet  #: volts_model(compute_modes(configuration="0g", parameters=this)): the nominal model
    model: VoltsModel  #: the updated nominal 0-g model
    rule: BoundRule  #: the rule that set the frequency bounds
    source: str  #: which measurement model the residual errors come from
    dropped: tuple[str, ...] = field(default=())  #: measured modes without a 0-g counterpart (suspension, violins)

    @property
    def frequency_bounds(self) -> dict[int, float]:
        """1-based open-loop mode -> relative bound, for the FMU's frequency_scale_mode_<k> min/max."""
        return {r.mode: r.bound for r in self.rows if r.mode is not None}


def table_4_7_zero_g_patterns() -> tuple[str | None, ...]:
    """For each row of Table 4.7, the label pattern of its 0-g pole (Table 5.2's rows), None where the
    mode has no 0-g counterpart (suspension, violin and delay modes)."""
    pending = [(r["label"], r["ours"]) for r in thesis_data()["table_5_2"]]
    out = []
    for row in thesis_data()["table_4_7"]:
        hit = next((k for k, (label, _) in enumerate(pending) if label == row["label"]), None)
        out.append(None if hit is None else pending.pop(hit)[1])
    return tuple(out)


def read_zero_g_measured(path: str | Path) -> tuple[tuple[MeasuredMode, ...], tuple[str | None, ...]]:
    """A measurement model (the CSV of ``mace-fmu update mace --measured``) with a ``pattern_0g`` column: the label
    pattern of each mode's 0-g pole, empty where the mode has no 0-g counterpart."""
    modes = read_measured_modes(path)
    rows = list(csv.DictReader(Path(path).read_text(encoding="utf-8").splitlines()))
    if "pattern_0g" not in rows[0]:
        raise MaceError(f"{path}: no column pattern_0g (the label pattern of each mode's 0-g pole, e.g. "
                        "'* Y bending'; empty for modes the 0-g structure lacks)")
    return modes, tuple((row["pattern_0g"] or "").strip() or None for row in rows)


def _pair(modes: Sequence[tuple[str, str, float]], poles: Sequence[ClosedLoopPole], *, what: str) -> list[int]:
    """Pole index per (label, pattern, Hz); a MaceError names every mode that pairs with no pole."""
    index = pair_poles([(pattern, hz) for _, pattern, hz in modes], poles)
    missing = [f"{label!r} ({hz:.3f} Hz, pattern {pattern!r})" for (label, pattern, hz), i in zip(modes, index)
               if i is None]
    if missing:
        low, high = min(hz for *_, hz in modes) / 2, max(hz for *_, hz in modes) * 2
        near = sorted({p.label for p in poles if p.damping < REAL_POLE_DAMPING and low <= p.frequency_hz <= high})
        raise MaceError(f"measured mode(s) {', '.join(missing)} pair with no pole of {what}; its poles from "
                        f"{low:.3g} to {high:.3g} Hz: {', '.join(near)}")
    return [int(i) for i in index]


class _Adjuster:
    """Open-loop frequency scales and damping ratios of chosen modes -> closed-loop poles, by rebuilding."""

    def __init__(self, model: VoltsModel, modes: Sequence[int]):
        self.system = ParametricSystem(parametric_arrays(model, physical=False))
        self.modes = list(modes)
        self.scale = [self.system.index(FREQUENCY_SCALE.fmu_name(m + 1)) for m in self.modes]
        self.damping = [self.system.index(DAMPING.fmu_name(m + 1)) for m in self.modes]
        self.open_damping = self.system.nominal[self.damping]

    def params(self, x: np.ndarray) -> np.ndarray:
        n = len(self.modes)
        p = self.system.nominal.copy()
        p[self.scale] = np.exp(x[:n])
        p[self.damping] = self.open_damping * x[n:]
        return p

    def poles(self, x: np.ndarray, near_hz: np.ndarray) -> list[ClosedLoopPole]:
        """For each mode, the closed-loop pole it dominates nearest ``near_hz`` (a MaceError when it dominates none)."""
        a, *_ = self.system.build(self.params(x))
        poles = [p for p in label_poles(a, state_names=self.system.state_names,
                                        mode_labels=self.system.state_mode_labels) if p.damping < REAL_POLE_DAMPING]
        out = []
        for m, hz in zip(self.modes, near_hz):
            mine = [p for p in poles if p.mode == m]
            if not mine:
                raise MaceError(f"0-g adjustment: open-loop mode {m + 1} ({self.system.mode_labels[m]}) no longer "
                                "dominates any closed-loop pole")
            out.append(min(mine, key=lambda p: abs(p.frequency_hz - hz)))
        return out


def _adjustable_modes(model: VoltsModel, poles: Sequence[tuple[str, ClosedLoopPole]]) -> list[int]:
    """The open-loop mode (0-based) behind each (measured label, 0-g pole); a MaceError where it cannot be
    adjusted alone: no structural vibration mode, shared by two measured modes, or a label other modes carry."""
    modes = [pole.mode for _, pole in poles]
    labels = model.structure_modes.labels
    for (label, pole), m in zip(poles, modes):
        what = f"measured mode {label!r}: its 0-g pole ({pole.label})"
        if m is None or abs(model.plant.frequencies_hz[m]) < ZERO_HZ:
            raise MaceError(f"{what} is no structural vibration mode; its frequency cannot be adjusted")
        if modes.count(m) > 1:
            raise MaceError(f"{what} and another measured mode both live mostly in open-loop mode {m + 1} "
                            f"({model.plant.labels[m]}): one open-loop mode cannot take two corrections")
        if labels.count(model.plant.labels[m]) > 1:
            raise MaceError(f"{what} lives in open-loop mode {m + 1}, whose label {model.plant.labels[m]!r} other "
                            "modes share: a correction by label would move them too")
    return modes


def _solve_adjustment(adjuster: _Adjuster, target_hz: np.ndarray, target_zeta: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    """(unknowns, damping pinned) that put the adjusted modes' closed-loop poles on their targets [Hz, -].

    Unknowns: log frequency scales (within a factor 2) and open-loop damping ratios relative to the
    unaltered ones (>= 0, below 0.95 absolute). Servo damping can put a closed-loop damping target out
    of reach; such a damping ratio is pinned at its limit and its target dropped, and the rest solved
    again, so that no other mode trades its fit for it.
    """
    n = len(target_hz)
    lower = np.concatenate([np.full(n, -np.log(2.0)), np.zeros(n)])
    upper = np.concatenate([np.full(n, np.log(2.0)), 0.95 / np.maximum(adjuster.open_damping, 1e-12)])
    x = np.concatenate([np.zeros(n), np.ones(n)])
    pinned = np.zeros(n, dtype=bool)

    def misses(full: np.ndarray) -> np.ndarray:
        poles = adjuster.poles(full, target_hz)
        return np.concatenate([np.log([p.frequency_hz for p in poles] / target_hz),
                               np.array([p.damping for p in poles]) / target_zeta - 1.0])

    weight = np.concatenate([np.full(n, _FREQUENCY_WEIGHT), np.ones(n)])
    for _ in range(n + 1):
        free = np.concatenate([np.ones(n, dtype=bool), ~pinned])

        def residual(z: np.ndarray, free: np.ndarray = free) -> np.ndarray:
            full = x.copy()
            full[free] = z
            return (weight * misses(full))[free]

        if n:
            x[free] = least_squares(residual, x[free], bounds=(lower[free], upper[free]), xtol=1e-14, ftol=1e-14,
                                    gtol=1e-14).x
        miss = misses(x) if n else np.zeros(0)
        at_limit = np.isclose(x[n:], lower[n:], rtol=0, atol=1e-9) | np.isclose(x[n:], upper[n:], rtol=1e-9)
        newly = ~pinned & at_limit & (np.abs(miss[n:]) > _TOLERANCE)
        if not newly.any():
            break
        pinned |= newly
        x[n:][newly] = np.where(x[n:] - lower[n:] < upper[n:] - x[n:], lower[n:], upper[n:])[newly]
    bad = np.flatnonzero((np.abs(miss) > _TOLERANCE) & np.concatenate([np.ones(n, dtype=bool), ~pinned]))
    if bad.size:
        worst = int(bad[np.argmax(np.abs(miss[bad]))])
        raise MaceError(f"0-g adjustment: the closed-loop {'frequency' if worst < n else 'damping ratio'} of open-loop "
                        f"mode {adjuster.modes[worst % n] + 1} misses its target by {abs(miss[worst]):.1e} (relative)")
    return x, pinned


def _with_closed_loop_shifts(rows: Sequence[ZeroGRow], core: VoltsModel) -> list[ZeroGRow]:
    """``rows`` with the closed-loop shift of each bounded mode's pole, its frequency scale at 1 -+ bound, by
    rebuilding ``core`` (the nominal model without output filters) as the FMUs do."""
    system = ParametricSystem(parametric_arrays(core, physical=False))
    out = []
    for row in rows:
        if row.mode is None:
            out.append(row)
            continue
        shift = []
        for side in (-1.0, 1.0):
            params = system.nominal.copy()
            params[system.index(FREQUENCY_SCALE.fmu_name(row.mode))] = 1.0 + side * row.bound
            a, *_ = system.build(params)
            poles = [p for p in label_poles(a, state_names=system.state_names, mode_labels=system.state_mode_labels)
                     if p.mode == row.mode - 1 and p.damping < REAL_POLE_DAMPING]
            pole = min(poles, key=lambda p: abs(p.frequency_hz - row.nominal_hz * (1.0 + side * row.bound)))
            shift.append(pole.frequency_hz / row.nominal_hz - 1.0)
        out.append(replace(row, closed_loop_shift=(shift[0], shift[1])))
    return out


def _deck_provenance(parameters: ParameterSet | None, deck: Deck | None, *, source: str) -> Provenance:
    """Provenance of the nominal 0-g set: the input's (same deck), marked 0-g and thesis 5.3."""
    base = parameters.provenance if parameters is not None else None
    method = "thesis 5.3: 0-g open-loop frequencies and damping ratios adjusted by the residual 1-g errors"
    if base is None:
        from mace_fmu.structure.file import bundled_deck_path

        path = Path(deck.path) if deck is not None else bundled_deck_path()
        return Provenance(created=now_utc(), tool=tool_version(), deck=path.name, deck_sha256=deck_fingerprint(path),
                          configuration="0g", data=source, method=method)
    return Provenance(created=now_utc(), tool=tool_version(), deck=base.deck, deck_sha256=base.deck_sha256,
                      configuration="0g", data=source, method=method,
                      notes=f"from a {base.configuration or 'parameter'} set made {base.created} "
                            f"({base.method})".strip())


@dataclass(frozen=True)
class _Adjustment:
    """The solved 0-g adjustment: which open-loop modes moved, and every parameter of the rebuilt system."""

    adjuster: _Adjuster
    params: np.ndarray  #: the rebuilt system's parameters (adjuster.system's order) after the adjustment
    pinned: np.ndarray  #: per adjusted mode: its closed-loop damping target was out of reach

    def updates(self, labels: Sequence[str]) -> dict[str, float]:
        """``frequency_scale:<label>`` and ``damping:<label>`` of each adjusted mode (``labels``: the plant's)."""
        out = {}
        for k, m in enumerate(self.adjuster.modes):
            out[FREQUENCY_SCALE.set_name(labels[m])] = float(self.params[self.adjuster.scale[k]])
            out[DAMPING.set_name(labels[m])] = float(self.params[self.adjuster.damping[k]])
        return out

    def frequency_scale(self, mode: int) -> float:
        """The frequency scale of open-loop mode ``mode`` (0-based) after the adjustment."""
        return float(self.params[self.adjuster.system.index(FREQUENCY_SCALE.fmu_name(mode + 1))])


def _measurement_model(measured: Sequence[MeasuredMode] | None, zero_g_patterns: Sequence[str | None] | None, *,
                       deck: Deck | None) -> tuple[Sequence[MeasuredMode], Sequence[str | None]]:
    """The measured 1-g modes and their 0-g patterns: the given ones, checked, or Table 4.7's for the bundled deck."""
    if measured is None:
        if deck is not None and not is_bundled_deck(deck):
            raise MaceError(f"{deck.path} is not the bundled MACE deck: its 1-g measurement model is not Table 4.7's; "
                            "give it (CLI --measured FILE: label, pattern, frequency_hz, damping, pattern_0g)")
        measured, zero_g_patterns = measured_modes(band_hz=None), table_4_7_zero_g_patterns()
    if zero_g_patterns is None or len(zero_g_patterns) != len(measured):
        raise MaceError(f"the measurement model has {len(measured)} modes but "
                        f"{0 if zero_g_patterns is None else len(zero_g_patterns)} 0-g patterns; give one per mode")
    if not any(zero_g_patterns):
        raise MaceError("no measured mode has a 0-g counterpart (every pattern_0g is empty)")
    return measured, zero_g_patterns


def _nominal_set(parameters: ParameterSet | None, updates: Mapping[str, float], *, labels: Sequence[str],
                 held: Sequence[str], deck: Deck | None, source: str) -> ParameterSet:
    """The parameter set of the nominal 0-g model: the input's values that exist in 0-g, and the adjustments."""
    base = {name: value for name, value in (parameters.values if parameters is not None else {}).items()
            if not getattr(kind_of_set_name(name), "per_mode", False)
            or mode_label(name) in set(labels)}  # 1-g only modes (suspension, violins) do not exist in 0-g
    provenance = _deck_provenance(parameters, deck, source=source)
    if held:  # a damping ratio of 0 in the set is a result, not a slip: say why where it is read
        provenance = dataclasses.replace(provenance, notes="; ".join(filter(None, [provenance.notes, (
            f"open-loop damping 0 for {', '.join(held)}: the servos alone give more closed-loop damping in 0-g than "
            "the target, which is out of reach (docs/guide/zero_g.md)")])))
    return ParameterSet({**base, **updates}, provenance)


@single_blas_thread
def predict_zero_g(*, parameters: ParameterSet | None = None, measured: Sequence[MeasuredMode] | None = None,
                   zero_g_patterns: Sequence[str | None] | None = None, rule: BoundRule = BoundRule(),
                   deck: Deck | None = None, structure_file: StructureFile | str | os.PathLike | None = None,
                   source: str = "Table 4.7 measurement model",
                   progress: ProgressCallback | None = None) -> ZeroGPrediction:
    """The updated nominal 0-g model and its bounds (thesis 5.3) from ``parameters`` and a 1-g measurement model.

    Parameters
    ----------
    parameters : ParameterSet, optional
        The updated 1-g parameter set (default: the bundled deck's values).
    measured : sequence of MeasuredMode, optional
        The 1-g measured modes (default: Table 4.7's measured column).
    zero_g_patterns : sequence of str or None, optional
        One per measured mode: which 0-g mode continues it (None: no 0-g counterpart); default:
        Table 5.2's rows, for the bundled MACE deck only (any other deck needs its own).
    rule : BoundRule
        How each 0-g mode's frequency bound follows from its 1-g residual error.
    deck : Deck, optional
        The deck (default: the bundled MACE deck).
    structure_file : StructureFile or path, optional
        As :func:`~mace_fmu.iomodel.volts.volts_model`'s.
    source : str
        Which measurement model the residual errors come from (written into the files).
    progress : callable, optional
        Receives a :class:`~mace_fmu.util.progress.Step` as each of the four stages begins.

    Returns
    -------
    ZeroGPrediction
        The rows (1-g error, 0-g nominal frequency [Hz] and bound), the parameter set that builds the
        nominal 0-g model (frequency scales included) and the model itself. A row whose closed-loop
        damping target was out of reach says so (``damping_reached``).

    Raises
    ------
    MaceError
        A parameter set with frequency scales, or measured modes and patterns of different lengths.
    """
    if parameters is not None and parameters.of_kind("frequency_scale"):
        # frequency scales act on whichever structure the set is used with: a 1-g model must not get them
        raise MaceError(f"the parameter set has frequency scales ({', '.join(parameters.of_kind('frequency_scale'))}):"
                        " predict-0g starts from physical parameters (e.g. from mace-fmu update), not from an "
                        "updated nominal 0-g set")
    measured, zero_g_patterns = _measurement_model(measured, zero_g_patterns, deck=deck)
    kept = [k for k, pattern in enumerate(zero_g_patterns) if pattern]

    begin_stage(progress, "1-g closed-loop model and the residual errors", number=1, stages=4)
    v1 = volts_model(compute_modes(deck, configuration="1g", structure_file=structure_file, parameters=parameters))
    if parameters is not None:  # mode numbers (an FMU update's) count the 1-g modes: the 0-g model gets their labels
        parameters = ParameterSet(label_mode_names(parameters.values, mode_labels=v1.structure_modes.labels,
                                                   model="1g structure", source=parameters.source),
                                  parameters.provenance, source=parameters.source)
    p1 = closed_loop_poles(v1)
    one_g = [p1[i] for i in _pair([(m.label, m.pattern, m.frequency_hz) for m in measured], p1, what="the 1-g model")]

    begin_stage(progress, "0-g closed-loop model", number=2, stages=4)
    v0 = volts_model(compute_modes(deck, configuration="0g", structure_file=structure_file, parameters=parameters))
    p0 = closed_loop_poles(v0)
    unaltered = [p0[i] for i in _pair([(measured[k].label, zero_g_patterns[k], one_g[k].frequency_hz) for k in kept],
                                      p0, what="the 0-g model")]
    heavy = [measured[k].damping >= rule.heavy_damping for k in kept]
    adjusted = [j for j, h in enumerate(heavy) if rule.correct_heavy or not h]

    begin_stage(progress, f"adjusting {len(adjusted)} open-loop 0-g modes", number=3, stages=4)
    # each adjusted 0-g pole moves by its 1-g pole's ratio measured / model, in frequency and damping alike
    target_hz = np.array([unaltered[j].frequency_hz * measured[kept[j]].frequency_hz / one_g[kept[j]].frequency_hz
                          for j in adjusted])
    target_zeta = np.array([unaltered[j].damping * measured[kept[j]].damping / one_g[kept[j]].damping
                            for j in adjusted])
    modes = _adjustable_modes(v0, [(measured[kept[j]].label, unaltered[j]) for j in adjusted])
    # the output filters sit outside every loop: the closed-loop structural poles are those of the model without them
    adjuster = _Adjuster(volts_model(v0.structure_modes, parameters=parameters,
                                     electronics=ModelledElectronics(bessel="none")), modes)
    x, pinned = _solve_adjustment(adjuster, target_hz, target_zeta)
    adjustment = _Adjustment(adjuster=adjuster, params=adjuster.params(x), pinned=pinned)
    nominal_set = _nominal_set(parameters, adjustment.updates(v0.plant.labels), labels=v0.structure_modes.labels,
                               held=[measured[kept[j]].label for j, p in zip(adjusted, pinned) if p], deck=deck,
                               source=source)

    begin_stage(progress, "updated nominal 0-g model", number=4, stages=4)
    nominal = volts_model(v0.structure_modes, parameters=nominal_set)
    pn = closed_loop_poles(nominal)
    near = [p.frequency_hz for p in unaltered]
    for j, hz in zip(adjusted, target_hz):
        near[j] = hz
    index = _pair([(measured[k].label, zero_g_patterns[k], hz) for k, hz in zip(kept, near)], pn,
                  what="the nominal 0-g model")
    rows = []
    for j, k in enumerate(kept):
        m, pole = measured[k], pn[index[j]]
        mode = pole.mode if pole.mode is not None and abs(nominal.plant.frequencies_hz[pole.mode]) >= ZERO_HZ else None
        rows.append(ZeroGRow(
            label=m.label, heavy=heavy[j], measured_1g_hz=m.frequency_hz, measured_1g_damping=m.damping,
            model_1g_hz=one_g[k].frequency_hz, model_1g_damping=one_g[k].damping,
            unaltered_hz=unaltered[j].frequency_hz, unaltered_damping=unaltered[j].damping,
            nominal_hz=pole.frequency_hz, nominal_damping=pole.damping,
            bound=rule.bound(heavy=heavy[j], frequency_error=one_g[k].frequency_hz / m.frequency_hz - 1.0),
            pole_label=pole.label, mode=None if mode is None else mode + 1,
            mode_label=nominal.plant.labels[mode] if mode is not None else "",
            frequency_scale=adjustment.frequency_scale(mode) if mode is not None else 1.0,
            open_loop_damping=float(nominal.plant.damping[mode]) if mode is not None else math.nan,
            adjusted=j in adjusted, damping_reached=j not in adjusted or not pinned[adjusted.index(j)]))
    core = volts_model(v0.structure_modes, parameters=nominal_set, electronics=ModelledElectronics(bessel="none"))
    return ZeroGPrediction(rows=tuple(_with_closed_loop_shifts(rows, core)), parameters=nominal_set, model=nominal,
                           rule=rule, source=source,
                           dropped=tuple(measured[k].label for k, p in enumerate(zero_g_patterns) if not p))
