"""The MACE update of thesis 4.5: from the pre-update moduli to an updated 1-g model, by the modal route
(:func:`~mace_fmu.updating.modal.update.select_and_update`) on the bundled deck.

Start: the "engineering insight" model, whose moduli follow from Table 4.4 as E_updated /
(1 + change); the bundled deck holds the updated ones. Data: the measurement-model column of
Table 4.7 (frequencies and damping ratios, the only measured numbers the thesis prints). Cost:
the modal cost (eq. 4.2 plus a damping term) on the closed-loop (servoed) volts-volts model, modes
paired by label and frequency (Table 4.7 prints no mode shapes, so the MAC pairing and the shape terms of the
modal route have nothing to work on). Candidates: the 13 of section 4.5, judged by the orthogonality and
strength tests. Sequence: physical parameters, then the gimbal servo delays, then the damping
ratios, twice.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import numpy as np

from mace_fmu.fe.preload import PreloadKind
from mace_fmu.parameters.kinds import DAMPING, MODULUS
from mace_fmu.parameters.sets import ParameterSet, Provenance, deck_fingerprint, now_utc, tool_version
from mace_fmu.thesis import thesis_data
from mace_fmu.updating.engine.costs import ModalCost
from mace_fmu.updating.engine.measured import MeasuredMode
from mace_fmu.updating.engine.selection import Selection, SelectionRule
from mace_fmu.updating.engine.sensitivity import CostSensitivities
from mace_fmu.updating.engine.solve import Stage, UpdateResult, UpdateSettings
from mace_fmu.updating.mace.family import MaceFamily
from mace_fmu.updating.modal.update import select_and_update
from mace_fmu.util.progress import ProgressCallback, begin_stage
from mace_fmu.util.threads import single_blas_thread

#: the 13 candidates of section 4.5, numbered as in Figures 4.11 and 4.12
CANDIDATES = ("E_lexan_end", "E_lexan_center", "E_stainless_steel", "E_aluminium", "E_cable_1", "E_cable_2",
              "E_cable_3", "E_active_strut_end", "E_active_strut_piezo", "E_active_strut_center",
              "k_suspension_device_1", "k_suspension_device_2", "k_suspension_device_3")
#: what the thesis kept (section 4.5): aluminium, stainless steel and the three springs dropped
THESIS_KEPT = ("E_lexan_end", "E_lexan_center", "E_cable_1", "E_cable_2", "E_cable_3", "E_active_strut_end",
               "E_active_strut_piezo", "E_active_strut_center")
#: the active strut's moduli are kept or dropped together (thesis 4.5)
ACTIVE_STRUT = ("E_active_strut_end", "E_active_strut_piezo", "E_active_strut_center")
#: delays inside the gimbal servo loops: the only delays closed-loop poles see
SERVO_DELAYS = ("delay_gimbal_primary_x", "delay_gimbal_primary_z", "delay_gimbal_secondary_x",
                "delay_gimbal_secondary_z")
HEAVY_DAMPING = 0.10  #: thesis 5.3: heavily damped means zeta >= 10 %
HEAVY_WEIGHT = 0.2  #: servo-dominated modes count less in the physical update
#: lightly damped bending modes count double: the 0-g model for control design keeps them, while
#: the suspension and violin modes vanish with the suspension (chapter 5)
STRUCTURAL_WEIGHT = 2.0


def pre_update_parameters() -> ParameterSet:
    """Table 4.4 back-computed: E_before = E_updated / (1 + change)."""
    rows = thesis_data()["table_4_4"]
    return ParameterSet({MODULUS.named(name): row["e"] / (1.0 + row["change_percent"] / 100.0)
                         for name, row in rows.items()})


def table_4_4_moduli() -> dict[str, float]:
    """The updated moduli [Pa] of Table 4.4 by parameter name."""
    return {MODULUS.named(name): row["e"] for name, row in thesis_data()["table_4_4"].items()}


#: the thesis's update band (4.5): above the low-frequency scatter, below the roll-off of gyros and filters
UPDATE_BAND_HZ = (0.5, 60.0)


def measured_modes(*, heavy_weight: float = HEAVY_WEIGHT, structural_weight: float = STRUCTURAL_WEIGHT,
                   band_hz: tuple[float, float] | None = UPDATE_BAND_HZ) -> tuple[MeasuredMode, ...]:
    """Table 4.7's measurement-model column within ``band_hz`` [Hz] (None: all), with the label
    patterns that pair our poles and the weights: heavily damped modes ``heavy_weight``, lightly
    damped bending modes ``structural_weight``, the others 1."""
    lo, hi = band_hz if band_hz is not None else (0.0, np.inf)

    def weight(row) -> float:
        if row["mm_zeta"] >= HEAVY_DAMPING:
            return heavy_weight
        return structural_weight if is_structural(row["label"]) else 1.0

    return tuple(MeasuredMode(label=r["label"], pattern=r["ours"], frequency_hz=r["mm_hz"], damping=r["mm_zeta"],
                              weight=weight(r))
                 for r in thesis_data()["table_4_7"] if lo <= r["mm_hz"] <= hi)


def damping_labels(family: MaceFamily) -> tuple[str, ...]:
    """Mode labels whose damping ratio the data file sets by label and the model has (bending and
    suspension modes; violin families keep their table)."""
    table = family.solution(family.base.values).volts.instruments.damping.by_label
    present = set(family.solution(family.base.values).system.mode_labels)
    return tuple(label for label in table if label in present)


@dataclass(frozen=True)
class MaceUpdate:
    """Everything the MACE update produced."""

    family: MaceFamily  #: the MACE model family updated
    cost: ModalCost  #: the modal cost (Table 4.7's measured modes)
    start: ParameterSet  #: the pre-update parameter set
    selection_sensitivities: CostSensitivities  #: cost sensitivities of every candidate parameter at the start
    selection: Selection  #: the parameters chosen and why
    result: UpdateResult  #: where the update ended
    parameters: ParameterSet  #: the updated set (start values for the rest), with provenance
    seconds: Mapping[str, float] = field(default_factory=dict)  #: wall time per stage
    measured: tuple[MeasuredMode, ...] = ()  #: every measured mode (the cost sees those in the update band)


@single_blas_thread
def run_mace_update(*, start: ParameterSet | None = None, measured: Sequence[MeasuredMode] | None = None,
                    preload: PreloadKind = "large", settings: UpdateSettings = UpdateSettings(rounds=2),
                    rule: SelectionRule | None = None, candidates: Sequence[str] = CANDIDATES, deck=None,
                    runner: Callable = map, progress: ProgressCallback | None = None) -> MaceUpdate:
    """The thesis's MACE update: selection of the candidates about ``start``, then the staged update.

    Parameters
    ----------
    start : ParameterSet, optional
        Where the update starts (default: the pre-update moduli, Table 4.4 back-computed).
    measured : sequence of MeasuredMode, optional
        The 1-g measured modes (default: Table 4.7's measurement model; the update band applies).
    preload : {"large", "linear"}
        The 1-g gravity preload.
    settings : UpdateSettings
        Method and stopping tests (default: the cost-sensitivity method, two rounds).
    rule : SelectionRule, optional
        Which candidates are kept (default: the thesis's).
    candidates : sequence of str
        The candidate parameters (default: the thesis's 13).
    deck : Deck, optional
        The deck (default: the bundled MACE deck).
    runner : callable
        ``map``-like function the perturbed models go to.
    progress : callable, optional
        Receives a :class:`~mace_fmu.util.progress.Step` as each of the three stages begins, and the steps of the
        long ones (cost sensitivities, the update's iterations).

    Returns
    -------
    MaceUpdate
        The selection, the update's result, the updated parameter set (with provenance) and the time per
        stage [s].
    """
    seconds: dict[str, float] = {}
    start = start if start is not None else pre_update_parameters()
    t0 = time.perf_counter()
    begin_stage(progress, "1-g model at the start point", number=1, stages=3)
    family = MaceFamily(configuration="1g", base=start, deck=deck, preload=preload)
    data = "thesis Table 4.7, measurement model column (frequencies and damping ratios)"
    if measured is None:
        measured = measured_modes(band_hz=None)
    else:
        data = f"{len(measured)} measured modes ({', '.join(sorted({m.label for m in measured}))})"
    lo, hi = UPDATE_BAND_HZ
    cost = ModalCost(measured=tuple(m for m in measured if lo <= m.frequency_hz <= hi))
    cost.pairs(family.full(family.base.values))  # a mode no pole can be: say so before any work
    seconds["start model"] = time.perf_counter() - t0

    rule = rule if rule is not None else SelectionRule(groups=(ACTIVE_STRUT,))
    damp = tuple(DAMPING.set_name(label) for label in damping_labels(family))
    # stiffness dominates the closed-loop frequencies, damping ratios and servo delays the damping
    # (thesis 4.3): the stiffness stage sees the frequency errors only
    frequencies_only = ModalCost(measured=cost.measured, damping_weight=0.0)

    def stages_of(selection: Selection) -> list[Stage]:
        return [Stage("physical", selection.keep, cost=frequencies_only), Stage("delays", SERVO_DELAYS),
                Stage("damping", damp)]

    # the modal route's sequence (updating.modal): cost sensitivities of the candidates, the selection tests,
    # the staged update on what they keep
    selected = select_and_update(family, cost, candidates=candidates, rule=rule, stages_of=stages_of,
                                 settings=settings, runner=runner, progress=progress)
    seconds.update(selected.seconds)
    sens, selection, result = selected.sensitivities, selected.selection, selected.result
    stages = stages_of(selection)
    deck_path = family.deck.path
    prov = Provenance(created=now_utc(), tool=tool_version(), deck=str(deck_path).rsplit("/", 1)[-1],
                      deck_sha256=deck_fingerprint(deck_path), configuration="1g",
                      data=data,
                      cost=f"modal (eq. 4.2 + damping term, damping weight {cost.damping_weight}; modes with "
                           f"zeta >= {HEAVY_DAMPING} weighted {HEAVY_WEIGHT}, lightly damped bending modes "
                           f"{STRUCTURAL_WEIGHT}; {UPDATE_BAND_HZ[0]}-{UPDATE_BAND_HZ[1]} Hz; the physical stage on "
                           "frequencies only), closed-loop 1-g volts-volts model",
                      method=f"{settings.method} ({settings.perturbation} perturbations, step {settings.relative_step}), "
                             f"penalty {'on' if settings.penalty else 'off'}, {settings.rounds} rounds of "
                             + ", ".join(s.name for s in stages) + f"; {preload} preload",
                      initial_cost=result.initial_cost, final_cost=result.final_cost)
    updated = start.updated(family.values_for_rebuild({**start.values, **result.values}), provenance=prov)
    return MaceUpdate(family=family, cost=cost, start=start, selection_sensitivities=sens, selection=selection,
                      result=result, parameters=updated, seconds=seconds, measured=tuple(measured))


@dataclass(frozen=True)
class ModeRow:
    """One measured mode: the thesis's FE model, ours before and after the update."""

    label: str
    measured_hz: float
    measured_zeta: float
    thesis_hz: float
    thesis_zeta: float
    before_hz: float
    before_zeta: float
    before_label: str
    after_hz: float
    after_zeta: float
    after_label: str

    def error(self, hz: float) -> float:
        return 100.0 * (hz - self.measured_hz) / self.measured_hz


def mode_rows(outcome: MaceUpdate) -> list[ModeRow]:
    """Mode by mode over every measured mode: measured, thesis FE (Table 4.7's data only), ours before,
    ours after (poles paired as in the cost)."""
    fam, cost = outcome.family, ModalCost(measured=outcome.measured or measured_modes(band_hz=None))
    before = fam.full(outcome.result.start)
    after = fam.full(outcome.result.values)
    pb, pa = before.poles(), after.poles()
    ib, ia = cost.pairs(before), cost.pairs(after)
    table = thesis_data()["table_4_7"]
    is_table_4_7 = [(m.label, m.frequency_hz) for m in cost.measured] == [(r["label"], r["mm_hz"]) for r in table]
    rows = []
    for k, (m, i, j) in enumerate(zip(cost.measured, ib, ia)):
        fe_hz, fe_zeta = (table[k]["fe_hz"], table[k]["fe_zeta"]) if is_table_4_7 else (np.nan, np.nan)
        rows.append(ModeRow(m.label, m.frequency_hz, m.damping, fe_hz, fe_zeta, pb[i].frequency_hz,
                            pb[i].damping, pb[i].label, pa[j].frequency_hz, pa[j].damping, pa[j].label))
    return rows


@dataclass(frozen=True)
class PreUpdateRow:
    """One row of Table 4.1 (after engineering insight, before automated updating) beside our pre-update model."""

    label: str
    measured_hz: float
    thesis_hz: float  #: Table 4.1's finite element column
    ours_hz: float
    ours_label: str


def table_4_1_rows(family: MaceFamily, values: Mapping[str, float]) -> list[PreUpdateRow]:
    """Our closed-loop model at ``values`` paired with Table 4.1's rows (label pattern, then frequency)."""
    from mace_fmu.iomodel.pole_pairing import pair_poles

    rows = thesis_data()["table_4_1"]
    poles = family.full(values).poles()
    pairs = pair_poles([(r["ours"], r["fe_hz"]) for r in rows], poles)
    return [PreUpdateRow(r["label"], r["mm_hz"], r["fe_hz"], poles[i].frequency_hz if i is not None else np.nan,
                         poles[i].label if i is not None else "(none)") for r, i in zip(rows, pairs)]


def format_table_4_1(rows: Sequence[PreUpdateRow]) -> str:
    """Table 4.1 beside our pre-update model: measured, thesis FE, ours, and the gap to the thesis."""
    head = f"{'mode (Table 4.1)':16s} {'meas Hz':>7s} | {'thesis FE':>9s} {'err%':>5s} | {'ours':>7s} {'err%':>5s} " \
           f"{'vs FE%':>6s}  our label"
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r.label:16s} {r.measured_hz:7.2f} | {r.thesis_hz:9.2f} "
                     f"{100 * (r.thesis_hz / r.measured_hz - 1):5.1f} | {r.ours_hz:7.3f} "
                     f"{100 * (r.ours_hz / r.measured_hz - 1):5.1f} {100 * (r.ours_hz / r.thesis_hz - 1):6.1f}  "
                     f"{r.ours_label}")
    return "\n".join(lines)


def is_structural(label: str) -> bool:
    """Bending modes of the test article (not suspension, violin, gimbal or delay modes)."""
    return "bending" in label


@dataclass(frozen=True)
class Scores:
    """The goals of the MACE update in numbers."""

    rms_light_thesis: float  #: RMS frequency error [%] over measured modes with zeta < 10 %, Table 4.7
    rms_light_before: float
    rms_light_after: float
    worst_structural_before: tuple[str, float]  #: (mode, error %) of the lightly damped bending modes
    worst_structural_after: tuple[str, float]


def scores(rows: Sequence[ModeRow]) -> Scores:
    light = [r for r in rows if r.measured_zeta < HEAVY_DAMPING]

    def rms(values):
        return float(np.sqrt(np.mean(np.square(values))))

    structural = [r for r in light if is_structural(r.label)]

    def worst(attr):
        if not structural:
            return "(no lightly damped bending mode measured)", float("nan")
        r = max(structural, key=lambda r: abs(r.error(getattr(r, attr))))
        return f"{r.label} {r.measured_hz:g} Hz", r.error(getattr(r, attr))

    return Scores(rms_light_thesis=rms([r.error(r.thesis_hz) for r in light]),
                  rms_light_before=rms([r.error(r.before_hz) for r in light]),
                  rms_light_after=rms([r.error(r.after_hz) for r in light]),
                  worst_structural_before=worst("before_hz"), worst_structural_after=worst("after_hz"))


def format_mode_rows(rows: Sequence[ModeRow]) -> str:
    """The before/after table, one line per measured mode."""
    head = (f"{'mode (Table 4.7)':16s} {'meas Hz':>7s} {'zeta':>5s} | {'thesis':>6s} {'err%':>5s} | "
            f"{'before':>7s} {'err%':>5s} {'zeta':>5s} | {'after':>7s} {'err%':>5s} {'zeta':>5s}  our label (after)")
    lines = [head, "-" * len(head)]
    for r in rows:
        mark = "*" if r.measured_zeta >= HEAVY_DAMPING else " "
        lines.append(f"{r.label:15s}{mark} {r.measured_hz:7.2f} {r.measured_zeta:5.3f} | {r.thesis_hz:6.2f} "
                     f"{r.error(r.thesis_hz):5.1f} | {r.before_hz:7.3f} {r.error(r.before_hz):5.1f} "
                     f"{r.before_zeta:5.3f} | {r.after_hz:7.3f} {r.error(r.after_hz):5.1f} {r.after_zeta:5.3f}  "
                     f"{r.after_label}")
    lines.append("* heavily damped (zeta >= 10 %): servo-dominated, weighted "
                 f"{HEAVY_WEIGHT} in the cost, not in the RMS below")
    s = scores(rows)
    lines.append(f"RMS frequency error over the {sum(r.measured_zeta < HEAVY_DAMPING for r in rows)} modes with "
                 f"zeta < 10 %: thesis {s.rms_light_thesis:.2f} %, ours before {s.rms_light_before:.2f} %, "
                 f"after {s.rms_light_after:.2f} %")
    lines.append(f"worst lightly damped bending mode: before {s.worst_structural_before[0]} "
                 f"{s.worst_structural_before[1]:+.2f} %, after {s.worst_structural_after[0]} "
                 f"{s.worst_structural_after[1]:+.2f} %")
    return "\n".join(lines)


def format_moduli(outcome: MaceUpdate) -> str:
    """Our updated moduli next to Table 4.4's, with the changes from the pre-update values."""
    thesis = table_4_4_moduli()
    start = outcome.result.start
    lines = [f"{'parameter':24s} {'start':>11s} {'ours':>11s} {'change%':>8s} | {'Table 4.4':>11s} {'change%':>8s}"]
    for n in CANDIDATES:
        if n not in outcome.result.values and n not in thesis:
            continue
        s0 = start.get(n, outcome.parameters.values.get(n, np.nan))
        ours = outcome.result.values.get(n, s0)
        th = thesis.get(n, np.nan)
        lines.append(f"{n:24s} {s0:11.4g} {ours:11.4g} {100 * (ours / s0 - 1):8.2f} | {th:11.4g} "
                     f"{100 * (th / s0 - 1):8.2f}")
    return "\n".join(lines)


def cost_history(outcome: MaceUpdate) -> list[tuple[str, float, float]]:
    """(stage/round/outer, cost before, predicted cost) per outer iteration."""
    return [(f"round {it.round + 1} {it.stage} #{it.outer + 1}", it.cost_before, it.cost_predicted)
            for it in outcome.result.history]
