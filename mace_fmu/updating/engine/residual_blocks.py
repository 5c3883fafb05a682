"""What a cost's residual vector is made of: blocks, one per measured channel, each a signal over time or
frequency that the residual analysis (:mod:`~mace_fmu.updating.engine.residuals`) and the residuals'
own covariance (:mod:`~mace_fmu.updating.engine.uncertainty`) read.

A cost that states its blocks (``residual_blocks()``) gets a verdict on its residuals: whether they are
noise or a model's misfit. A time block is one output's error samples; a frequency block is one
input-output pair's log errors, its real rows (log magnitude) and imaginary rows (phase) taken together.
Every block knows its rows in the cost's vector, so the same slices cut the Jacobian's rows.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Literal, Mapping

import numpy as np

Domain = Literal["time", "frequency"]


@dataclass(frozen=True)
class ResidualBlock:
    """One measured channel's share of a residual vector."""

    name: str  #: the output ("gyro_bus_y"), a test's output ("test.csv: gyro_bus_y") or a pair ("u -> y")
    domain: Domain
    rows: np.ndarray  #: indices into the residual vector: the samples (time), the log magnitudes (frequency)
    axis: np.ndarray  #: times [s] or frequencies [Hz], one per row
    #: frequency blocks: the rows of the phase differences, one per line (same order as ``rows``)
    imaginary_rows: np.ndarray | None = None
    #: time blocks: the measured inputs [their units] the error is correlated with (the ``resid`` test)
    inputs: Mapping[str, np.ndarray] = field(default_factory=dict)
    #: the noise's standard deviation per residual in the vector's units (None: not known)
    noise_sd: float | None = None
    scale: float = 1.0  #: the factor the cost put on this block (a test's weight among several tests)
    group: str = ""  #: the test (record or file) the block belongs to: blocks of one test share its noise
    #: frequency blocks: the weight the cost put on each line (the entries are weight x log error; None: 1)
    line_weights: np.ndarray | None = None

    def values(self, vector: np.ndarray) -> np.ndarray:
        """This block's entries of ``vector`` (a residual, or a Jacobian's rows): real samples for a time
        block, complex log errors (magnitude + j phase) for a frequency block; first axis the block's axis."""
        v = np.asarray(vector)
        if self.imaginary_rows is None:
            return v[self.rows]
        return v[self.rows] + 1j * v[self.imaginary_rows]

    def shifted(self, offset: int, *, prefix: str = "", scale: float = 1.0) -> ResidualBlock:
        """The same block inside a longer vector that starts ``offset`` rows earlier, its name prefixed and its
        entries (and noise) multiplied by ``scale``."""
        return replace(self, name=f"{prefix}{self.name}", rows=self.rows + offset, group=f"{prefix}{self.group}",
                       imaginary_rows=None if self.imaginary_rows is None else self.imaginary_rows + offset,
                       noise_sd=None if self.noise_sd is None else self.noise_sd * scale, scale=self.scale * scale)

    def with_noise(self, noise_sd: float | None) -> ResidualBlock:
        """The same block with its noise's standard deviation per residual (in the block's own units, before
        ``scale``)."""
        return replace(self, noise_sd=None if noise_sd is None else noise_sd * self.scale)


def time_blocks(*, outputs: tuple[str, ...], times_s: np.ndarray, inputs: Mapping[str, np.ndarray],
                offset: int = 0) -> tuple[ResidualBlock, ...]:
    """The blocks of a time cost stacked output after output, ``len(times_s)`` samples each."""
    n = len(times_s)
    return tuple(ResidualBlock(name=o, domain="time", rows=offset + np.arange(k * n, (k + 1) * n), axis=times_s,
                               inputs=inputs) for k, o in enumerate(outputs))


def frequency_blocks(*, pairs: tuple[tuple[str, str], ...], frequencies_hz: np.ndarray, offset: int = 0,
                     weights: np.ndarray | None = None, outputs: tuple[str, ...] = (),
                     inputs: tuple[str, ...] = ()) -> tuple[ResidualBlock, ...]:
    """The blocks of a log-FRF cost: every pair's log magnitudes (pair after pair), then every pair's phases.
    ``weights``: w[k, output, input] the cost multiplied the log errors by (``outputs``, ``inputs`` its axes)."""
    n, half = len(frequencies_hz), len(pairs) * len(frequencies_hz)
    return tuple(ResidualBlock(name=f"{i} -> {o}", domain="frequency",
                               rows=offset + np.arange(k * n, (k + 1) * n), axis=frequencies_hz,
                               imaginary_rows=offset + half + np.arange(k * n, (k + 1) * n), noise_sd=None,
                               line_weights=None if weights is None else
                               np.asarray(weights)[:, outputs.index(o), inputs.index(i)])
                 for k, (i, o) in enumerate(pairs))
