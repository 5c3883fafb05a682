"""The modal update of any structure (thesis 4.2): measured modes paired by MAC, the cost on their frequencies
(eq. 4.2) and shapes, parameter selection on the cost sensitivities (eq. 4.14-4.16), the staged update by the
cost-sensitivity method (eq. 4.11-4.13), the damping ratios taken from the measurement model.

:func:`select_and_update` is the thesis's sequence on any family and cost: cost sensitivities of the candidates,
the orthogonality and strength tests, then the stages on what they keep. :func:`run_modal_update` runs it on a
deck and structure file against a modes file; :func:`~mace_fmu.updating.mace.update.run_mace_update` on the
bundled deck against Table 4.7.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.parameters.kinds import DAMPING
from mace_fmu.parameters.sets import ParameterSet, Provenance, deck_fingerprint, now_utc, tool_version
from mace_fmu.updating.engine.bounds import default_bounds
from mace_fmu.updating.engine.costs import ModeShapeCost
from mace_fmu.updating.engine.measured import MeasuredMode
from mace_fmu.updating.engine.selection import Selection, SelectionRule, select_parameters
from mace_fmu.updating.engine.sensitivity import CostSensitivities, cost_sensitivities
from mace_fmu.updating.engine.solve import Stage, UpdateResult, UpdateSettings, update
from mace_fmu.updating.modal.correlation import DEFAULT_MIN_MAC, Correlation, correlate
from mace_fmu.updating.modal.family import StructureFamily
from mace_fmu.updating.modal.modes_file import ModesFile
from mace_fmu.util.progress import ProgressCallback, begin_stage
from mace_fmu.util.threads import single_blas_thread

#: the modal route's update: the thesis's cost-sensitivity method, its perturbed models full FE re-solves (a small
#: deck re-solves in a fraction of a second), two rounds; no penalty (eq. 4.18) unless asked for, as in the FMU route:
#: the bounds (x0.5-1.5 for moduli and masses) hold the parameters, and a measured modes file pulls towards data, not
#: towards a start that may be 20 % off (the frame's stated moduli)
MODAL_SETTINGS = UpdateSettings(method="cost-sensitivity", perturbation="full", penalty=False, rounds=2)
#: c_phi of :class:`~mace_fmu.updating.engine.costs.ModeShapeCost`
DEFAULT_SHAPE_WEIGHT = 0.1


def exact_pattern(label: str) -> str:
    """An fnmatch pattern that matches ``label`` only (its wildcard characters escaped)."""
    return "".join(f"[{c}]" if c in "*?[" else c for c in label)


@dataclass(frozen=True)
class Selected:
    """The thesis's sequence on one family: sensitivities, selection, the update, and the time of each."""

    sensitivities: CostSensitivities
    selection: Selection
    result: UpdateResult
    seconds: Mapping[str, float]


def select_and_update(family, cost, *, candidates: Sequence[str], rule: SelectionRule,
                      stages_of: Callable[[Selection], Sequence[Stage]], settings: UpdateSettings,
                      runner: Callable = map, progress: ProgressCallback | None = None, keep_all: bool = False,
                      stage_numbers: tuple[int, int, int] = (2, 3, 3)) -> Selected:
    """Cost sensitivities of ``candidates`` about the family's base point (eq. 4.12), the orthogonality and strength
    tests and ``rule`` (eq. 4.15-4.16), then ``update`` over ``stages_of(selection)``.

    Parameters
    ----------
    family : ModelFamily
        The model (``full``, ``basis``, ``base``, ``current_values``).
    cost : Cost
        The cost the candidates are judged on and the update lowers (a stage may carry its own).
    candidates : sequence of str
        The parameters judged.
    rule : SelectionRule
        Which candidates are kept.
    stages_of : callable
        The stages to run, given the selection.
    settings : UpdateSettings
        The update's method and tests.
    runner : callable
        ``map``-like function the model runs go to (``map`` or a Dask runner).
    progress : callable, optional
        Called with a Step at each stage.
    keep_all : bool
        Report the tests but keep every candidate.
    stage_numbers : (int, int, int)
        (the selection's stage, the update's stage, stages in all), for the progress lines.

    Returns
    -------
    Selected
        The sensitivities, the selection, the update's result and the seconds of each step.
    """
    seconds: dict[str, float] = {}
    t0 = time.perf_counter()
    begin_stage(progress, f"parameter selection: cost sensitivities of {len(candidates)} candidates",
                number=stage_numbers[0], stages=stage_numbers[2])
    values = family.current_values(candidates)
    base = family.base.updated(values).values
    perturbed = family.full if settings.perturbation == "full" else family.basis(base).model
    sens = cost_sensitivities(cost, base_model=family.full(base), perturbed=perturbed, base=base, names=candidates,
                              relative_step=settings.relative_step, perturbation=settings.perturbation, runner=runner,
                              progress=progress)
    selection = select_parameters(sens, rule=rule)
    if keep_all:
        selection = Selection(names=selection.names, orthogonality=selection.orthogonality,
                              strength=selection.strength, keep=selection.names,
                              reasons={n: r if n in selection.keep else f"{r}; kept (every candidate kept)"
                                       for n, r in selection.reasons.items()})
    seconds["selection"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    stages = list(stages_of(selection))
    names = [n for s in stages for n in s.parameters]
    values = {**base, **family.current_values(names)}
    begin_stage(progress, f"update: {', '.join(f'{s.name} ({len(s.parameters)})' for s in stages)}, "
                          f"{settings.rounds} rounds", number=stage_numbers[1], stages=stage_numbers[2])
    result = update(family, cost, start=values, stages=stages, bounds=default_bounds(names, values), settings=settings,
                    runner=runner, progress=progress)
    seconds["update"] = time.perf_counter() - t0
    for k, v in result.stage_seconds.items():
        seconds[f"update: {k}"] = v
    return Selected(sensitivities=sens, selection=selection, result=result, seconds=seconds)


def paired_cost(measured: ModesFile, correlation: Correlation, *, shape_weight: float = DEFAULT_SHAPE_WEIGHT,
                scaled: bool | None = None) -> ModeShapeCost:
    """The cost on the paired modes: frequencies (eq. 4.2) and shapes, each measured mode held to the model mode it
    was paired with by label (labels follow the modes through every re-solve)."""
    if not correlation.pairs:
        raise MaceError("no measured mode pairs with a model mode: nothing to update against")
    scaled = measured.scaled if scaled is None else scaled
    if scaled and not measured.scaled:
        raise MaceError(f"{measured.source}: mass-normalised shapes asked for, but not every mode has one (a driving "
                        "point among the outputs gives them)")
    modes = [measured.modes[p.measured] for p in correlation.pairs]
    shapes = np.column_stack([m.shape_mass_normalised if scaled else m.shape_real for m in modes])
    table = tuple(MeasuredMode(label=m.label, pattern=exact_pattern(p.model_label), frequency_hz=m.frequency_hz,
                               damping=m.damping) for m, p in zip(modes, correlation.pairs))
    return ModeShapeCost(measured=table, shapes=shapes, dofs=measured.dof_names, scaled=scaled,
                         shape_weight=shape_weight)


@dataclass(frozen=True)
class ModalUpdate:
    """Everything the modal update produced."""

    family: StructureFamily  #: the deck and structure file updated
    measured: ModesFile  #: the measured modes
    cost: ModeShapeCost  #: frequencies and shapes of the paired modes
    before: Correlation  #: at the start
    after: Correlation  #: at the updated values
    selected: Selected  #: the sensitivities, selection and update
    parameters: ParameterSet  #: the updated set: the start set, the updated values, the measured damping ratios
    damping: Mapping[str, float]  #: damping:<label> -> the measured mode's ratio (thesis 4.2.1)
    seconds: Mapping[str, float] = field(default_factory=dict)  #: wall time per step [s]

    @property
    def result(self) -> UpdateResult:
        return self.selected.result

    @property
    def selection(self) -> Selection:
        return self.selected.selection


@single_blas_thread
def run_modal_update(*, family: StructureFamily, measured: ModesFile, names: Sequence[str],
                     settings: UpdateSettings = MODAL_SETTINGS, rule: SelectionRule = SelectionRule(),
                     keep_all: bool = False, shape_weight: float = DEFAULT_SHAPE_WEIGHT, scaled: bool | None = None,
                     min_mac: float = DEFAULT_MIN_MAC, runner: Callable = map,
                     progress: ProgressCallback | None = None) -> ModalUpdate:
    """Update the structure file's parameters ``names`` against measured modes (see the module docstring).

    Parameters
    ----------
    family : StructureFamily
        The deck and structure file, the measured DOFs placed on it.
    measured : ModesFile
        The measured modes (``mace-fmu ema``'s modes.toml).
    names : sequence of str
        Candidate parameters: moduli, springs, masses the structure file names.
    settings : UpdateSettings
        Default: the cost-sensitivity method on full re-solves, two rounds, no penalty.
    rule : SelectionRule
        Which candidates the selection keeps (thesis 4.2.2).
    keep_all : bool
        Keep every candidate whatever the tests say.
    shape_weight : float
        c_phi of the shape residuals.
    scaled : bool, optional
        Compare mass-normalised shapes (default: when the modes file has them).
    min_mac : float
        A measured mode whose best partner's MAC is below this is unpaired (an error: leave it out of the file).
    runner : callable
        ``map``-like function the perturbed models go to.
    progress : callable, optional
        Receives a Step as each stage begins and as the long ones advance.

    Returns
    -------
    ModalUpdate
        The correlation before and after, the selection, the update's result, the updated parameter set.
    """
    if not names:
        raise MaceError("name the parameters to update: --update NAME[,NAME...] (moduli, springs, masses of the "
                        "structure file's [parameters])")
    twice = sorted({n for n in names if list(names).count(n) > 1})
    if twice:
        raise MaceError(f"parameter {twice[0]!r} named twice in --update")
    family.check_names(names)
    seconds: dict[str, float] = {}
    t0 = time.perf_counter()
    begin_stage(progress, "start model and correlation", number=1, stages=3)
    before = correlate(measured, family.full({}), min_mac=min_mac)
    if before.unpaired_measured:
        lost = ", ".join(f"{before.measured_labels[i]} at {before.measured_hz[i]:.4g} Hz" for i in before.unpaired_measured)
        raise MaceError(f"{measured.source}: measured mode(s) {lost} pair with no model mode (MAC >= {min_mac:g}); "
                        "see mace-fmu correlate, and leave them out of the modes file or lower --min-mac")
    cost = paired_cost(measured, before, shape_weight=shape_weight, scaled=scaled)
    seconds["start model"] = time.perf_counter() - t0
    selected = select_and_update(family, cost, candidates=list(names), rule=rule, keep_all=keep_all,
                                 stages_of=lambda selection: [Stage("physical", selection.keep)], settings=settings,
                                 runner=runner, progress=progress)
    seconds.update(selected.seconds)
    result = selected.result
    after = correlate(measured, family.full(result.values), min_mac=min_mac)
    fresh = family.fresh_labels(result.values)
    damping = {DAMPING.set_name(fresh.get(p.model_label, p.model_label)): measured.modes[p.measured].damping
               for p in before.pairs}
    deck = family.deck.path
    prov = Provenance(
        created=now_utc(), tool=tool_version(), deck=str(deck).rsplit("/", 1)[-1] if deck else "",
        deck_sha256=deck_fingerprint(deck) if deck else "", configuration=family.configuration,
        data=f"{len(before.pairs)} measured modes of {measured.source} ({measured.identification.get('method', '')})",
        cost=f"modal: frequencies (eq. 4.2) and {'mass-normalised' if cost.scaled else 'unscaled (1 - MAC)'} shapes "
             f"of the modes paired by MAC, shape weight {cost.shape_weight}; damping ratios taken from the measured "
             "modes (thesis 4.2.1)",
        method=f"{settings.method} ({settings.perturbation} perturbations, step {settings.relative_step}), penalty "
               f"{'on' if settings.penalty else 'off'}, {settings.rounds} rounds; parameter selection (eq. 4.15-4.16) "
               f"kept {', '.join(selected.selection.keep)}",
        initial_cost=result.initial_cost, final_cost=result.final_cost)
    parameters = family.base.updated({**result.values, **damping}, provenance=prov)
    return ModalUpdate(family=family, measured=measured, cost=cost, before=before, after=after, selected=selected,
                       parameters=parameters, damping=damping, seconds=seconds)


def mode_table(outcome: ModalUpdate) -> str:
    """Measured modes against the model before and after: frequencies, differences, MAC."""
    before = {p.measured: p for p in outcome.before.pairs}
    after = {p.measured: p for p in outcome.after.pairs}
    head = (f"{'measured':10s} {'f [Hz]':>9s} {'zeta %':>6s} | {'model mode':24s} {'before':>9s} {'diff%':>6s} "
            f"{'MAC':>5s} | {'after':>9s} {'diff%':>6s} {'MAC':>5s}")
    lines = [head, "-" * len(head)]
    for i, m in enumerate(outcome.measured.modes):
        b, a = before.get(i), after.get(i)
        if b is None:
            continue
        tail = (f"{a.model_hz:9.4f} {a.difference_percent:+6.2f} {a.mac:5.3f}" if a is not None else "(unpaired)")
        lines.append(f"{m.label:10s} {m.frequency_hz:9.4f} {100 * m.damping:6.3f} | {b.model_label[:24]:24s} "
                     f"{b.model_hz:9.4f} {b.difference_percent:+6.2f} {b.mac:5.3f} | {tail}")
    lines.append(f"RMS frequency difference: before {outcome.before.rms_difference_percent():.2f} %, after "
                 f"{outcome.after.rms_difference_percent():.2f} %")
    if outcome.before.scaled is not None and outcome.after.scaled is not None:
        lines.append("mass-normalised shapes' relative difference [%]: before "
                     + ", ".join(f"{100 * x:.1f}" for x in outcome.before.scaled) + "; after "
                     + ", ".join(f"{100 * x:.1f}" for x in outcome.after.scaled))
    return "\n".join(lines)


def summary(outcome: ModalUpdate) -> dict:
    """The update's numbers as data (summary.json)."""
    res = outcome.result

    def pairs(c: Correlation) -> list[dict]:
        return [{"measured": p.measured_label, "measured_hz": p.measured_hz, "model": p.model_label,
                 "model_hz": p.model_hz, "difference_percent": p.difference_percent, "mac": p.mac,
                 **({"shape_difference": float(c.scaled[k])} if c.scaled is not None else {})}
                for k, p in enumerate(c.pairs)]

    return {"deck": str(outcome.family.deck.path), "modes": outcome.measured.source,
            "configuration": outcome.family.configuration, "cost": outcome.cost.name,
            "scaled_shapes": outcome.cost.scaled, "shape_weight": outcome.cost.shape_weight,
            "initial_cost": res.initial_cost, "final_cost": res.final_cost, "reduction": res.reduction,
            "selection": {"candidates": list(outcome.selection.names), "kept": list(outcome.selection.keep),
                          "strength": [float(x) for x in outcome.selection.strength],
                          "reasons": dict(outcome.selection.reasons)},
            "start": dict(res.start), "values": dict(res.values), "damping": dict(outcome.damping),
            "before": pairs(outcome.before), "after": pairs(outcome.after),
            "rms_difference_percent": {"before": outcome.before.rms_difference_percent(),
                                       "after": outcome.after.rms_difference_percent()},
            "seconds": dict(outcome.seconds), "solves": outcome.family.solves}

