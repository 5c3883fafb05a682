"""A periodic excitation in a record (a multisine, a stepped or periodic chirp): its lines, their fundamental, and
the H1 segments that put every line on a bin.

An H1 estimate of a periodic excitation is exact at its lines when each segment holds a whole number of periods:
the lines then fall on the segment's bins and do not leak (a rectangular window is enough), and between the
lines the inputs hold nothing (the estimate is taken at the lines only). A segment of m periods is m fs / f0
samples, f0 the lines' fundamental: a whole number of samples for some m when the generator and the data
acquisition share a clock (fs / f0 rational), within :data:`BIN_TOLERANCE` of a bin at the highest line
otherwise. The lines need not be neighbours: 100, 120 and 150 Hz are multiples of 10 Hz, not of their
smallest gap.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.measured import TimeHistory

#: a line stands this many times above the spectrum's median about it (a white noise's periodogram peaks at
#: about ln(N) times its mean: 14 for a million bins)
LINE_RATIO = 1e3
#: a line is at least this share of the strongest line's power (lower peaks are round-off, 60 dB down)
LINE_FLOOR = 1e-6
#: the lines hold at least this share of the inputs' power (else the excitation is broadband, lines or not)
LINE_SHARE = 0.5
#: the largest distance of a line from a segment's bin it is put on [bins]: a rectangular window's leakage there
#: is 1 - sinc(0.05) = 0.4 % of the line, the same on the data and on the model's response
BIN_TOLERANCE = 0.05
#: a segment whose lines fall this close to bins holds whole periods exactly (to the lines' round-off)
EXACT = 1e-3
#: a periodic H1 needs at least this many segments (the noise of its lines, :func:`log_h1_weights`)
MIN_SEGMENTS = 4


@dataclass(frozen=True)
class PeriodicExcitation:
    """The lines of a record's inputs and their fundamental."""

    lines_hz: np.ndarray  #: the lines found [Hz]: ``multiples`` x ``fundamental_hz``
    multiples: np.ndarray  #: each line's multiple of the fundamental
    fundamental_hz: float  #: f0 [Hz]
    sample_time_s: float  #: of the record
    samples: int  #: of the record

    @property
    def period_samples(self) -> float:
        """One period in samples, fs / f0 (not a whole number in general)."""
        return 1.0 / (self.fundamental_hz * self.sample_time_s)

    def describe(self) -> str:
        """'3 lines from 100 to 150 Hz, multiples of 10 Hz (period 0.1 s, 100 samples)'."""
        return (f"{self.lines_hz.size} line{'s' if self.lines_hz.size != 1 else ''} from {self.lines_hz[0]:.6g} to "
                f"{self.lines_hz[-1]:.6g} Hz, multiples of {self.fundamental_hz:.6g} Hz (period "
                f"{1 / self.fundamental_hz:.6g} s, {self.period_samples:.6g} samples)")

    def bin_offset(self, segment_length: int) -> float:
        """The largest distance [bins] of a line from the nearest bin of ``segment_length``-sample segments."""
        k = self.multiples * self.fundamental_hz * segment_length * self.sample_time_s
        return float(np.max(np.abs(k - np.rint(k))))

    def fits(self, segment_length: int) -> bool:
        """Every line within :data:`BIN_TOLERANCE` of a bin of ``segment_length``-sample segments."""
        return self.bin_offset(segment_length) <= BIN_TOLERANCE

    def segment_lengths(self, *, longest: int) -> list[int]:
        """Every segment length [samples] up to ``longest`` that holds a whole number of periods (to
        :data:`BIN_TOLERANCE` of a bin), shortest first."""
        out = []
        for m in range(1, int(longest / self.period_samples) + 1):
            length = int(round(m * self.period_samples))
            if 2 <= length <= longest and self.fits(length) and length not in out:
                out.append(length)
        return out

    def segment(self, *, given_s: float | None = None, where: str = "") -> int:
        """The H1 segment [samples]: ``given_s`` when every line falls on its bins, else the shortest of whole
        periods that leaves :data:`MIN_SEGMENTS` segments in the record (one whose lines fall on bins to
        :data:`EXACT` first: the generator's clock the data acquisition's); a MaceError that says which lengths
        would do when none can."""
        dt = self.sample_time_s
        longest = self.samples // MIN_SEGMENTS
        if given_s is not None:
            length = int(round(given_s / dt))
            if self.fits(length):
                return length
            would = self.segment_lengths(longest=max(longest, length))[:6]
            k = self.multiples * self.fundamental_hz * length * dt
            worst = int(np.argmax(np.abs(k - np.rint(k))))
            raise MaceError(f"{where}--segment-s {given_s:g}: the inputs are periodic ({self.describe()}), and the "
                            f"{self.lines_hz[worst]:.6g} Hz line falls {abs(k[worst] - np.rint(k[worst])):.2f} bins "
                            f"from the segments' bins; segments of whole periods put every line on a bin: "
                            + (", ".join(f"{n * dt:.6g} s" for n in would) + " ..." if would else
                               f"none of up to {longest * dt:.6g} s holds one at this sample rate")
                            + " (or leave --segment-s out to take the shortest)")
        fitting = self.segment_lengths(longest=longest)
        exact = [n for n in fitting if self.bin_offset(n) <= EXACT]
        if fitting:
            return (exact or fitting)[0]
        beyond = self.segment_lengths(longest=self.samples)
        if beyond:
            raise MaceError(f"{where}the inputs are periodic ({self.describe()}): segments of "
                            f"{beyond[0] * dt:.6g} s ({beyond[0]} samples) put every line on a bin, but the record "
                            f"({self.samples} samples) holds fewer than {MIN_SEGMENTS} of them to average: record at "
                            f"least {MIN_SEGMENTS * beyond[0] * dt:.6g} s")
        m = max(1, int(round(longest / self.period_samples)))
        raise MaceError(f"{where}the inputs are periodic ({self.describe()}), but no segment of a whole number of "
                        f"samples holds a whole number of periods (to {BIN_TOLERANCE:g} of a bin at the "
                        f"{self.lines_hz[-1]:.6g} Hz line; e.g. {m} periods are {m * self.period_samples:.4f} "
                        f"samples): segments of m / {self.fundamental_hz:.6g} s would; record at a sample rate that "
                        "is a multiple of the fundamental, or compare with --cost time")


def periodic_excitation(history: TimeHistory) -> PeriodicExcitation | None:
    """The lines of ``history``'s inputs and their fundamental, when the inputs are periodic: isolated lines
    (each :data:`LINE_RATIO` above the spectrum about it) holding :data:`LINE_SHARE` of the inputs' power; None
    for a broadband excitation."""
    n = history.times_s.size
    dt = history.sample_time_s
    if n < 64 or not history.inputs:
        return None
    window = np.hanning(n)
    power = sum(np.abs(np.fft.rfft((np.asarray(u) - np.mean(u)) * window)) ** 2 for u in history.inputs.values())
    power = np.asarray(power, dtype=float)
    if not np.any(power > 0):
        return None
    power[0] = 0.0
    around = _local_median(power, half_width=32)
    peaks = np.flatnonzero((power[1:-1] > power[:-2]) & (power[1:-1] >= power[2:])) + 1
    peaks = peaks[peaks > 3]  # the mean's own main lobe (and a drift) is no line
    # isolated, and not the round-off between lines: within LINE_FLOOR of the strongest
    peaks = peaks[(power[peaks] > LINE_RATIO * around[peaks]) & (power[peaks] > LINE_FLOOR * power.max())]
    if peaks.size == 0:
        return None
    in_lines = sum(float(power[max(k - 3, 0):k + 4].sum()) for k in peaks)
    if in_lines < LINE_SHARE * float(power.sum()):
        return None
    lines = np.array([_refined(power, k) for k in peaks]) / (n * dt)
    found = _fundamental(lines, resolution_hz=1.0 / (n * dt))
    if found is None:
        return None
    fundamental, multiples = found
    excitation = PeriodicExcitation(lines_hz=lines, multiples=multiples, fundamental_hz=fundamental, sample_time_s=dt,
                                    samples=n)
    # a generator on the data acquisition's clock: m periods are L samples exactly, and f0 is m / (L dt), not the
    # lines' estimate (good to a tenth of the record's resolution)
    for m in range(1, int(n / excitation.period_samples) + 1):
        length = int(round(m * excitation.period_samples))
        if excitation.bin_offset(length) <= EXACT:
            f0 = m / (length * dt)
            return PeriodicExcitation(lines_hz=multiples * f0, multiples=multiples, fundamental_hz=f0,
                                      sample_time_s=dt, samples=n)
    return excitation


def _local_median(power: np.ndarray, *, half_width: int) -> np.ndarray:
    """The median of ``power`` over +-``half_width`` bins about each bin, its own main lobe (+-3) left out."""
    import scipy.ndimage

    footprint = np.ones(2 * half_width + 1, dtype=bool)
    footprint[half_width - 3:half_width + 4] = False
    return scipy.ndimage.median_filter(power, footprint=footprint, mode="nearest")


def _refined(power: np.ndarray, k: int) -> float:
    """The peak's position [bins] from a parabola through the log power of its bin and its neighbours."""
    if k <= 0 or k >= power.size - 1:
        return float(k)
    a, b, c = np.log(np.maximum(power[k - 1:k + 2], np.finfo(float).tiny))
    denominator = a - 2 * b + c
    return float(k + 0.5 * (a - c) / denominator) if denominator < 0 else float(k)


def _fundamental(lines: np.ndarray, *, resolution_hz: float) -> tuple[float, np.ndarray] | None:
    """(f0, each line's multiple): the largest f0 of which every line is a multiple to a quarter of the record's
    resolution, f0 the lowest line over a whole number (least squares over all the lines); None when only f0
    below four resolutions would do (the record does not resolve the lines' grid)."""
    tolerance = 0.25 * resolution_hz
    for divisor in range(1, int(lines[0] / (4 * resolution_hz)) + 2):
        f0 = lines[0] / divisor
        if f0 < 4 * resolution_hz:
            return None
        k = np.rint(lines / f0)
        if np.all(k >= 1) and np.all(np.abs(lines - k * f0) <= tolerance * (1.0 + k / divisor)):
            f0 = float(np.sum(k * lines) / np.sum(k * k))
            return f0, k.astype(int)
    return None
