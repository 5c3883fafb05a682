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

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal, Protocol, TypeVar, runtime_checkable

import numpy as np
from scipy.optimize import linear_sum_assignment

from mace_fmu.errors import MaceError

Inclusion = Literal["full", "reanalysis", "modal-sensitivity"]
Values = Mapping[str, float]
M = TypeVar("M")  #: the models a family makes
M_co = TypeVar("M_co", covariant=True)
#: values -> model (bare: a model of any kind)
Evaluator = Callable[[Values], M]


class ModalBasis(Protocol[M_co]):
    """The modes of one base point and what a model needs besides them."""

    @property
    def physical(self) -> tuple[str, ...]:
        """Parameter names that act through the modes (moduli, springs)."""
        ...

    def model(self, values: Values, *, frequencies_hz: np.ndarray | None = None,
              phi_r: np.ndarray | None = None) -> M_co:
        """The model at ``values``: base modes re-analysed (default) or replaced by
        ``frequencies_hz`` [Hz] and ``phi_r`` (new modes in base-mode coordinates, Phi = Phi0 Phi_R)."""
        ...

    def modes_of(self, values: Values) -> tuple[np.ndarray, np.ndarray]:
        """A full modal solution at ``values`` in base coordinates: (frequencies [Hz], T = Phi0^T M Phi)."""
        ...


class ModelFamily(Protocol[M_co]):
    """A parametrised model: what the engine asks of the MACE model, the sample problem, an FMU or a user's.

    A family that can also reanalyse about a base point is a :class:`ReanalysisFamily`; one that cannot (an FMU,
    whose "reanalysis" is its own initialisation) makes every model by :meth:`full`.
    """

    def full(self, values: Values) -> M_co:
        """The model at ``values`` by a complete re-solve."""
        ...


@runtime_checkable
class ReanalysisFamily(ModelFamily[M_co], Protocol[M_co]):
    """A family with a modal basis to reanalyse on (the capability the ``reanalysis`` and ``modal-sensitivity``
    inclusions use): the MACE model and the sample problem."""

    def basis(self, values: Values) -> ModalBasis[M_co]:
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

    basis: ModalBasis[Any]
    base: Mapping[str, float]
    names: tuple[str, ...]  #: the physical parameters differenced
    f0: np.ndarray
    df: np.ndarray  #: (n_names, n_modes) [Hz per unit relative change]
    dt: np.ndarray  #: (n_names, n_modes, n_modes)

    def __call__(self, values: Values) -> Any:
        x = np.array([values[n] / self.base[n] - 1.0 for n in self.names])
        f = self.f0 + x @ self.df
        phi_r = np.eye(len(self.f0)) + np.tensordot(x, self.dt, axes=1)
        return self.basis.model(values, frequencies_hz=f, phi_r=phi_r)


def modal_sensitivity(basis: ModalBasis[Any], base: Values, names: Sequence[str], *, relative_step: float,
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


def evaluator(family: ModelFamily[M], inclusion: Inclusion, base: Values, names: Sequence[str], *,
              relative_step: float = 1e-2, runner: Callable = map) -> Evaluator[M]:
    """values -> model by ``inclusion``, valid about ``base`` (exact everywhere for ``full``).

    A family without a modal basis (not a :class:`ReanalysisFamily`: an FMU) reanalyses by a full solve, and
    has no modal sensitivities (:func:`check_inclusion` says so before any run).
    """
    check_inclusion(family, inclusion)
    if inclusion == "full" or (inclusion == "reanalysis" and not isinstance(family, ReanalysisFamily)):
        return family.full
    assert isinstance(family, ReanalysisFamily)  # check_inclusion refused the rest
    if inclusion == "reanalysis":
        return family.basis(base).model
    return modal_sensitivity(family.basis(base), base, names, relative_step=relative_step, runner=runner)


def check_inclusion(family: ModelFamily[Any], inclusion: str) -> None:
    """MaceError for an unknown ``inclusion``, or modal sensitivities of a family without a modal basis.

    Raises
    ------
    MaceError
        ``inclusion`` is not one of "full", "reanalysis" and "modal-sensitivity", or it is "modal-sensitivity"
        and ``family`` has no modes to difference (no :class:`ReanalysisFamily`: an FMU).
    """
    if inclusion not in ("full", "reanalysis", "modal-sensitivity"):
        raise MaceError(f"inclusion must be 'full', 'reanalysis' or 'modal-sensitivity', got {inclusion!r}")
    if inclusion == "modal-sensitivity" and not isinstance(family, ReanalysisFamily):
        raise MaceError(f"{type(family).__name__} gives no modes (an FMU has none): update its parameters with the "
                        "cost-sensitivity method or 'full'")
