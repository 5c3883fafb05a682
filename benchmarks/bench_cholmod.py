"""CHOLMOD's factorisation and solves, and the eigen-solution they serve, on a 100k-DOF lattice: with the BLAS
cvxopt's wheels link (``--blas shipped``) and with the one ``mace_fmu.sparse.cholmod`` chooses (``--blas chosen``).

Run by hand: ``python benchmarks/bench_cholmod.py [--size wide100k] [--eigen]``; each BLAS in its own process
(the choice is made once, when CHOLMOD loads). Paste the tables into benchmarks/RESULTS.md with the machine,
date and load. The matrix is K - sigma M of tests/support/decks.py's ``frame_tower`` (the shapes of
bench_fe_scale.py), clamped base, sigma as the modal solution takes it.

Columns: the factorisation [s]; ms per right-hand-side column for blocks of 1, 8, 16 and 32 columns solved in
one ``cholmod_l_solve`` call, the same blocks shared between two threads (16 and 32), and cvxopt's own
``cholmod.solve`` (column by column) on 16; the same matrix as two substructures on two cores
(mace_fmu.sparse.substructures, forced: their analyses, factors and interface [s], ms a column for 16, and the
largest difference of their solution from the whole factor's, relative to its largest entry); with ``--eigen`` the 50 lowest modes by the block Lanczos and by
ARPACK's single-vector Lanczos on the same factor (columns solved, seconds, largest relative difference of
the eigenvalues).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE.parent), str(HERE.parent / "tests")]

from bench_fe_scale import SIZES  # noqa: E402  (the benchmarks' shapes, importable after the path above)


def shifted_matrix(size: str):
    """K - sigma M, M, K and the grid of each row of the lattice of ``size``."""
    import numpy as np
    from scipy import sparse
    from support.decks import frame_tower

    from mace_fmu.deck.reader import read_deck_text
    from mace_fmu.fe.assembly import assemble
    from mace_fmu.fe.constraints import build_constraints

    nx, ny, levels = SIZES[size]
    deck = read_deck_text(frame_tower(nx=nx, ny=ny, levels=levels), name="lattice.bdf")
    model = assemble(deck)
    constraints = build_constraints(deck, model.dofs, model.cd_frames, spc_set=1, mpc_set=None)
    k = constraints.reduce_sparse(model.stiffness)
    m = constraints.reduce_sparse(model.mass)
    k, m = sparse.csr_array(0.5 * (k + k.T)), sparse.csr_array(0.5 * (m + m.T))
    sigma = -1e-6 * float(np.median(k.diagonal()[k.diagonal() > 0]) / np.median(m.diagonal()[m.diagonal() > 0]))
    return sparse.csr_array(k - sigma * m), k, m, sigma, np.array([g for g, _ in constraints.independent])


def run_one(size: str, blas: str, eigen: bool) -> dict:
    """In this process: the timings for one BLAS."""
    import numpy as np

    from mace_fmu.sparse import cholmod

    if blas == "shipped":
        cholmod._prepare_blas = lambda: None  # CHOLMOD on the BLAS its wheel links
    from mace_fmu.sparse.ordering import _symbolic, analyse

    shifted, k, m, sigma, grids = shifted_matrix(size)
    out = {"size": size, "blas": blas, "rows": shifted.shape[0]}
    analysis = analyse(shifted, groups=grids)
    # cvxopt's own factor in the chosen order: its one-column-at-a-time solve is one of the columns measured
    symbolic = _symbolic(cholmod.load(), analysis.lower, analysis.permutation)
    t0 = time.perf_counter()
    cholmod.load().numeric(analysis.lower, symbolic)
    out["factor_s"] = time.perf_counter() - t0
    solve = cholmod.CholeskySolve(symbolic, shifted.shape[0])
    rhs = np.random.default_rng(0).standard_normal((shifted.shape[0], 32))
    solve(rhs[:, :1])  # the first call touches the factor's pages

    def per_column_ms(call, width: int) -> float:
        t0 = time.perf_counter()
        call(rhs[:, :width])
        return 1e3 * (time.perf_counter() - t0) / width

    out["one_call_ms"] = {w: per_column_ms(lambda b: solve._solve_block(b, solve._commons[0]), w) for w in (1, 8, 16, 32)}
    out["two_threads_ms"] = {w: per_column_ms(solve, w) for w in (16, 32)}
    out["cvxopt_ms"] = per_column_ms(solve._cvxopt_solve, 16)
    from mace_fmu.sparse.substructures import substructured_cholesky

    t0 = time.perf_counter()
    halves = substructured_cholesky(shifted, analysis, min_factor_entries=0)
    out["substructures_s"] = time.perf_counter() - t0
    halves(rhs[:, :1])
    out["substructures_ms"] = per_column_ms(halves, 16)
    whole = solve(rhs[:, :16])
    out["substructures_apart"] = float(np.abs(halves(rhs[:, :16]) - whole).max() / np.abs(whole).max())
    if eigen:
        from scipy.sparse.linalg import LinearOperator, eigsh

        from mace_fmu.fe.modal import LANCZOS_TOLERANCE
        from mace_fmu.sparse.lanczos import lowest_modes

        t0 = time.perf_counter()
        block = lowest_modes(stiffness=k, mass=m, solve=solve, shift=sigma, count=50, tolerance=LANCZOS_TOLERANCE,
                             max_dimension=2000)
        out["block_lanczos"] = {"columns": block.solved_columns, "s": time.perf_counter() - t0}
        columns = 0

        def one_column(x: np.ndarray) -> np.ndarray:
            nonlocal columns
            columns += 1
            return solve(np.asarray(x, dtype=float).ravel())

        op = LinearOperator(shifted.shape, matvec=one_column, dtype=float)
        t0 = time.perf_counter()
        values = np.sort(eigsh(k, k=50, M=m, sigma=sigma, which="LM", OPinv=op, tol=LANCZOS_TOLERANCE, ncv=101,
                               return_eigenvectors=False))
        out["arpack"] = {"columns": columns, "s": time.perf_counter() - t0}
        out["eigenvalue_difference"] = float(np.max(np.abs(block.eigenvalues[:50] / values - 1)))
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--size", default="wide100k", choices=sorted(SIZES))
    parser.add_argument("--eigen", action="store_true", help="also the 50 lowest modes, block Lanczos and ARPACK")
    parser.add_argument("--one", choices=["shipped", "chosen"], help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(run_one(args.size, args.one, args.eigen)))
        return
    from common import print_run_header

    print_run_header(size=args.size)
    print("| BLAS | rows | factor [s] | 1 / 8 / 16 / 32 columns, one call [ms a column] | 16 / 32, two threads | "
          "cvxopt's solve, 16 | substructures: factor [s], 16 [ms a column], apart | block Lanczos: columns, s | "
          "ARPACK: columns, s | eigenvalues apart |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for blas in ("shipped", "chosen"):
        cmd = [sys.executable, str(Path(__file__).resolve()), "--one", blas, "--size", args.size]
        proc = subprocess.run(cmd + (["--eigen"] if args.eigen else []), capture_output=True, text=True, cwd=HERE,
                              check=False)
        if proc.returncode != 0:
            print(f"| {blas} | failed: {(proc.stderr.strip().splitlines() or ['?'])[-1]} |")
            continue
        r = json.loads(proc.stdout.strip().splitlines()[-1])
        one = " / ".join(f"{v:.0f}" for v in r["one_call_ms"].values())
        two = " / ".join(f"{v:.0f}" for v in r["two_threads_ms"].values())
        eig = (f"{r['block_lanczos']['columns']}, {r['block_lanczos']['s']:.1f} | {r['arpack']['columns']}, "
               f"{r['arpack']['s']:.1f} | {r['eigenvalue_difference']:.1e}") if "arpack" in r else "- | - | -"
        halves = f"{r['substructures_s']:.2f}, {r['substructures_ms']:.0f}, {r['substructures_apart']:.0e}"
        print(f"| {blas} | {r['rows']} | {r['factor_s']:.2f} | {one} | {two} | {r['cvxopt_ms']:.0f} | {halves} | {eig} |",
              flush=True)


if __name__ == "__main__":
    main()
