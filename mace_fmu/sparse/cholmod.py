"""CHOLMOD as cvxopt's wheels ship it: loaded on a BLAS that suits the processor, and solving many
right-hand sides in one pass over the factor.

Two things in cvxopt's Linux wheels (1.3.x, CHOLMOD 3.0.6) cost the 100k-DOF lattices most of their
time (benchmarks/RESULTS.md, "A BLAS for CHOLMOD and block solves"; the figures by module in "The sparse
solver's figures, by module"):

* Their CHOLMOD is linked against a serial reference-grade ATLAS (``libsatlas``), although the wheels
  carry an OpenBLAS for cvxopt's own BLAS module, and that OpenBLAS (0.3.15) does not know recent
  processors and falls back to its Prescott (SSE3) kernels, a fraction of the speed of the processor's
  AVX-512 ones. CHOLMOD's supernodal factorisation is dense BLAS 3 on its supernodes, so its time is the
  BLAS's. :func:`load` therefore has OpenBLAS select its kernels again with the processor's name
  for them (AVX-512: SkylakeX, AVX2 and FMA: Haswell) unless the user named them
  (``OPENBLAS_CORETYPE``), and makes the OpenBLAS that cvxopt loaded the one CHOLMOD's BLAS calls
  bind to (RTLD_GLOBAL, before CHOLMOD is loaded). Both only where they apply: Linux, CHOLMOD not
  loaded before, the libraries found; otherwise CHOLMOD runs as shipped, slower, with the same results.
* cvxopt's ``cholmod.solve`` solves the columns of a right-hand side one after another, each a full
  pass over the factor (hundreds of megabytes at 100k DOFs), and a solve's cost is that reading.
  CHOLMOD's own ``cholmod_l_solve`` takes them together, in dense blocks, in one pass.
  :class:`CholeskySolve` calls it through ctypes on the factor cvxopt computed, after checking that the
  factor's layout is the one expected; two halves of a wide block go to the two cores (the call releases
  the GIL, and cvxopt's OpenBLAS runs one thread).

CHOLMOD's structures are read and written through their declarations in
:mod:`mace_fmu.sparse.cholmod_structs`, never by offset.
"""

from __future__ import annotations

import ctypes
import functools
import glob
import os
import platform
import sys
import threading
import weakref
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np
from scipy import sparse

from mace_fmu.sparse.cholmod_structs import (CHOLMOD_A, CHOLMOD_AUTO, CHOLMOD_DOUBLE, CHOLMOD_LONG, CHOLMOD_REAL,
                                             CHOLMOD_SUPERNODAL, CholmodCommon, CholmodDense, CholmodFactor,
                                             CholmodSparse)

#: Columns below which a block is solved on one core: on fewer the two threads' overhead ate what the second core
#: saved (benchmarks/RESULTS.md, "The sparse solver's figures, by module").
PARALLEL_MIN_COLUMNS = 16


def load() -> ModuleType | None:
    """cvxopt's ``cholmod`` module, loaded on the fastest BLAS the wheels carry; None without cvxopt.

    Returns
    -------
    module or None
        ``cvxopt.cholmod``.
    """
    if "cvxopt.cholmod" not in sys.modules:
        _prepare_blas()
    try:
        from cvxopt import cholmod
    except ImportError:
        return None
    return cholmod


def _prepare_blas() -> None:
    """Give cvxopt's OpenBLAS the kernels of this processor and put it first in the global symbol scope."""
    if platform.system() != "Linux":
        return
    try:
        import cvxopt  # python-control imports it too: its OpenBLAS may be loaded already, on either route
    except ImportError:
        return
    for path in _wheel_libraries(Path(cvxopt.__file__).parent, "libopenblas"):
        try:
            library = ctypes.CDLL(str(path), mode=ctypes.RTLD_GLOBAL)  # loaded by cvxopt: promoted, not reloaded
        except OSError:
            continue
        _choose_kernels(library)
        return


def _choose_kernels(openblas: ctypes.CDLL) -> None:
    """Re-run OpenBLAS's kernel selection (DYNAMIC_ARCH) with this processor's name for it, unless the user
    named one (``OPENBLAS_CORETYPE``) or the library chose it already. OpenBLAS reads the variable when it
    selects, which it did when cvxopt loaded it; ``gotoblas_dynamic_quit`` and ``gotoblas_dynamic_init``
    select again, here before any of CHOLMOD's calls."""
    wanted = None if "OPENBLAS_CORETYPE" in os.environ else _openblas_coretype()
    try:
        corename, again, forget = openblas.openblas_get_corename, openblas.gotoblas_dynamic_init, \
            openblas.gotoblas_dynamic_quit
    except AttributeError:  # not a DYNAMIC_ARCH build: its kernels are fixed
        return
    corename.restype = ctypes.c_char_p
    if wanted is None or corename().decode().lower() == wanted.lower():
        return
    os.environ["OPENBLAS_CORETYPE"] = wanted
    try:
        forget()
        again()
    finally:
        del os.environ["OPENBLAS_CORETYPE"]  # the processes this one starts choose for themselves


def _openblas_coretype() -> str | None:
    """OpenBLAS's name for the widest kernels this x86-64 processor runs, from /proc/cpuinfo's flags."""
    if platform.machine() not in ("x86_64", "AMD64"):
        return None
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as cpuinfo:
            flags = next((line.split(":", 1)[1].split() for line in cpuinfo if line.startswith("flags")), [])
    except OSError:
        return None
    if {"avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"} <= set(flags):
        return "SkylakeX"
    if {"avx2", "fma"} <= set(flags):
        return "Haswell"
    return None


def _wheel_libraries(package: Path, stem: str) -> list[Path]:
    """Shared libraries named ``stem*`` that a cvxopt wheel carries (auditwheel's and delocate's folders)."""
    folders = (package.parent / "cvxopt.libs", package / ".dylibs", package)
    return [Path(found) for folder in folders for found in sorted(glob.glob(str(folder / f"{stem}*")))]


@dataclass(frozen=True)
class FactorLayout:
    """What a cholmod_factor (:class:`~mace_fmu.sparse.cholmod_structs.CholmodFactor`) says of itself: where it
    lies, its order and size, and the types of its integers and values."""

    address: int  #: where the cholmod_factor lies
    rows: int  #: its order n
    entries: int  #: xsize: entries of the supernodal factor, its dense blocks' padding included
    index_type: int  #: itype (2: 64-bit integers, cholmod_l_*)
    value_type: int  #: xtype (1: real)
    precision: int  #: dtype (0: double)
    supernodal_ll: bool = False  #: is_super and is_ll: a supernodal L L^T (what :meth:`CholeskySolve.triangular` needs)


def factor_layout(symbolic: object, rows: int) -> FactorLayout | None:
    """The cholmod_factor inside cvxopt's capsule ``symbolic`` (or a :class:`SymbolicFactor`), when it is one of
    order ``rows``.

    Parameters
    ----------
    symbolic : object
        ``cvxopt.cholmod.symbolic``'s result or a :class:`SymbolicFactor`.
    rows : int
        The order of the analysed matrix.

    Returns
    -------
    FactorLayout or None
        None when the object is not a CHOLMOD factor of that order or its sizes are out of range.
    """
    if isinstance(symbolic, SymbolicFactor):
        return _layout_at(symbolic.address, rows)
    api = ctypes.pythonapi
    api.PyCapsule_GetName.restype = ctypes.c_char_p
    api.PyCapsule_GetName.argtypes = [ctypes.py_object]
    api.PyCapsule_GetPointer.restype = ctypes.c_void_p
    api.PyCapsule_GetPointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
    try:
        name = api.PyCapsule_GetName(symbolic)
        if not name or not name.startswith(b"CHOLMOD FACTOR"):
            return None
        address = api.PyCapsule_GetPointer(symbolic, name)
    except (TypeError, ValueError, ctypes.ArgumentError):
        return None
    return _layout_at(address, rows)


def _layout_at(address: int, rows: int) -> FactorLayout | None:
    factor = CholmodFactor.from_address(address)
    if factor.n != rows or not rows <= factor.xsize <= rows * (rows + 1):
        return None
    return FactorLayout(address, factor.n, factor.xsize, factor.itype, factor.xtype, factor.dtype,
                        supernodal_ll=bool(factor.is_ll) and bool(factor.is_super))


def _long_array(address: int, count: int) -> np.ndarray:
    """A copy of ``count`` 64-bit integers at ``address`` (an array a cholmod_l_* factor holds)."""
    return np.ctypeslib.as_array((ctypes.c_int64 * count).from_address(address)).copy() if count else \
        np.zeros(0, dtype=np.int64)


@functools.cache
def _cholmod_library() -> ctypes.CDLL | None:
    """The CHOLMOD library cvxopt's extension uses (the same file, so the same loaded copy), or None."""
    try:
        import cvxopt.cholmod
    except ImportError:
        return None
    package = Path(cvxopt.__file__).parent
    for candidate in [*_wheel_libraries(package, "libcholmod"), Path(cvxopt.cholmod.__file__)]:
        try:
            library = ctypes.CDLL(str(candidate))
            solve, start, finish, free, factorize = (library.cholmod_l_solve, library.cholmod_l_start,
                                                     library.cholmod_l_finish, library.cholmod_l_free_dense,
                                                     library.cholmod_l_factorize)
            analyze, analyze_p = library.cholmod_l_analyze, library.cholmod_l_analyze_p
            free_factor = library.cholmod_l_free_factor
            sweeps = library.cholmod_l_super_lsolve, library.cholmod_l_super_ltsolve
        except (OSError, AttributeError):
            continue
        factorize.restype = ctypes.c_int
        common = ctypes.POINTER(CholmodCommon)  # a factor goes by its address, cvxopt's capsule's or CHOLMOD's
        factorize.argtypes = [ctypes.POINTER(CholmodSparse), ctypes.c_void_p, common]
        analyze.restype = analyze_p.restype = ctypes.c_void_p
        analyze.argtypes = [ctypes.POINTER(CholmodSparse), common]
        analyze_p.argtypes = [ctypes.POINTER(CholmodSparse), ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, common]
        free_factor.argtypes = [ctypes.POINTER(ctypes.c_void_p), common]
        for sweep in sweeps:
            sweep.restype = ctypes.c_int
            sweep.argtypes = [ctypes.c_void_p, ctypes.POINTER(CholmodDense), ctypes.POINTER(CholmodDense), common]
        solve.restype = ctypes.POINTER(CholmodDense)
        solve.argtypes = [ctypes.c_int, ctypes.c_void_p, ctypes.POINTER(CholmodDense), common]
        free.argtypes = [ctypes.POINTER(ctypes.POINTER(CholmodDense)), common]
        start.argtypes = finish.argtypes = [common]
        return library
    return None


def _lower_triangle(lower: sparse.csc_array) -> tuple[CholmodSparse, tuple[np.ndarray, ...]]:
    """``lower`` as CHOLMOD's sparse matrix (stype -1: the lower triangle of a symmetric one), and the arrays it
    points into, which must outlive CHOLMOD's use of it."""
    n = lower.shape[0]
    indptr, indices = lower.indptr.astype(np.int64), lower.indices.astype(np.int64)
    values = np.ascontiguousarray(lower.data, dtype=float)
    matrix = CholmodSparse(n, n, len(values), indptr.ctypes.data, indices.ctypes.data, None, values.ctypes.data,
                           None, -1, CHOLMOD_LONG, CHOLMOD_REAL, CHOLMOD_DOUBLE, 1, 1)
    return matrix, (indptr, indices, values)


class SymbolicFactor:
    """A CHOLMOD factor made by a symbolic analysis through ctypes (:func:`symbolic_factor`), freed with this
    object. :func:`numeric` fills it, :class:`CholeskySolve` solves with it, as with cvxopt's."""

    def __init__(self, library: ctypes.CDLL, address: int):
        self.address = address
        weakref.finalize(self, _free_factor, library, address)


def symbolic_factor(lower: sparse.csc_array, permutation: np.ndarray | None = None) -> SymbolicFactor | None:
    """CHOLMOD's supernodal symbolic analysis of ``lower``'s matrix in the order ``permutation`` (None: CHOLMOD's
    own, AMD), through ctypes with Python's lock released.

    The factor ``cvxopt.cholmod.symbolic`` makes with cvxopt's options (supernodal; with a permutation, that one
    only), without holding the lock: the candidate orderings' analyses run beside each other and beside the
    nested dissection's ordering (mace_fmu.sparse.ordering; AMD's the longest), and two substructures' side by
    side (mace_fmu.sparse.substructures), where cvxopt's made the second wait for the first.

    Parameters
    ----------
    lower : scipy.sparse.csc_array
        The lower triangle of the symmetric matrix, its row indices sorted within each column.
    permutation : numpy.ndarray, optional
        Row ``permutation[i]`` goes to position i; None for CHOLMOD's own ordering.

    Returns
    -------
    SymbolicFactor or None
        None when CHOLMOD is not reachable through ctypes or its workspace is not laid out as expected.
    """
    library = _cholmod_library()
    if library is None:
        return None
    matrix, _arrays = _lower_triangle(lower)
    order = None if permutation is None else np.ascontiguousarray(permutation, dtype=np.int64)
    common = CholmodCommon()
    library.cholmod_l_start(common)
    try:
        # cholmod_l_start's defaults, from the first field read to the last: a CHOLMOD whose cholmod_common is not
        # laid out as declared (another version) is left to cvxopt
        if (common.supernodal_switch != 40.0 or common.supernodal != CHOLMOD_AUTO or common.print != 3
                or common.nmethods != 0 or common.itype != CHOLMOD_LONG or common.dtype != CHOLMOD_DOUBLE):
            return None
        common.supernodal = CHOLMOD_SUPERNODAL  # as cvxopt's analyses, whatever the matrix's size
        if order is None:
            address = library.cholmod_l_analyze(ctypes.byref(matrix), common)
        else:
            common.nmethods = 1  # the given order only, as cvxopt's analysis with a permutation
            address = library.cholmod_l_analyze_p(ctypes.byref(matrix), order.ctypes.data, None, 0, common)
        return SymbolicFactor(library, address) if address else None
    finally:
        library.cholmod_l_finish(common)


def _free_factor(library: ctypes.CDLL, address: int) -> None:
    common = CholmodCommon()
    library.cholmod_l_start(common)
    library.cholmod_l_free_factor(ctypes.byref(ctypes.c_void_p(address)), common)
    library.cholmod_l_finish(common)


def numeric(symbolic: object, lower: sparse.csc_array) -> bool | None:
    """CHOLMOD's numeric factorisation of ``lower``'s matrix into the ``symbolic`` factor, through ctypes.

    What ``cvxopt.cholmod.numeric`` does, but with the GIL released while CHOLMOD works, so that two
    factors can be computed on two cores at once (mace_fmu.sparse.substructures).

    Parameters
    ----------
    symbolic : object
        ``cvxopt.cholmod.symbolic``'s result or :func:`symbolic_factor`'s for the same pattern.
    lower : scipy.sparse.csc_array
        The lower triangle of the symmetric matrix, its row indices sorted within each column.

    Returns
    -------
    bool or None
        True when the matrix is positive definite and factored, False when CHOLMOD met a non-positive pivot,
        None when the factor cannot be reached through ctypes (the caller takes cvxopt's route).
    """
    n = lower.shape[0]
    layout = factor_layout(symbolic, n)
    library = _cholmod_library()
    if library is None or layout is None or layout.index_type != CHOLMOD_LONG:
        return None
    matrix, _arrays = _lower_triangle(lower)
    common = CholmodCommon()
    library.cholmod_l_start(common)
    try:
        done = library.cholmod_l_factorize(ctypes.byref(matrix), layout.address, common)
    finally:
        library.cholmod_l_finish(common)
    if not done:
        return None
    return CholmodFactor.from_address(layout.address).minor == n  # minor: where a non-positive pivot stopped it


class CholeskySolve:
    """x = solve(b) on a CHOLMOD factor: every column of ``b`` in one call.

    Parameters
    ----------
    factor : object
        ``cvxopt.cholmod``'s numeric factor (the symbolic one after ``cholmod.numeric``), or a
        :class:`SymbolicFactor` after :func:`numeric`.
    rows : int
        Its order.
    """

    def __init__(self, factor: object, rows: int):
        self._factor = factor  # keeps the cholmod_factor alive as long as this object
        self.rows = rows
        layout = factor_layout(factor, rows)
        library = _cholmod_library()
        self._direct = (library is not None and layout is not None and layout.index_type == CHOLMOD_LONG
                        and layout.value_type == CHOLMOD_REAL and layout.precision == CHOLMOD_DOUBLE)
        if not self._direct:
            return
        assert library is not None and layout is not None  # as _direct says
        self._library: ctypes.CDLL = library
        self._address = layout.address
        self._fields = CholmodFactor.from_address(layout.address)  # read in place: what CHOLMOD holds now
        # one cholmod_common (CHOLMOD's workspace) for each of the two threads a block is shared between
        self._commons = [CholmodCommon() for _ in range(2)]
        self._busy = threading.Lock()
        for common in self._commons:
            library.cholmod_l_start(common)
        weakref.finalize(self, _finish, library, self._commons)

    def __call__(self, b: np.ndarray) -> np.ndarray:
        """Solve for ``b`` of shape (rows,) or (rows, k)."""
        b = np.asarray(b, dtype=float)
        columns = b.reshape(self.rows, -1)
        if not self._direct:
            return self._cvxopt_solve(columns).reshape(b.shape)
        width = columns.shape[1]
        with self._busy:  # a cholmod_common keeps CHOLMOD's status and memory counts: one caller at a time
            if width < PARALLEL_MIN_COLUMNS:
                return self._solve_block(columns, self._commons[0]).reshape(b.shape)
            half = width // 2
            with ThreadPoolExecutor(max_workers=2) as threads:
                parts = list(threads.map(self._solve_block, (columns[:, :half], columns[:, half:]), self._commons))
        return np.hstack(parts).reshape(b.shape)

    @functools.cached_property  # fixed once factored; read by every sweep
    def supernodal_ll(self) -> bool:
        """True when CHOLMOD's own solve is called through ctypes on a supernodal L L^T factor: what
        :meth:`triangular`, :meth:`permutation` and :meth:`trailing_block` need (a simplicial factor, which
        CHOLMOD may choose for a very sparse matrix, holds L D L^T and none of the supernodes read)."""
        if not self._direct:
            return False
        layout = factor_layout(self._factor, self.rows)
        return layout is not None and layout.supernodal_ll

    def triangular(self, b: np.ndarray, *, transpose: bool) -> np.ndarray:
        """Solve L x = b (or L^T x = b) with the factor's own triangle, in its order (P A P^T = L L^T).

        Parameters
        ----------
        b : numpy.ndarray
            Shape (rows, k), in the factor's order (row j is the matrix's row ``permutation()[j]``).
        transpose : bool
            Solve with L^T instead of L.

        Returns
        -------
        numpy.ndarray
            x, shape (rows, k).
        """
        x = np.array(b, dtype=float, order="F")
        self.sweep(x, transpose=transpose, workspace=self.sweep_workspace(x.shape[1]))
        return x

    def sweep_workspace(self, columns: int) -> np.ndarray:
        """The workspace :meth:`sweep` needs for ``columns`` right-hand sides (the largest supernode's rows below
        its columns, times ``columns``)."""
        return np.empty(max(columns * self._fields.maxesize, 1))

    def sweep(self, x: np.ndarray, *, transpose: bool, workspace: np.ndarray) -> None:
        """Solve L x = b (or L^T x = b) in place: ``x`` holds b, in the factor's order, and is overwritten by x.

        What :meth:`triangular` does without allocating: CHOLMOD's supernodal sweep on the caller's arrays (the
        substructures' solves keep theirs from one block to the next).

        Parameters
        ----------
        x : numpy.ndarray
            Shape (rows, k), column-major (Fortran order), float64.
        transpose : bool
            Solve with L^T instead of L.
        workspace : numpy.ndarray
            From :meth:`sweep_workspace` for k columns or more.
        """
        rows, width = x.shape
        if (rows != self.rows or x.dtype != np.float64 or not x.flags.f_contiguous or workspace.dtype != np.float64
                or not workspace.flags.c_contiguous or workspace.size < width * self._fields.maxesize):
            raise ValueError("sweep needs a column-major float64 array of the factor's rows and a large enough "
                             "workspace (sweep_workspace)")
        if not self.supernodal_ll:
            raise ValueError("only a supernodal L L^T factor has the sweeps")
        solution = CholmodDense(rows, width, rows * width, rows, x.ctypes.data, None, CHOLMOD_REAL, CHOLMOD_DOUBLE)
        scratch = CholmodDense(workspace.size, 1, workspace.size, workspace.size, workspace.ctypes.data, None,
                               CHOLMOD_REAL, CHOLMOD_DOUBLE)
        sweep = self._library.cholmod_l_super_ltsolve if transpose else self._library.cholmod_l_super_lsolve
        with self._busy:  # the status CHOLMOD writes into the cholmod_common
            done = sweep(self._address, ctypes.byref(solution), ctypes.byref(scratch), self._commons[0])
        if not done:
            raise ArithmeticError("CHOLMOD's triangular sweep failed (an integer overflow in the BLAS)")

    def permutation(self) -> np.ndarray:
        """The factor's ordering P: row j of the factor is row ``permutation()[j]`` of the matrix."""
        return _long_array(self._fields.Perm, self.rows)

    def trailing_block(self, size: int) -> np.ndarray:
        """The last ``size`` rows and columns of the supernodal factor L, a dense lower triangle.

        Parameters
        ----------
        size : int
            How many of the factor's last rows and columns.

        Returns
        -------
        numpy.ndarray
            Shape (size, size), in the factor's order.
        """
        factor = self._fields
        supernodes, first = factor.nsuper, self.rows - size
        bounds = _long_array(factor.super, supernodes + 1)  # each supernode's first column
        row_start = _long_array(factor.pi, supernodes + 1)  # where its row indices start in s
        value_start = _long_array(factor.px, supernodes + 1)  # where its values start in x
        last = int(np.searchsorted(bounds, first, side="right")) - 1  # the supernode that holds column ``first``
        # s: the row indices of those supernodes only (all of them are millions of entries)
        rows_of = _long_array(factor.s + 8 * int(row_start[last]), int(row_start[-1] - row_start[last]))
        values = np.ctypeslib.as_array((ctypes.c_double * factor.xsize).from_address(factor.x))
        block = np.zeros((size, size))
        # a supernode is a dense column-major block: its columns, and every row below them that they reach
        for k in range(last, supernodes):
            k1, k2 = int(bounds[k]), int(bounds[k + 1])
            rows = rows_of[row_start[k] - row_start[last]:row_start[k + 1] - row_start[last]]
            dense = values[value_start[k]:value_start[k] + len(rows) * (k2 - k1)].reshape(k2 - k1, len(rows)).T
            c0, below = max(k1, first), int(np.searchsorted(rows, first))  # a supernode's rows are sorted
            at = rows[below:] - first
            if len(at) and at[-1] - at[0] == len(at) - 1:  # consecutive rows (the last supernodes' are): a slice
                block[at[0]:at[-1] + 1, c0 - first:k2 - first] = dense[below:, c0 - k1:]
            else:
                block[at, c0 - first:k2 - first] = dense[below:, c0 - k1:]
        return np.tril(block)

    def _solve_block(self, columns: np.ndarray, common: CholmodCommon) -> np.ndarray:
        rhs = np.asfortranarray(columns)
        rows, width = rhs.shape
        dense = CholmodDense(rows, width, rows * width, rows, rhs.ctypes.data, None, CHOLMOD_REAL, CHOLMOD_DOUBLE)
        solution = self._library.cholmod_l_solve(CHOLMOD_A, self._address, ctypes.byref(dense), common)
        if not solution and isinstance(self._factor, SymbolicFactor):  # cvxopt cannot solve with it
            raise MemoryError("CHOLMOD could not allocate the workspace of a solve")
        if not solution:  # CHOLMOD could not allocate its workspace: the slower route has its own
            return self._cvxopt_solve(columns)
        try:
            values = ctypes.cast(solution.contents.x, ctypes.POINTER(ctypes.c_double))
            # CHOLMOD's columns as they lie (column-major): a copy without a transposition
            return np.ctypeslib.as_array(values, shape=(width, rows)).T.copy(order="F")
        finally:
            self._library.cholmod_l_free_dense(ctypes.byref(solution), common)

    def _cvxopt_solve(self, columns: np.ndarray) -> np.ndarray:
        import cvxopt
        import cvxopt.cholmod

        x = cvxopt.matrix(np.ascontiguousarray(columns))
        cvxopt.cholmod.solve(self._factor, x)
        return np.asarray(x)


def _finish(library: ctypes.CDLL, commons: list[CholmodCommon]) -> None:
    for common in commons:
        library.cholmod_l_finish(common)
