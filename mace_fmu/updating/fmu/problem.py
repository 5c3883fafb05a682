"""An FMU update as a user states it: an FMU file, measured-data files, parameter names, a cost; checked before any run.

Everything that can be wrong with the request (files, parameter names, channels the FMU lacks,
a frequency response without the time history it needs) is found here, before the first FMU
simulation, and reported as one :class:`~mace_fmu.errors.MaceError`: the request's own values once, when an
:class:`FmuUpdateRequest` is made, then the files against the FMU and each other. The data read are of one of
three kinds (time histories; one time history and a frequency response; frequency responses alone), and
:data:`TEST_COSTS` maps each kind and cost to the cost of one test; a cost the data cannot be compared by is
refused naming the first measured frequency response.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.costs import Cost, SeveralTests, TimeResponseCost, WithPriors
from mace_fmu.updating.engine.measured import MeasuredFrf, TimeHistory
from mace_fmu.updating.engine.models import SimulatedModel
from mace_fmu.updating.engine.periodic import periodic_excitation
from mace_fmu.updating.engine.simulated_frf import H1Estimator
from mace_fmu.updating.engine.solve import Bounds
from mace_fmu.updating.fmu.model import FmuFamily, FmuInterface, gain_parameter, read_fmu_interface
from mace_fmu.updating.fmu.update import (COST_KINDS, WEIGHTINGS, CostKind, Weighting, declared_bounds,
                                          log_frf_cost, record_from)

if TYPE_CHECKING:
    from mace_fmu.updating.engine.frf_noise import FrfNoise
    from mace_fmu.updating.files.channels import ChannelMap

FmuCost = Cost[SimulatedModel]  #: a cost of the FMU (any simulated model)
#: what the measured data are: time histories (each a test whose inputs drive the FMU), one time history and a
#: measured frequency response compared with the FMU's H1, or measured frequency responses alone
DataKind = Literal["time histories", "time history and frequency response", "frequency responses"]


@dataclass(frozen=True)
class FmuProblem:
    """A checked FMU update: the FMU, what it starts from, the measured data and the cost."""

    family: FmuFamily  #: the FMU with every start value from the start file set on each run
    names: tuple[str, ...]  #: parameters to update
    start: Mapping[str, float]  #: their start values [FMU units]
    history: TimeHistory | None  #: the measured time history of the first test (None: frequency responses only)
    frequency_data: MeasuredFrf | None  #: measured frequency responses (None: a time cost)
    cost: FmuCost  #: the cost the update minimises
    data_files: tuple[str, ...]  #: the measured data files read
    histories: tuple[TimeHistory, ...] = ()  #: every test's time history (``history`` is the first)
    responses: tuple[MeasuredFrf, ...] = ()  #: every measured frequency response, in the band
    #: what was made of the data before the update, said where it runs (a file's lines put on the analyser's grid)
    notes: tuple[str, ...] = ()
    #: each updated parameter's range [FMU units]: the defaults by kind within the FMU's declared range, or given
    bounds: Mapping[str, Bounds] = field(default_factory=dict)


@dataclass(frozen=True)
class FmuUpdateRequest:
    """An FMU update as a user states it: the arguments of :func:`fmu_problem` (which documents each), checked
    once when made, before any file is read.

    Raises
    ------
    MaceError
        An unknown cost or weighting, no parameter or one named twice, a data file given twice.
    """

    fmu: str | os.PathLike[str]  #: the FMU file
    data: tuple[str | os.PathLike[str], ...]  #: the measured-data files, each a test
    names: tuple[str, ...]  #: the FMU parameters to update
    cost: CostKind  #: "time" or "log-frf"
    start: Mapping[str, float] = field(default_factory=dict)  #: values set on every run [FMU units]
    channel_map: str | os.PathLike[str] | None = None  #: the data's channels -> the FMU's signals
    segment_s: float | None = None  #: time histories: the H1 segment [s]
    weighting: Weighting | None = None  #: log-FRF: "noise" or "none" (None: by the data)
    held_inputs: tuple[str, ...] = ()  #: FMU inputs held at 0 V
    noise_rms_fraction: float | None = None  #: the tests' noise RMS over their outputs' RMS
    gain_uncertainty: Mapping[str, float] = field(default_factory=dict)  #: output -> gain standard deviation
    bands_hz: tuple[tuple[float, float], ...] = ()  #: (low, high) [Hz] bands
    averages: int | None = None  #: frequency responses alone: their averages
    frf_floor: float | None = None  #: frequency responses alone: the error floor (fraction)
    window_s: tuple[float, float] | None = None  #: time histories: (START, END) [s]
    bounds: Mapping[str, tuple[float | None, float | None]] = field(default_factory=dict)  #: name -> (low, high)
    bounds_source: Mapping[str, str] = field(default_factory=dict)  #: name -> where its bounds came from

    def __post_init__(self) -> None:
        for name in ("data", "names", "held_inputs", "bands_hz"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        for name in ("start", "gain_uncertainty", "bounds", "bounds_source"):
            object.__setattr__(self, name, dict(getattr(self, name) or {}))
        if self.cost not in COST_KINDS:
            raise MaceError(f"cost must be one of {', '.join(COST_KINDS)}, got {self.cost!r}")
        if self.weighting is not None and self.weighting not in WEIGHTINGS:
            raise MaceError(f"weighting must be one of {', '.join(WEIGHTINGS)}, got {self.weighting!r}")
        twice = sorted({n for n in self.names if self.names.count(n) > 1})
        if twice:
            raise MaceError(f"parameter {twice[0]!r} named twice in --update (name each once)")
        if not self.names:
            raise MaceError("name at least one FMU parameter to update")
        paths = [os.fspath(p) for p in self.data]
        repeated = sorted({p for p in paths if paths.count(p) > 1})
        if repeated:
            raise MaceError(f"{repeated[0]}: given twice as --data (each test once)")

    def check_options(self, kind: DataKind) -> None:
        """MaceError naming the options that have no meaning for data of ``kind``: refused, never ignored.

        Parameters
        ----------
        kind : DataKind
            The kind of the request's data files, as ``problem_of`` read them.
        """
        if kind == "frequency responses":
            # what shapes an H1 estimate or a time record's noise has no meaning here
            unused = {"segment_s (--segment-s)": self.segment_s,
                      "noise_rms_fraction (--noise-rms-percent)": self.noise_rms_fraction,
                      "held_inputs (--hold-input)": self.held_inputs or None,
                      "window_s (--window)": self.window_s}
            given = [option for option, value in unused.items() if value is not None]
            if given:
                raise MaceError(f"{', '.join(given)}: for time histories; measured frequency responses given alone "
                                "are compared line by line (each over its noise, from the coherence and the "
                                "averages) and each input is driven alone, so this has no effect: leave it out")
            return
        frf_only = {"averages (--averages)": self.averages, "frf_floor (--frf-floor-percent)": self.frf_floor}
        given = [option for option, value in frf_only.items() if value is not None]
        if given:
            raise MaceError(f"{', '.join(given)}: for measured frequency responses given alone (the noise of a time "
                            "history's H1 is estimated from the record itself): leave it out")
        if len(self.bands_hz) > 1:
            raise MaceError(f"--band-hz given {len(self.bands_hz)} times: with time histories one band (the time "
                            "cost's band-pass, the log-FRF cost's H1 band); several bands select lines of frequency "
                            "responses given alone")


def fmu_problem(*, fmu: str | os.PathLike[str], data: Sequence[str | os.PathLike[str]], names: Sequence[str],
                cost: CostKind, start: Mapping[str, float] | None = None,
                channel_map: str | os.PathLike[str] | None = None, segment_s: float | None = None,
                weighting: Weighting | None = None, held_inputs: Sequence[str] = (),
                noise_rms_fraction: float | None = None, gain_uncertainty: Mapping[str, float] | None = None,
                bands_hz: Sequence[tuple[float, float]] = (), averages: int | None = None,
                frf_floor: float | None = None, window_s: tuple[float, float] | None = None,
                bounds: Mapping[str, tuple[float | None, float | None]] | None = None,
                bounds_source: Mapping[str, str] | None = None) -> FmuProblem:
    """Read and check everything an FMU update needs; no simulation runs.

    The arguments are checked once as an :class:`FmuUpdateRequest`, then :func:`problem_of` reads the files.

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
        an output no test records or not positive, an unknown cost or weighting, a cost the data cannot be
        compared by, an option that has no effect on the data: the message names the file, channel,
        parameter or option.
    """
    request = FmuUpdateRequest(fmu=fmu, data=tuple(data), names=tuple(names), cost=cost, start=dict(start or {}),
                               channel_map=channel_map, segment_s=segment_s, weighting=weighting,
                               held_inputs=tuple(held_inputs), noise_rms_fraction=noise_rms_fraction,
                               gain_uncertainty=dict(gain_uncertainty or {}), bands_hz=tuple(bands_hz),
                               averages=averages, frf_floor=frf_floor, window_s=window_s, bounds=dict(bounds or {}),
                               bounds_source=dict(bounds_source or {}))
    return problem_of(request)


@dataclass(frozen=True)
class _Data:
    """What the request's files hold, checked against the FMU."""

    interface: FmuInterface
    mapping: ChannelMap | None  #: the channel map read (None: none given)
    histories: tuple[TimeHistory, ...]
    responses: tuple[MeasuredFrf, ...]

    def kind(self) -> DataKind:
        """What the data are; MaceError for frequency responses beside several time histories, or several
        beside one."""
        if not self.histories:
            return "frequency responses"
        if len(self.responses) > 1 or (self.responses and len(self.histories) > 1):
            raise MaceError(f"give one or more time histories (each a test whose measured inputs drive the FMU) and, "
                            f"with a single one, at most one frequency response, or frequency responses alone; got "
                            f"{len(self.histories)} time histories and {len(self.responses)} frequency responses")
        return "time history and frequency response" if self.responses else "time histories"


@dataclass(frozen=True)
class _Test:
    """One test as its cost compares it: the record that drives the FMU (None: a frequency response alone) and
    the measured frequency response (None: the record's H1), compared from ``compare_from_s`` [s]; ``band_hz``:
    the time cost's band-pass, the log-FRF cost's H1 band; ``noise``: a frequency response's noise."""

    history: TimeHistory | None = None
    frd: MeasuredFrf | None = None
    compare_from_s: float = 0.0
    band_hz: tuple[float, float] | None = None
    noise: FrfNoise | None = None


#: the cost of one test: (the request, the test, the notes to add to) -> its cost
TestCost = Callable[[FmuUpdateRequest, _Test, list[str]], FmuCost]


def problem_of(request: FmuUpdateRequest) -> FmuProblem:
    """The checked problem of ``request`` (:func:`fmu_problem`): its files read and checked against the FMU and
    each other, the cost of each test from :data:`TEST_COSTS`; no simulation runs.

    Raises
    ------
    MaceError
        As :func:`fmu_problem`.
    """
    found = _read_data(request)
    kind = found.kind()
    request.check_options(kind)
    test_cost = TEST_COSTS.get((kind, request.cost))
    if test_cost is None:
        raise MaceError(REFUSED_COSTS[kind].format(source=found.responses[0].source, cost=request.cost))
    if kind == "frequency responses":
        return _frequency_response_problem(request, found, test_cost)
    return _time_history_problem(request, found, test_cost)


def _read_data(request: FmuUpdateRequest) -> _Data:
    """The FMU's interface, the channel map and the measured data of ``request``, each file's channels and
    units checked against the FMU, the parameters named checked to be the FMU's."""
    from mace_fmu.updating.files import read_channel_map, read_measured_data

    interface = read_fmu_interface(request.fmu)
    interface.check_parameters(request.names)
    interface.check_parameters(list(request.start))
    mapping = read_channel_map(request.channel_map) if request.channel_map is not None else None
    histories: list[TimeHistory] = []
    responses: list[MeasuredFrf] = []
    for path in request.data:
        if not Path(path).is_file():
            raise MaceError(f"{path}: no such measured-data file")
        item = read_measured_data(path, channel_map=mapping)
        interface.check_signals(inputs=list(item.inputs), outputs=list(item.outputs), where=os.fspath(path),
                                units={n: item.unit(n) for n in (*item.inputs, *item.outputs)})
        if isinstance(item, TimeHistory):
            histories.append(item)
        else:
            responses.append(item)
    return _Data(interface=interface, mapping=mapping, histories=tuple(histories), responses=tuple(responses))


def _time_history_problem(request: FmuUpdateRequest, found: _Data, test_cost: TestCost) -> FmuProblem:
    """An update on time histories (and, beside a single one, a measured frequency response): each test's cost
    from ``test_cost``, several tests summed in units of their noise, sensor gains estimated with their priors."""
    histories, frd = list(found.histories), (found.responses[0] if found.responses else None)
    band = None
    if request.bands_hz:
        from mace_fmu.updating.engine.band import check_band

        low, high = request.bands_hz[0]
        band = check_band((float(low), float(high)), sample_time_s=histories[0].sample_time_s, where="--band-hz")
    _check_tests(request, found.interface, histories, frd)
    gains = _gain_priors(request.gain_uncertainty, found.mapping, histories)
    windowed = [_windowed(test, request.window_s) for test in histories]
    histories = [test for test, _ in windowed]
    notes: list[str] = []
    if request.window_s is not None:
        notes += [f"{test.source}: compared from {start_s:g} s (the FMU driven from the record's first sample, "
                  f"{test.times_s[0]:g} s)" for test, start_s in windowed]
    costs = [test_cost(request, _Test(history=test, frd=frd, compare_from_s=start_s, band_hz=band), notes)
             for test, start_s in windowed]
    the_cost = costs[0] if len(costs) == 1 else _several_tests(costs, histories, request.noise_rms_fraction)
    family = FmuFamily(interface=found.interface, fixed=request.start, gain_outputs=tuple(gains))
    names, values = request.names, _start_values(request, found.interface)
    if gains:
        the_cost = WithPriors(the_cost, priors={gain_parameter(o): (1.0, sd) for o, sd in gains.items()},
                              noise_sd=_noise_per_residual(the_cost, histories[0], request.noise_rms_fraction))
        names += family.gain_parameters
        values.update({g: 1.0 for g in family.gain_parameters})
    return FmuProblem(family=family, names=names, start=values, history=histories[0],
                      frequency_data=frd, cost=the_cost, data_files=tuple(os.fspath(p) for p in request.data),
                      histories=tuple(histories), notes=tuple(notes),
                      bounds=declared_bounds(family, names, values, request.bounds, request.bounds_source))


def _check_tests(request: FmuUpdateRequest, interface: FmuInterface, histories: Sequence[TimeHistory],
                 frd: MeasuredFrf | None) -> None:
    """MaceError for tests of different sample times, a frequency response whose inputs the time history lacks,
    a held input the FMU does not have, a test without inputs or without a channel for an FMU input not held."""
    history = histories[0]
    for other in histories[1:]:
        if abs(other.sample_time_s - history.sample_time_s) > 1e-9 * history.sample_time_s:
            raise MaceError(f"{other.source}: sample time {other.sample_time_s:g} s, but {history.source} has "
                            f"{history.sample_time_s:g} s: the tests of one update share one sample time")
    missing = [i for i in (frd.inputs if frd is not None else ()) if i not in history.inputs]
    if missing:
        assert frd is not None
        raise MaceError(f"{frd.source}: input(s) {', '.join(missing)} are not in the time history "
                        f"{history.source}, which drives the FMU")
    unknown_held = [i for i in request.held_inputs if i not in interface.inputs]
    if unknown_held:
        raise MaceError(f"--hold-input: {', '.join(unknown_held)} is not an input of {interface.path} "
                        f"(its inputs: {', '.join(interface.inputs)})")
    for test in histories:
        if not test.inputs:
            raise MaceError(f"{test.source}: no input channels: the FMU must be driven by the measured inputs")
        absent = [i for i in interface.inputs if i not in test.inputs and i not in request.held_inputs]
        if absent:
            raise MaceError(f"{test.source}: no channel for the FMU input(s) {', '.join(absent)}; record them, or "
                            "hold each at 0 explicitly (--hold-input NAME=0)")


def _start_values(request: FmuUpdateRequest, interface: FmuInterface) -> dict[str, float]:
    """The start value of each parameter updated: the request's, else the FMU's."""
    return {n: request.start.get(n, interface.parameters[n]) for n in request.names}


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



def _frequency_response_problem(request: FmuUpdateRequest, found: _Data, test_cost: TestCost) -> FmuProblem:
    """An update on measured frequency responses alone: each file's FRFs in the band against the FMU's, from
    periodic runs at exactly the files' frequencies, each log error over its noise (``weighting`` "noise": from
    the coherence and the averages, :mod:`~mace_fmu.updating.engine.frf_noise`) or unweighted ("none"); by
    default "noise" for a file with coherence, "none" for one without (its noise is not known)."""
    from mace_fmu.updating.engine.frf_noise import DEFAULT_FLOOR, frf_noise

    if request.gain_uncertainty:
        raise MaceError("--gain-uncertainty weighs a gain against the noise of time histories; measured frequency "
                        "responses alone do not give it")
    in_band = [_in_bands(frd, request.bands_hz) for frd in found.responses]
    chosen = [request.weighting or ("noise" if frd.coherence is not None else "none") for frd in in_band]
    if "noise" not in chosen and (request.averages is not None or request.frf_floor is not None):
        raise MaceError("--averages and --frf-floor-percent set the noise the lines are weighted by: the data are "
                        "compared unweighted (--weighting none, or files without coherence), so they have no "
                        "effect; leave them out")
    floor = DEFAULT_FLOOR if request.frf_floor is None else request.frf_floor
    tests = [_Test(frd=frd, noise=frf_noise(frd, averages=request.averages, floor=floor) if how == "noise" else None)
             for frd, how in zip(in_band, chosen)]
    notes: list[str] = []
    costs = [test_cost(request, test, notes) for test in tests]
    the_cost = costs[0] if len(costs) == 1 else SeveralTests(tests=tuple(costs), weights=(1.0,) * len(costs),
                                                               labels=tuple(frd.source for frd in in_band))
    family = FmuFamily(interface=found.interface, fixed=request.start)
    values = _start_values(request, found.interface)
    return FmuProblem(family=family, names=request.names, start=values,
                      history=None, frequency_data=in_band[0], cost=the_cost,
                      data_files=tuple(os.fspath(p) for p in request.data), responses=tuple(in_band),
                      notes=tuple(notes),
                      bounds=declared_bounds(family, request.names, values, request.bounds, request.bounds_source))


def _time_cost(request: FmuUpdateRequest, test: _Test, notes: list[str]) -> FmuCost:
    """The time cost of a time history (eq. 4.3), through the band-pass where one is given."""
    assert test.history is not None
    if test.band_hz is not None:
        low, high = test.band_hz
        note = (f"the measured and the FMU's outputs band-passed to {low:g}-{high:g} Hz (zero phase; the FMU driven "
                "by the measured inputs as they are)")
        if note not in notes:  # one band for every test: said once
            notes.append(note)
    return TimeResponseCost(test.history, compare_from_s=test.compare_from_s, band_hz=test.band_hz)


def _h1_cost(request: FmuUpdateRequest, test: _Test, notes: list[str]) -> FmuCost:
    """The log-FRF cost of a time history's own H1 against the FMU's: a periodic excitation's at its lines with
    segments of whole periods (said in ``notes``), any other in the band (default :func:`_default_band`)."""
    history = test.history
    assert history is not None
    dt, band_hz = history.sample_time_s, test.band_hz
    periodic = periodic_excitation(record_from(history, test.compare_from_s))
    if periodic is not None:
        length = periodic.segment(given_s=request.segment_s, where=f"{history.source}: ")
        lines = periodic.lines_hz if band_hz is None else periodic.lines_hz[
            (periodic.lines_hz >= band_hz[0]) & (periodic.lines_hz <= band_hz[1])]
        if lines.size == 0:
            assert band_hz is not None
            raise MaceError(f"--band-hz {band_hz[0]:g} {band_hz[1]:g}: none of the excitation's lines in it "
                            f"({periodic.describe()})")
        estimator = H1Estimator(segment_length=length, window="boxcar", overlap=0.0,
                                lines_hz=tuple(float(x) for x in lines))
        notes.append(f"{history.source}: periodic inputs, {periodic.describe()}: H1 at the lines, "
                     f"{length}-sample segments ({length * dt:.6g} s, {length / periodic.period_samples:.4g} "
                     "periods), rectangular window")
    else:
        estimator = H1Estimator(segment_length=_segment_length(request, history),
                                band_hz=band_hz if band_hz is not None else _default_band(history))
    return log_frf_cost(history=history, estimator=estimator, compare_from_s=test.compare_from_s,
                        weighting=request.weighting or "noise")


def _frf_beside_history_cost(request: FmuUpdateRequest, test: _Test, notes: list[str]) -> FmuCost:
    """The log-FRF cost of a measured frequency response against the FMU's H1 when driven by the time history's
    inputs, the estimator's band the response's; weighted by the record's noise where the response sits on the
    estimator's bins."""
    history, frd = test.history, test.frd
    assert history is not None and frd is not None
    estimator = H1Estimator(segment_length=_segment_length(request, history),
                            band_hz=(float(frd.frequencies_hz[0]), float(frd.frequencies_hz[-1])))
    if test.band_hz is not None:
        raise MaceError("--band-hz: with a measured frequency response beside the time history its frequencies are "
                        "the band; leave --band-hz out")
    weighting = request.weighting or "noise"
    return log_frf_cost(history=history, frequency_data=frd, estimator=estimator, compare_from_s=test.compare_from_s,
                        weighting=weighting if _same_bins(frd, history, estimator) else "none")


def _segment_length(request: FmuUpdateRequest, history: TimeHistory) -> int:
    """The H1 segment of ``--segment-s`` (default 2 s) in samples of ``history``."""
    return round((2.0 if request.segment_s is None else request.segment_s) / history.sample_time_s)


def _probed_cost(request: FmuUpdateRequest, test: _Test, notes: list[str]) -> FmuCost:
    """The log-FRF cost of a measured frequency response alone against the FMU's from periodic runs at its lines
    (:mod:`~mace_fmu.updating.engine.multisine`), put back on the analyser's grid (said in ``notes``)."""
    from mace_fmu.updating.engine.multisine import ProbedFrequencyResponseCost, multisine_probe

    frd = test.frd
    assert frd is not None
    # a file keeps its frequencies to some digits (UFF 58: six): the probe puts them back on the analyser's grid
    probe = multisine_probe(frd.frequencies_hz, precision=frd.frequency_precision)
    if probe.note:
        notes.append(f"{frd.source}: {probe.note}")
    return ProbedFrequencyResponseCost(data=frd, probe=probe, noise=test.noise)


#: (what the data are, the cost asked for) -> the cost of one test; a pair not here is refused (REFUSED_COSTS)
TEST_COSTS: Mapping[tuple[DataKind, CostKind], TestCost] = {
    ("time histories", "time"): _time_cost,
    ("time histories", "log-frf"): _h1_cost,
    ("time history and frequency response", "log-frf"): _frf_beside_history_cost,
    ("frequency responses", "log-frf"): _probed_cost,
}
#: what the data are -> why a cost TEST_COSTS has not for them is refused ({source}: the first frequency response)
REFUSED_COSTS: Mapping[DataKind, str] = {
    "time history and frequency response": "{source}: a frequency response is compared by the log-frf cost only "
                                           "(--cost log-frf), not by {cost!r}",
    "frequency responses": "{source}: measured frequency responses are compared by the log-frf cost "
                           "(--cost log-frf), not by {cost!r}; a time cost needs the time histories",
}


def _in_bands(frd: MeasuredFrf, bands_hz: Sequence[tuple[float, float]]) -> MeasuredFrf:
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


def _same_bins(frd: MeasuredFrf, history: TimeHistory, estimator: H1Estimator) -> bool:
    """Whether ``frd`` sits on the estimator's bins (the noise weights are computed there)."""
    import numpy as np

    spacing = 1.0 / (estimator.segment_length * history.sample_time_s)
    k = frd.frequencies_hz / spacing
    return bool(np.allclose(k, np.round(k), atol=1e-6))
