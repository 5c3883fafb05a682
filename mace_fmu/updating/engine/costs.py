"""Costs as residual vectors j (thesis eq. 4.11): the scalar cost is j^T j.

Each cost maps a model to one real vector, stacked over modes, or over actuator/sensor pairs and frequencies or
times, so the cost-sensitivity method (eq. 4.12-4.13) and least squares see the same thing. A cost is a
``Cost[M]`` of the models it reads (:mod:`~mace_fmu.updating.engine.models`): the modal costs read poles
(:class:`~mace_fmu.updating.engine.models.PoleModel`), the time cost simulates
(:class:`~mace_fmu.updating.engine.models.SimulatedModel`: the state-space model and an FMU alike). A user adds a
cost by writing a class with ``name``, ``residual(model)`` and ``entry_labels()``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Generic, Protocol, TypeVar

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.iomodel.pole_pairing import pair_poles
from mace_fmu.updating.engine.linear_model import LinearModel
from mace_fmu.updating.engine.measured import MeasuredFrf, MeasuredMode, TimeHistory
from mace_fmu.updating.engine.modal_model import ModalModel
from mace_fmu.updating.engine.models import PoleModel, SimulatedModel
from mace_fmu.updating.engine.residual_blocks import ResidualBlock, frequency_blocks, time_blocks

M = TypeVar("M")  #: the models a cost reads
M_contra = TypeVar("M_contra", contravariant=True)


class Cost(Protocol[M_contra]):
    """What the updating engine needs of a cost of models ``M_contra`` (a cost of any
    :class:`~mace_fmu.updating.engine.models.SimulatedModel` is one of the linear model and of an FMU)."""

    @property
    def name(self) -> str:
        """What the cost is called in reports ("time", "log-frf", ...)."""
        ...

    def residual(self, model: M_contra) -> np.ndarray:
        """The residual vector j of ``model`` (real, fixed length)."""
        ...

    def entry_labels(self) -> list[str]:
        """What each entry of j is, for tables and cost spectra."""
        ...


def residual_blocks(cost: object) -> tuple[ResidualBlock, ...]:
    """The measured channels of ``cost``'s residual vector (its ``residual_blocks()``); () for a cost that
    has none (modal costs: one number per mode, no signal to analyse)."""
    blocks = getattr(cost, "residual_blocks", None)
    return tuple(blocks()) if callable(blocks) else ()


def _end(blocks: tuple[ResidualBlock, ...]) -> int:
    """The length of a residual vector made of ``blocks`` (they cover it)."""
    return 1 + max(int(max(b.rows.max(), -1 if b.imaginary_rows is None else b.imaginary_rows.max()))
                   for b in blocks) if blocks else 0


class UnpairedModeError(MaceError):
    """A measured mode no model pole can be paired with."""


@dataclass(frozen=True)
class ModalCost:
    """Relative frequency errors (eq. 4.2) and damping errors of measured modes against the model's poles.

    j = [w_i (f_meas,i - f_model,i) / f_meas,i ; w_i c_zeta ln(max(zeta_meas,i, z0) / max(zeta_model,i, z0))]
    with poles paired to measured modes by label pattern and then the nearest frequency
    (:func:`~mace_fmu.iomodel.pole_pairing.pair_poles`), never by sort order. The damping term is a log
    ratio: for small errors the relative error, but bounded for the servo-dominated modes whose
    damping is off by factors (Table 4.7: 2nd Z bending 0.445 against 0.105). ``damping_weight``
    (c_zeta) makes a 10 % damping error count like a 1 % frequency error at its default 0.1.
    """

    measured: tuple[MeasuredMode, ...]
    damping_weight: float = 0.1
    damping_floor: float = 0.001  #: z0: damping errors of nearly undamped modes stay bounded
    name: str = "modal"

    def pairs(self, model: PoleModel) -> list[int]:
        """Index into ``model.poles()`` of each measured mode's pole; UnpairedModeError names the first
        that has none."""
        poles = model.poles()
        found = pair_poles([(m.pattern, m.frequency_hz) for m in self.measured], poles)
        for m, i in zip(self.measured, found):
            if i is None:
                near = sorted(poles, key=lambda p: abs(p.frequency_hz - m.frequency_hz))[:3]
                raise UnpairedModeError(
                    f"measured mode {m.label!r} at {m.frequency_hz} Hz: no model pole matches its pattern "
                    f"{m.pattern!r} (nearest poles: " + ", ".join(f"{p.label} {p.frequency_hz:.2f} Hz" for p in near)
                    + ")")
        return [int(i) for i in found]

    def residual(self, model: PoleModel) -> np.ndarray:
        poles = model.poles()
        idx = self.pairs(model)
        w = np.array([m.weight for m in self.measured])
        f_meas = np.array([m.frequency_hz for m in self.measured])
        z_meas = np.array([m.damping for m in self.measured])
        f = np.array([poles[i].frequency_hz for i in idx])
        z = np.array([poles[i].damping for i in idx])
        freq = w * (f_meas - f) / f_meas
        floor = self.damping_floor
        damp = w * self.damping_weight * np.log(np.maximum(z_meas, floor) / np.maximum(z, floor))
        return np.concatenate([freq, damp])

    def entry_labels(self) -> list[str]:
        return [f"f {m.label} {m.frequency_hz:g} Hz" for m in self.measured] + \
            [f"zeta {m.label} {m.frequency_hz:g} Hz" for m in self.measured]


@dataclass(frozen=True)
class ModeShapeCost:
    """Frequencies (eq. 4.2), damping and the shapes of measured modes paired with the model's.

    j = [ModalCost's residual ; c_phi w_i r_i for each measured mode i], r_i its shape residual at the measured
    DOFs (u_i measured, v_i the model's mass-normalised shape there, s_i = sign(u_i . v_i)):

    - ``scaled`` (mass-normalised measured shapes, from a driving point): r_i = (u_i - s_i v_i) / ||u_i||, the
      shape's relative difference, its scale included (what sets masses apart from stiffnesses: frequencies and
      unscaled shapes are the same for a structure whose every mass and stiffness is doubled);
    - otherwise: r_i = u^_i - (u^_i . v^_i) v^_i with unit vectors u^, v^, whose squared length is 1 - MAC.

    The thesis prints no shape term (it cites [24] for updating with mode shapes); c_phi (``shape_weight``, 0.1
    by default) makes a 10 % shape difference, or a MAC of 0.99, count like a 1 % frequency error, as the
    damping term's default does for a 10 % damping error. The model must give its shapes at the measured DOFs
    (:class:`~mace_fmu.updating.engine.modal_model.ModalModel`); measured modes are paired with poles as in
    :class:`ModalCost` (``pattern``: the paired model mode's label).
    """

    measured: tuple[MeasuredMode, ...]
    shapes: np.ndarray  #: (DOF, measured mode) measured shapes at ``dofs``
    dofs: tuple[str, ...]
    scaled: bool = False  #: the measured shapes are mass-normalised (compare with their scale)
    shape_weight: float = 0.1
    damping_weight: float = 0.0  #: of the frequency part (ModalCost's c_zeta)
    name: str = "modal + shapes"

    def __post_init__(self) -> None:
        shapes = np.asarray(self.shapes, dtype=float)
        object.__setattr__(self, "shapes", shapes)
        if shapes.shape != (len(self.dofs), len(self.measured)):
            raise MaceError(f"mode-shape cost: shapes of shape {shapes.shape}, expected ({len(self.dofs)}, "
                            f"{len(self.measured)}) (DOF, measured mode)")
        if not (np.isfinite(self.shape_weight) and self.shape_weight >= 0):
            raise MaceError(f"mode-shape cost: shape weight must be >= 0, got {self.shape_weight!r}")

    @property
    def modal(self) -> ModalCost:
        """The frequency (and damping) part."""
        return ModalCost(measured=self.measured, damping_weight=self.damping_weight)

    def model_shapes(self, model: ModalModel) -> np.ndarray:
        """The model's shapes at the measured DOFs, one column per measured mode (its paired mode's)."""
        dofs = tuple(getattr(model, "dofs", ()))
        if dofs != self.dofs:
            raise MaceError(f"the model's shapes are at {', '.join(dofs) or 'no DOF'}, the measured ones at "
                            f"{', '.join(self.dofs)}")
        poles = model.poles()
        return np.column_stack([model.shapes[:, poles[i].mode] for i in self.modal.pairs(model)])

    def residual(self, model: ModalModel) -> np.ndarray:
        freq = self.modal.residual(model)
        v = self.model_shapes(model)
        u = self.shapes
        w = np.array([m.weight for m in self.measured])
        if self.scaled:
            s = np.sign(np.sum(u * v, axis=0))
            r = (u - s * v) / np.linalg.norm(u, axis=0)
        else:
            uu = u / np.linalg.norm(u, axis=0)
            vv = v / np.maximum(np.linalg.norm(v, axis=0), 1e-300)
            r = uu - np.sum(uu * vv, axis=0) * vv
        return np.concatenate([freq, (self.shape_weight * w * r).T.ravel()])

    def mac(self, model: ModalModel) -> np.ndarray:
        """MAC of each measured mode with its paired model mode."""
        v = self.model_shapes(model)
        u = self.shapes
        return np.sum(u * v, axis=0) ** 2 / (np.sum(u * u, axis=0) * np.sum(v * v, axis=0))

    def entry_labels(self) -> list[str]:
        return self.modal.entry_labels() + [f"shape {m.label} {d}" for m in self.measured for d in self.dofs]


@dataclass(frozen=True)
class FrequencyResponseCost:
    """Frequency-response errors over every measured channel and frequency.

    ``kind="magnitude"`` (eq. 4.4): j = [Re, Im] of G_data - G_model, which weights the poles;
    ``kind="log"`` (eq. 4.5, 4.17): j = [Re, Im] of log(G_data / G_model) = [log magnitude ratio,
    phase difference in rad], which weights poles and zeros alike and includes the phase. The phase
    difference is the principal value (within +-180 deg), as the complex logarithm gives it.
    """

    data: MeasuredFrf
    kind: str = "log"
    name: str = "log-frf"

    def __post_init__(self) -> None:
        if self.kind not in ("log", "magnitude"):
            raise MaceError(f"frequency-response cost: kind must be 'log' or 'magnitude', got {self.kind!r}")
        object.__setattr__(self, "name", "log-frf" if self.kind == "log" else "frf-magnitude")

    def residual(self, model: LinearModel) -> np.ndarray:
        h = model.frequency_response(self.data.frequencies_hz, inputs=self.data.inputs, outputs=self.data.outputs)
        g = self.data.response
        if self.kind == "log":
            with np.errstate(divide="ignore", invalid="ignore"):
                e = np.log(g / h)
            if not np.all(np.isfinite(e)):
                raise MaceError(f"{self.data.source}: the model's response is zero or infinite where data exist; "
                                "the log cost needs both nonzero")
        else:
            e = g - h
        e = e.transpose(2, 1, 0).reshape(-1)  # (input, output, frequency): one spectrum per channel pair
        return np.concatenate([e.real, e.imag])

    def residual_blocks(self) -> tuple[ResidualBlock, ...]:
        """One block per input-output pair (input-major, as the residual is stacked)."""
        if self.kind != "log":
            return ()  # differences of complex responses are not log errors: no noise model for them here
        return frequency_blocks(pairs=tuple((i, o) for i in self.data.inputs for o in self.data.outputs),
                                frequencies_hz=self.data.frequencies_hz)

    def entry_labels(self) -> list[str]:
        one = [f"{i} -> {o} {f:.4g} Hz" for i in self.data.inputs for o in self.data.outputs
               for f in self.data.frequencies_hz]
        return [f"{'log|G| ' if self.kind == 'log' else 'Re '}{x}" for x in one] + \
            [f"{'phase ' if self.kind == 'log' else 'Im '}{x}" for x in one]


@dataclass(frozen=True)
class TimeResponseCost:
    """Output errors of a simulation driven by the measured inputs (eq. 4.3), zero-order hold.

    j = [(y_data - y_model)(t_i) / s_o] stacked over the outputs, with s_o each output's RMS in the
    data when ``normalise`` (so that channels in different units weigh alike), else 1. The model is
    driven from the record's first sample, at rest; the errors are compared from ``compare_from_s`` [s]
    on, so that a part of a record (its second half, a window) is compared with the structure in the
    state the record's earlier part left it in, and a record that starts mid-stream (the structure
    already moving, which the model at rest cannot know) is compared after its start's transient.

    With ``band_hz`` the errors are those of the measured and the model's outputs through one zero-phase
    band-pass (:mod:`~mace_fmu.updating.engine.band`), s_o the filtered output's RMS: the model is still
    driven by the measured inputs as they are, and what lies outside the band (a shaker's broadband force
    noise, a drift) is not compared. The residual analysis correlates the errors with the inputs through the
    same filter.
    """

    data: TimeHistory
    normalise: bool = True
    name: str = "time"
    compare_from_s: float = 0.0  #: errors before this time [s] are not compared (the simulation still runs)
    band_hz: tuple[float, float] | None = None  #: the zero-phase band-pass of both outputs [Hz] (None: none)

    def __post_init__(self) -> None:
        t = self.data.times_s
        if not (np.isfinite(self.compare_from_s) and t[0] <= self.compare_from_s <= t[-2]):
            raise MaceError(f"{self.data.source}: comparison from {self.compare_from_s!r} s, expected a time in "
                            f"[{t[0]:g}, {t[-2]:g}] s (the record's)")
        if self.band_hz is not None:
            from mace_fmu.updating.engine.band import check_band

            object.__setattr__(self, "band_hz", check_band(self.band_hz, sample_time_s=self.data.sample_time_s,
                                                           where=f"{self.data.source}: band"))

    def _filtered(self, values: np.ndarray) -> np.ndarray:
        """``values`` (samples along the first axis) through the band's filter; unchanged without a band."""
        if self.band_hz is None:
            return np.asarray(values, dtype=float)
        from mace_fmu.updating.engine.band import band_filtered

        return band_filtered(values, self.band_hz, self.data.sample_time_s)

    @property
    def _first(self) -> int:
        """The first sample compared."""
        return int(np.searchsorted(self.data.times_s, self.compare_from_s - 1e-9 * self.data.sample_time_s))

    @property
    def compared(self) -> TimeHistory:
        """The part of the record the errors are taken over, through the band's filter where there is one
        (the whole record filtered, then cut: the filter's start sees the record before the window)."""
        keep = slice(self._first, None)
        if self.band_hz is None and self._first == 0:
            return self.data
        return TimeHistory(self.data.times_s[keep], {k: self._filtered(v)[keep] for k, v in self.data.inputs.items()},
                           {k: self._filtered(v)[keep] for k, v in self.data.outputs.items()},
                           source=f"{self.data.source} ({self._part()})", units=self.data.units)

    def _part(self) -> str:
        parts = [f"from {self.compare_from_s:g} s"] if self._first else []
        if self.band_hz is not None:
            parts.append(f"{self.band_hz[0]:g}-{self.band_hz[1]:g} Hz")
        return ", ".join(parts)

    def residual(self, model: SimulatedModel) -> np.ndarray:
        outs = list(self.data.outputs)
        y = self._filtered(model.time_response(self.data.times_s, self.data.inputs, outputs=outs))
        first = self._first
        err = []
        for k, name in enumerate(outs):
            measured = self._measured(name)
            scale = float(np.sqrt(np.mean(measured**2))) if self.normalise else 1.0
            err.append((measured - y[first:, k]) / (scale if scale > 0 else 1.0))
        return np.concatenate(err)

    def _measured(self, name: str) -> np.ndarray:
        """The measured output ``name`` as compared (filtered, from the first sample compared); kept once made."""
        cache = self.__dict__.setdefault("_compared_outputs", {})
        if name not in cache:
            cache[name] = self._filtered(self.data.outputs[name])[self._first:]
        return cache[name]

    def residual_blocks(self) -> tuple[ResidualBlock, ...]:
        """One block per output, its error samples over the output's RMS (or 1); the inputs they are correlated
        with through the band's filter."""
        compared = self.compared
        return time_blocks(outputs=tuple(compared.outputs), times_s=compared.times_s, inputs=compared.inputs)

    def entry_labels(self) -> list[str]:
        t = self.data.times_s[self._first:]
        return [f"{o} t={x:.4g} s" for o in self.data.outputs for x in t]


@dataclass(frozen=True)
class SeveralTests(Generic[M]):
    """The costs of several tests of one structure (a gimbal test, an active-strut test, ...) as one cost.

    j = [w_1 j_1; w_2 j_2; ...]: each test's residual times its weight, 1 / (its noise standard
    deviation per residual) when known, so that every test counts in units of its own noise.
    """

    tests: tuple[Cost[M], ...]  #: the tests' costs
    weights: tuple[float, ...]  #: one per test
    labels: tuple[str, ...]  #: one per test (its data file)
    name: str = "several tests"

    def residual(self, model: M) -> np.ndarray:
        return np.concatenate([w * c.residual(model) for c, w in zip(self.tests, self.weights)])

    def residual_blocks(self) -> tuple[ResidualBlock, ...]:
        """Each test's blocks, named "<test>: <channel>", scaled by its weight; () unless every test has them."""
        out: list[ResidualBlock] = []
        offset = 0
        for c, w, label in zip(self.tests, self.weights, self.labels):
            blocks = residual_blocks(c)
            if not blocks:
                return ()
            out += [b.shifted(offset, prefix=f"{label}: ", scale=w) for b in blocks]
            offset += _end(blocks)
        return tuple(out)

    def entry_labels(self) -> list[str]:
        return [f"{label}: {e}" for c, label in zip(self.tests, self.labels) for e in c.entry_labels()]


@dataclass(frozen=True)
class WithPriors(Generic[M]):
    """A cost with Gaussian prior knowledge of some parameters (a sensor gain calibrated to 1 %).

    j = [j_data; s (p_k - mean_k) / sd_k]: ``s``, the noise standard deviation per residual of
    j_data, puts each prior in the data's units, so that the least-squares answer is the posterior
    mode and sigma^2 (J^T J)^-1 its covariance, the priors' information included. The model must say
    its parameter values (``model.parameter_values``, as an FMU model does).
    """

    cost: Cost[M]  #: the data's cost
    priors: Mapping[str, tuple[float, float]]  #: parameter -> (mean, standard deviation) [the parameter's units]
    noise_sd: float  #: s: noise standard deviation per residual of ``cost``
    name: str = ""

    def __post_init__(self) -> None:
        bad = [n for n, (_, sd) in self.priors.items() if not (np.isfinite(sd) and sd > 0)]
        if bad:
            raise MaceError(f"prior standard deviation must be positive: {', '.join(bad)}")
        if not (np.isfinite(self.noise_sd) and self.noise_sd > 0):
            raise MaceError(f"noise standard deviation per residual must be positive, got {self.noise_sd!r}")
        object.__setattr__(self, "name", self.name or f"{self.cost.name} with priors")

    def residual(self, model: M) -> np.ndarray:
        values: Mapping[str, float] | None = getattr(model, "parameter_values", None)
        if values is None:
            raise MaceError(f"priors on {', '.join(self.priors)} need a model that says its parameter values")
        missing = [n for n in self.priors if n not in values]
        if missing:
            raise MaceError(f"prior on {', '.join(missing)}, which the model has no parameter of")
        prior = [self.noise_sd * (values[n] - mean) / sd for n, (mean, sd) in self.priors.items()]
        return np.concatenate([self.cost.residual(model), np.array(prior, dtype=float)])

    def residual_blocks(self) -> tuple[ResidualBlock, ...]:
        """The data's blocks (the priors, after them, are no measured channel)."""
        return residual_blocks(self.cost)

    def entry_labels(self) -> list[str]:
        return self.cost.entry_labels() + [f"prior {n}" for n in self.priors]


def scalar_cost(residual: np.ndarray) -> float:
    """j^T j."""
    return float(residual @ residual)
