"""CHOLMOD's structures as declared in mace_fmu.sparse.cholmod_structs, held to the header and to the library.

Two independent sources: the offsets the C compiler (gcc, x86-64) gives for the fields of CHOLMOD 3.0.6's
``cholmod_core.h`` (SuiteSparse 4.4.6, the CHOLMOD cvxopt's wheels carry; ``offsetof`` on that header), which are
also the byte offsets and word indices the code read before the structures were declared; and the library itself:
``cholmod_l_start``'s documented defaults, and the factors CHOLMOD makes of small matrices whose factor is known
(dense and block-diagonal ones, a matrix whose fifth leading minor is negative), against numpy.
"""

from __future__ import annotations

import ctypes

import numpy as np
import pytest
from scipy import sparse

from mace_fmu.sparse import cholmod
from mace_fmu.sparse.cholmod_structs import (CHOLMOD_AUTO, CHOLMOD_DOUBLE, CHOLMOD_LONG, CHOLMOD_NOT_POSDEF,
                                             CHOLMOD_REAL, COMMON_BYTES, CholmodCommon, CholmodDense, CholmodFactor,
                                             CholmodMethod, CholmodSparse)

WORD = 8  # the offsets below are a 64-bit platform's (LP64 and LLP64 alike: size_t and pointers are 8 bytes)

#: offsetof(cholmod_common, field): the four the code read by byte offset before (supernodal_switch at 40,
#: supernodal 48, print 144, nmethods 168), then the compiler's for those after the method array
COMMON_OFFSETS = {"supernodal_switch": 40, "supernodal": 48, "print": 144, "nmethods": 168, "method": 184,
                  "postorder": 1864, "metis_nswitch": 1888, "itype": 1960, "dtype": 1964, "status": 1972,
                  "blas_ok": 2076}
#: the machine words (size_t and pointers) that open a cholmod_factor, by the index the code read them at before
FACTOR_WORDS = {"n": 0, "minor": 1, "Perm": 2, "x": 8, "nsuper": 13, "xsize": 15, "maxesize": 17, "super": 18,
                "pi": 19, "px": 20, "s": 21}
#: the ints after those 22 words, by their index there
FACTOR_INTS = {"ordering": 0, "is_ll": 1, "is_super": 2, "is_monotonic": 3, "itype": 4, "xtype": 5, "dtype": 6,
               "useGPU": 7}

pytestmark = pytest.mark.skipif(ctypes.sizeof(ctypes.c_void_p) != WORD, reason="the offsets are a 64-bit platform's")


def test_the_fields_lie_where_the_header_puts_them():
    """Each field at its offset in the C compiler's layout of cholmod_core.h, the sizes with it (a method 168 bytes,
    a factor 208, a sparse matrix 88, a dense one 56), and a common of 64 KiB in all, its room included."""
    assert {name: getattr(CholmodCommon, name).offset for name in COMMON_OFFSETS} == COMMON_OFFSETS
    assert ctypes.sizeof(CholmodMethod) == 168
    assert CholmodMethod.ordering.offset == 132 and CholmodMethod.nd_small.offset == 72
    assert ctypes.sizeof(CholmodCommon) == COMMON_BYTES == 1 << 16
    assert {name: getattr(CholmodFactor, name).offset for name in FACTOR_WORDS} == {
        name: WORD * index for name, index in FACTOR_WORDS.items()}
    assert {name: getattr(CholmodFactor, name).offset for name in FACTOR_INTS} == {
        name: 22 * WORD + 4 * index for name, index in FACTOR_INTS.items()}
    assert ctypes.sizeof(CholmodFactor) == 208
    assert (ctypes.sizeof(CholmodSparse), CholmodSparse.stype.offset, CholmodSparse.packed.offset) == (88, 64, 84)
    assert (ctypes.sizeof(CholmodDense), CholmodDense.x.offset, CholmodDense.dtype.offset) == (56, 32, 52)


@pytest.fixture(scope="module")
def library() -> ctypes.CDLL:
    pytest.importorskip("cvxopt")
    cholmod.load()
    found = cholmod._cholmod_library()
    if found is None:
        pytest.skip("CHOLMOD cannot be reached through ctypes")
    return found


def test_cholmod_l_start_fills_the_common_with_its_documented_defaults(library):
    """cholmod_core.h's defaults, read from every part of the declared common: the parameters before the methods, the
    nine methods' orderings (the given one, AMD, METIS, NESDIS, natural, NESDIS with nd_small 20000, with nd_small 4
    and no constrained minimum degree, with no dense rows removed, COLAMD), what follows them, the integer and
    value types of cholmod_l_*, the status and the BLAS flag."""
    common = CholmodCommon()
    library.cholmod_l_start(common)
    try:
        assert (common.grow0, common.grow1, common.grow2, common.maxrank) == (1.2, 1.2, 5, 8)
        assert (common.supernodal_switch, common.supernodal) == (40.0, CHOLMOD_AUTO)
        assert (common.final_asis, common.final_super, common.final_ll) == (1, 1, 0)
        assert (list(common.zrelax), list(common.nrelax)) == ([0.8, 0.1, 0.05], [4, 16, 48])
        assert (common.print, common.nmethods, common.current, common.selected) == (3, 0, 0, 0)
        assert [method.ordering for method in common.method][:9] == [1, 2, 3, 4, 0, 4, 4, 4, 5]
        assert [method.nd_small for method in common.method][4:7] == [200, 20000, 4]
        assert (common.method[6].nd_camd, common.method[7].prune_dense, common.method[0].prune_dense) == (0, -1.0, 10.0)
        assert (common.postorder, common.metis_dswitch, common.metis_nswitch) == (1, 0.66, 3000)
        assert (common.itype, common.dtype, common.status, common.blas_ok) == (CHOLMOD_LONG, CHOLMOD_DOUBLE, 0, 1)
    finally:
        library.cholmod_l_finish(common)


def _lower(matrix: np.ndarray) -> sparse.csc_array:
    lower = sparse.csc_array(np.tril(matrix))
    lower.sort_indices()
    return lower


def _spd(n: int, seed: int) -> np.ndarray:
    a = np.random.default_rng(seed).standard_normal((n, n))
    return a @ a.T + n * np.eye(n)


def test_a_dense_matrixs_factor_is_one_supernode_equal_to_lapacks(library):
    """A dense 10 x 10 positive definite matrix in a given order: one supernode of 10 columns and 10 rows, its 100
    values the lower triangle of numpy's Cholesky factor of the reordered matrix, the given order kept; the symbolic
    factor holds a pattern, the numeric one real doubles; the solve equals numpy's."""
    n = 10
    matrix = _spd(n, seed=1)
    order = np.random.default_rng(2).permutation(n)
    symbolic = cholmod.symbolic_factor(_lower(matrix), order)
    factor = CholmodFactor.from_address(symbolic.address)
    assert (factor.n, factor.is_ll, factor.is_super, factor.ordering, factor.nsuper) == (n, 1, 1, 1, 1)
    assert (factor.xsize, factor.ssize) == (n * n, n)
    assert (factor.itype, factor.xtype, factor.dtype) == (CHOLMOD_LONG, 0, CHOLMOD_DOUBLE)  # 0: a pattern yet
    assert cholmod.numeric(symbolic, _lower(matrix)) is True
    assert (factor.minor, factor.xtype) == (n, CHOLMOD_REAL)
    assert list(cholmod._long_array(factor.super, 2)) == [0, n]
    assert list(cholmod._long_array(factor.pi, 2)) == [0, n] and list(cholmod._long_array(factor.px, 2)) == [0, n * n]
    assert list(cholmod._long_array(factor.s, n)) == list(range(n))
    assert list(cholmod._long_array(factor.Perm, n)) == list(order)
    values = np.ctypeslib.as_array((ctypes.c_double * factor.xsize).from_address(factor.x)).reshape(n, n).T
    expected = np.linalg.cholesky(matrix[np.ix_(order, order)])
    np.testing.assert_allclose(np.tril(values), expected, rtol=0, atol=1e-13 * np.abs(expected).max())
    b = np.random.default_rng(3).standard_normal((n, 3))
    np.testing.assert_allclose(cholmod.CholeskySolve(symbolic, n)(b), np.linalg.solve(matrix, b), rtol=1e-12)


def test_a_block_diagonal_matrixs_factor_is_one_supernode_a_block(library):
    """Two dense blocks of 6 and 7 rows that share no entry, in their own order: two supernodes starting at columns
    0 and 6, 36 + 49 values, no row below either; the solve equals numpy's."""
    matrix = np.zeros((13, 13))
    matrix[:6, :6], matrix[6:, 6:] = _spd(6, seed=4), _spd(7, seed=5)
    symbolic = cholmod.symbolic_factor(_lower(matrix), np.arange(13))
    assert cholmod.numeric(symbolic, _lower(matrix)) is True
    factor = CholmodFactor.from_address(symbolic.address)
    assert (factor.nsuper, factor.xsize, factor.ssize) == (2, 36 + 49, 13)
    assert list(cholmod._long_array(factor.super, 3)) == [0, 6, 13]
    assert list(cholmod._long_array(factor.px, 3)) == [0, 36, 85]
    b = np.random.default_rng(6).standard_normal(13)
    np.testing.assert_allclose(cholmod.CholeskySolve(symbolic, 13)(b), np.linalg.solve(matrix, b), rtol=1e-12)


def test_a_non_positive_pivot_is_where_minor_and_status_say(library):
    """T D T^T with T unit lower triangular and D's fifth entry negative: the first four leading minors are positive,
    the fifth is not, so CHOLMOD stops at column 4 (from 0): Factor->minor is 4, Common->status CHOLMOD_NOT_POSDEF,
    and mace_fmu.sparse.cholmod.numeric says False."""
    n = 9
    unit = np.tril(np.random.default_rng(7).standard_normal((n, n)), -1) + np.eye(n)
    matrix = unit @ np.diag([1.0, 2.0, 1.5, 3.0, -1.0, 1.0, 2.0, 1.0, 1.0]) @ unit.T
    lower = _lower(matrix)
    symbolic = cholmod.symbolic_factor(lower, np.arange(n))
    assert cholmod.numeric(symbolic, lower) is False
    assert CholmodFactor.from_address(symbolic.address).minor == 4
    again = cholmod.symbolic_factor(lower, np.arange(n))
    sparse_matrix, _arrays = cholmod._lower_triangle(lower)
    common = CholmodCommon()
    library.cholmod_l_start(common)
    try:
        assert library.cholmod_l_factorize(ctypes.byref(sparse_matrix), again.address, common) == 1
        assert common.status == CHOLMOD_NOT_POSDEF
    finally:
        library.cholmod_l_finish(common)
    assert CholmodFactor.from_address(again.address).minor == 4
