"""A periodic excitation's H1: the lines found in the record, their fundamental (not their
smallest gap), segments of whole periods that put every line on a bin, and a refusal that says which segment
lengths would do only when the one asked for cannot."""

from __future__ import annotations

import numpy as np
import pytest

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.engine.periodic import periodic_excitation
from mace_fmu.updating.engine.simulated_frf import H1Estimator

FIR = np.array([0.5, 0.3, 0.2])  # y[k] = 0.5 u[k] + 0.3 u[k-1] + 0.2 u[k-2]


def _multisine(lines_hz, *, fs: float, seconds: float, noise: float = 0.0, seed: int = 48) -> TimeHistory:
    """A periodic input at ``lines_hz`` (random phases) plus white noise, through :data:`FIR` taken circularly
    over the record (its steady state: every sample of the output sees the input's past)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(seconds * fs))) / fs
    u = sum(np.cos(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi)) for f in lines_hz)
    u = u + noise * rng.standard_normal(t.size)
    y = sum(c * np.roll(u, k) for k, c in enumerate(FIR))
    return TimeHistory(t, {"force": u}, {"acc": y})


def test_a_10_hz_multisine_s_lines_at_100_120_150_hz_are_found_and_put_on_bins():
    """A shaker record: lines at 100, 120 and 150 Hz of a 10 Hz multisine, broadband force noise to Nyquist.
    Their fundamental is 10 Hz (the smallest gap is 20); 100-sample segments (0.1 s, one period) put each on a
    bin, and the H1 there is the system's exact response."""
    record = _multisine([100.0, 120.0, 150.0], fs=1000.0, seconds=20.0, noise=0.02)
    found = periodic_excitation(record)
    assert found is not None and found.fundamental_hz == pytest.approx(10.0, rel=1e-6)
    assert found.multiples.tolist() == [10, 12, 15] and found.segment() == 100
    clean = _multisine([100.0, 120.0, 150.0], fs=1000.0, seconds=20.0)
    estimate = H1Estimator(segment_length=100, window="boxcar", overlap=0.0, lines_hz=tuple(found.lines_hz))(clean)
    np.testing.assert_allclose(estimate.frequencies_hz, [100.0, 120.0, 150.0])
    z = np.exp(-2j * np.pi * estimate.frequencies_hz / 1000.0)
    np.testing.assert_allclose(estimate.response[:, 0, 0], FIR[0] + FIR[1] * z + FIR[2] * z**2, rtol=1e-9)


def test_a_period_of_no_whole_number_of_samples_takes_the_whole_periods_that_are():
    """7 Hz at 1 kHz: a period is 142.857 samples; seven of them are 1000 samples exactly."""
    record = _multisine([21.0, 35.0, 56.0], fs=1000.0, seconds=30.0)
    found = periodic_excitation(record)
    assert found.fundamental_hz == pytest.approx(7.0, rel=1e-6) and found.segment() == 1000
    assert found.bin_offset(1000) < 1e-6


def test_broadband_noise_and_a_band_limited_noise_are_not_periodic():
    rng = np.random.default_rng(1)
    t = np.arange(20000) / 1000.0
    white = rng.standard_normal(t.size)
    spectrum = np.fft.rfft(rng.standard_normal(t.size))
    spectrum[np.fft.rfftfreq(t.size, 1e-3) > 60.0] = 0.0
    for u in (white, np.fft.irfft(spectrum, t.size)):
        assert periodic_excitation(TimeHistory(t, {"force": u}, {"acc": u})) is None


def test_a_segment_that_leaves_the_lines_between_bins_is_refused_with_the_lengths_that_would_do():
    found = periodic_excitation(_multisine([100.0, 120.0, 150.0], fs=1000.0, seconds=20.0))
    assert found.segment(given_s=2.0) == 2000  # 20 periods: the lines on bins, taken as asked
    with pytest.raises(MaceError) as refused:
        found.segment(given_s=0.25, where="rec.lvm: ")
    assert str(refused.value) == (
        "rec.lvm: --segment-s 0.25: the inputs are periodic (3 lines from 100 to 150 Hz, multiples of 10 Hz (period "
        "0.1 s, 100 samples)), and the 150 Hz line falls 0.50 bins from the segments' bins; segments of whole periods "
        "put every line on a bin: 0.1 s, 0.2 s, 0.3 s, 0.4 s, 0.5 s, 0.6 s ... (or leave --segment-s out to take the "
        "shortest)")


def test_a_record_too_short_for_the_segments_that_fit_says_how_long_it_must_be():
    """3 Hz lines to 399 Hz at 1 kHz, 3 s: one period (333 samples) or two (667) leave the 399 Hz line 0.13 bins off a
    bin; three periods (1000 samples) fit exactly, and the record holds three of them, not four."""
    found = periodic_excitation(_multisine(np.arange(10, 134) * 3.0, fs=1000.0, seconds=3.0))
    expected = (r"^x: the inputs are periodic \(124 lines from 30 to 399 Hz, multiples of 3 Hz .*\): segments of 1 s "
                r"\(1000 samples\) put every line on a bin, but the record \(3000 samples\) holds fewer than 4 of them "
                r"to average: record at least 4 s$")
    with pytest.raises(MaceError, match=expected):
        found.segment(where="x: ")
