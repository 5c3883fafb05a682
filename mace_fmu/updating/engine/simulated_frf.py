"""The log-FRF cost (thesis eq. 4.5, 4.17) of a model known only by simulation, e.g. an FMU.

The model is driven by the measured inputs and its response goes through the same H1 estimator
as the measured data: the estimator's own errors (leakage, window, the finite number of
averages) are then alike on both sides and cancel in the ratio G_data / G_model, so only
the model's error and the measurement noise remain.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.signal as signal

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.h1 import h1_estimate
from mace_fmu.updating.engine.residual_blocks import ResidualBlock, frequency_blocks
from mace_fmu.updating.engine.measured import MeasuredFrf, TimeHistory
from mace_fmu.updating.engine.models import SimulatedModel


@dataclass(frozen=True)
class H1Estimator:
    """The settings of :func:`~mace_fmu.updating.files.h1_estimate` (H1 = S_yu S_uu^-1, all inputs at once):
    ``segment_length`` samples per segment, ``window``, ``overlap`` (fraction), ``band_hz`` [Hz] (None: every bin
    above 0 Hz), ``lines_hz`` (None: every bin; else a periodic excitation's lines, each on a bin). One object for
    the measured data and the model's simulated response alike."""

    segment_length: int
    window: str = "hann"
    overlap: float = 0.5
    band_hz: tuple[float, float] | None = None
    lines_hz: tuple[float, ...] | None = None

    def __call__(self, history: TimeHistory) -> MeasuredFrf:
        """The frequency response estimated from ``history`` (inputs and outputs in their units)."""
        return h1_estimate(history, segment_length=self.segment_length, window=self.window, overlap=self.overlap,
                           band_hz=self.band_hz, lines_hz=self.lines_hz)


def log_h1_weights(history: TimeHistory, estimate: MeasuredFrf, *, segment_length: int,
                   window: str = "hann", overlap: float = 0.5) -> np.ndarray:
    """w[k, output, input] = 1 / (standard deviation of log H1): |H| / sqrt(S_nn [S_uu^-1]_ii / n_avg).

    S_nn = S_yy - S_yu S_uu^-1 S_uy is the part of an output's spectrum no input explains (the
    noise), n_avg the number of Welch segments (Bendat and Piersol, random errors of
    multiple-input frequency responses). Bins where noise buries the response weigh little.
    """
    fs = 1.0 / history.sample_time_s
    kw = dict(fs=fs, window=window, nperseg=segment_length, noverlap=int(round(overlap * segment_length)),
              detrend="constant")
    f = signal.csd(history.inputs[estimate.inputs[0]], history.inputs[estimate.inputs[0]], **kw)[0]
    keep = np.isin(np.round(f, 9), np.round(estimate.frequencies_hz, 9))
    if keep.sum() != estimate.frequencies_hz.size:
        raise MaceError(f"{history.source}: the estimate's frequencies are not this estimator's bins")
    n_in = len(estimate.inputs)
    suu = np.empty((keep.sum(), n_in, n_in), complex)
    for i, a in enumerate(estimate.inputs):
        for j, b in enumerate(estimate.inputs):
            suu[:, j, i] = signal.csd(history.inputs[a], history.inputs[b], **kw)[1][keep]
    inv_diag = np.real(np.diagonal(np.linalg.inv(suu), axis1=1, axis2=2))  # (k, input)
    step = segment_length - int(round(overlap * segment_length))
    n_avg = 1 + (len(history.times_s) - segment_length) // step
    w = np.empty(estimate.response.shape)
    for o, name in enumerate(estimate.outputs):
        syy = np.real(signal.csd(history.outputs[name], history.outputs[name], **kw)[1][keep])
        h = estimate.response[:, o, :]  # (k, input)
        explained = np.real(np.einsum("ki,kij,kj->k", h, suu, h.conj()))  # H S_uu H^H
        snn = np.maximum(syy - explained, 1e-12 * syy)
        w[:, o, :] = np.abs(h) / np.sqrt(snn[:, None] * inv_diag / n_avg)
    return w


@dataclass(frozen=True)
class SimulatedFrequencyResponseCost:
    """j = [log |G_data / G_model|, phase difference] over ``pairs`` (input, output) and the data's
    frequencies, G_model the H1 estimate of the model's simulated response to ``excitation``'s inputs.

    ``data`` is usually ``estimator(excitation)`` itself; data from elsewhere (e.g. a UFF file) at
    other frequencies are compared with the model's estimate interpolated to them. The model is driven from
    the excitation's first sample, at rest; its estimate is taken from ``compare_from_s`` [s] on, as the
    data's (a window of a record: the structure in the state the record's earlier part left it in).
    """

    data: MeasuredFrf
    excitation: TimeHistory  #: the measured inputs the model is driven with
    estimator: H1Estimator
    pairs: tuple[tuple[str, str], ...] = ()  #: (input, output) channels compared; () means every pair
    weights: np.ndarray | None = None  #: w[k, output, input] multiplying each log error (None: 1, eq. 4.17)
    name: str = "log-frf"
    compare_from_s: float = 0.0  #: the model's response before this time [s] is not estimated from

    def __post_init__(self) -> None:
        pairs = measured_pairs(self.data, self.pairs)
        missing = [i for i in self.data.inputs if i not in self.excitation.inputs]
        if missing:
            raise MaceError(f"{self.excitation.source}: the excitation lacks the measured input(s) {missing}")
        object.__setattr__(self, "pairs", tuple(pairs))

    def model_response(self, model: SimulatedModel) -> MeasuredFrf:
        """The H1 estimate of ``model``'s response to the excitation, at the estimator's bins."""
        outs = sorted({o for _, o in self.pairs}, key=self.data.outputs.index)
        y = model.time_response(self.excitation.times_s, self.excitation.inputs, outputs=outs)
        t = self.excitation.times_s
        first = int(np.searchsorted(t, self.compare_from_s - 1e-9 * self.excitation.sample_time_s))
        simulated = TimeHistory(t[first:], {k: v[first:] for k, v in self.excitation.inputs.items()},
                                {o: y[first:, k] for k, o in enumerate(outs)}, source="the model's simulated response")
        return self.estimator(simulated)

    def residual(self, model: SimulatedModel) -> np.ndarray:
        est = self.model_response(model)
        f = self.data.frequencies_hz
        same = est.frequencies_hz.shape == f.shape and np.allclose(est.frequencies_hz, f, rtol=1e-9, atol=0.0)
        if not same and (f[0] < est.frequencies_hz[0] or f[-1] > est.frequencies_hz[-1]):
            raise MaceError(f"{self.data.source}: data from {f[0]:g} to {f[-1]:g} Hz, but the estimate of the model's "
                            f"response covers {est.frequencies_hz[0]:g} to {est.frequencies_hz[-1]:g} Hz only")
        h = np.empty_like(self.data.response)
        for k, o in enumerate(self.data.outputs):
            for j, i in enumerate(self.data.inputs):
                if (i, o) not in self.pairs:
                    continue
                g = est.response[:, est.outputs.index(o), est.inputs.index(i)]
                h[:, k, j] = g if same else np.interp(f, est.frequencies_hz, g.real) + 1j * np.interp(
                    f, est.frequencies_hz, g.imag)
        return log_ratio_residual(self.data, h, pairs=self.pairs, weights=self.weights)

    def residual_blocks(self) -> tuple[ResidualBlock, ...]:
        """One block per compared pair; with noise weights each entry's noise is 1."""
        blocks = frequency_blocks(pairs=self.pairs, frequencies_hz=self.data.frequencies_hz, weights=self.weights,
                                  outputs=self.data.outputs, inputs=self.data.inputs)
        return blocks if self.weights is None else tuple(b.with_noise(1.0) for b in blocks)

    def entry_labels(self) -> list[str]:
        return log_ratio_labels(self.data, self.pairs)


def measured_pairs(data: MeasuredFrf, pairs: Sequence[tuple[str, str]]) -> tuple[tuple[str, str], ...]:
    """``pairs`` (input, output), every pair of the data where empty; a MaceError for a pair without a
    measured response."""
    chosen = tuple(pairs) or tuple((i, o) for i in data.inputs for o in data.outputs)
    bad = [p for p in chosen if p[0] not in data.inputs or p[1] not in data.outputs]
    if bad:
        raise MaceError(f"{data.source}: no measured response for {bad} (inputs {data.inputs}, outputs "
                        f"{data.outputs})")
    return chosen


def log_ratio_residual(data: MeasuredFrf, model_response: np.ndarray, *,
                       pairs: Sequence[tuple[str, str]], weights: np.ndarray | None) -> np.ndarray:
    """j = w [Re log(G_data / G_model), Im log(G_data / G_model)] over ``pairs`` (input, output) and the data's
    frequencies (thesis eq. 4.17): log magnitude ratios, then phase differences [rad]. ``model_response``:
    H[k, output, input] at the data's frequencies, outputs and inputs; ``weights`` likewise (None: 1)."""
    e = []
    for i, o in pairs:
        k, j = data.outputs.index(o), data.inputs.index(i)
        w = 1.0 if weights is None else weights[:, k, j]
        with np.errstate(divide="ignore", invalid="ignore"):
            e.append(w * np.log(data.response[:, k, j] / model_response[:, k, j]))
    e = np.concatenate(e)
    if not np.all(np.isfinite(e)):
        raise MaceError(f"{data.source}: the model's response is zero or infinite where data exist; the log "
                        "cost needs both nonzero")
    return np.concatenate([e.real, e.imag])


def log_ratio_labels(data: MeasuredFrf, pairs: Sequence[tuple[str, str]]) -> list[str]:
    """What each entry of :func:`log_ratio_residual` is."""
    one = [f"{i} -> {o} {f:.4g} Hz" for i, o in pairs for f in data.frequencies_hz]
    return [f"log|G| {x}" for x in one] + [f"phase {x}" for x in one]


def principal_pairs(inputs: Sequence[str], outputs: Sequence[str]) -> tuple[tuple[str, str], ...]:
    """Input-output pairs about the same axis (an input and output name ending in the same _x/_y/_z), and
    X inputs also to Y outputs: thesis 4.5's gimbal-to-rate-gyro transfer functions."""
    def axis(name: str) -> str:
        return name.rsplit("_", 1)[-1]

    return tuple((i, o) for i in inputs for o in outputs
                 if axis(i) == axis(o) or (axis(i) == "x" and axis(o) == "y"))
