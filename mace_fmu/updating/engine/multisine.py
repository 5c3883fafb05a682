"""A simulated model's frequency response at given frequency lines, from one periodic multisine run per input.

The model is known only by simulation (an FMU): its inputs are held over each sample (zero-order hold)
and its outputs read at the samples. A multisine whose lines are the wanted frequencies, all multiples of
1 / period, drives each input in turn; once the free response has died out, one period of the output's DFT
holds the response at every line at once (Pintelon and Schoukens, System Identification, ch. 2). Two
details make it the continuous-time response a measured FRF is compared with:

- each held value is the multisine at the middle of its sample, so the held staircase has no half-sample
  delay, and each line's amplitude is divided by sinc(w T / 2), the hold's gain, so that the staircase's
  component at the line is exactly the intended one;
- the direct feedthrough D (an accelerometer's mass line) reads the held value at the sample, half a
  sample after the multisine's middle: its share of the DFT, D e^(j w T / 2) / sinc(w T / 2), is replaced
  by D, with D measured by a two-sample pulse. Left are the images of the staircase at 1/T -+ f, folded
  back by the sampling, second order in f T: against the frame's exact state-space response
  (tests/updating/engine/test_multisine.py), at 20 samples per cycle of the highest line, 2e-7 at the
  resonances, 3e-6 in the median and 3.5e-3 at an antiresonance; without the feedthrough's term the
  error at the resonances was 1.7e-3.

How long the free response takes to die out depends on the model's damping: the run is repeated with
twice the periods until the last two periods agree (:attr:`MultisineProbe.tolerance`), and the model
family's later runs use that length.

Both corrections assume that what the outputs read of the input at once is a constant D. A feedthrough
behind fast dynamics breaks that: a delay of a few samples (a Pade approximation) in front of an
accelerometer's mass line reads the staircase through its own transient. On an FMU of NASTRAN's modes
(a free plate, an accelerometer at the shaker behind a 20 us delay, 6.3 kHz) 20 samples per cycle were
47 % off at the driving point, with the error falling as the square of the sample time (14 %, 3.6 %, 0.9 %,
0.23 % at 40 to 320). So the first response a probe gives is checked against the same probe at twice
the sample rate: where the two differ by more than :attr:`MultisineProbe.rate_tolerance` of the largest
response, the rate is doubled until they agree (the later runs use that rate), and a model that needs
more than :attr:`MultisineProbe.max_rate_doublings` doublings is refused, naming the input.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from typing import Sequence

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.frf_noise import FrfNoise
from mace_fmu.updating.engine.residual_blocks import ResidualBlock, frequency_blocks
from mace_fmu.updating.engine.measured import MeasuredFrf
from mace_fmu.updating.engine.models import SimulatedModel
from mace_fmu.updating.engine.simulated_frf import log_ratio_labels, log_ratio_residual, measured_pairs


@dataclass
class ProbeLearning:
    """What a :class:`MultisineProbe` learns as it runs a model, kept for its later runs: how many periods the
    free response takes to die out, and the sample rate each input needs (module docstring)."""

    periods: int = 2  #: the periods of the next run (doubled until the last two agree)
    #: input -> the probe at the sample rate its response needs (this one or a finer one, each learning its own)
    rates: dict[str, MultisineProbe] = field(default_factory=dict)


@dataclass(frozen=True)
class MultisineProbe:
    """The periodic runs that give a simulated model's response at ``frequencies_hz`` (multiples of
    1 / ``period_s``); what the runs teach it is in ``learnt``, the record itself never changes."""

    frequencies_hz: np.ndarray  #: the lines [Hz], each a whole multiple of 1 / period_s
    period_s: float  #: the multisine's period [s]
    samples_per_period: int  #: the period in samples; the sample time is period_s / samples_per_period
    tolerance: float = 1e-7  #: largest change between the last two periods, relative to the largest response
    max_periods: int = 256  #: a model that settles in no fewer periods is reported, not run for ever
    #: largest change of the response, relative to the largest, when the sample rate doubles (module docstring)
    rate_tolerance: float = 1e-3
    max_rate_doublings: int = 6  #: 20 samples per cycle become at most 1280
    #: the lines as the data state them, before :func:`multisine_probe` put them on the grid (None: the same)
    given_hz: np.ndarray | None = None
    note: str = ""  #: how the lines were put on the grid, when any moved by more than round-off ("": none did)
    #: the run length and sample rates learnt from the runs so far
    learnt: ProbeLearning = field(default_factory=ProbeLearning, repr=False, compare=False)

    @property
    def sample_time_s(self) -> float:
        return self.period_s / self.samples_per_period

    @property
    def bins(self) -> np.ndarray:
        """Each line's DFT bin in one period."""
        return np.rint(self.frequencies_hz * self.period_s).astype(int)

    def excitation(self, periods: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(times [s], held input values, complex amplitude of each line): ``periods`` periods of the
        multisine, Schroeder phases (a low crest factor), unit amplitude per line before the hold's
        correction."""
        values, lines = self._one_period
        return np.arange(periods * self.samples_per_period) * self.sample_time_s, np.tile(values, periods), lines

    @functools.cached_property
    def _one_period(self) -> tuple[np.ndarray, np.ndarray]:
        """(held input values of one period, complex amplitude of each line): made once, from the record alone."""
        k = np.arange(len(self.frequencies_hz))
        lines = np.exp(-1j * np.pi * k * (k + 1) / max(len(k), 1))
        w = 2 * np.pi * self.frequencies_hz
        amplitude = lines / self._hold_gain  # the staircase's component at each line is then ``lines``
        n = self.samples_per_period
        bins = self.frequencies_hz * self.period_s
        if np.allclose(bins, np.rint(bins), rtol=0.0, atol=1e-9):
            # every line on the period's DFT grid: the sum over lines at the samples' middles, (m + 1/2) T, is
            # one inverse FFT of the amplitudes, each turned by its half-sample phase exp(i pi b / n)
            b = np.rint(bins).astype(np.int64)
            spectrum = np.zeros(n, dtype=complex)
            np.add.at(spectrum, b % n, amplitude * np.exp(1j * np.pi * b / n))
            return n * np.real(np.fft.ifft(spectrum)), lines
        middle = (np.arange(n) + 0.5) * self.sample_time_s
        values = np.zeros(n)
        for start in range(0, len(w), 64):  # a block of lines at a time: the (n x lines) table stays small
            block = slice(start, start + 64)
            values += np.real(np.exp(1j * np.outer(middle, w[block])) @ amplitude[block])
        return values, lines

    @property
    def _hold_gain(self) -> np.ndarray:
        """The zero-order hold's gain at each line, sinc(w T / 2) (numpy's sinc is sin(pi x) / (pi x))."""
        return np.sinc(self.frequencies_hz * self.sample_time_s)

    def response(self, model: SimulatedModel, *, inputs: Sequence[str], outputs: Sequence[str]) -> np.ndarray:
        """H[line, output, input] of ``model`` (anything with ``time_response(times, {input: values},
        outputs=...)`` that starts at rest, as an FMU does), in its outputs' units per its inputs' units.

        The first call checks the sample rate (module docstring) and may raise it for every later call.

        Raises
        ------
        MaceError
            A response that still changes with the sample rate after :attr:`max_rate_doublings` doublings, or
            that does not settle.
        """
        h = np.empty((len(self.frequencies_hz), len(outputs), len(inputs)), dtype=complex)
        for j, name in enumerate(inputs):
            h[:, :, j] = self._resolved(model, name, list(outputs))
        return h

    def _resolved(self, model: SimulatedModel, name: str, outputs: list[str]) -> np.ndarray:
        """One input's response at a sample rate that resolves it: checked once per input against twice the
        rate (and raised until the two agree); later calls run at the rate found."""
        rates = self.learnt.rates
        if name in rates:
            return rates[name]._one_input(model, name, outputs)
        d = self._feedthrough(model, name, outputs)  # the first sample's: the same at every sample rate
        probe, h = self, self._one_input(model, name, outputs, d=d)
        for _ in range(self.max_rate_doublings + 1):
            finer = replace(probe, samples_per_period=2 * probe.samples_per_period,
                            learnt=ProbeLearning(periods=probe.learnt.periods))
            h_finer = finer._one_input(model, name, outputs, d=d)
            change = np.max(np.abs(h_finer - h)) / max(np.max(np.abs(h_finer)), np.finfo(float).tiny)
            if change <= self.rate_tolerance:
                rates[name] = probe
                return h
            probe, h = finer, h_finer
        raise MaceError(f"the model's response to {name} still changes by {change:.1e} when the sample rate doubles "
                        f"at {probe.samples_per_period // 2} samples per period of {self.period_s:g} s: what its "
                        "outputs read of the input at once passes through dynamics faster than that (a delay in "
                        "front of a feedthrough); compare it with a time record instead (--cost time)")

    def _feedthrough(self, model: SimulatedModel, name: str, outputs: list[str]) -> np.ndarray:
        """D[output] of ``name``: the first sample of a unit input less that of none (the state is the same)."""
        times = np.array([0.0, self.sample_time_s])
        pulse = np.asarray(model.time_response(times, {name: np.array([1.0, 0.0])}, outputs=outputs), dtype=float)
        rest = np.asarray(model.time_response(times, {name: np.zeros(2)}, outputs=outputs), dtype=float)
        return pulse[0] - rest[0]

    def _one_input(self, model: SimulatedModel, name: str, outputs: list[str], *, d: np.ndarray | None = None) -> np.ndarray:
        """``name``'s response H[line, output]; ``d``: its feedthrough (:meth:`_feedthrough`) where known."""
        n = self.samples_per_period
        # the feedthrough sees the held value at the sample, half a sample after the multisine's middle: its
        # share of the DFT is D e^(j w T / 2) / sinc(w T / 2), not D
        shift = np.exp(1j * np.pi * self.frequencies_hz * self.sample_time_s) / self._hold_gain - 1.0
        if d is None:
            d = self._feedthrough(model, name, outputs)
        while True:
            periods = self.learnt.periods
            times, values, lines = self.excitation(periods)
            y = np.asarray(model.time_response(times, {name: values}, outputs=outputs), dtype=float)
            last, before = (np.fft.rfft(y[len(y) - (m + 1) * n:len(y) - m * n], axis=0)[self.bins] for m in (0, 1))
            scale = 2.0 / (n * lines[:, None])
            h, h_before = last * scale - shift[:, None] * d, before * scale - shift[:, None] * d
            change = np.max(np.abs(h - h_before)) / max(np.max(np.abs(h)), np.finfo(float).tiny)
            if change <= self.tolerance:
                return h
            if 2 * periods > self.max_periods:
                raise MaceError(f"the model's response to a periodic input on {name} still changes by {change:.1e} "
                                f"after {periods} periods of {self.period_s:g} s: it is unstable or so lightly "
                                "damped that its free response outlasts the run")
            self.learnt.periods = 2 * periods


#: the finest grid tried is the smallest gap between lines over this (a period this many times its gaps' longest)
MAX_DIVISOR = 1000
#: the floor of every line's tolerance, in steps of the grid: the round-off of frequencies computed as k x spacing
#: (CSV '%.17g', an estimate in memory), which earlier versions held every file to
GRID_FLOOR = 1e-6


def multisine_probe(frequencies_hz: np.ndarray, *, samples_per_cycle: int = 20,
                    precision: float = 0.0) -> MultisineProbe:
    """The probe for measured frequencies on a uniform grid (as an FFT analyser gives them): the period is one
    over the grid's spacing, the sample time at least ``samples_per_cycle`` per cycle of the highest line.

    A file keeps each frequency to some digits (UFF 58: six, ``precision`` 5e-6): a line may then lie up to
    ``precision`` x f from its multiple of the spacing. The spacing is the one every line agrees with within its
    precision (one step of the grid is the smallest gap between two lines), estimated by least squares over all
    the lines; the probe runs at the lines put exactly on the grid, k x spacing (a periodic signal has no other),
    and says so in :attr:`MultisineProbe.note` when any line moved by more than round-off.

    Parameters
    ----------
    frequencies_hz : numpy.ndarray
        The lines [Hz], increasing and positive.
    samples_per_cycle : int, optional
        Samples per cycle of the highest line (the sample rate may rise later, :class:`MultisineProbe`).
    precision : float, optional
        How exactly the lines are stated, relative (the data's ``frequency_precision``; 0: exactly, to the
        round-off of k x spacing, :data:`GRID_FLOOR` of a step).

    Returns
    -------
    MultisineProbe
        Its ``frequencies_hz`` on the grid, ``given_hz`` the lines as stated.

    Raises
    ------
    MaceError
        Frequencies that are not whole multiples of one spacing within their precision (no periodic signal has
        all of them).
    """
    f = np.asarray(frequencies_hz, dtype=float)
    if f.ndim != 1 or f.size == 0 or not np.all(f > 0):
        raise MaceError("a periodic probe needs one or more positive frequencies")
    if f.size > 1 and np.any(np.diff(f) <= 0):
        raise MaceError("a periodic probe needs increasing frequencies")
    if not 0.0 <= precision < 1e-2:
        raise MaceError(f"precision {precision!r}: expected a relative precision in [0, 0.01)")
    spacing, k, several = _grid(f, precision)
    lines = k * spacing
    moved = np.abs(lines / f - 1.0)
    note = ""
    if moved.max() > 1e-12:
        note = (f"{f.size} lines from {f[0]:g} to {f[-1]:g} Hz put on the grid k x {spacing:.10g} Hz (the spacing by "
                f"least squares over every line; the largest move {moved.max():.2g} of a line"
                + (f", within the {precision:g} the data state them to" if precision else "")
                + ("; the lines' digits fit finer grids too: the coarsest was taken, the shortest period" if several
                   else "") + ")")
    period = 1.0 / spacing
    samples = int(np.ceil(samples_per_cycle * lines[-1] * period))
    samples += samples % 2  # an even period: the lines sit below the Nyquist bin
    return MultisineProbe(frequencies_hz=lines, period_s=period, samples_per_period=samples, given_hz=f, note=note)


def _grid(f: np.ndarray, precision: float) -> tuple[float, np.ndarray, bool]:
    """(spacing [Hz], each line's multiple k, whether the data fit other grids too) of lines that are whole
    multiples of one spacing within their precision; MaceError otherwise.

    Each line f_i allows the spacings [f_i - t_i, f_i + t_i] / k_i (t_i its tolerance). The smallest gaps (one
    step each) bound the spacing at first; a line whose multiple is then the only one possible narrows the
    bounds, until every line's multiple is known. Lines far above their spacing, stated to few digits, may fit
    several grids (400 Hz to six digits is 400 +- 0.002 Hz, 4 % of a 0.049 Hz step): then the coarsest grid that
    fits every line is taken (the shortest period), each of them within the data's precision of the lines. The
    spacing is the least-squares one (each line weighed by its tolerance), kept within the bounds every line
    allows."""
    if f.size == 1:
        return float(f[0]), np.ones(1, dtype=int), False
    gaps = np.diff(f)
    smallest = float(gaps.min())
    tolerance = precision * f + GRID_FLOOR * smallest
    gap_tolerance = tolerance[:-1] + tolerance[1:]
    # every gap as small as the smallest within the tolerances is one step: each bounds the spacing
    one_step = gaps - gap_tolerance <= smallest + gap_tolerance[int(np.argmin(gaps))]
    low = float(np.max((gaps - gap_tolerance)[one_step]))
    high = float(np.min((gaps + gap_tolerance)[one_step]))

    def refuse(detail: str) -> MaceError:
        return MaceError(f"frequencies from {f[0]:g} to {f[-1]:g} Hz are not whole multiples of one spacing (the "
                         f"smallest gap {smallest:g} Hz, nor any fraction of it down to {smallest / divisor:g} Hz): "
                         f"no periodic signal has all of them ({detail}; give the data on a uniform grid)")

    def fit(low: float, high: float):
        found = _multiples(f, tolerance, low, high)
        several = isinstance(found, tuple) and found[0] == "several"
        if several:  # the lowest line's multiple decides the rest: the smallest that fits every line
            fewest, most = (int(v) for v in found[1:])
            for k0 in range(fewest, min(most, fewest + 100_000) + 1):
                tried = _multiples(f, tolerance, max(low, (f[0] - tolerance[0]) / k0),
                                   min(high, (f[0] + tolerance[0]) / k0))
                if isinstance(tried, np.ndarray):
                    return tried, several
        return found, several

    # the smallest gap is one step, or a whole number of them: lines at 100, 120 and 150 Hz are multiples of 10 Hz
    # (two and three steps apart), not of 20 Hz; the coarsest grid that fits is the multisine's. A line off every
    # grid fits the n-th fraction's by chance with probability about 2 n t / gap (t its tolerance), so the fractions
    # tried stop where the chances summed over them reach 1 %: t n^2 / gap = 0.01
    most = int(min(MAX_DIVISOR, max(1.0, math.sqrt(0.01 * smallest / float(tolerance.max())))))
    divisor, first = 1, None
    while True:
        found, several = fit(low / divisor, high / divisor)
        first = found if first is None else first
        if isinstance(found, np.ndarray) and divisor > 1 and \
                np.max((f - tolerance) / found) > np.min((f + tolerance) / found):
            found = ("none", int(np.argmax((f - tolerance) / found)))  # each line has a multiple, but no one spacing
        if isinstance(found, np.ndarray) or divisor >= most:
            break
        divisor += 1
    if not isinstance(found, np.ndarray):
        found = first
        line = int(found[1]) if found[0] == "none" else 0
        detail = (f"{f[line]:g} Hz is {f[line] / (0.5 * (low + high)):.4f} steps of {smallest:g} Hz"
                  + (f", more than its precision {precision:g} allows" if precision else "")
                  if found[0] == "none" else "no one spacing fits every line within its precision")
        raise refuse(detail)
    k = found
    bounds_low = float(np.max((f - tolerance) / k))
    bounds_high = float(np.min((f + tolerance) / k))
    weight = 1.0 / tolerance**2
    spacing = float(np.sum(weight * k * f) / np.sum(weight * k * k))
    return min(max(spacing, bounds_low), bounds_high), k, several


def _multiples(f: np.ndarray, tolerance: np.ndarray, low: float, high: float) -> np.ndarray | tuple:
    """Each line's multiple of a spacing in [low, high] that puts every line within its tolerance (an int array);
    else ("none", the first line no multiple fits) or ("several", fewest, most multiples of the lowest line)."""
    known = np.zeros(f.size, dtype=bool)
    while True:
        if low > high:
            return ("none", int(np.flatnonzero(known)[-1]) if known.any() else 0)
        fewest = np.maximum(np.ceil((f - tolerance) / high), 1)
        most = np.floor((f + tolerance) / low)
        if np.any(most < fewest):
            return ("none", int(np.flatnonzero(most < fewest)[0]))
        sure = most == fewest
        if sure.all():
            return fewest.astype(int)
        if not np.any(sure & ~known):
            return ("several", fewest[0], most[0])
        known |= sure
        low = max(low, float(np.max((f - tolerance)[known] / fewest[known])))
        high = min(high, float(np.min((f + tolerance)[known] / fewest[known])))


@dataclass(frozen=True)
class ProbedFrequencyResponseCost:
    """j = w [log |G_data / G_model|, phase difference] over ``pairs`` (input, output) and the data's
    frequencies, G_model the model's response from :class:`MultisineProbe` runs at exactly those frequencies:
    measured frequency responses (a UFF 58 or CSV file of an analyser) compared with a model known only by
    simulation. ``noise``: the data's noise (:func:`~mace_fmu.updating.engine.frf_noise.frf_noise`), w its
    weights, each log error in units of its noise; None: w = 1 (eq. 4.17 as printed)."""

    data: MeasuredFrf
    probe: MultisineProbe
    pairs: tuple[tuple[str, str], ...] = ()  #: (input, output) channels compared; () means every pair
    noise: FrfNoise | None = None
    name: str = "log-frf"

    @property
    def weights(self) -> np.ndarray | None:
        """w[k, output, input] of each log error (None: 1)."""
        return None if self.noise is None else self.noise.weights

    def __post_init__(self) -> None:
        pairs = measured_pairs(self.data, self.pairs)
        given = self.probe.given_hz if self.probe.given_hz is not None else self.probe.frequencies_hz
        if given.shape != self.data.frequencies_hz.shape or not np.allclose(given, self.data.frequencies_hz,
                                                                             rtol=1e-12, atol=0.0):
            raise MaceError(f"{self.data.source}: the probe's lines are not the data's frequencies")
        object.__setattr__(self, "pairs", tuple(pairs))

    def model_response(self, model: SimulatedModel) -> np.ndarray:
        """H[k, output, input] of ``model`` at the data's frequencies, over the data's inputs and outputs."""
        return self.probe.response(model, inputs=self.data.inputs, outputs=self.data.outputs)

    def residual(self, model: SimulatedModel) -> np.ndarray:
        return log_ratio_residual(self.data, self.model_response(model), pairs=self.pairs, weights=self.weights)

    def residual_blocks(self) -> tuple[ResidualBlock, ...]:
        """One block per compared pair; with noise weights each entry's noise is 1."""
        blocks = frequency_blocks(pairs=self.pairs, frequencies_hz=self.data.frequencies_hz, weights=self.weights,
                                  outputs=self.data.outputs, inputs=self.data.inputs)
        return blocks if self.weights is None else tuple(b.with_noise(1.0) for b in blocks)

    def entry_labels(self) -> list[str]:
        return log_ratio_labels(self.data, self.pairs)
