"""CHOLMOD through cvxopt: block solves through cholmod_l_solve equal scipy's sparse LU, and on the
wheels' layout CHOLMOD's BLAS calls go to OpenBLAS with kernels named for the processor."""

from __future__ import annotations

import os
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import sparse
from scipy.sparse.linalg import splu
from support.decks import frame_tower

from mace_fmu.deck.reader import read_deck_text
from mace_fmu.fe.assembly import assemble
from mace_fmu.fe.constraints import build_constraints
from mace_fmu.sparse import cholmod
from mace_fmu.sparse.factor import factorize

cvxopt = pytest.importorskip("cvxopt")


@pytest.fixture(scope="module")
def lattice() -> tuple[sparse.csr_array, np.ndarray]:
    """K + M of a clamped 4 x 4-grid lattice, 6 levels (576 DOFs), and the grid of each row."""
    deck = read_deck_text(frame_tower(nx=4, ny=4, levels=6), name="lattice.bdf")
    model = assemble(deck)
    constraints = build_constraints(deck, model.dofs, model.cd_frames, spc_set=1, mpc_set=None)
    k = constraints.reduce_sparse(model.stiffness)
    m = constraints.reduce_sparse(model.mass)
    return sparse.csr_array(0.5 * (k + k.T) + 0.5 * (m + m.T)), np.array([g for g, _ in constraints.independent])


@pytest.mark.parametrize("width", [1, 3, 16, 33])
def test_block_solves_equal_scipys_lu(lattice, width):
    """1, 3, 16 and 33 right-hand sides (16 and 33 shared between two threads): the solutions equal SuperLU's
    of the same matrix within 1e-11 of their largest entry."""
    matrix, grids = lattice
    b = np.random.default_rng(width).standard_normal((matrix.shape[0], width))
    solve = factorize(matrix, positive_definite=True, groups=grids)
    assert isinstance(solve, cholmod.CholeskySolve) and solve._direct  # CHOLMOD's block solve, not the fallback
    expected = splu(sparse.csc_array(matrix)).solve(b)
    np.testing.assert_allclose(solve(b), expected, rtol=0, atol=1e-11 * np.abs(expected).max())
    np.testing.assert_allclose(solve(b[:, 0]), expected[:, 0], rtol=0, atol=1e-11 * np.abs(expected).max())


def test_cvxopts_column_by_column_solve_gives_the_same(lattice):
    """The fallback (cvxopt's own solve, where the factor's layout is not the one expected: a factor cvxopt made,
    as where CHOLMOD cannot be reached through ctypes) agrees to 1e-13."""
    from mace_fmu.sparse.ordering import _symbolic, analyse

    matrix, grids = lattice
    b = np.random.default_rng(0).standard_normal((matrix.shape[0], 5))
    analysis = analyse(matrix, groups=grids)
    symbolic = _symbolic(cholmod.load(), analysis.lower, analysis.permutation)
    cholmod.load().numeric(analysis.lower, symbolic)
    solve = cholmod.CholeskySolve(symbolic, matrix.shape[0])
    direct = solve(b)
    solve._direct = False
    np.testing.assert_allclose(solve(b), direct, rtol=0, atol=1e-13 * np.abs(direct).max())


def test_the_factor_layout_is_read_and_checked(lattice):
    """The cholmod_factor's order, 64-bit indices, a pattern after the symbolic analysis and real doubles after
    the numeric factorisation; an object that is not a factor, or a factor of another order, gives None."""
    matrix, grids = lattice
    from mace_fmu.sparse.ordering import _symbolic, analyse

    analysis = analyse(matrix, groups=grids)
    symbolic = _symbolic(cholmod.load(), analysis.lower, analysis.permutation)  # cvxopt's capsule
    layout = cholmod.factor_layout(symbolic, matrix.shape[0])
    assert layout is not None
    assert (layout.rows, layout.index_type, layout.value_type, layout.precision) == (matrix.shape[0], 2, 0, 0)
    cholmod.load().numeric(analysis.lower, symbolic)
    assert cholmod.factor_layout(symbolic, matrix.shape[0]).value_type == 1
    assert layout.entries >= sparse.tril(matrix).nnz
    assert cholmod.factor_layout(symbolic, matrix.shape[0] + 1) is None
    assert cholmod.factor_layout(object(), matrix.shape[0]) is None
    # the analysis's own factor, made through ctypes, has the same layout and size
    assert isinstance(analysis.symbolic, cholmod.SymbolicFactor)
    assert cholmod.factor_layout(analysis.symbolic, matrix.shape[0]).entries == layout.entries


def _wheel_layout() -> bool:
    package = Path(cvxopt.__file__).parent
    return bool(cholmod._wheel_libraries(package, "libopenblas") and cholmod._wheel_libraries(package, "libcholmod"))


@pytest.mark.skipif(platform.system() != "Linux" or not _wheel_layout(),
                    reason="cvxopt's Linux wheels carry OpenBLAS and CHOLMOD as separate libraries")
def test_cholmods_blas_is_openblas_with_the_processors_kernels():
    """In a fresh process that imported python-control first (which loads cvxopt and its OpenBLAS, as the
    CLI does): after ``load`` the dynamic linker binds libcholmod's dgemm_, dsyrk_ and dpotrf_ to the
    wheels' OpenBLAS (not the ATLAS they link), OpenBLAS runs the kernels named for this processor, and
    OPENBLAS_CORETYPE is gone from the environment again."""
    code = ("import ctypes, os\n"
            "import control\n"
            "from pathlib import Path\n"
            "from mace_fmu.sparse import cholmod\n"
            "cholmod.load()\n"
            "import cvxopt\n"
            "lib = ctypes.CDLL(str(cholmod._wheel_libraries(Path(cvxopt.__file__).parent, 'libopenblas')[0]))\n"
            "lib.openblas_get_corename.restype = ctypes.c_char_p\n"
            "print('core', lib.openblas_get_corename().decode(), 'OPENBLAS_CORETYPE' in os.environ)\n")
    env = {key: value for key, value in os.environ.items() if key != "OPENBLAS_CORETYPE"}
    env["LD_DEBUG"] = "bindings"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    bindings = [line for line in run.stderr.splitlines() if "libcholmod" in line.split(" to ")[0]]
    for symbol in ("dgemm_", "dsyrk_", "dpotrf_"):
        bound = [line for line in bindings if line.endswith(f"`{symbol}'")]
        assert bound and all("libopenblas" in line.split(" to ")[1] for line in bound), symbol
    core, in_environment = run.stdout.split()[1:]
    expected = cholmod._openblas_coretype()
    if expected is not None:
        assert core.lower() == expected.lower()
    assert in_environment == "False"



@pytest.mark.parametrize("shape", [(2, 2, 3), (4, 4, 6), (10, 10, 3)])
def test_cholmods_analyses_through_ctypes_size_the_factor_as_cvxopts(shape):
    """CHOLMOD's symbolic analyses through ctypes, which run beside each other and beside the nested dissection,
    size the same supernodal factor as cvxopt.cholmod.symbolic: CHOLMOD's own order (AMD) and each candidate's
    given order, on lattices of 72 (where CHOLMOD's default would take a simplicial factor), 576 and 1,800
    DOFs."""
    from mace_fmu.sparse.ordering import _entries, _lower_spmatrix, _symbolic, candidate_permutations

    deck = read_deck_text(frame_tower(nx=shape[0], ny=shape[1], levels=shape[2]), name="lattice.bdf")
    model = assemble(deck)
    constraints = build_constraints(deck, model.dofs, model.cd_frames, spc_set=1, mpc_set=None)
    matrix = sparse.csr_array(constraints.reduce_sparse(model.stiffness) + constraints.reduce_sparse(model.mass))
    matrix = sparse.csr_array(0.5 * (matrix + matrix.T))
    lower = sparse.csc_array(sparse.tril(matrix))
    lower.sort_indices()
    grids = np.array([g for g, _ in constraints.independent])
    orders = {"AMD": None, **candidate_permutations(matrix, groups=grids)}
    for name, permutation in orders.items():
        expected = _entries(_symbolic(cholmod.load(), _lower_spmatrix(matrix), permutation), matrix.shape[0])
        assert expected > 0
        assert _entries(cholmod.symbolic_factor(lower, permutation), matrix.shape[0]) == expected, name
