"""Corotational 3-D beam: internal forces and tangent stiffness about a deformed state.

Each bar's strain energy is U = 1/2 d^T K_n d, where d are its natural deformations (stretch,
local rotations of both ends relative to a frame that follows the bar, Battini & Pacoste 2002).
U is exactly invariant under rigid motions, so the Hessian of the total potential about a
preloaded state contains every gravity effect of a hanging structure: string stiffness of the
cables, pendulum stiffness of hanging stages (whatever the orientation of the loaded members),
and stress stiffening of the bus.

Generalised coordinates are nodal translations and nodal spins (R -> expm(skew(dtheta)) R) in
basic axes, the same as the linear model's rotational DOFs. Derivatives of d are computed to
machine precision by complex step; second derivatives by central differences of complex-step
first derivatives, both vectorised over all bars.

Reference: J.-M. Battini, C. Pacoste, "Co-rotational beam elements with warping effects in
instability problems", Comput. Methods Appl. Mech. Engrg. 191 (2002) 1755-1789.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse

from mace_fmu.errors import MaceError  # fmu: inlined

_CS_STEP = 1e-30  # complex step: no cancellation, so any tiny step is exact to round-off
_FD_RELATIVE_STEP = 1e-4  # central differences of exact first derivatives: error ~1e-9
_MAX_LOCAL_ROTATION = 0.5  # rad; beyond this the bar is far outside small-strain beam theory
_CHUNK_BARS = 4000  # bars per derivative batch: large enough to vectorise, its temporaries ~60 MB each


@dataclass(frozen=True)
class Bars:
    """All CBARs as arrays (one row per bar) for vectorised geometric work."""

    ids: np.ndarray  #: element IDs
    node_a: np.ndarray  #: grid row of GA
    node_b: np.ndarray  #: grid row of GB
    frames0: np.ndarray  #: (n, 3, 3) undeformed element axes, rows x, y, z in basic
    lengths0: np.ndarray  #: undeformed lengths [m]
    k_natural: np.ndarray  #: (n, 7, 7) natural stiffness (see fe.beam.natural_stiffness)


def skew(v: np.ndarray) -> np.ndarray:
    """(..., 3) -> (..., 3, 3) cross-product matrices."""
    k = np.zeros(v.shape + (3,), dtype=v.dtype)
    k[..., 0, 1], k[..., 0, 2] = -v[..., 2], v[..., 1]
    k[..., 1, 0], k[..., 1, 2] = v[..., 2], -v[..., 0]
    k[..., 2, 0], k[..., 2, 1] = -v[..., 1], v[..., 0]
    return k


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product over the last axis (np.cross is slow on large complex batches)."""
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1], a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], -1)


def rotation_matrix(theta: np.ndarray) -> np.ndarray:
    """Rodrigues' formula for rotation vectors (..., 3); complex-safe for small complex parts."""
    phi2 = np.sum(theta * theta, axis=-1)[..., None, None]
    k = skew(theta)
    # skew(v)^2 = v v^T - |v|^2 I, without a batched 3 x 3 product (slow for many small matrices)
    k2 = theta[..., :, None] * theta[..., None, :] - phi2 * np.eye(3)
    if np.max(np.abs(phi2), initial=0.0) < 1e-6:  # every rotation tiny (derivative batches): series only
        return np.eye(3) + (1 - phi2 / 6 + phi2**2 / 120) * k + (0.5 - phi2 / 24 + phi2**2 / 720) * k2
    small = np.abs(phi2) < 1e-6
    phi = np.sqrt(np.where(small, 1.0, phi2))
    # Series below 1e-3 rad keep complex-step derivatives analytic and accurate.
    a = np.where(small, 1 - phi2 / 6 + phi2**2 / 120, np.sin(phi) / phi)
    b = np.where(small, 0.5 - phi2 / 24 + phi2**2 / 720, (1 - np.cos(phi)) / np.where(small, 1.0, phi2))
    return np.eye(3) + a * k + b * k2


def rotation_vector_small(r: np.ndarray) -> np.ndarray:
    """Rotation vector of rotation matrices near the identity (angle < 0.5 rad), complex-safe."""
    w = 0.5 * np.stack([r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]], -1)
    s2 = np.sum(w * w, axis=-1)
    # trace = 1 + 2 cos(angle): the sine alone cannot tell 0.1 rad from pi - 0.1 rad
    trace = (r[..., 0, 0] + r[..., 1, 1] + r[..., 2, 2]).real
    if trace.size and np.min(trace) < 1 + 2 * np.cos(_MAX_LOCAL_ROTATION):  # a deck may have no bars
        raise MaceError(f"a bar's local rotation exceeds {_MAX_LOCAL_ROTATION} rad: the preload deforms the "
                        f"structure beyond small-strain beam theory (or the solution diverged)")
    # asin(s)/s as a series in s^2 (no square root, so complex-step stays analytic)
    ratio = 1 + s2 * (1 / 6 + s2 * (3 / 40 + s2 * (5 / 112 + s2 * (35 / 1152 + s2 * 63 / 2816))))
    return w * ratio[..., None]


def natural_deformations(xa, xb, ra, rb, frames0, lengths0):
    """Stretch and local end rotations (..., 7) of bars with current ends (xa, ra), (xb, rb)."""
    chord = xb - xa
    length = np.sqrt(np.sum(chord * chord, axis=-1))
    e1 = chord / length[..., None]
    y0 = frames0[..., 1, :]
    q = 0.5 * (np.einsum("...ij,...j->...i", ra, y0) + np.einsum("...ij,...j->...i", rb, y0))
    e3 = _cross(e1, q)
    e3 = e3 / np.sqrt(np.sum(e3 * e3, axis=-1))[..., None]
    e2 = _cross(e3, e1)
    rows = np.stack([e1, e2, e3], -2)  # corotated frame, rows = axes in basic
    triad0 = np.swapaxes(frames0, -1, -2)  # columns = undeformed element axes
    theta_a = rotation_vector_small(rows @ ra @ triad0)
    theta_b = rotation_vector_small(rows @ rb @ triad0)
    # Stretch of the chord plus the shortening of the bowed axis (Hermite shape between the local
    # end rotations): with it the geometric stiffness is the consistent beam-column matrix
    # P/(30L) [36, 3L, -36, 3L; ...] rather than the string term P/L alone.
    bow = sum(4 * theta_a[..., i] ** 2 - 2 * theta_a[..., i] * theta_b[..., i] + 4 * theta_b[..., i] ** 2 for i in (1, 2))
    stretch = length - lengths0 + lengths0 / 60.0 * bow
    return np.concatenate([stretch[..., None], theta_a, theta_b], -1)


@dataclass(frozen=True)
class BarState:
    """Current configuration: grid positions [m] and nodal rotation matrices."""

    positions: np.ndarray  #: (n_grid, 3)
    rotations: np.ndarray  #: (n_grid, 3, 3), relative to the undeformed state


def advanced(state: BarState, delta: np.ndarray) -> BarState:
    """``state`` moved by incremental translations [m] and rotation vectors [rad] ``delta`` (n_dof,), the spins
    applied on the left (in basic axes)."""
    d6 = delta.reshape(-1, 6)
    return BarState(state.positions + d6[:, :3], rotation_matrix(d6[:, 3:]) @ state.rotations)


def _deformations(bars: Bars, state: BarState, dz: np.ndarray) -> np.ndarray:
    """Natural deformations for perturbations dz (n_bar, P, 9) of (chord, spin A, spin B)."""
    xa = state.positions[bars.node_a][:, None, :]
    xb = state.positions[bars.node_b][:, None, :] + dz[..., 0:3]
    ra = rotation_matrix(dz[..., 3:6]) @ state.rotations[bars.node_a][:, None]
    rb = rotation_matrix(dz[..., 6:9]) @ state.rotations[bars.node_b][:, None]
    return natural_deformations(xa, xb, ra, rb, bars.frames0[:, None], bars.lengths0[:, None])


# The 12 nodal coordinates q enter d only through 9 reduced ones z = (xb - xa, spin A, spin B):
# q-coordinate a is +/- z-coordinate _ZMAP[a] with sign _ZSIGN[a].
_ZMAP = np.array([0, 1, 2, 3, 4, 5, 0, 1, 2, 6, 7, 8])
_ZSIGN = np.array([-1.0, -1.0, -1.0, 1, 1, 1, 1, 1, 1, 1, 1, 1])
_PAIRS = np.array([(i, j) for i in range(9) for j in range(i, 9)])


def _nodal_vector(v_z: np.ndarray) -> np.ndarray:
    """(..., 9) derivative in z -> (..., 12) derivative in nodal coordinates."""
    return v_z[..., _ZMAP] * _ZSIGN


def _nodal_matrix(m_z: np.ndarray) -> np.ndarray:
    """(..., 9, 9) second derivative in z -> (..., 12, 12) in nodal coordinates."""
    return m_z[..., _ZMAP[:, None], _ZMAP[None, :]] * np.outer(_ZSIGN, _ZSIGN)


def _reduced_derivatives(bars: Bars, state: BarState, *, second: bool = True
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(d, dd/dz, d2d/dz2 or None): shapes (n, 7), (n, 7, 9), (n, 7, 9, 9)."""
    n = len(bars.ids)
    if n > _CHUNK_BARS:  # the complex batches hold ~15 kB per bar and temporary: bounded memory
        parts = [_reduced_derivatives(_bar_rows(bars, slice(k, k + _CHUNK_BARS)), state, second=second)
                 for k in range(0, n, _CHUNK_BARS)]
        return (np.concatenate([q[0] for q in parts]), np.concatenate([q[1] for q in parts]),
                np.concatenate([q[2] for q in parts]) if second else None)
    if not second:
        d_all = _deformations(bars, state, np.broadcast_to(1j * _CS_STEP * np.eye(9), (n, 9, 9)))
        return d_all[:, 0].real, np.swapaxes(d_all.imag, 1, 2) / _CS_STEP, None
    h = np.full((n, 9), _FD_RELATIVE_STEP)
    h[:, 0:3] *= bars.lengths0[:, None]
    eye = np.eye(9)
    # Batch: 9 complex steps, then for each pair i <= j: (+/- h_i e_i) + complex step e_j.
    cs = 1j * _CS_STEP * eye
    i, j = _PAIRS[:, 0], _PAIRS[:, 1]
    shift = h[:, i, None] * eye[i][None]
    batch = np.concatenate([np.broadcast_to(cs, (n, 9, 9)), shift + cs[j], -shift + cs[j]], 1)
    d_all = _deformations(bars, state, batch)
    m = len(_PAIRS)
    bz = np.swapaxes(d_all[:, :9].imag, 1, 2) / _CS_STEP
    diff = (d_all[:, 9:9 + m].imag - d_all[:, 9 + m:].imag) / (_CS_STEP * 2.0 * h[:, i, None])
    d2z = np.zeros((n, 7, 9, 9))
    d2z[:, :, i, j] = np.swapaxes(diff, 1, 2)
    d2z[:, :, j, i] = np.swapaxes(diff, 1, 2)
    return d_all[:, 0].real, bz, d2z


def _bar_rows(bars: Bars, rows: slice) -> Bars:
    return Bars(ids=bars.ids[rows], node_a=bars.node_a[rows], node_b=bars.node_b[rows], frames0=bars.frames0[rows],
                lengths0=bars.lengths0[rows], k_natural=bars.k_natural[rows])


def deformation_derivatives(bars: Bars, state: BarState) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(d, B = dd/dq, D2 = d2d/dq2) per bar: shapes (n, 7), (n, 7, 12), (n, 7, 12, 12)."""
    d, bz, d2z = _reduced_derivatives(bars, state)
    assert d2z is not None  # second derivatives by default
    return d, _nodal_vector(bz), _nodal_matrix(d2z)


def deformation_jacobian(bars: Bars, state: BarState) -> tuple[np.ndarray, np.ndarray]:
    """(d, B = dd/dq) per bar: shapes (n, 7), (n, 7, 12); first derivatives only, a ninth of the work of
    :func:`deformation_derivatives`."""
    d, bz, _ = _reduced_derivatives(bars, state, second=False)
    return d, _nodal_vector(bz)


def undeformed_jacobian(bars: Bars) -> np.ndarray:
    """B = dd/dq (n, 7, 12) at the undeformed state, in closed form: what :func:`deformation_jacobian` gives
    there, without its nine complex-step evaluations per bar.

    With the chord change dc = dx_B - dx_A and the end spins phi_A, phi_B (basic), the corotated frame
    turns by w = (phi_A + phi_B)/2 . e1 about e1 (its y axis follows the mean of the rotated ends' y axes),
    -dc . e3 / L about e2 and dc . e2 / L about e3 (its x axis follows the chord); the stretch is
    dc . e1 and each end's local rotation is its spin less w, in element axes (e1, e2, e3: the rows of
    ``frames0``). ``tests/fe/test_corotational.py`` checks it against the complex-step derivative.
    """
    e1, e2, e3 = bars.frames0[:, 0], bars.frames0[:, 1], bars.frames0[:, 2]
    per_length = 1.0 / bars.lengths0[:, None]
    bz = np.zeros((len(bars.ids), 7, 9))
    chord, spin_a, spin_b = slice(0, 3), slice(3, 6), slice(6, 9)
    bz[:, 0, chord] = e1
    for row, own, other in ((1, spin_a, spin_b), (4, spin_b, spin_a)):  # torsion: own spin less the mean
        bz[:, row, own], bz[:, row, other] = 0.5 * e1, -0.5 * e1
        bz[:, row + 1, chord], bz[:, row + 1, own] = e3 * per_length, e2  # about element y
        bz[:, row + 2, chord], bz[:, row + 2, own] = -e2 * per_length, e3  # about element z
    return _nodal_vector(bz)


def internal_force(bars: Bars, state: BarState, n_dof: int) -> np.ndarray:
    """Internal force vector [N, N m] of all bars at ``state`` (first derivatives only: cheap)."""
    d, bz, _ = _reduced_derivatives(bars, state, second=False)
    return _force(bars, bz, np.einsum("nij,nj->ni", bars.k_natural, d), n_dof)


def bar_energies(bars: Bars, state: BarState | None, natural_forces: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """(n_bar, n_vec) potential energy 1/2 v_e^T K_T,e v_e of each bar for global vectors (n_dof, n_vec);
    ``state`` None: the undeformed geometry, unstressed (its jacobian in closed form)."""
    stressed = bool(np.any(natural_forces))  # unstressed (0-g): no geometric part, first derivatives suffice
    if state is None:
        if stressed:
            raise ValueError("bar forces need the state they act in")
        b = undeformed_jacobian(bars)
        k_e = np.swapaxes(b, 1, 2) @ bars.k_natural @ b
    else:
        _, bz, d2z = _reduced_derivatives(bars, state, second=stressed)
        k_z = np.swapaxes(bz, 1, 2) @ bars.k_natural @ bz
        if stressed:
            assert d2z is not None  # asked for (second=stressed)
            k_z = k_z + np.einsum("nk,nkij->nij", natural_forces, d2z)
        k_e = _nodal_matrix(k_z)
    v = vectors[bar_dof_indices(bars)]
    return 0.5 * np.einsum("nim,nij,njm->nm", v, k_e, v)


def bar_dof_indices(bars: Bars) -> np.ndarray:
    """(n_bar, 12) global DOF indices (translations and spins of GA then GB)."""
    six = np.arange(6)
    return np.concatenate([6 * bars.node_a[:, None] + six, 6 * bars.node_b[:, None] + six], 1)


def _assemble(bars: Bars, k_z: np.ndarray, n_dof: int) -> sparse.csr_array:
    """Sparse global matrix of per-bar (n_bar, 9, 9) matrices in reduced coordinates (symmetrised)."""
    k_e = _nodal_matrix(k_z)
    k_e = 0.5 * (k_e + np.swapaxes(k_e, 1, 2))
    idx = bar_dof_indices(bars)
    rows = np.broadcast_to(idx[:, :, None], k_e.shape).ravel()
    cols = np.broadcast_to(idx[:, None, :], k_e.shape).ravel()
    return sparse.coo_array((k_e.ravel(), (rows, cols)), shape=(n_dof, n_dof)).tocsr()  # sums duplicates


def _force(bars: Bars, bz: np.ndarray, g: np.ndarray, n_dof: int) -> np.ndarray:
    f_e = _nodal_vector(np.einsum("nki,nk->ni", bz, g))
    return np.bincount(bar_dof_indices(bars).ravel(), weights=f_e.ravel(), minlength=n_dof)


def material_tangent(bars: Bars, state: BarState, n_dof: int) -> tuple[np.ndarray, sparse.csr_array]:
    """(internal force [n_dof], material stiffness B^T K_n B at ``state``): first derivatives only.

    An eleventh of the work of :func:`tangent`; with a geometric stiffness scaled from an earlier
    state it makes the iteration matrix of the preload's intermediate increments.
    """
    d, bz, _ = _reduced_derivatives(bars, state, second=False)
    g = np.einsum("nij,nj->ni", bars.k_natural, d)
    return _force(bars, bz, g, n_dof), _assemble(bars, np.swapaxes(bz, 1, 2) @ bars.k_natural @ bz, n_dof)


@dataclass(frozen=True)
class TangentParts:
    """The tangent stiffness of all bars about a state, split into its two parts (basic DOFs)."""

    internal_force: np.ndarray  #: (n_dof,) [N, N m]
    material: sparse.csr_array  #: B^T K_n B [N/m, N, N m]
    geometric: sparse.csr_array  #: sum_k g_k d^2 d_k / dq^2, the stress stiffness
    natural_forces: np.ndarray  #: (n_bar, 7) g: axial force [N], end moments [N m] (local)


def tangent_parts(bars: Bars, state: BarState, n_dof: int, *, natural_forces: np.ndarray | None = None
                  ) -> TangentParts:
    """Internal force, material and geometric stiffness of all bars about ``state`` (see :func:`tangent`)."""
    d, bz, d2z = _reduced_derivatives(bars, state)
    assert d2z is not None  # second derivatives by default
    g = np.einsum("nij,nj->ni", bars.k_natural, d) if natural_forces is None else natural_forces
    return TangentParts(internal_force=_force(bars, bz, g, n_dof),
                        material=_assemble(bars, np.swapaxes(bz, 1, 2) @ bars.k_natural @ bz, n_dof),
                        geometric=_assemble(bars, np.einsum("nk,nkij->nij", g, d2z), n_dof), natural_forces=g)


def tangent(bars: Bars, state: BarState, n_dof: int, *, natural_forces: np.ndarray | None = None
            ) -> tuple[np.ndarray, sparse.csr_array, np.ndarray]:
    """(internal force [n_dof], sparse tangent stiffness, natural forces [n_bar, 7]) of all bars.

    The natural forces default to K_n d at ``state``; pass them to build a linear-prestress
    stiffness (stresses from a linear solution, geometry of ``state``).
    """
    parts = tangent_parts(bars, state, n_dof, natural_forces=natural_forces)
    return parts.internal_force, sparse.csr_array(parts.material + parts.geometric), parts.natural_forces
