"""The structure solved again for new physical parameters: what an FMU does at initialisation to be exact.

A modulus, a spring or a mass changed in the 1-g model moves the gravity preload: the suspension cables
share the weight differently, the bars' forces and the geometry change, and with them the geometric
stiffness the modes are of. Carried to first order (:mod:`mace_fmu.iomodel.stiffness_route`) this was up to
7.8 % (RMS of the difference over the output's RMS) off a full re-solve over the declared ranges; a one-step
linear update of the forces about the nominal equilibrium was worse (1-2 %); the exact equilibrium with the
nominal state's second derivatives 0.12 %. So this module does what the re-solve does, from the nominal
equilibrium instead of from the unloaded structure:

1. the bars' natural stiffness, the springs and the concentrated masses scaled by their parameters;
2. 1-g with the large-displacement preload: Newton iterations on the updated geometry
   (:mod:`mace_fmu.fe.corotational`, the same element as the re-solve) from the nominal equilibrium to the
   new one, to the re-solve's work tolerance; the tangent there (material and geometric stiffness);
   0-g: the linear stiffness with the bars' material part scaled;
3. the modes: the modal constraints' reduced problem, the massless DOFs condensed statically, then shift and
   invert (:func:`_lowest_modes`);
4. each nominal mode continued by the new mode it became (largest total mass-weighted MAC, the zero
   cluster paired within itself), as ``export --parameters`` keys them.

The caller projects the shapes on the instruments (fixed influence rows, as the export does). Everything
here is numpy and scipy, so that an FMU carries it (pasted into the pythonfmu entry script with the
corotational element) and the updating engine runs the same code.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np
import scipy.linalg as sla
from scipy import sparse
from scipy.optimize import linear_sum_assignment

from mace_fmu.errors import MaceError  # fmu: inlined
from mace_fmu.fe.corotational import Bars, BarState, advanced, material_tangent, tangent_parts  # fmu: inlined

#: Newton's work tolerance |du . r| / |u . F|, the re-solve's final one (mace_fmu.fe.preload)
WORK_TOLERANCE = 1e-14
#: more iterations than this from the nominal equilibrium: the new one is not near it
MAX_ITERATIONS = 30
#: a diagonal entry of the reduced mass below this fraction of the largest is massless (mace_fmu.fe.modal)
MASSLESS_FRACTION = 1e-12
#: the eigen-solution finds this many times the retained modes, as the re-solve looks for their continuations
REACH = 1.5


def _csr(data: Mapping[str, np.ndarray], key: str, shape: tuple[int, int]) -> sparse.csr_array:
    """A sparse matrix stored as ``<key>_data``, ``<key>_rows``, ``<key>_cols``."""
    return sparse.coo_array((np.asarray(data[f"{key}_data"], dtype=np.float64),
                             (np.asarray(data[f"{key}_rows"]), np.asarray(data[f"{key}_cols"]))), shape=shape).tocsr()


class ExactModes:
    """The retained modes of the structure for any values of its physical parameters, by a full re-solve.

    ``data``: the ``resolve_*`` arrays (:func:`mace_fmu.iomodel.resolve_data.resolve_arrays`).
    """

    def __init__(self, data: Mapping[str, np.ndarray]):
        self.kind = str(data["resolve_kind"])  #: "large" (1-g, large-displacement preload) or "none" (0-g)
        n = self.n_dof = int(data["resolve_n_dof"])
        self.bars = Bars(ids=np.arange(len(data["resolve_bar_nodes"])),
                         node_a=np.asarray(data["resolve_bar_nodes"])[:, 0],
                         node_b=np.asarray(data["resolve_bar_nodes"])[:, 1],
                         frames0=np.asarray(data["resolve_bar_frames0"], dtype=np.float64),
                         lengths0=np.asarray(data["resolve_bar_lengths0"], dtype=np.float64),
                         k_natural=np.asarray(data["resolve_bar_k_natural"], dtype=np.float64))
        self.bar_parameter = np.asarray(data["resolve_bar_parameter"], dtype=int)  #: physical index, -1: none
        self.spring_vectors = np.asarray(data["resolve_spring_vectors"], dtype=np.float64).reshape(-1, n)
        self.spring_constants = np.asarray(data["resolve_spring_constants"], dtype=np.float64)
        self.spring_parameter = np.asarray(data["resolve_spring_parameter"], dtype=int)
        self.mass = _csr(data, "resolve_mass", (n, n))
        part = np.asarray(data["resolve_dm_part"], dtype=int)
        dm = sparse.coo_array((np.asarray(data["resolve_dm_data"], dtype=np.float64),
                               (np.asarray(data["resolve_dm_rows"]), np.asarray(data["resolve_dm_cols"]))),
                              shape=(n, n))
        self.mass_parts = {int(p): sparse.csr_array(sparse.coo_array(
            (dm.data[part == p], (dm.row[part == p], dm.col[part == p])), shape=(n, n))) for p in np.unique(part)}
        self.other_stiffness = _csr(data, "resolve_other", (n, n))  #: elements no parameter scales (0-g)
        self.gravity = np.asarray(data["resolve_gravity"], dtype=np.float64)  #: acceleration field [m/s^2, rad/s^2]
        self.load = np.asarray(data["resolve_load"], dtype=np.float64)  #: nominal dead load [N, N m]
        n_s, n_m = (int(x) for x in data["resolve_independent"])
        self.static_t = _csr(data, "resolve_static_t", (n, n_s))
        self.modal_t = _csr(data, "resolve_modal_t", (n, n_m))
        self.state = BarState(np.asarray(data["resolve_state_positions"], dtype=np.float64),
                              np.asarray(data["resolve_state_rotations"], dtype=np.float64))
        self.displacements = np.asarray(data["resolve_displacements"], dtype=np.float64)
        self.reference = np.asarray(data["resolve_reference_shapes"], dtype=np.float64)  #: (n_dof, n_modes)
        self.reference_zero = np.asarray(data["resolve_reference_zero"], dtype=bool)
        self.zero_hz = float(data["resolve_zero_hz"])
        self.iterations = 0  #: Newton iterations of the last solve
        self._last: tuple[bytes, np.ndarray, np.ndarray] | None = None  #: (key, frequencies, shapes) of the last

    def modes(self, relative_change: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(signed frequencies [Hz], mass-normalised shapes (n_dof, n_modes)) of the modes continuing the
        nominal ones, the physical parameters at (1 + ``relative_change``) times nominal."""
        key = np.asarray(relative_change, dtype=np.float64).tobytes()
        if self._last is not None and self._last[0] == key:  # a function of the parameters alone: the last result
            return self._last[1].copy(), self._last[2].copy()
        frequencies, shapes = self._solve(1.0 + np.asarray(relative_change, dtype=np.float64))
        self._last = (key, frequencies, shapes)
        return frequencies.copy(), shapes.copy()

    def _solve(self, factor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        scale = np.where(self.bar_parameter >= 0, factor[np.maximum(self.bar_parameter, 0)], 1.0)
        bars = Bars(ids=self.bars.ids, node_a=self.bars.node_a, node_b=self.bars.node_b, frames0=self.bars.frames0,
                    lengths0=self.bars.lengths0, k_natural=self.bars.k_natural * scale[:, None, None])
        k_springs = self._springs(factor)
        mass = self.mass.copy()
        load = self.load.copy()
        for p, dm in self.mass_parts.items():
            mass = mass + (factor[p] - 1.0) * dm
            load = load + (factor[p] - 1.0) * (dm @ self.gravity)
        if self.kind == "large":
            stiffness = self._equilibrium_tangent(bars, k_springs, load)
        else:  # no preload: the bars' linear stiffness is their tangent at the undeformed state
            stiffness = material_tangent(bars, self.state, self.n_dof)[1] + k_springs + self.other_stiffness
        return self._continued_modes(stiffness, mass)

    def _springs(self, factor: np.ndarray) -> sparse.csr_array:
        k = self.spring_constants * np.where(self.spring_parameter >= 0,
                                             factor[np.maximum(self.spring_parameter, 0)], 1.0)
        e = sparse.csr_array(self.spring_vectors)
        return sparse.csr_array(e.T @ sparse.diags_array(k) @ e)

    def _equilibrium_tangent(self, bars: Bars, k_springs: sparse.csr_array, load: np.ndarray) -> sparse.csr_array:
        """Full Newton from the nominal equilibrium to the new one; the tangent stiffness there (the native runtime
        keeps a tangent once the work ratio is below 1e-8: the same equilibrium to the same tolerance)."""
        t = self.static_t
        state, u = self.state, self.displacements.copy()
        for iteration in range(1, MAX_ITERATIONS + 1):
            parts = tangent_parts(bars, state, self.n_dof)
            k_t = parts.material + parts.geometric + k_springs
            residual = t.T @ (load - parts.internal_force - k_springs @ u)
            reduced = (t.T @ k_t @ t).toarray()
            try:
                factor = sla.cho_factor(0.5 * (reduced + reduced.T))
            except (np.linalg.LinAlgError, sla.LinAlgError):
                raise MaceError("the gravity preload's tangent stiffness is not positive definite for these "
                                "parameters (the structure buckles or hangs unstably)") from None
            delta = t @ sla.cho_solve(factor, residual)
            state, u = advanced(state, delta), u + delta
            if abs(delta @ (t @ residual)) <= WORK_TOLERANCE * max(abs(u @ load), 1e-300):
                self.iterations = iteration
                parts = tangent_parts(bars, state, self.n_dof)
                return sparse.csr_array(parts.material + parts.geometric + k_springs)
        raise MaceError(f"the gravity preload did not converge in {MAX_ITERATIONS} Newton iterations from the "
                         "nominal equilibrium: the parameters are too far from nominal for this structure")

    def _continued_modes(self, stiffness: sparse.csr_array, mass: sparse.csr_array) -> tuple[np.ndarray, np.ndarray]:
        t = self.modal_t
        k = (t.T @ stiffness @ t).toarray()
        m = (t.T @ mass @ t).toarray()
        k, m = 0.5 * (k + k.T), 0.5 * (m + m.T)
        count = min(int(np.ceil(REACH * self.reference.shape[1])), k.shape[0])
        eigval, vec = _lowest_modes(k, m, count)
        shapes = t @ vec
        frequencies = np.sign(eigval) * np.sqrt(np.abs(eigval)) / (2.0 * np.pi)
        order = self._continuation(frequencies, shapes)
        return frequencies[order], shapes[:, order]

    def _continuation(self, frequencies: np.ndarray, shapes: np.ndarray) -> np.ndarray:
        """Index of the new mode each nominal mode became (mace_fmu.fe.pairing.continue_modes)."""
        zero = np.abs(frequencies) < self.zero_hz
        if zero.sum() != self.reference_zero.sum():
            raise MaceError(f"the re-solve has {int(zero.sum())} zero-frequency modes, the nominal structure "
                             f"{int(self.reference_zero.sum())}: a parameter value that frees or holds a rigid-body "
                             "motion or a mechanism")
        weighted = self.mass @ self.reference
        cross = weighted.T @ shapes
        mac = cross**2 / np.outer(np.einsum("im,im->m", self.reference, weighted),
                                  np.einsum("im,im->m", shapes, self.mass @ shapes))
        order = np.empty(self.reference.shape[1], dtype=int)
        for ref, new in ((np.flatnonzero(self.reference_zero), np.flatnonzero(zero)),
                         (np.flatnonzero(~self.reference_zero), np.flatnonzero(~zero))):
            rows, cols = linear_sum_assignment(-mac[np.ix_(ref, new)])
            order[ref[rows]] = new[cols]
        return order


def _lowest_modes(k: np.ndarray, m: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``count`` lowest eigenvalues [rad^2/s^2] and M-normalised vectors of K x = w^2 M x.

    The massless DOFs (a zero on M's diagonal) condensed statically, then shift and invert: the largest
    eigenvalues mu of L^-1 M L^-T, K - sigma M = L L^T, are 1 / (w^2 - sigma), computed to a relative precision of
    round-off, so are the low modes, whose w^2 (a pendulum's 2 rad^2/s^2) lie ten decades below the stiff links'
    ones; solved directly, they came out 1e-5 off the nominal modes. The shift, a millionth of a typical
    K_ii / M_ii below zero, lies under every mode of a stable structure, its rigid-body zeros included
    (mace_fmu.fe.modal). The native runtime does the same (mace_resolve.c, lowest_modes)."""
    md = np.diag(m)
    massless = md <= MASSLESS_FRACTION * float(md.max())
    a, o = np.flatnonzero(~massless), np.flatnonzero(massless)
    coupling = sla.cho_solve(sla.cho_factor(k[np.ix_(o, o)]), k[np.ix_(o, a)]) if len(o) else np.zeros((0, len(a)))
    k_c = k[np.ix_(a, a)] - k[np.ix_(a, o)] @ coupling
    k_c, m_c = 0.5 * (k_c + k_c.T), m[np.ix_(a, a)]
    kd, mdc = np.diag(k_c), np.diag(m_c)
    sigma = -1e-6 * float(np.median(kd[kd > 0]) / np.median(mdc[mdc > 0]))
    factor = sla.cholesky(k_c - sigma * m_c, lower=True)
    half = sla.solve_triangular(factor, m_c, lower=True)  # L^-1 M
    inverse = sla.solve_triangular(factor, half.T, lower=True)  # L^-1 M L^-T (M symmetric)
    count = min(count, len(a))
    mu, y = sla.eigh(0.5 * (inverse + inverse.T), subset_by_index=[len(a) - count, len(a) - 1])
    vectors = sla.solve_triangular(factor, y, lower=True, trans="T")
    vectors /= np.sqrt(np.sum(vectors * (m_c @ vectors), axis=0))
    out = np.zeros((len(md), count))
    out[a] = vectors[:, ::-1]
    out[o] = -coupling @ out[a]
    return (sigma + 1.0 / mu)[::-1], out
