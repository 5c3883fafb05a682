"""The whole study: the nominal 0-g model -> its FMU with frequency bounds, the LQG compensator, the sweep,
and the state-space cross-check of the nominal and the worst point.

The FMU and the compensator come from one model, so the sweep's nominal point is the design
point. The cross-check closes the same compensator around the Python model at the same
parameter values (``statespace.py``): its spectral radius says whether the loop is stable, and
its response gives the cost again, independently of the FMU's C runtime.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping

from mace_fmu.control_studies.lqg import LqgWeights
from mace_fmu.iomodel.volts import VoltsModel
from mace_fmu.util.atomic import write_text_atomic
from mace_fmu.util.progress import ProgressCallback
from mace_fmu.zero_g.robust.design import DEFAULT_REDUCED_STATES, DEFAULT_WEIGHTS, RobustDesign, design_compensator
from mace_fmu.zero_g.robust.loop import LoopSpec
from mace_fmu.zero_g.robust.sweep import SweepResult, robust_sweep

#: named after what made it: the 0-g model with the frequency bounds of the robustness study (never the plain
#: model's name, which mace-fmu build writes)
FMU_NAME = "MACE_0g_native_bounded"


@dataclass(frozen=True)
class CrossCheck:
    """One sweep point computed twice: FMU co-simulation and the sampled state-space closed loop."""

    point: int  #: index into SweepResult.points
    fmu_cost_rms_v: float
    state_space_cost_rms_v: float
    spectral_radius: float  #: of the state-space closed loop; < 1: asymptotically stable
    fmu_stable: bool  #: the growth test on the FMU run

    @property
    def relative_difference(self) -> float:
        """|FMU - state space| / state space, of the cost."""
        return abs(self.fmu_cost_rms_v - self.state_space_cost_rms_v) / abs(self.state_space_cost_rms_v)


@dataclass(frozen=True)
class RobustStudy:
    """What ``robust_0g_study`` made and found."""

    fmu: Path  #: the 0-g FMU the sweep ran
    design: RobustDesign  #: the controller studied
    sweep: SweepResult  #: its closed loop over the box
    cross_checks: tuple[CrossCheck, ...]  #: nominal and worst point


def prediction_bounds(prediction) -> dict[int, float]:
    """1-based open-loop mode -> relative frequency bound of a ``zero_g.ZeroGPrediction`` (Table 5.3's rows
    that fall on a flexible mode; the gimbal pendulum rows are servo poles, not modes the FMU can scale)."""
    return prediction.frequency_bounds


def cross_check(model: VoltsModel, sweep: SweepResult, design: RobustDesign, *, point: int) -> CrossCheck:
    """Sweep point ``point`` again through the Python model in a sampled state-space loop."""
    from mace_fmu.iomodel.parametric import ParametricSystem
    from mace_fmu.iomodel.parametric_data import parametric_arrays
    from mace_fmu.zero_g.robust.statespace import simulate_state_space, state_space_loop

    reference = ParametricSystem(parametric_arrays(model, physical=False))
    values = dict(zip(sweep.box.names, sweep.points[point].values))
    closed = state_space_loop(reference, loop=sweep.loop, compensator=design.compensator, parameters=values)
    _, _, verdict = simulate_state_space(closed, sweep.loop)
    run = sweep.runs[point]
    return CrossCheck(point=point, fmu_cost_rms_v=run.cost_rms_v, state_space_cost_rms_v=verdict.cost_rms_v,
                      spectral_radius=closed.spectral_radius, fmu_stable=run.stable)


def robust_0g_study(model: VoltsModel, *, frequency_bounds: Mapping[int, float], out_dir: str | os.PathLike,
                    loop: LoopSpec = LoopSpec(), weights: LqgWeights = DEFAULT_WEIGHTS,
                    reduced_states: int = DEFAULT_REDUCED_STATES, samples: int = 100, seed: int = 1,
                    critical_count: int = 4, runner: Callable = map,
                    progress: ProgressCallback | None = None) -> RobustStudy:
    """Export ``model`` (the nominal 0-g volts model) as a native FMU whose ``frequency_scale_mode_<k>``
    span ``frequency_bounds`` (1-based mode -> relative bound), design the compensator on it, run the sweep.

    Parameters
    ----------
    model : VoltsModel
        The nominal 0-g volts model.
    frequency_bounds : mapping of int to float
        1-based mode -> relative bound of its frequency scale.
    out_dir : path
        Folder of the FMU and the sweep's files.
    loop : LoopSpec
        The loop and its disturbance.
    weights : LqgWeights
        The LQG weighting.
    reduced_states : int
        States of the design model.
    samples : int
        Random points of the box.
    seed : int
        Seed of the samples.
    critical_count : int
        How many of the most influential parameters get corner runs.
    runner : callable
        ``map``-like function the runs go to.
    progress : callable, optional
        Progress steps.

    Returns
    -------
    RobustStudy
        The FMU, the design, the sweep and its cross-checks against the state-space loop.
    """
    from mace_fmu.fmu.export import export_fmu

    fmu = export_fmu(model, runtime="native", out_dir=Path(out_dir), name=FMU_NAME, frequency_bounds=dict(frequency_bounds),
                     progress=progress)
    design = design_compensator(model.system, loop=loop, weights=weights, reduced_states=reduced_states)
    sweep = robust_sweep(fmu, compensator=design.compensator, loop=loop, samples=samples, seed=seed,
                         critical_count=critical_count, runner=runner, progress=progress)
    checks = tuple(cross_check(model, sweep, design, point=i) for i in sorted({0, sweep.worst}))
    return RobustStudy(fmu=fmu, design=design, sweep=sweep, cross_checks=checks)


def write_runs_csv(sweep: SweepResult, path: str | os.PathLike) -> Path:
    """Every run as one CSV row: kind, note, parameter values, cost [V], growth ratio, stable."""
    head = ["kind", "note", *sweep.box.names, "cost_rms_v", "growth_ratio", "stable"]
    rows = [",".join(head)]
    for p, r in zip(sweep.points, sweep.runs):
        rows.append(",".join([p.kind, f'"{p.note}"', *(repr(float(v)) for v in p.values), repr(r.cost_rms_v),
                              repr(r.growth_ratio), str(r.stable).lower()]))
    write_text_atomic(path, "\n".join(rows) + "\n")
    return Path(path)


def format_cross_checks(checks: tuple[CrossCheck, ...], sweep: SweepResult) -> str:
    """One line per cross-checked point."""
    lines = ["cross-check (Python model, sampled state-space loop, control.feedback):"]
    for c in checks:
        p = sweep.points[c.point]
        lines.append(f"  {p.kind:8s} cost FMU {c.fmu_cost_rms_v:.6f}, state space {c.state_space_cost_rms_v:.6f} "
                     f"(rel. diff {c.relative_difference:.1e}); spectral radius {c.spectral_radius:.6f} "
                     f"({'stable' if c.spectral_radius < 1 else 'UNSTABLE'}), growth test "
                     f"{'stable' if c.fmu_stable else 'UNSTABLE'}")
    return "\n".join(lines)

