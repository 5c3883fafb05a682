"""Block shift-invert Lanczos: the lowest modes of K x = lambda M x from solves with K - sigma M, a block of
right-hand sides at a time.

The method of NASTRAN's READ module (Grimes, Lewis and Simon, "A shifted block Lanczos algorithm for
solving sparse symmetric generalized eigenproblems", SIAM J. Matrix Anal. Appl. 15, 1994), at one
shift: the Krylov space of W = (K - sigma M)^-1 M grows a block of ``block_size`` vectors at a time,
M-orthonormal with full reorthogonalisation, and W's projection on it (a band matrix, symmetric in
the M inner product) gives Ritz values theta = 1 / (lambda - sigma) and their residuals without a
further solve.

Why blocks: at 100k DOFs a solve is a pass over a factor of up to a gigabyte, and its cost is the
reading, not the arithmetic: CHOLMOD solves a block of columns in one pass (mace_fmu.sparse.cholmod).
A block Krylov space needs more vectors than ARPACK's single-vector one for the same modes, about
twice as many, but each costs a fraction of a lone column's (benchmarks/RESULTS.md, "A BLAS for
CHOLMOD and block solves" and "The sparse solver's figures, by module").

The massless DOFs' infinite eigenvalues are W's zeros: every vector is an image of W (the start
block too), so they never enter the basis. A block of ``block_size`` finds eigenvalues of that
multiplicity; a Krylov space that closes early (a deflated direction) is refilled with fresh random
images, so an invariant subspace found early is not the end of the search.

Only the DOFs that M touches take part in the iteration. W Q needs Q on them alone (M Q is zero
elsewhere), and so does every M inner product, so the basis is kept and orthogonalised on those rows:
a beam model without rotary inertia has half its DOFs massless, and the Gram-Schmidt, the largest
cost after the solves, reads half as much. The other rows of each image W Q_j are kept as the solve
gives them, and the Ritz vectors are returned as W x / theta = (W V y) / theta: one more step of
inverse iteration, whose massless DOFs carry the static response of the massive ones exactly.

Memory: there is no restart, so the basis keeps every vector, about five per mode wanted (at 100k DOFs
a few hundred megabytes for 50 modes to the modal solution's tolerance); hundreds of modes at 100k DOFs
take gigabytes.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from threadpoolctl import threadpool_limits

from mace_fmu.util.threads import usable_cores

#: Vectors in a block: CHOLMOD's solve shares 16 columns between two cores (mace_fmu.sparse.cholmod), and
#: 16 gave the fewest seconds of solves on the wide lattice: fewer columns cost more each, more columns more
#: of them (benchmarks/RESULTS.md, "The sparse solver's figures, by module").
BLOCK_SIZE = 16
#: A direction whose M-norm after reorthogonalisation is below this fraction of the largest Ritz value
#: (of the block's largest vector for a fresh block) is dropped: the Gram matrix that orthonormalises a
#: block resolves norms down to the square root of the rounding (1e-8), and a direction that small
#: means the space is all but invariant there.
DEFLATION_TOLERANCE = 1e-7
#: From this many basis entries the Gram-Schmidt's products run on every usable core (_SharedRows);
#: below, the threads would cost more than they share out (mace_fmu.util.threads).
SHARED_GRAM_SCHMIDT_ENTRIES = 1 << 22


@dataclass(frozen=True)
class LanczosModes:
    """The lowest eigenpairs found, ascending."""

    eigenvalues: np.ndarray  #: lambda = omega^2 [rad^2/s^2]
    vectors: np.ndarray  #: (n, modes), M-normalised: x^T M x = 1
    solved_columns: int  #: right-hand sides solved with K - sigma M [-]


def lowest_modes(*, stiffness: sparse.sparray, mass: sparse.sparray, solve: Callable[[np.ndarray], np.ndarray],
                 shift: float, count: int, above: float | None = None, tolerance: float = 1e-8,
                 max_dimension: int, block_size: int = BLOCK_SIZE, seed: int = 0) -> LanczosModes | None:
    """The lowest ``count`` eigenpairs of K x = lambda M x, and more until one lies above ``above``.

    Parameters
    ----------
    stiffness, mass : scipy.sparse array
        K and M, symmetric, of the same order n (M may be singular: massless DOFs).
    solve : callable
        x = solve(b) with K - ``shift`` M for b of shape (n, k): the factor's block solve.
    shift : float
        sigma [rad^2/s^2], below every eigenvalue (K - sigma M positive definite).
    count : int
        Eigenpairs wanted at least.
    above : float, optional
        Go on until the highest converged eigenvalue exceeds this [rad^2/s^2].
    tolerance : float
        A Ritz pair has converged when the M-norm of its residual W x - theta x is below this fraction of theta.
    max_dimension : int
        Largest Krylov space [vectors]: None is returned rather than build a larger one.
    block_size : int
        Vectors added to the space at a time.
    seed : int
        The random start block's seed (the result does not depend on it beyond ``tolerance``).

    Returns
    -------
    LanczosModes or None
        Every leading converged eigenpair, at least ``count``; None when ``max_dimension`` is reached first.
    """
    n = stiffness.shape[0]
    rng = np.random.default_rng(seed)
    touched = _MassRows(mass)
    space = _Space(touched.rows.size, n - touched.rows.size, min(max_dimension, max(6 * count, 8 * block_size)),
                   max_dimension)

    def images_of(vectors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # W Q on M's rows and on the others
        loads = np.zeros((n, vectors.shape[1]))
        loads[touched.rows] = touched.loads(vectors)
        images = solve(loads)
        return touched.coordinates(images[touched.rows]), images[touched.others]

    # numpy's BLAS on one thread, the Gram-Schmidt's products shared out by threads of our own (_SharedRows):
    # OpenBLAS's own threads spin for a while after each product, and in the solve that follows that spinning
    # took cores from the substructures' sweeps
    with threadpool_limits(limits=1, user_api="blas"), _SharedRows(touched.rows.size) as rows:
        block = _fresh_images(images_of, touched, space.basis(), rng, block_size)
        solved = block_size
        while True:
            first = space.size
            if block is None or not space.append(block):
                return None
            images, elsewhere = images_of(block)  # W Q_j
            space.set_images(first, elsewhere)
            solved += images.shape[1]
            basis = space.basis()
            coupling = _orthogonalise(images, touched, basis, recent=max(first - block_size, 0), rows=rows)
            space.set_projection(first, coupling)
            theta, ritz = np.linalg.eigh(space.projection())
            theta, ritz = theta[::-1], ritz[:, ::-1]  # largest theta: lowest lambda
            floor = DEFLATION_TOLERANCE * max(abs(theta[0]), 1e-300)
            block, residual_map = _orthonormal(images, touched, floor=floor)
            residual = np.linalg.norm(residual_map @ ritz[first:space.size], axis=0)
            converged = residual <= tolerance * np.abs(theta)
            leading = int(np.argmin(converged)) if not converged.all() else len(converged)
            eigenvalues = shift + 1.0 / theta[:leading]
            if leading >= count and (above is None or (leading and eigenvalues[-1] > above)):
                y, theta = ritz[:, :leading], theta[:leading]
                # W x = V T y + Q_(j+1) R_j y_j with T y = theta y: on M's rows V y plus the residual's share
                on_rows = basis @ y + block @ (residual_map @ y[first:]) / theta
                norms = np.sqrt(np.einsum("im,im->m", on_rows, touched @ on_rows))
                vectors = np.empty((n, leading))
                vectors[touched.rows] = touched.rows_of(on_rows) / norms
                vectors[touched.others] = space.images() @ y / (theta * norms)
                return LanczosModes(eigenvalues, vectors, solved)
            if block.shape[1] < block_size:  # deflated: fresh directions keep the block's width
                missing = block_size - block.shape[1]
                fresh = _fresh_images(images_of, touched, np.hstack([basis, block]), rng, missing)
                solved += missing
                block = block if fresh is None else np.hstack([block, fresh])
                if block.shape[1] == 0:  # the whole space is invariant: no mode left to find
                    return None


class _MassRows:
    """M on the DOFs it touches (``rows``, a row or column with a nonzero entry), and the coordinates the iteration
    takes on those rows: for a positive diagonal M (lumped masses) x~ = M^(1/2) x, in which M is the identity and
    no M product is needed (a hundred of them in a Lanczos at 100k DOFs), for any other M x itself.

    ``touched @ x`` is M in the iteration's coordinates."""

    def __init__(self, mass: sparse.sparray):
        coo = sparse.coo_array(mass)
        nonzero = coo.data != 0
        self.rows = np.unique(np.concatenate([coo.row[nonzero], coo.col[nonzero]]))
        self.others = np.setdiff1d(np.arange(mass.shape[0]), self.rows)
        block = sparse.csr_array(mass)[self.rows][:, self.rows]
        diagonal = block.diagonal()
        lumped = block.count_nonzero() == np.count_nonzero(diagonal) and bool(np.all(diagonal > 0))
        self._root = np.sqrt(diagonal)[:, None] if lumped else None
        self._block = block

    def __matmul__(self, x: np.ndarray) -> np.ndarray:
        return x if self._root is not None else self._block @ x

    def loads(self, x: np.ndarray) -> np.ndarray:
        """M x on the rows, for x in the iteration's coordinates: a solve's right-hand side there."""
        return self._root * x if self._root is not None else self._block @ x

    def coordinates(self, x: np.ndarray) -> np.ndarray:
        """x on the rows in the iteration's coordinates."""
        return self._root * x if self._root is not None else x

    def rows_of(self, x: np.ndarray) -> np.ndarray:
        """x in the iteration's coordinates back on the rows."""
        return x / self._root if self._root is not None else x


class _Space:
    """The Krylov basis V on M's rows, the images W V on the other rows, and W's projection V^T M W V, grown
    in place (capacity half as large again when full)."""

    def __init__(self, rows: int, other_rows: int, capacity: int, limit: int):
        self.size, self.limit = 0, limit
        # row-major: a block's columns land as a short run in each row, the order the solve's images come in
        # (column-major storage took longer to fill)
        self._vectors = np.empty((rows, capacity))
        self._images = np.empty((other_rows, capacity))
        self._projection = np.zeros((capacity, capacity))

    def basis(self) -> np.ndarray:
        return self._vectors[:, :self.size]

    def images(self) -> np.ndarray:
        """W V on the rows M does not touch."""
        return self._images[:, :self.size]

    def append(self, block: np.ndarray) -> bool:
        """Add M-orthonormal vectors; False when that would exceed the limit."""
        end = self.size + block.shape[1]
        if end > self.limit:
            return False
        if end > self._vectors.shape[1]:
            capacity = min(self.limit, max(end, 3 * self._vectors.shape[1] // 2))
            self._vectors, self._images = (_grown(array, self.size, capacity) for array in (self._vectors,
                                                                                             self._images))
            projection = np.zeros((capacity, capacity))
            projection[:self.size, :self.size] = self._projection[:self.size, :self.size]
            self._projection = projection
        self._vectors[:, self.size:end] = block
        self.size = end
        return True

    def set_images(self, first: int, images: np.ndarray) -> None:
        """W of the vectors from ``first`` on, on the rows M does not touch."""
        self._images[:, first:first + images.shape[1]] = images

    def set_projection(self, first: int, coupling: np.ndarray) -> None:
        """The columns of V^T M W V for the block from ``first`` (and, by symmetry, its rows)."""
        self._projection[:self.size, first:self.size] = coupling
        self._projection[first:self.size, :self.size] = coupling.T

    def projection(self) -> np.ndarray:
        p = self._projection[:self.size, :self.size]
        return 0.5 * (p + p.T)


def _grown(array: np.ndarray, used: int, capacity: int) -> np.ndarray:
    grown = np.empty((array.shape[0], capacity))
    grown[:, :used] = array[:, :used]
    return grown


class _SharedRows:
    """The Gram-Schmidt's products with the basis, V^T Y and Y - V S, each core taking a share of the rows (a
    context manager: its threads end with it).

    The basis is read twice a pass: at 100k DOFs a hundred megabytes and more, which every core reads faster
    than one. The threads are ours, not BLAS's: OpenBLAS's wait for more work by spinning, and that spinning
    took the cores from the substructures' sweeps in the solve that follows.
    """

    def __init__(self, rows: int):
        cores = usable_cores()
        bounds = np.linspace(0, rows, cores + 1).astype(int)
        self._shares = [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]
        self._threads = ThreadPoolExecutor(max_workers=cores) if cores > 1 else None

    def __enter__(self) -> _SharedRows:
        return self

    def __exit__(self, *exc: object) -> None:
        if self._threads is not None:
            self._threads.shutdown()

    def _shared(self, basis: np.ndarray) -> bool:
        """Whether ``basis`` is large enough for the threads to pay (below, they cost more than they share out)."""
        return self._threads is not None and basis.size >= SHARED_GRAM_SCHMIDT_ENTRIES

    def project(self, basis: np.ndarray, vectors: np.ndarray) -> np.ndarray:
        """V^T Y (``basis`` V and ``vectors`` Y on the same rows)."""
        if not self._shared(basis):
            return basis.T @ vectors
        assert self._threads is not None  # _shared says so
        return sum(self._threads.map(lambda rows: basis[rows].T @ vectors[rows], self._shares))

    def subtract(self, vectors: np.ndarray, basis: np.ndarray, coefficients: np.ndarray) -> None:
        """Y -= V S in place."""
        if not self._shared(basis):
            vectors -= basis @ coefficients
            return

        def share(rows: slice) -> None:
            vectors[rows] -= basis[rows] @ coefficients
        assert self._threads is not None  # _shared says so
        list(self._threads.map(share, self._shares))


def _orthogonalise(images: np.ndarray, mass: _MassRows, basis: np.ndarray, *, recent: int,
                   rows: _SharedRows) -> np.ndarray:
    """Make ``images`` M-orthogonal to ``basis`` in place; the coefficients V^T M Y removed.

    Classical Gram-Schmidt, first against the vectors from ``recent`` on (the last two blocks, which
    hold all of W Q_j's projection in exact arithmetic), then against the whole basis, which removes
    the rounding by which Lanczos vectors lose their orthogonality; once more if that pass removed
    more than half of what was left (twice is enough after a pass that removes little).
    """
    coupling = np.zeros((basis.shape[1], images.shape[1]))
    mass_images = mass @ images
    for part in (slice(recent, None), slice(None), slice(None)):
        before = np.einsum("im,im->m", images, mass_images)
        step = rows.project(basis[:, part], mass_images)  # V^T M Y, with M V never stored
        rows.subtract(images, basis[:, part], step)
        coupling[part] += step
        mass_images = mass @ images  # the next pass's, and the norms after this one
        if part.start is None and np.all(np.einsum("im,im->m", images, mass_images) > 0.25 * before):
            break
    return coupling


def _orthonormal(vectors: np.ndarray, mass: _MassRows, *, floor: float) -> tuple[np.ndarray, np.ndarray]:
    """M-orthonormal Q and R with vectors = Q R, the directions whose M-norm is below ``floor`` dropped.

    From the eigen-decomposition of the Gram matrix, twice: one pass leaves Q's columns orthogonal to
    rounding times the square of the block's condition, the second to rounding.
    """
    q, r = vectors, None
    for _ in range(2):
        gram = q.T @ (mass @ q)
        values, axes = np.linalg.eigh(0.5 * (gram + gram.T))
        keep = values > floor ** 2
        root = np.sqrt(values[keep])
        q, step = q @ (axes[:, keep] / root), root[:, None] * axes[:, keep].T
        r = step if r is None else step @ r
        floor = 0.5  # the second pass: columns of norm ~1, none to drop
    assert r is not None  # two passes made it
    return q, r


def _fresh_images(images_of: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]], mass: _MassRows,
                  basis: np.ndarray, rng: np.random.Generator, width: int) -> np.ndarray | None:
    """``width`` images of W of random vectors (on M's rows), M-orthonormal to ``basis``; None when none is left
    outside it."""
    images, _ = images_of(rng.standard_normal((basis.shape[0], width)))
    before = float(np.sqrt(np.max(np.einsum("im,im->m", images, mass @ images)))) if width else 0.0
    for _ in range(2):
        images -= basis @ (basis.T @ (mass @ images))
    fresh, _ = _orthonormal(images, mass, floor=DEFLATION_TOLERANCE * max(before, 1e-300))
    return fresh if fresh.shape[1] else None
