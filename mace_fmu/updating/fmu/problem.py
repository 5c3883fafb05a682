"""An FMU update as a user states it: an FMU file, measured-data files, parameter names, a cost; checked before any run.

Everything that can be wrong with the request (files, parameter names, channels the FMU lacks,
a frequency response without the time history it needs) is found here, before the first FMU
simulation, and reported as one :class:`~mace_fmu.errors.MaceError`.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.costs import Cost, WithPriors
from mace_fmu.updating.engine.measured import FrequencyResponseData, TimeHistory
from mace_fmu.updating.engine.periodic import periodic_excitation
from mace_fmu.updating.engine.simulated_frf import H1Estimator
from mace_fmu.updating.engine.solve import Bounds
from mace_fmu.updating.fmu.model import FmuFamily, gain_parameter, read_fmu_interface
from mace_fmu.updating.fmu.update import (COST_KINDS, WEIGHTINGS, CostKind, Weighting, declared_bounds, fmu_cost,
                                          record_from)


@dataclass(frozen=True)
class FmuProblem:
    """A checked FMU update: the FMU, what it starts from, the measured data and the cost."""

    family: FmuFamily  #: the FMU with every start value from the start file set on each run
    names: tuple[str, ...]  #: parameters to update
    start: Mapping[str, float]  #: their start values [FMU units]
    history: TimeHistory | None  #: the measured time history of the first test (None: frequency responses only)
    frequency_data: FrequencyResponseData | None  #: measured frequency responses (None: a time cost)
    cost: Cost  #: the cost the update minimises
    data_files: tuple[str, ...]  #: the measured data files read
    histories: tuple[TimeHistory, ...] = ()  #: every test's time history (``history`` is the first)
    responses: tuple[FrequencyResponseData, ...] = ()  #: every measured frequency response, in the band
    #: what was made of the data before the update, said where it runs (a file's lines put on the analyser's grid)
    notes: tuple[str, ...] = ()
    #: each updated parameter's range [FMU units]: the defaults by kind within the FMU's declared range, or given
    bounds: Mapping[str, Bounds] = field(default_factory=dict)


def fmu_problem(*, fmu: str | os.PathLike, data: Sequence[str | os.PathLike], names: Sequence[str],
                cost: CostKind, start: Mapping[str, float] | None = None, channel_map: str | os.PathLike | None = None,
                segment_s: float | None = None, weighting: Weighting | None = None,
                held_inputs: Sequence[str] = (), noise_rms_fraction: float | None = None,
                gain_uncertainty: Mapping[str, float] | None = None,
                bands_hz: Sequence[tuple[float, float]] = (), averages: int | None = None,
                frf_floor: float | None = None, window_s: tuple[float, float] | None = None,
                bounds: Mapping[str, tuple[float | None, float | None]] | None = None,
                bounds_source: Mapping[str, str] | None = None) -> FmuProblem:
    """Read and check everything an FMU update needs; no simulation runs.

    Parameters
    ----------
    fmu : path
        An FMI 2.0 co-simulation FMU (any tool's; a native FMU of this package runs fastest).
    data : sequence of paths
        One or more time histories (CSV/npz: the measured inputs and outputs of one test each; several
        tests are summed, each in units of its own noise) and, with a single one and the log-FRF cost,
        optionally one frequency response (UFF 58/CSV) to compare with instead of the H1 of the time
        history. Or, with the log-FRF cost, one or more measured frequency responses alone (an
        analyser's FRFs, one file per test): the FMU's response at their frequencies comes from
        periodic runs (:mod:`mace_fmu.updating.engine.multisine`), and several files are summed.
    names : sequence of str
        The FMU parameters to update, each named once.
    cost : {"time", "log-frf"}
        Output errors over their RMS (eq. 4.3), or log ratios of H1 estimates (eq. 4.5/4.17).
    start : mapping of str to float, optional
        Values [FMU units] set on every run (default: the FMU's own start values).
    channel_map : path, optional
        CSV mapping the data's channels to the FMU's signals (with units and, optionally, a
        ``gain_uncertainty_percent`` column).
    segment_s : float, optional
        Time histories: H1 segment length [s] of the log-FRF cost (default 2 s; for periodic inputs, the
        shortest segment of whole periods that puts every line on a bin,
        :mod:`~mace_fmu.updating.engine.periodic`).
    weighting : {"noise", "none"}, optional
        Log-FRF: each bin over its noise standard deviation (the default), or eq. 4.17 as printed. The
        noise of a time history's H1 is estimated from the record; that of a measured frequency response
        from its coherence and number of averages (:mod:`~mace_fmu.updating.engine.frf_noise`).
    held_inputs : sequence of str
        FMU inputs the data lack that are to be held at 0 V (any other input the data lack is an
        error: a silently grounded input biases every parameter).
    noise_rms_fraction : float, optional
        The tests' noise RMS over their outputs' RMS, when it cannot be estimated from the data.
    gain_uncertainty : mapping of str to float, optional
        Output -> standard deviation of its sensor's gain as a fraction (0.01: known to 1 %). Each such
        gain is estimated with the update as a nuisance parameter "gain:<output>" with a Gaussian prior
        of mean 1, so the stated uncertainty of the parameters includes the gains'.
    bands_hz : sequence of (float, float)
        Measured frequency responses alone: the bands [Hz] the cost compares, e.g. one about each
        resonance (default: every frequency of the files). Time histories: one band, the time cost's
        zero-phase band-pass of the measured and the FMU's outputs (the FMU still driven by the measured
        inputs as they are), or the log-FRF cost's H1 band.
    averages : int, optional
        Measured frequency responses alone: the averages behind their estimates, where the files do not
        state them (the coherence's noise needs them).
    frf_floor : float, optional
        Measured frequency responses alone: the error floor, a fraction of each output's response
        (default :data:`~mace_fmu.updating.engine.frf_noise.DEFAULT_FLOOR`).
    window_s : (float, float), optional
        Time histories: (START, END) [s] on each record's time axis. The FMU is driven from the record's first
        sample to END, and compared (time) or estimated (log-frf) from START on: a record that starts
        mid-stream (the structure already moving, which the FMU at rest cannot know) is compared from a START
        past that transient.
    bounds : mapping of str to (float or None, float or None), optional
        name -> (low, high) [FMU units] replacing the default bounds (None keeps that side's).
    bounds_source : mapping of str to str, optional
        name -> where its bounds came from (the option, the file), named in errors.

    Returns
    -------
    FmuProblem
        The FMU as a model family, the parameters (gains appended) and their start values, the data
        and the cost, ready for :func:`~mace_fmu.updating.fmu.update.update_fmu`.

    Raises
    ------
    MaceError
        A missing or malformed file, an unknown parameter or channel, a parameter named twice, tests
        with different sample times, an FMU input the data lack and that is not held, a gain prior on
        an output no test records or not positive: the message names the file, channel or parameter.
    """
    from mace_fmu.updating.files import read_channel_map, read_measured_data

    if cost not in COST_KINDS:
        raise MaceError(f"cost must be one of {', '.join(COST_KINDS)}, got {cost!r}")
    interface = read_fmu_interface(fmu)
    twice = sorted({n for n in names if list(names).count(n) > 1})
    if twice:
        raise MaceError(f"parameter {twice[0]!r} named twice in --update (name each once)")
    names = tuple(names)
    if not names:
        raise MaceError("name at least one FMU parameter to update")
    interface.check_parameters(names)
    start = dict(start or {})
    interface.check_parameters(list(start))
    mapping = read_channel_map(channel_map) if channel_map is not None else None
    repeated = sorted({os.fspath(p) for p in data if [os.fspath(q) for q in data].count(os.fspath(p)) > 1})
    if repeated:
        raise MaceError(f"{repeated[0]}: given twice as --data (each test once)")
    histories, responses = [], []
    for path in data:
        if not Path(path).is_file():
            raise MaceError(f"{path}: no such measured-data file")
        item = read_measured_data(path, channel_map=mapping)
        interface.check_signals(inputs=list(item.inputs), outputs=list(item.outputs), where=os.fspath(path),
                                units={n: item.unit(n) for n in (*item.inputs, *item.outputs)})
        (histories if isinstance(item, TimeHistory) else responses).append(item)
    if not histories:
        # what shapes an H1 estimate or a time record's noise has no meaning here: refused, never ignored
        unused = {"segment_s (--segment-s)": segment_s,
                  "noise_rms_fraction (--noise-rms-percent)": noise_rms_fraction,
                  "held_inputs (--hold-input)": tuple(held_inputs) or None,
                  "window_s (--window)": window_s}
        given = [option for option, value in unused.items() if value is not None]
        if given:
            raise MaceError(f"{', '.join(given)}: for time histories; measured frequency responses given alone are "
                            "compared line by line (each over its noise, from the coherence and the averages) and "
                            "each input is driven alone, so this has no effect: leave it out")
        return _frequency_response_problem(interface, responses, names=names, start=start, cost=cost,
                                           bands_hz=bands_hz, gain_uncertainty=gain_uncertainty, data=data,
                                           weighting=weighting, averages=averages, floor=frf_floor,
                                           bounds=bounds, bounds_source=bounds_source)
    frf_only = {"averages (--averages)": averages, "frf_floor (--frf-floor-percent)": frf_floor}
    given = [option for option, value in frf_only.items() if value is not None]
    if given:
        raise MaceError(f"{', '.join(given)}: for measured frequency responses given alone (the noise of a time "
                        "history's H1 is estimated from the record itself): leave it out")
    weighting = "noise" if weighting is None else weighting
    if len(bands_hz) > 1:
        raise MaceError(f"--band-hz given {len(bands_hz)} times: with time histories one band (the time cost's "
                        "band-pass, the log-FRF cost's H1 band); several bands select lines of frequency responses "
                        "given alone")
    band = tuple(float(x) for x in bands_hz[0]) if bands_hz else None
    if band is not None:
        from mace_fmu.updating.engine.band import check_band

        band = check_band(band, sample_time_s=histories[0].sample_time_s, where="--band-hz")
    if len(responses) > 1 or (responses and len(histories) > 1):
        raise MaceError(f"give one or more time histories (each a test whose measured inputs drive the FMU) and, with "
                        f"a single one, at most one frequency response, or frequency responses alone; got "
                        f"{len(histories)} time histories and {len(responses)} frequency responses")
    if responses and cost != "log-frf":
        raise MaceError(f"{responses[0].source}: a frequency response is compared by the log-frf cost only "
                        f"(--cost log-frf), not by {cost!r}")
    history, frd = histories[0], (responses[0] if responses else None)
    for other in histories[1:]:
        if abs(other.sample_time_s - history.sample_time_s) > 1e-9 * history.sample_time_s:
            raise MaceError(f"{other.source}: sample time {other.sample_time_s:g} s, but {history.source} has "
                            f"{history.sample_time_s:g} s: the tests of one update share one sample time")
    missing = [i for i in (frd.inputs if frd is not None else ()) if i not in history.inputs]
    if missing:
        raise MaceError(f"{frd.source}: input(s) {', '.join(missing)} are not in the time history "
                        f"{history.source}, which drives the FMU")
    unknown_held = [i for i in held_inputs if i not in interface.inputs]
    if unknown_held:
        raise MaceError(f"--hold-input: {', '.join(unknown_held)} is not an input of {interface.path} "
                        f"(its inputs: {', '.join(interface.inputs)})")
    for test in histories:
        if not test.inputs:
            raise MaceError(f"{test.source}: no input channels: the FMU must be driven by the measured inputs")
        absent = [i for i in interface.inputs if i not in test.inputs and i not in held_inputs]
        if absent:
            raise MaceError(f"{test.source}: no channel for the FMU input(s) {', '.join(absent)}; record them, or "
                            "hold each at 0 explicitly (--hold-input NAME=0)")
    gains = _gain_priors(gain_uncertainty or {}, mapping, histories)
    windowed = [_windowed(test, window_s) for test in histories]
    histories = [test for test, _ in windowed]
    history = histories[0]
    notes: list[str] = []
    if window_s is not None:
        notes += [f"{test.source}: compared from {start_s:g} s (the FMU driven from the record's first sample, "
                  f"{test.times_s[0]:g} s)" for test, start_s in windowed]
    if band is not None and cost == "time":
        notes.append(f"the measured and the FMU's outputs band-passed to {band[0]:g}-{band[1]:g} Hz (zero phase; "
                     "the FMU driven by the measured inputs as they are)")
    costs = [_test_cost(cost, test, frd, segment_s=segment_s, weighting=weighting, compare_from_s=start_s,
                        band_hz=band, notes=notes) for test, start_s in windowed]
    the_cost = costs[0] if len(costs) == 1 else _several_tests(costs, histories, noise_rms_fraction)
    family = FmuFamily(interface=interface, fixed=start, gain_outputs=tuple(gains))
    values = {n: start.get(n, interface.parameters[n]) for n in names}
    if gains:
        the_cost = WithPriors(the_cost, priors={gain_parameter(o): (1.0, sd) for o, sd in gains.items()},
                              noise_sd=_noise_per_residual(the_cost, histories[0], noise_rms_fraction))
        names += family.gain_parameters
        values.update({g: 1.0 for g in family.gain_parameters})
    return FmuProblem(family=family, names=names, start=values, history=history,
                      frequency_data=frd, cost=the_cost, data_files=tuple(os.fspath(p) for p in data),
                      histories=tuple(histories), notes=tuple(notes),
                      bounds=declared_bounds(family, names, values, bounds, bounds_source))


def _windowed(history: TimeHistory, window_s: tuple[float, float] | None) -> tuple[TimeHistory, float]:
    """(the record cut after END, START) of ``--window START END``; (the record, its first time) without one.
    A window outside the record, or of fewer than two samples, is refused naming the record's times."""
    t = history.times_s
    if window_s is None:
        return history, float(t[0])
    start_s, end_s = (float(x) for x in window_s)
    span = f"{history.source}: the record runs from {t[0]:.9g} to {t[-1]:.9g} s"
    if not (math.isfinite(start_s) and math.isfinite(end_s) and start_s < end_s):
        raise MaceError(f"--window {start_s:g} {end_s:g}: expected START < END [s] on the record's time axis")
    tiny = 1e-9 * history.sample_time_s
    if start_s < t[0] - tiny or end_s > t[-1] + tiny:
        raise MaceError(f"--window {start_s:g} {end_s:g}: {span}; the window must lie within it")
    keep = t <= end_s + tiny
    if np.count_nonzero(keep & (t >= start_s - tiny)) < 2:
        raise MaceError(f"--window {start_s:g} {end_s:g}: fewer than two samples in it ({span}, sample time "
                        f"{history.sample_time_s:g} s)")
    if keep.all():
        return history, start_s
    return TimeHistory(t[keep], {k: v[keep] for k, v in history.inputs.items()},
                       {k: v[keep] for k, v in history.outputs.items()},
                       source=f"{history.source} (to {end_s:g} s)", units=history.units), start_s


def _frequency_response_problem(interface, responses: list[FrequencyResponseData], *, names: tuple[str, ...],
                                start: dict[str, float], cost: CostKind, bands_hz: Sequence[tuple[float, float]],
                                gain_uncertainty: Mapping[str, float] | None,
                                data: Sequence[str | os.PathLike], weighting: Weighting | None,
                                averages: int | None, floor: float | None,
                                bounds: Mapping[str, tuple[float | None, float | None]] | None,
                                bounds_source: Mapping[str, str] | None) -> FmuProblem:
    """An update on measured frequency responses alone: each file's FRFs in the band against the FMU's, from
    periodic runs at exactly the files' frequencies, each log error over its noise (``weighting`` "noise": from
    the coherence and the averages, :mod:`~mace_fmu.updating.engine.frf_noise`) or unweighted ("none"); by
    default "noise" for a file with coherence, "none" for one without (its noise is not known)."""
    from mace_fmu.updating.engine.costs import SeveralTests
    from mace_fmu.updating.engine.frf_noise import DEFAULT_FLOOR, frf_noise
    from mace_fmu.updating.engine.multisine import ProbedFrequencyResponseCost, multisine_probe

    if cost != "log-frf":
        raise MaceError(f"{responses[0].source}: measured frequency responses are compared by the log-frf cost "
                        f"(--cost log-frf), not by {cost!r}; a time cost needs the time histories")
    if gain_uncertainty:
        raise MaceError("--gain-uncertainty weighs a gain against the noise of time histories; measured frequency "
                        "responses alone do not give it")
    if weighting is not None and weighting not in WEIGHTINGS:
        raise MaceError(f"weighting must be one of {', '.join(WEIGHTINGS)}, got {weighting!r}")
    in_band = [_in_bands(frd, bands_hz) for frd in responses]
    chosen = [weighting or ("noise" if frd.coherence is not None else "none") for frd in in_band]
    if "noise" not in chosen and (averages is not None or floor is not None):
        raise MaceError("--averages and --frf-floor-percent set the noise the lines are weighted by: the data are "
                        "compared unweighted (--weighting none, or files without coherence), so they have no "
                        "effect; leave them out")
    floor = DEFAULT_FLOOR if floor is None else floor
    noises = [frf_noise(frd, averages=averages, floor=floor) if how == "noise" else None
              for frd, how in zip(in_band, chosen)]
    # a file keeps its frequencies to some digits (UFF 58: six): the probe puts them back on the analyser's grid
    probes = [multisine_probe(frd.frequencies_hz, precision=frd.frequency_precision) for frd in in_band]
    costs = [ProbedFrequencyResponseCost(data=frd, probe=probe, noise=noise)
             for frd, probe, noise in zip(in_band, probes, noises)]
    the_cost = costs[0] if len(costs) == 1 else SeveralTests(tests=tuple(costs), weights=(1.0,) * len(costs),
                                                               labels=tuple(frd.source for frd in in_band))
    family = FmuFamily(interface=interface, fixed=start)
    values = {n: start.get(n, interface.parameters[n]) for n in names}
    return FmuProblem(family=family, names=names, start=values,
                      history=None, frequency_data=in_band[0], cost=the_cost,
                      data_files=tuple(os.fspath(p) for p in data), responses=tuple(in_band),
                      notes=tuple(f"{frd.source}: {probe.note}" for frd, probe in zip(in_band, probes) if probe.note),
                      bounds=declared_bounds(family, names, values, bounds, bounds_source))


def _in_bands(frd: FrequencyResponseData, bands_hz: Sequence[tuple[float, float]]) -> FrequencyResponseData:
    """The lines of ``frd`` in any of ``bands_hz`` (all of them without a band)."""
    import numpy as np

    if not bands_hz:
        return frd
    keep = np.zeros(frd.frequencies_hz.shape, dtype=bool)
    for low, high in bands_hz:
        if not (0 <= low < high):
            raise MaceError(f"--band-hz {low:g} {high:g}: expected 0 <= LOW < HIGH")
        keep |= (frd.frequencies_hz >= low) & (frd.frequencies_hz <= high)
    if keep.sum() < 2:
        bands = ", ".join(f"{low:g}-{high:g}" for low, high in bands_hz)
        raise MaceError(f"{frd.source}: {int(keep.sum())} frequencies in {bands} Hz (the file has "
                        f"{frd.frequencies_hz[0]:g} to {frd.frequencies_hz[-1]:g} Hz)")
    return frd.lines(keep)


def _gain_priors(given: Mapping[str, float], mapping, histories: Sequence[TimeHistory]) -> dict[str, float]:
    """output -> gain standard deviation [fraction] from ``given`` (--gain-uncertainty) and the channel map's
    column; each must be an output some test records, positive, and stated once."""
    gains: dict[str, float] = {}
    recorded = {o for h in histories for o in h.outputs}
    from_map = {ch.signal: ch.gain_uncertainty_percent / 100.0 for ch in (mapping.channels if mapping else ())
                if ch.gain_uncertainty_percent is not None and ch.signal in recorded}
    for where, table in (("--gain-uncertainty", given), (mapping.source if mapping else "", from_map)):
        for output, sd in table.items():
            if output in gains:
                raise MaceError(f"{where}: the gain uncertainty of {output!r} is given twice (on the command line "
                                "and in the channel map): state it once")
            if not (math.isfinite(sd) and sd > 0):
                raise MaceError(f"{where}: gain uncertainty of {output!r} must be a positive percentage, got "
                                f"{100 * sd:g} %")
            gains[output] = float(sd)
    absent = [o for o in gains if o not in recorded]
    if absent:
        raise MaceError(f"--gain-uncertainty: no test records the output(s) {', '.join(absent)} (recorded: "
                        f"{', '.join(sorted(recorded))})")
    return gains


def _noise_per_residual(cost: Cost, history: TimeHistory, noise_rms_fraction: float | None) -> float:
    """The noise standard deviation per residual of ``cost``: 1 for costs already in units of their noise
    (several tests, the noise-weighted log-FRF cost), from the noise floor for one test's time cost."""
    from mace_fmu.updating.engine.convergence import time_noise_floor
    from mace_fmu.updating.engine.costs import SeveralTests, TimeResponseCost
    from mace_fmu.updating.engine.simulated_frf import SimulatedFrequencyResponseCost

    def weighted_frf(c) -> bool:
        return isinstance(c, SimulatedFrequencyResponseCost) and c.weights is not None

    if weighted_frf(cost) or (isinstance(cost, SeveralTests) and all(isinstance(c, TimeResponseCost) or weighted_frf(c)
                                                                      for c in cost.tests)):
        return 1.0
    if isinstance(cost, TimeResponseCost):
        floor = time_noise_floor(cost, noise_rms_fraction=noise_rms_fraction)
        if floor is None:
            raise MaceError(f"{history.source}: a gain prior weighs against the measurement noise, which cannot be "
                            "estimated from this test (its inputs fill the band): give --noise-rms-percent")
        return math.sqrt(floor.expected_cost / sum(len(v) for v in cost.compared.outputs.values()))
    raise MaceError("a gain prior weighs against the measurement noise: use the time cost or the noise-weighted "
                    "log-frf cost (--weighting noise)")


def _test_cost(cost: CostKind, history: TimeHistory, frd: FrequencyResponseData | None, *, segment_s: float | None,
               weighting: Weighting, compare_from_s: float, band_hz: tuple[float, float] | None,
               notes: list[str]) -> Cost:
    """The cost of one test (its time history, and a measured frequency response if given), compared from
    ``compare_from_s`` [s]; ``band_hz``: the time cost's band-pass, the log-FRF cost's H1 band. A periodic
    excitation's H1 is taken at its lines with segments of whole periods (said in ``notes``)."""
    if cost == "time":
        return fmu_cost(cost, history=history, compare_from_s=compare_from_s, band_hz=band_hz)
    dt = history.sample_time_s
    estimator = H1Estimator(segment_length=int(round((2.0 if segment_s is None else segment_s) / dt)),
                            band_hz=(float(frd.frequencies_hz[0]), float(frd.frequencies_hz[-1])) if frd is not None
                            else None)
    if frd is None:
        periodic = periodic_excitation(record_from(history, compare_from_s))
        if periodic is not None:
            length = periodic.segment(given_s=segment_s, where=f"{history.source}: ")
            lines = periodic.lines_hz if band_hz is None else periodic.lines_hz[
                (periodic.lines_hz >= band_hz[0]) & (periodic.lines_hz <= band_hz[1])]
            if lines.size == 0:
                raise MaceError(f"--band-hz {band_hz[0]:g} {band_hz[1]:g}: none of the excitation's lines in it "
                                f"({periodic.describe()})")
            estimator = H1Estimator(segment_length=length, window="boxcar", overlap=0.0,
                                    lines_hz=tuple(float(x) for x in lines))
            notes.append(f"{history.source}: periodic inputs, {periodic.describe()}: H1 at the lines, "
                         f"{length}-sample segments ({length * dt:.6g} s, {length / periodic.period_samples:.4g} "
                         "periods), rectangular window")
        else:
            estimator = H1Estimator(segment_length=estimator.segment_length,
                                    band_hz=band_hz if band_hz is not None else _default_band(history))
    elif band_hz is not None:
        raise MaceError("--band-hz: with a measured frequency response beside the time history its frequencies are "
                        "the band; leave --band-hz out")
    return fmu_cost(cost, history=history, frequency_data=frd, estimator=estimator, compare_from_s=compare_from_s,
                    weighting=weighting if frd is None or _same_bins(frd, history, estimator) else "none")


def _several_tests(costs: list[Cost], histories: list[TimeHistory], noise_rms_fraction: float | None) -> Cost:
    """The tests' costs summed, each in units of its own noise: a time cost is divided by its noise's
    standard deviation per residual (its noise floor, estimated above the inputs' band or given); a
    noise-weighted log-FRF cost already is in those units."""
    from mace_fmu.updating.engine.convergence import time_noise_floor
    from mace_fmu.updating.engine.costs import SeveralTests, TimeResponseCost

    weights = []
    for c, test in zip(costs, histories):
        if isinstance(c, TimeResponseCost):
            floor = time_noise_floor(c, noise_rms_fraction=noise_rms_fraction)
            if floor is None:
                raise MaceError(f"{test.source}: the noise of this test cannot be estimated (its inputs fill the "
                                "band); several tests are weighed by their noise: give --noise-rms-percent")
            n = sum(len(v) for v in c.compared.outputs.values())
            weights.append(1.0 / (floor.expected_cost / n) ** 0.5)
        else:
            weights.append(1.0)
    return SeveralTests(tests=tuple(costs), weights=tuple(weights), labels=tuple(h.source for h in histories))


def _default_band(history: TimeHistory) -> tuple[float, float]:
    """0.5 Hz to 60 Hz (thesis 4.5), cut to what the sampling allows."""
    return 0.5, min(60.0, 0.4 / history.sample_time_s)


def _same_bins(frd: FrequencyResponseData, history: TimeHistory, estimator: H1Estimator) -> bool:
    """Whether ``frd`` sits on the estimator's bins (the noise weights are computed there)."""
    import numpy as np

    spacing = 1.0 / (estimator.segment_length * history.sample_time_s)
    k = frd.frequencies_hz / spacing
    return bool(np.allclose(k, np.round(k), atol=1e-6))
