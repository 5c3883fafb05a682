"""Planning a test before anyone runs it: how sure an update would be of each parameter, from the model alone.

A candidate is one or more tests; a test drives some FMU inputs with band-limited white noise,
records some outputs for a duration at a sample time with white noise of a stated fraction of
each output's RMS, and may know some sensor gains only to a stated accuracy. For each candidate the
FMU at its start values is simulated without noise, the time cost's sensitivities are taken as the
FMU update takes them (central differences, step 1e-3), each test in units of its own noise, the
gains' priors appended (:class:`~mace_fmu.updating.engine.costs.WithPriors`), and the linearised covariance
(J^T J)^-1 is the uncertainty an update on such data would report: where the linearisation holds,
the spread of its answers over noise realisations. Candidates are ranked by the largest standard
deviation they leave among the parameters (the gains are nuisances, not ranked on).

A prediction holds near the values it linearises about (``values``: best the current estimate). Where
modes nearly coincide it can move fast: for the 1-g FMU's cable moduli (the close 7 Hz violin modes of
cables 1 and 3) the predicted standard deviations halved between the FMU's start values and a point
with the cables moved 2-3 % (``examples/plan_then_update.py``).
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.costs import SeveralTests, TimeResponseCost, WithPriors
from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.engine.sensitivity import cost_sensitivities
from mace_fmu.updating.engine.uncertainty import StageUncertainty, linearised_uncertainty
from mace_fmu.updating.fmu.model import FmuFamily, gain_parameter, read_fmu_interface, ship_fmu
from mace_fmu.updating.fmu.truth import band_limited_noise
from mace_fmu.updating.fmu.update import FMU_SETTINGS
from mace_fmu.util.progress import ProgressCallback


@dataclass(frozen=True)
class TestDesign:
    """One test as it would be run: which inputs are driven, which outputs recorded, for how long, how noisily."""

    name: str  #: test name
    inputs: tuple[str, ...]  #: FMU inputs driven with band-limited white noise (every other input held at 0 V)
    outputs: tuple[str, ...]  #: FMU outputs recorded
    seconds: float = 8.0  #: record length [s]
    sample_time_s: float = 0.002  #: [s]
    band_hz: tuple[float, float] = (0.5, 60.0)  #: the excitation's band [Hz]
    noise_rms_percent: float = 2.0  #: white output noise, % of each output's RMS
    gain_uncertainty_percent: Mapping[str, float] = field(default_factory=dict)  #: output -> gain sd [%]

    __test__ = False  # a class named Test*, not a pytest test


@dataclass(frozen=True)
class Candidate:
    """One or more tests whose data one update would take together."""

    name: str  #: name of the candidate test campaign
    tests: tuple[TestDesign, ...]  #: the tests it runs together


@dataclass(frozen=True)
class PlannedCandidate:
    """A candidate and the uncertainty an update on its data would report."""

    candidate: Candidate
    parameters: tuple[str, ...]  #: the update's parameters (the gains are in ``uncertainty`` too)
    uncertainty: StageUncertainty

    @property
    def worst_percent(self) -> float:
        """The largest standard deviation [%] among the parameters: what the candidate is ranked by."""
        return max(self.uncertainty.standard_deviation_percent[n] for n in self.parameters)


def predict_uncertainty(*, family: FmuFamily, parameters: Sequence[str], candidate: Candidate,
                        values: Mapping[str, float] | None = None, seed: int = 0, runner: Callable = map,
                        progress: ProgressCallback | None = None) -> StageUncertainty:
    """The linearised uncertainty an update of ``parameters`` on ``candidate``'s data would report.

    ``values``: the values [FMU units] about which to linearise (default: the FMU's start values); those of
    parameters not updated are held there; ``seed``: of the excitation's noise (test k, input j: ``seed + 1000 k + j``).
    """
    interface = family.interface
    names = tuple(parameters)
    if not names:
        raise MaceError("name at least one parameter to plan a test for")
    interface.check_parameters(names)
    gains: dict[str, float] = {}
    for test in candidate.tests:
        interface.check_signals(inputs=test.inputs, outputs=test.outputs, where=f"test {test.name!r}")
        for o, percent in test.gain_uncertainty_percent.items():
            if o not in test.outputs:
                raise MaceError(f"test {test.name!r}: a gain uncertainty for {o!r}, which it does not record")
            if o in gains and gains[o] != percent / 100:
                raise MaceError(f"candidate {candidate.name!r}: the gain of {o!r} is known to {100 * gains[o]:g} % in "
                                f"one test and {percent:g} % in another (one sensor, one calibration)")
            gains[o] = percent / 100
    # the point: the updated parameters at ``values``, any other value given held there too
    held = {n: float(v) for n, v in (values or {}).items() if n not in names}
    interface.check_parameters(list(held))
    family = dataclasses.replace(family, gain_outputs=tuple(gains), fixed={**family.fixed, **held})
    if interface.written_by_pythonfmu:
        family = dataclasses.replace(family, runner=runner)
    ship_fmu(interface, runner)  # the workers read the FMU's bytes, not the client's path
    base = {n: float((values or {}).get(n, interface.parameters[n])) for n in names}
    base.update({gain_parameter(o): 1.0 for o in gains})
    truth = family.full(base)
    costs, weights = [], []
    for k, test in enumerate(candidate.tests):
        n = int(round(test.seconds / test.sample_time_s)) + 1
        t = np.arange(n) * test.sample_time_s
        driven = {name: band_limited_noise(samples=n, step_s=test.sample_time_s, band_hz=test.band_hz,
                                           seed=seed + 1000 * k + j) for j, name in enumerate(test.inputs)}
        u = {name: driven.get(name, np.zeros(n)) for name in interface.inputs}
        y = truth.time_response(t, u, outputs=list(test.outputs))
        history = TimeHistory(t, u, {o: y[:, j] for j, o in enumerate(test.outputs)}, source=test.name)
        costs.append(TimeResponseCost(history))
        weights.append(1.0 / (test.noise_rms_percent / 100.0))  # each test in units of its noise
    cost = SeveralTests(tests=tuple(costs), weights=tuple(weights), labels=tuple(t.name for t in candidate.tests))
    if gains:
        cost = WithPriors(cost, priors={gain_parameter(o): (1.0, sd) for o, sd in gains.items()}, noise_sd=1.0)
    all_names = names + tuple(gain_parameter(o) for o in gains)
    sens = cost_sensitivities(cost, base_model=truth, perturbed=family.full, base=base, names=all_names,
                              relative_step=FMU_SETTINGS.relative_step, difference="central", runner=runner,
                              progress=progress)
    return linearised_uncertainty(stage=candidate.name, names=all_names, values=base, jacobian=sens.matrix,
                                  noise_variance=1.0)


def plan_tests(*, fmu: str | os.PathLike, parameters: Sequence[str], candidates: Sequence[Candidate],
               values: Mapping[str, float] | None = None, seed: int = 0, runner: Callable = map,
               progress: ProgressCallback | None = None) -> tuple[PlannedCandidate, ...]:
    """Every candidate's predicted uncertainty of ``parameters``, best (smallest largest standard deviation) first.

    Parameters
    ----------
    fmu : path
        The FMI 2.0 co-simulation FMU that will be updated.
    parameters : sequence of str
        The FMU parameters the update will estimate.
    candidates : sequence of Candidate
        The experiments to compare (see :func:`read_test_plan`).
    values : mapping of str to float, optional
        Parameter values [FMU units] to linearise about (default: the FMU's start values).
    seed : int
        Seed of the excitation's white noise.
    runner : callable
        ``map``-like function the FMU runs go to (``map`` or a Dask runner).
    progress : callable, optional
        Called with a Step as the candidates are run.

    Returns
    -------
    tuple of PlannedCandidate
        Ranked, best first.
    """
    if not candidates:
        raise MaceError("no candidate tests to plan")
    family = FmuFamily(interface=read_fmu_interface(fmu))
    planned = [PlannedCandidate(candidate=c, parameters=tuple(parameters),
                                uncertainty=predict_uncertainty(family=family, parameters=parameters, candidate=c,
                                                                values=values, seed=seed, runner=runner,
                                                                progress=progress))
               for c in candidates]
    return tuple(sorted(planned, key=lambda p: p.worst_percent))


def format_plan(planned: Sequence[PlannedCandidate]) -> str:
    """The ranking as a table: each candidate's standard deviation [%] of every parameter, and its weak combinations."""
    names = planned[0].parameters
    width = max([9, *(len(p.candidate.name) for p in planned)])
    lines = ["predicted standard deviation [%] of each parameter (linearised, before the test); best first",
             f"{'rank':<4} {'candidate':<{width}} " + " ".join(f"{n:>{max(9, len(n))}}" for n in names)
             + f" {'largest':>8}"]
    for k, p in enumerate(planned, start=1):
        sd = p.uncertainty.standard_deviation_percent
        lines.append(f"{k:<4} {p.candidate.name:<{width}} " + " ".join(f"{sd[n]:>{max(9, len(n))}.3g}" for n in names)
                     + f" {p.worst_percent:>8.3g}")
    for p in planned:
        for w in p.uncertainty.weak_directions:
            lines.append(f"  {p.candidate.name}: not identifiable (sd {w.standard_deviation_percent:.3g} %): "
                         f"{w.text()}")
    return "\n".join(lines)


_TEST_KEYS = {"name", "inputs", "outputs", "seconds", "sample_time_s", "band_hz", "noise_rms_percent",
              "gain_uncertainty_percent"}


def read_test_plan(path: str | os.PathLike) -> tuple[Candidate, ...]:
    """Candidates from a TOML file.

    Parameters
    ----------
    path : path
        A test plan: ``[[test]]`` tables (name, inputs, outputs and optionally seconds [s],
        sample_time_s [s], band_hz = [low, high] [Hz], noise_rms_percent [%],
        gain_uncertainty_percent = {output = P} [%]) and ``[[candidate]]`` tables (name, tests = [test
        names]); without candidates, each test is one.

    Returns
    -------
    tuple of Candidate
        In the file's order.

    Raises
    ------
    MaceError
        An unknown table or key, a value of the wrong kind or out of range, a band at or above the
        Nyquist frequency, a candidate naming a test the file lacks: the message names the file and
        the entry.
    """
    from mace_fmu.util.textfile import read_toml

    path = Path(path)
    table = read_toml(path, what="test-plan")
    unknown = set(table) - {"test", "candidate"}
    if unknown:
        raise MaceError(f"{path}: unknown table(s) {sorted(unknown)}; a test plan has [[test]] and [[candidate]]")
    tests: dict[str, TestDesign] = {}
    for k, entry in enumerate(table.get("test", []), start=1):
        where = f"{path}: [[test]] {k}"
        if not isinstance(entry, dict):
            raise MaceError(f"{where}: expected a table")
        bad = set(entry) - _TEST_KEYS
        if bad:
            raise MaceError(f"{where}: unknown key(s) {sorted(bad)}; allowed: {sorted(_TEST_KEYS)}")
        test = _test_design(entry, where=where)
        if test.name in tests:
            raise MaceError(f"{where}: test name {test.name!r} used twice")
        tests[test.name] = test
    if not tests:
        raise MaceError(f"{path}: no [[test]] tables (each: name, inputs, outputs, ...)")
    candidates = []
    for k, entry in enumerate(table.get("candidate", []), start=1):
        where = f"{path}: [[candidate]] {k}"
        if not isinstance(entry, dict) or set(entry) != {"name", "tests"} or not isinstance(entry["tests"], list) \
                or not entry["tests"] or not all(isinstance(x, str) for x in entry["tests"]):
            raise MaceError(f"{where}: expected name = \"...\" and tests = [\"test name\", ...]")
        missing = [x for x in entry["tests"] if x not in tests]
        if missing:
            raise MaceError(f"{where}: no [[test]] named {', '.join(map(repr, missing))} (tests: {', '.join(tests)})")
        candidates.append(Candidate(name=str(entry["name"]), tests=tuple(tests[x] for x in entry["tests"])))
    return tuple(candidates) or tuple(Candidate(name=t.name, tests=(t,)) for t in tests.values())


def _test_design(entry: dict, *, where: str) -> TestDesign:
    def names(key: str) -> tuple[str, ...]:
        value = entry.get(key)
        if not isinstance(value, list) or not value or not all(isinstance(x, str) for x in value):
            raise MaceError(f"{where}: {key} must be a list of signal names")
        return tuple(value)

    def positive(key: str, default: float) -> float:
        value = entry.get(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and value > 0):
            raise MaceError(f"{where}: {key} must be a positive number, got {value!r}")
        return float(value)

    if not isinstance(entry.get("name"), str) or not entry["name"]:
        raise MaceError(f"{where}: name must be a non-empty string")
    band = entry.get("band_hz", [0.5, 60.0])
    if not (isinstance(band, list) and len(band) == 2 and all(isinstance(x, (int, float)) for x in band)
            and 0 <= band[0] < band[1]):
        raise MaceError(f"{where}: band_hz must be [low, high] with 0 <= low < high, got {band!r}")
    gains = entry.get("gain_uncertainty_percent", {})
    if not isinstance(gains, dict) or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0
                                              for v in gains.values()):
        raise MaceError(f"{where}: gain_uncertainty_percent must be a table output = positive percentage")
    test = TestDesign(name=entry["name"], inputs=names("inputs"), outputs=names("outputs"),
                      seconds=positive("seconds", 8.0), sample_time_s=positive("sample_time_s", 0.002),
                      band_hz=(float(band[0]), float(band[1])), noise_rms_percent=positive("noise_rms_percent", 2.0),
                      gain_uncertainty_percent={str(k): float(v) for k, v in gains.items()})
    if test.band_hz[1] >= 0.5 / test.sample_time_s:
        raise MaceError(f"{where}: band_hz ends at {test.band_hz[1]:g} Hz, at or above the Nyquist frequency "
                        f"{0.5 / test.sample_time_s:g} Hz of sample_time_s {test.sample_time_s:g} s")
    return test
