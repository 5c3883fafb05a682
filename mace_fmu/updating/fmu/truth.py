"""A test article whose truth is known (the proof of an FMU update): the 1-g FMU of the bundled deck measured through files.

The bundled deck holds the updated moduli of Table 4.4 and the FMU the updated delays of Tables
4.5 and 4.6: that FMU, simulated once, is the "test article". Its measured data are its response
to band-limited white noise on the four gimbal inputs (the thesis's update inputs), recorded at the
five rate gyros with white output noise of a given fraction of each gyro's RMS, and written to a
CSV time history and a UFF 58 (and CSV) frequency response, as a user's data would arrive. The
model being updated is another FMU, exported at other moduli (the pre-update ones: a full re-solve),
which its parameter route must bring to the truth: the truth is never read back except from the
files, and never the updated FMU's own route.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.measured import MeasuredFrf, TimeHistory
from mace_fmu.updating.engine.simulated_frf import H1Estimator
from mace_fmu.updating.fmu.model import FmuFamily, FmuModel
from mace_fmu.util.atomic import output_folder

GIMBALS = ("gimbal_primary_x", "gimbal_primary_z", "gimbal_secondary_x", "gimbal_secondary_z")
RATE_GYROS = ("gyro_payload_x", "gyro_payload_z", "gyro_bus_x", "gyro_bus_y", "gyro_bus_z")
BAND_HZ = (0.5, 60.0)  #: thesis 4.5's update band
#: the four gimbal-to-payload-gyro transfer functions checked in dB: the collocated primary gimbal and the
#: secondary gimbal (disturbance) to the payload gyro (performance), thesis Figures 4.15 and 4.16
CHECKED_FRFS = (("gimbal_primary_x", "gyro_payload_x"), ("gimbal_primary_z", "gyro_payload_z"),
                ("gimbal_secondary_x", "gyro_payload_x"), ("gimbal_secondary_z", "gyro_payload_z"))
SERVO_DELAYS = ("delay_gimbal_primary_x", "delay_gimbal_primary_z", "delay_gimbal_secondary_x",
                "delay_gimbal_secondary_z")
GYRO_DELAYS = ("delay_gyro_payload_x", "delay_gyro_payload_z", "delay_gyro_bus_x", "delay_gyro_bus_y",
               "delay_gyro_bus_z")


def band_limited_noise(*, samples: int, step_s: float, band_hz: tuple[float, float], seed: int) -> np.ndarray:
    """Gaussian white noise [V, unit RMS] with every frequency outside ``band_hz`` [Hz] removed (FFT mask)."""
    rng = np.random.default_rng(seed)
    spectrum = np.fft.rfft(rng.standard_normal(samples))
    f = np.fft.rfftfreq(samples, step_s)
    spectrum[(f < band_hz[0]) | (f > band_hz[1])] = 0.0
    x = np.fft.irfft(spectrum, samples)
    return x / np.sqrt(np.mean(x**2))


@dataclass(frozen=True)
class TestArticle:
    """The measured data of the truth FMU and where they were written."""

    history: TimeHistory  #: inputs [V] and noisy rate-gyro outputs [V]
    frequency_response: MeasuredFrf  #: H1 of ``history`` within the band
    files: tuple[Path, ...]  #: time history (CSV), frequency response (UFF 58, CSV)
    noise_fraction: float
    seed: int


def measure_test_article(family: FmuFamily, *, out_dir: str | os.PathLike, seconds: float = 20.0,
                         step_s: float = 0.002, noise_fraction: float = 0.02, seed: int = 2026,
                         estimator: H1Estimator | None = None) -> TestArticle:
    """Simulate the truth (``family`` at its own start values) once, add output noise, write the files.

    Inputs: band-limited (0.5-60 Hz) white noise of 1 V RMS on the four gimbals, independent seeds;
    outputs: the five rate gyros plus white noise of ``noise_fraction`` of each one's RMS.
    """
    from mace_fmu.updating.files import write_frequency_response, write_time_history

    n = int(round(seconds / step_s)) + 1
    t = np.arange(n) * step_s
    inputs = {name: band_limited_noise(samples=n, step_s=step_s, band_hz=BAND_HZ, seed=seed + k)
              for k, name in enumerate(GIMBALS)}
    y = family.full({}).time_response(t, inputs, outputs=RATE_GYROS)
    rng = np.random.default_rng(seed + 100)
    y = y + noise_fraction * np.sqrt(np.mean(y**2, axis=0)) * rng.standard_normal(y.shape)
    history = TimeHistory(t, inputs, {o: y[:, k] for k, o in enumerate(RATE_GYROS)}, source="test article")
    estimator = estimator or default_estimator(step_s=step_s)
    frd = estimator(history)
    out = output_folder(out_dir)  # one line naming it, not a traceback, if it cannot be made
    files = (write_time_history(history, out / "test_article_time.csv"),
             write_frequency_response(frd, out / "test_article_frf.uff"),
             write_frequency_response(frd, out / "test_article_frf.csv"))
    return TestArticle(history=history, frequency_response=frd, files=files, noise_fraction=noise_fraction, seed=seed)


def default_estimator(*, step_s: float, segment_s: float = 2.0) -> H1Estimator:
    """H1 over ``segment_s`` [s] Hann segments, half overlapping, within the update band."""
    return H1Estimator(segment_length=int(round(segment_s / step_s)), band_hz=BAND_HZ)


@dataclass(frozen=True)
class FrfComparison:
    """Largest |dB| difference of each checked transfer function over the band, away from its zeros."""

    max_db: Mapping[tuple[str, str], float]
    bins_used: Mapping[tuple[str, str], int]
    bins_total: int


def compare_frfs(family: FmuFamily, *, truth: Mapping[str, float], updated: Mapping[str, float] | FmuModel,
                 history: TimeHistory, estimator: H1Estimator,
                 pairs: Sequence[tuple[str, str]] = CHECKED_FRFS, zero_depth_db: float = 10.0) -> FrfComparison:
    """Noise-free H1 of the FMU at ``truth`` and at ``updated`` (values of the same FMU, or another FMU's
    model) with the same inputs and estimator, compared in dB.

    "Away from the zeros": bins where the truth's magnitude is more than ``zero_depth_db`` below its
    median over +-2 Hz are left out (an antiresonance's depth is not a model property the update
    can be asked to match to 0.5 dB).
    """
    outs = sorted({o for _, o in pairs})
    h = []
    for model in (family.full(truth), updated if isinstance(updated, FmuModel) else family.full(updated)):
        y = model.time_response(history.times_s, history.inputs, outputs=outs)
        h.append(estimator(TimeHistory(history.times_s, history.inputs, {o: y[:, k] for k, o in enumerate(outs)})))
    f = h[0].frequencies_hz
    max_db, used = {}, {}
    for i, o in pairs:
        a = h[0].response[:, h[0].outputs.index(o), h[0].inputs.index(i)]
        b = h[1].response[:, h[1].outputs.index(o), h[1].inputs.index(i)]
        mag = np.abs(a)
        local = np.array([np.median(mag[np.abs(f - fk) <= 2.0]) for fk in f])
        keep = 20 * np.log10(mag / local) > -zero_depth_db
        d = np.abs(20 * np.log10(np.abs(b[keep]) / mag[keep]))
        max_db[(i, o)] = float(np.max(d))
        used[(i, o)] = int(keep.sum())
    return FrfComparison(max_db=max_db, bins_used=used, bins_total=int(f.size))


def perturbed(values: Mapping[str, float], *, factors: Sequence[float]) -> dict[str, float]:
    """``values`` each times its factor (in order): a start away from the truth."""
    if len(factors) != len(values):
        raise MaceError(f"{len(factors)} factors for {len(values)} values")
    return {n: v * f for (n, v), f in zip(values.items(), factors)}
