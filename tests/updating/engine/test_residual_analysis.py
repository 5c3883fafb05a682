"""The noise of a measured FRF's logarithm, and the residual analysis that tells noise from a model's misfit.

The FRF noise is checked against its definition, by a second route: the spread of H1 estimates over 300
independent records of a known system (Monte Carlo), one input and two. The residual tests are checked on
residuals whose nature is known by construction: white noise, a filtered copy of the input (a misfit the input
drives), coloured noise independent of the input, and a phase error that is a pure delay.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

from mace_fmu.updating.engine.frf_noise import frf_noise
from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.engine.residual_blocks import frequency_blocks, time_blocks
from mace_fmu.updating.engine.residuals import analyse_residuals
from mace_fmu.updating.files import h1_estimate

SEGMENT = 256
AVERAGES = 16


def _record(rng, *, inputs: int, noise: float) -> TimeHistory:
    """White inputs of one level through well-damped filters (second order, zeta 0.3 at 0.05 and 0.12 of the
    sample rate), summed, plus white output noise; 16 half-overlapping 256-sample segments."""
    n = SEGMENT * (AVERAGES + 1) // 2
    u = rng.standard_normal((inputs, n))
    y = np.zeros(n)
    for k in range(inputs):
        b, a = scipy.signal.iirpeak([0.1, 0.24][k], Q=1.7)
        y += [1.0, 0.5][k] * scipy.signal.lfilter(b, a, u[k])
    y += noise * rng.standard_normal(n)
    return TimeHistory(np.arange(n, dtype=float), {f"u{k}": u[k] for k in range(inputs)}, {"y": y})


@pytest.mark.parametrize("inputs", [1, 2])
def test_the_coherence_s_noise_is_the_spread_of_h1_over_independent_records(inputs):
    """300 records of one system: the standard deviation of log |H1| and of its phase over the records, line by
    line, against frf_noise's (floor 1e-6: the random error and the leakage term). With two inputs the weak path
    (half the gain, off its peak) carries the strong path's error: the share term. Compared where the formula,
    first order in the error, applies (predicted standard deviation below 0.25; above it the logarithm of a noisy
    number saturates and the spread is smaller than any first-order formula says): median ratio within 15 %,
    90 % of those lines within 35 %. The leakage term, read from each record's own curvature, adds about 10 %
    on these well-damped records (the spread of a 300-sample standard deviation is 4 %)."""
    rng = np.random.default_rng(51)
    estimates, predicted = [], []
    for _ in range(300):
        frd = h1_estimate(_record(rng, inputs=inputs, noise=0.3), segment_length=SEGMENT, band_hz=(0.02, 0.45))
        assert frd.averages == AVERAGES
        estimates.append(np.log(frd.response[:, 0, :]))
        predicted.append(frf_noise(frd, floor=1e-6).standard_deviation[:, 0, :])
    logs = np.array(estimates)
    expected = np.sqrt(np.mean(np.array(predicted) ** 2, axis=0))
    first_order = expected < 0.25
    assert first_order.sum() > 20 * inputs
    for part in (logs.real, np.unwrap(logs.imag, axis=0)):
        ratio = (np.std(part, axis=0) / expected)[first_order]
        assert abs(np.median(ratio) - 1) < 0.15, np.median(ratio)
        assert np.mean(np.abs(ratio - 1) < 0.35) > 0.9, np.percentile(ratio, [5, 50, 95])


def test_frf_noise_refuses_what_it_cannot_know():
    from mace_fmu.errors import MaceError

    rng = np.random.default_rng(1)
    frd = h1_estimate(_record(rng, inputs=2, noise=0.3), segment_length=SEGMENT)
    with pytest.raises(MaceError, match="the file states 16 averages, --averages says 8"):
        frf_noise(frd, averages=8)
    bare = type(frd)(frd.frequencies_hz, frd.inputs, frd.outputs, frd.response, source="analyser.csv",
                     coherence=frd.coherence)
    with pytest.raises(MaceError, match=r"analyser.csv: the coherence's noise needs the number of averages.*--averages N"):
        frf_noise(bare)
    assert frf_noise(bare, averages=16).averages == 16
    with pytest.raises(MaceError, match="1 averages for 2 inputs"):
        frf_noise(bare, averages=1)
    without = type(frd)(frd.frequencies_hz, frd.inputs, frd.outputs, frd.response, source="a.csv")
    with pytest.raises(MaceError, match=r"a.csv: no coherence.*--weighting none"):
        frf_noise(without, averages=16)


def _time_case(residual: np.ndarray, u: np.ndarray, noise_sd: float | None):
    t = np.arange(u.size) * 0.01
    block = time_blocks(outputs=("y",), times_s=t, inputs={"u": u})[0].with_noise(noise_sd)
    return analyse_residuals(residual, (block,)).channels[0]


def test_white_noise_is_explained_a_filtered_input_is_not_and_coloured_noise_is_coloured_not_a_misfit():
    rng = np.random.default_rng(7)
    n = 8192
    u = rng.standard_normal(n)
    noise = 0.05 * rng.standard_normal(n)
    white = _time_case(noise, u, 0.05)
    assert white.explained and white.white and abs(white.rms_over_noise - 1) < 0.03
    # a lightly damped misfit driven by the input, a third of the noise's RMS: coherent with it at its resonance
    b, a = scipy.signal.iirpeak(0.08, Q=30)
    driven = scipy.signal.lfilter(b, a, u)
    misfit = _time_case(noise + 0.02 * driven / np.std(driven), u, 0.05)
    assert misfit.correlated_inputs == ("u",) and not misfit.explained
    assert 3.0 < misfit.band_hz[0] <= 4.0 <= misfit.band_hz[1] < 5.0  # about its 4 Hz peak (0.08 of Nyquist, 50 Hz)
    # coloured noise independent of the input: not white, but not a misfit of the model either
    coloured = scipy.signal.lfilter(b, a, rng.standard_normal(n))
    coloured = 0.05 * coloured / np.std(coloured)
    finding = _time_case(coloured, u, 0.05)
    assert finding.white is False and not finding.correlated_inputs and finding.explained


def test_a_phase_error_that_is_a_delay_is_read_as_that_delay():
    """Log errors of noise 1 (in noise units, weights 20) with a phase falling like 1 ms: read to 5 % (its standard error is 1.5 %)."""
    rng = np.random.default_rng(3)
    f = np.linspace(1.0, 60.0, 945)
    w = np.full(f.size, 20.0)
    phase = -2 * np.pi * f * 1e-3
    log_error = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / w + 1j * phase
    weights = w[:, None, None]
    (block,) = frequency_blocks(pairs=(("u", "y"),), frequencies_hz=f, weights=weights, outputs=("y",), inputs=("u",))
    block = block.with_noise(1.0)
    residual = np.concatenate([w * log_error.real, w * log_error.imag])
    (finding,) = analyse_residuals(residual, (block,)).channels
    assert finding.delay_s == pytest.approx(1e-3, rel=0.05) and not finding.explained
    clean = np.concatenate([w * (log_error.real), w * (log_error.imag - phase)])
    (finding,) = analyse_residuals(clean, (block,)).channels
    assert finding.delay_s is None and finding.explained
