"""The sweep: the compensator closed around the FMU at the nominal point, one parameter at a time at each
bound, at the corners of the most critical parameters, and at a seeded Monte Carlo sample of the box.

Corners: all 2^n when the box has at most ``critical_count`` parameters; otherwise the
``critical_count`` parameters whose bounds alone move the cost most (the one-at-a-time screening
runs) span the corners and the rest stay nominal: 2^n corners of 15 Table 5.3 bounds would be
32768 runs. Every run goes through ``runner`` (``map``, or a :class:`~mace_fmu.util.runner.DaskRunner`);
the runs are independent and their results come back in order, so any runner gives the same
numbers bit for bit. A runner with workers (a DaskRunner) gets the FMU's bytes
(:meth:`~mace_fmu.util.runner.DaskRunner.ship`): each worker extracts its own copy once, wherever it runs.
"""

from __future__ import annotations

import functools
import os
import tempfile
import threading
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Callable

import numpy as np
import scipy.stats

from mace_fmu.errors import MaceError
from mace_fmu.util.progress import ProgressCallback, Step
from mace_fmu.util.shipping import sha256_of, shipped_copy
from mace_fmu.zero_g.robust.box import (DEFAULT_PATTERN, ParameterBox, SweepPoint, corner_points, monte_carlo_points,
                                        nominal_point, read_box, screening_points)
from mace_fmu.zero_g.robust.cosim import SampledCompensator, run_fmu_loop
from mace_fmu.zero_g.robust.loop import LoopSpec

OPEN_LOOP = SampledCompensator(a=np.zeros((0, 0)), b=np.zeros(0), c=np.zeros(0), d=0.0)


@dataclass(frozen=True)
class RunResult:
    """What one run returns from a worker (small: no time histories)."""

    cost_rms_v: float
    growth_ratio: float
    stable: bool
    failure: str


@dataclass(frozen=True)
class Driver:
    """How strongly one parameter drives the cost."""

    name: str
    label: str  #: e.g. the mode's label
    rank_correlation: float  #: Spearman's rho of value and cost over the Monte Carlo sample (nan below 3 samples)
    low_change_percent: float  #: cost change [%] with this parameter alone at its low bound
    high_change_percent: float  #: ... at its high bound


@dataclass(frozen=True)
class SweepResult:
    """Every run of the sweep, in order, with the summary numbers."""

    box: ParameterBox  #: the parameter box swept
    loop: LoopSpec  #: the loop evaluated
    points: tuple[SweepPoint, ...]  #: nominal, screening, corners, samples
    runs: tuple[RunResult, ...]  #: one per point
    open_loop: RunResult  #: the FMU at nominal values with the loop open
    critical: tuple[str, ...]  #: the parameters whose corners were run
    drivers: tuple[Driver, ...]  #: every parameter, strongest first
    seed: int  #: seed of the random samples

    def _select(self, kind: str) -> list[int]:
        return [i for i, p in enumerate(self.points) if p.kind == kind]

    @property
    def nominal(self) -> RunResult:
        return self.runs[self._select("nominal")[0]]

    def costs(self, kind: str) -> np.ndarray:
        """Costs [V] of the runs of one kind ("screen", "corner", "sample")."""
        return np.array([self.runs[i].cost_rms_v for i in self._select(kind)])

    def stable(self, kind: str) -> np.ndarray:
        return np.array([self.runs[i].stable for i in self._select(kind)], dtype=bool)

    @property
    def worst(self) -> int:
        """Index of the run with the largest cost among corners and samples (an unstable one if any)."""
        candidates = self._select("corner") + self._select("sample")
        return max(candidates, key=lambda i: (not self.runs[i].stable, self.runs[i].cost_rms_v))


@dataclass(frozen=True)
class _SweptFmu:
    """The FMU of a sweep as its runs find it: the client's path and extraction, and the bytes' SHA-256."""

    path: str  #: as the client names it
    sha256: str
    folder: str  #: where the client extracted it

    def unzipped(self) -> str:
        """The extracted FMU this process runs: a Dask worker's own copy of the bytes shipped to it, else the
        client's extraction (a serial run, or a runner that shipped nothing)."""
        copy = shipped_copy(sha256=self.sha256, name=Path(self.path).name)
        if copy is None:
            if not os.path.isdir(self.folder):
                raise MaceError(f"{self.path}: no extracted FMU at {self.folder} in this process, and none was sent "
                                "to it: run the sweep through robust_sweep with the DaskRunner, which sends it")
            return self.folder
        with _EXTRACTING:  # two tasks at once in one worker: one extracts, the other waits and reuses it
            return _extracted(os.fspath(copy))


_EXTRACTING = threading.Lock()


@functools.lru_cache(maxsize=4)
def _extracted(copy: str) -> str:
    """``copy`` (a shipped FMU in a worker's local directory) extracted beside it, once per process."""
    import fmpy

    folder = Path(copy).parent / "unzipped"
    if not (folder / "modelDescription.xml").is_file():
        # extracted aside and renamed: a folder left by an interrupted extraction is never taken for a whole one
        partial_folder = tempfile.mkdtemp(prefix=".unzipping-", dir=Path(copy).parent)
        fmpy.extract(copy, unzipdir=partial_folder)
        os.replace(partial_folder, folder)
    return os.fspath(folder)


def _run_point(values: tuple[float, ...], *, fmu: _SweptFmu, names: tuple[str, ...], loop: LoopSpec,
               compensator: SampledCompensator) -> RunResult:
    """One closed-loop co-simulation (module level, so Dask can pickle it)."""
    run = run_fmu_loop(fmu.unzipped(), loop=loop, compensator=compensator, parameters=dict(zip(names, values)))
    v = run.verdict
    return RunResult(cost_rms_v=v.cost_rms_v, growth_ratio=v.growth_ratio, stable=v.stable, failure=run.failure)


def check_loop_signals(fmu: str | os.PathLike, loop: LoopSpec) -> None:
    """MaceError unless ``fmu`` is a co-simulation FMU with the loop's inputs and measurement."""
    import fmpy

    md = fmpy.read_model_description(os.fspath(fmu))
    if md.coSimulation is None:
        raise MaceError(f"{os.fspath(fmu)} has no co-simulation interface (export it with mace-fmu export 0g)")
    ins = {v.name for v in md.modelVariables if v.causality == "input"}
    outs = {v.name for v in md.modelVariables if v.causality == "output"}
    missing = [n for n in (loop.control_input, loop.disturbance_input) if n not in ins] + \
        [n for n in (loop.measurement,) if n not in outs]
    if missing:
        raise MaceError(f"{os.fspath(fmu)} lacks the loop's signal(s) {', '.join(missing)}")


def _change_percent(cost: float, nominal: float) -> float:
    return 100.0 * (cost - nominal) / nominal if np.isfinite(cost) else float("inf")


def robust_sweep(fmu: str | os.PathLike, *, compensator, loop: LoopSpec = LoopSpec(), samples: int = 100,
                 seed: int = 1, critical_count: int = 4, pattern: str = DEFAULT_PATTERN,
                 ranges: dict[str, tuple[float, float]] | None = None, runner: Callable = map,
                 progress: ProgressCallback | None = None) -> SweepResult:
    """Run the sweep of ``compensator`` (discrete ``control.StateSpace``, measurement -> control) on ``fmu``.

    The box is ``read_box(fmu, pattern=..., ranges=...)``. The workers of a DaskRunner get the FMU's bytes
    (they need not see ``fmu``'s path: another folder, another machine).

    Parameters
    ----------
    fmu : path
        The 0-g FMU with frequency scales.
    compensator : control.StateSpace
        Discrete, measurement -> control.
    loop : LoopSpec
        The loop and its disturbance.
    samples : int
        Random points of the box.
    seed : int
        Seed of the samples.
    critical_count : int
        How many of the most influential parameters get corner runs.
    pattern : str
        Which parameters span the box.
    ranges : dict, optional
        Name -> (low, high) replacing the declared min/max.
    runner : callable
        ``map``-like function the runs go to.
    progress : callable, optional
        Progress steps.

    Returns
    -------
    SweepResult
        The box, every point and its run (stable or not, cost), and the open loop.
    """
    if critical_count < 0:
        raise MaceError(f"critical_count must be 0 or more, got {critical_count}")
    import fmpy

    box = read_box(fmu, pattern=pattern, ranges=ranges)
    check_loop_signals(fmu, loop)
    sampled = SampledCompensator.of(compensator)
    digest = sha256_of(Path(fmu).read_bytes())
    ship = getattr(runner, "ship", None)
    if ship is not None:  # the workers read the FMU's bytes, not the client's path
        ship(fmu, sha256=digest)
    with tempfile.TemporaryDirectory(prefix="mace_fmu_robust_") as tmp:
        swept = _SweptFmu(path=os.fspath(fmu), sha256=digest, folder=fmpy.extract(os.fspath(fmu), unzipdir=tmp))
        run = partial(_run_point, fmu=swept, names=box.names, loop=loop, compensator=sampled)
        first = [nominal_point(box)] + screening_points(box)
        if progress:
            progress(Step("robustness sweep", 0, 2, f"{len(first) + 1} nominal, open-loop and screening runs"))
        open_loop = list(runner(partial(_run_point, fmu=swept, names=(), loop=loop, compensator=OPEN_LOOP), [()]))[0]
        first_runs = list(runner(run, [p.values for p in first]))
        nominal = first_runs[0].cost_rms_v
        screen = np.array([r.cost_rms_v for r in first_runs[1:]]).reshape(len(box.names), 2)
        # a failed run (inf) is the strongest effect; an unstable nominal point (inf - inf) leaves no ranking
        effect = np.nan_to_num(np.abs(screen - nominal), nan=0.0).max(axis=1)
        if len(box.names) <= critical_count:
            critical = list(range(len(box.names)))
        else:  # stable sort: ties keep the box's order
            critical = sorted(np.argsort(-effect, kind="stable")[:critical_count].tolist())
        second = corner_points(box, critical) + monte_carlo_points(box, samples=samples, seed=seed)
        if progress:
            progress(Step("robustness sweep", 1, 2, f"{len(second)} corner and Monte Carlo runs"))
        second_runs = list(runner(run, [p.values for p in second]))
    points = tuple(first + second)
    runs = tuple(first_runs + second_runs)
    drivers = _drivers(box, points, runs, screen, nominal)
    if progress:
        progress(Step("robustness sweep", 2, 2))
    return SweepResult(box=box, loop=loop, points=points, runs=runs, open_loop=open_loop,
                       critical=tuple(box.names[i] for i in critical), drivers=drivers, seed=seed)


def _drivers(box: ParameterBox, points, runs, screen: np.ndarray, nominal: float) -> tuple[Driver, ...]:
    """Every parameter with its rank correlation to the cost (samples) and its screening changes, strongest first."""
    rows = [i for i, p in enumerate(points) if p.kind == "sample"]
    values = np.array([points[i].values for i in rows]).reshape(len(rows), len(box.names))
    costs = np.array([runs[i].cost_rms_v for i in rows])
    drivers = []
    for k, name in enumerate(box.names):
        if len(rows) >= 3 and np.ptp(values[:, k]) > 0 and np.ptp(costs[np.isfinite(costs)]) > 0:
            rho = float(scipy.stats.spearmanr(values[:, k], costs).statistic)  # inf costs rank last: fine
        else:
            rho = float("nan")
        drivers.append(Driver(name=name, label=box.label(k), rank_correlation=rho,
                              low_change_percent=_change_percent(screen[k, 0], nominal),
                              high_change_percent=_change_percent(screen[k, 1], nominal)))
    # the screening change first: it is what the parameter does alone; a rank correlation of a weak
    # parameter over 100 samples is mostly the strong ones' scatter
    strength = [(max(abs(d.low_change_percent), abs(d.high_change_percent)),
                 abs(d.rank_correlation) if np.isfinite(d.rank_correlation) else -1.0) for d in drivers]
    order = sorted(range(len(drivers)), key=lambda k: strength[k], reverse=True)
    return tuple(drivers[k] for k in order)
