"""How parameter values become a model: the ways of including update parameters of thesis 4.2.1.

- ``full``: a complete re-solve (FE model, preload, eigen-solution, input-output model);
- ``reanalysis`` (eq. 4.6-4.9): Ritz on the modes of a base point, the stiffness changes
  projected on them (the code the FMUs run at initialisation);
- ``modal-sensitivity`` (eq. 4.10): frequencies and mode shapes extrapolated linearly from
  finite differences about a base point, each perturbed mode tracked to the base mode it
  continues (largest mass-weighted overlap) and its sign aligned;
- the cost-sensitivity method (eq. 4.12-4.13) linearises the cost itself; it lives in
  :mod:`mace_fmu.updating.engine.sensitivity` and makes its perturbed models with ``full`` or
  ``reanalysis``.

Parameters that do not act through the modes (damping ratios, delays, servo gains) enter every
route exactly: they are blocks of the input-output model.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Literal, Mapping, Protocol, Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.linear_model import LinearModel

Inclusion = Literal["full", "reanalysis", "modal-sensitivity"]
Values = Mapping[str, float]
Evaluator = Callable[[Values], LinearModel]


class ModalBasis(Protocol):
    """The modes of one base point and what a model needs besides them."""

    physical: tuple[str, ...]  #: parameter names that act through the modes (moduli, springs)

    def model(self, values: Values, *, frequencies_hz: np.ndarray | None = None,
              phi_r: np.ndarray | None = None) -> LinearModel:
        """The model at ``values``: base modes re-analysed (default) or replaced by
        ``frequencies_hz`` [Hz] and ``phi_r`` (new modes in base-mode coordinates, Phi = Phi0 Phi_R)."""
        ...

    def modes_of(self, values: Values) -> tuple[np.ndarray, np.ndarray]:
        """A full modal solution at ``values`` in base coordinates: (frequencies [Hz], T = Phi0^T M Phi)."""
        ...


class ModelFamily(Protocol):
    """A parametrised model: what the engine asks of the MACE model, the sample problem or a user's."""

    def full(self, values: Values) -> LinearModel:
        """The model at ``values`` by a complete re-solve."""
        ...

    def basis(self, values: Values) -> ModalBasis:
        """The modal basis about ``values`` (a complete solve plus what reanalysis needs)."""
        ...


def track_modes(frequencies_hz: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Perturbed modes reordered to the base modes they continue, signs aligned with them.

    ``t`` = Phi0^T M Phi (columns: perturbed modes in base coordinates). The pairing maximises
    the total squared overlap (a mass-weighted MAC); a mode whose sign flipped is flipped back,
    so a difference quotient is not twice the mode shape (thesis 4.2.1).
    """
    _, order = linear_sum_assignment(-(t**2))  # row i: base mode i; order[i]: the perturbed mode it becomes
    f, t = frequencies_hz[order], t[:, order]
    sign = np.where(np.diag(t) < 0, -1.0, 1.0)
    return f, t * sign[None, :]


@dataclass(frozen=True)
class ModalSensitivity:
    """Eq. 4.10: f = f0 + sum_i df/dx_i x_i, Phi_R = I + sum_i dT/dx_i x_i about a base point.

    x_i is the relative change of physical parameter i from the base (p_i / p_i0 - 1).
    """

    basis: ModalBasis
    base: Mapping[str, float]
    names: tuple[str, ...]  #: the physical parameters differenced
    f0: np.ndarray
    df: np.ndarray  #: (n_names, n_modes) [Hz per unit relative change]
    dt: np.ndarray  #: (n_names, n_modes, n_modes)

    def __call__(self, values: Values) -> LinearModel:
        x = np.array([values[n] / self.base[n] - 1.0 for n in self.names])
        f = self.f0 + x @ self.df
        phi_r = np.eye(len(self.f0)) + np.tensordot(x, self.dt, axes=1)
        return self.basis.model(values, frequencies_hz=f, phi_r=phi_r)


def modal_sensitivity(basis: ModalBasis, base: Values, names: Sequence[str], *, relative_step: float,
                      runner: Callable = map) -> ModalSensitivity:
    """Finite-difference frequency and mode-shape sensitivities about ``base`` for the physical ``names``."""
    physical = tuple(n for n in names if n in basis.physical)
    f0, t0 = basis.modes_of(base)
    f0, _ = track_modes(f0, t0)
    perturbed = list(runner(basis.modes_of, [{**base, n: base[n] * (1.0 + relative_step)} for n in physical]))
    df, dt = [], []
    for f, t in perturbed:
        f, t = track_modes(f, t)
        df.append((f - f0) / relative_step)
        dt.append((t - np.eye(len(f0))) / relative_step)
    n = len(f0)
    return ModalSensitivity(basis=basis, base=dict(base), names=physical, f0=f0,
                            df=np.array(df).reshape(len(physical), n), dt=np.array(dt).reshape(len(physical), n, n))


def evaluator(family: ModelFamily, inclusion: Inclusion, base: Values, names: Sequence[str], *,
              relative_step: float = 1e-2, runner: Callable = map) -> Evaluator:
    """values -> model by ``inclusion``, valid about ``base`` (exact everywhere for ``full``)."""
    if inclusion == "full":
        return family.full
    if inclusion == "reanalysis":
        return family.basis(base).model
    if inclusion == "modal-sensitivity":
        return modal_sensitivity(family.basis(base), base, names, relative_step=relative_step, runner=runner)
    raise MaceError(f"inclusion must be 'full', 'reanalysis' or 'modal-sensitivity', got {inclusion!r}")
