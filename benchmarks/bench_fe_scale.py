"""Scale of the FE core: time and peak memory from a generated beam-frame deck to its 50 lowest modes,
to a volts-volts model of them, and through the 1-g gravity preload.

Each size runs in its own process, so its peak resident memory (ru_maxrss) is that size's alone.
Run by hand: ``python benchmarks/bench_fe_scale.py [--sizes 1k 10k 30k 100k] [--preload-sizes 1k 3k]``
and paste the table into benchmarks/RESULTS.md with the machine, date and load (``uptime``).
The deck is tests/support/decks.py's ``frame_tower`` (aluminium tube lattice, clamped base, 5 kg masses on
the top level, EIGRL ND = 50). Two shapes: ``tower`` (from 10k DOFs a 6 x 6-grid section, taller with the
size) and ``wide`` (16 x 16 grids a level: 256 grids, 1536 DOFs across; 64 levels at 100k DOFs):
``--sizes 100k wide100k``. ``--ordering rcm`` factors in reverse Cuthill-McKee's order whatever the matrix
(what the core did before the ordering was chosen by fill), ``--fmu`` adds deck -> FMU (``mace-fmu export``
in its own process, wall time and peak memory by /usr/bin/time). Each run also records the machine's state: a
fixed Python loop's time before it, and the CPU time the host took from the virtual machine during it
(benchmarks/common.py): on the 2-core machine the same tree's deck -> 50 modes varies by a third with them.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
# the project's folder before tests/, as pytest's pythonpath: tests/modelica_like would shadow the package
sys.path[:0] = [str(HERE.parent), str(HERE.parent / "tests")]

#: (nx, ny, levels) of each size: 6 nx ny (levels + 1) DOFs
#: from 10k up the same 6 x 6 section, taller: the growth with DOFs is then the solver's, not the shape's
SIZES = {"1k": (3, 3, 18), "3k": (4, 4, 30), "10k": (6, 6, 46), "30k": (6, 6, 138), "100k": (6, 6, 462),
         "wide10k": (16, 16, 6), "wide30k": (16, 16, 19), "wide100k": (16, 16, 64)}

STRUCTURE_FILE = """# instruments of the generated frame tower (benchmarks/bench_fe_scale.py)
[[actuators]]
name = "push_x"
description = "force along X at the top corner"
dofs = [[{top}, 1, 1.0]]
gain = 1.0
[[actuators]]
name = "push_y"
description = "force along Y at the top corner"
dofs = [[{top}, 2, 1.0]]
gain = 1.0
[[sensors]]
name = "top_x"
description = "displacement along X at the top corner"
kind = "displacement"
dofs = [[{top}, 1, 1.0]]
gain = 1.0
[[sensors]]
name = "top_y"
description = "displacement along Y at the top corner"
kind = "displacement"
dofs = [[{top}, 2, 1.0]]
gain = 1.0
"""


def write_deck(size: str, kind: str, folder: Path) -> Path:
    """The deck of ``size`` and its structure file (tower.toml beside it) in ``folder``."""
    from support.decks import frame_tower

    nx, ny, levels = SIZES[size]
    deck_path = folder / "tower.bdf"
    deck_path.write_text(frame_tower(nx=nx, ny=ny, levels=levels, with_gravity=kind == "1g"))
    top = nx * ny * levels + 1  # the first grid of the top level
    (folder / "tower.toml").write_text(STRUCTURE_FILE.format(top=top))
    return deck_path


def rcm_only() -> None:
    """Make the factorisations take reverse Cuthill-McKee's order whatever the matrix (the core before issue 35)."""
    from mace_fmu.sparse import factor, ordering

    chosen = factor.analyse

    def analyse_rcm(matrix: object, *, groups: object = None, with_amd: bool = True) -> object:  # analyse's signature
        return chosen(matrix, groups=None, with_amd=False)

    factor.analyse = analyse_rcm
    ordering.candidate_permutations = lambda matrix, *, groups=None: {
        ordering.RCM: ordering.reverse_cuthill_mckee(ordering.sparse.csr_matrix(matrix), symmetric_mode=True)}


def fill_of(deck: object, kind: str) -> dict:
    """The ordering the factorisation of K - sigma M takes and each candidate's factor entries per DOF."""
    import numpy as np

    from mace_fmu.fe.assembly import assemble
    from mace_fmu.fe.constraints import build_constraints
    from mace_fmu.sparse import factor

    model = assemble(deck)
    constraints = build_constraints(deck, model.dofs, model.cd_frames, spc_set=1, mpc_set=None)
    k = constraints.reduce_sparse(model.stiffness)
    m = constraints.reduce_sparse(model.mass)
    analysis = factor.analyse(k + m, groups=np.array([g for g, _ in constraints.independent]))  # K - sigma M's pattern
    return {"ordering": analysis.choice.method,
            "fill": {name: round(v) for name, v in analysis.choice.entries_per_row(k.shape[0]).items()}}


def run_one(size: str, kind: str, volts: bool) -> dict:
    """In this process: the stages for one deck, with their wall times [s] and the peak memory [MB]."""
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.assembly import assemble
    from mace_fmu.fe.modes import compute_modes

    from common import python_loop_s, stolen_cpu_s

    folder = Path(tempfile.mkdtemp())
    deck_path = write_deck(size, kind, folder)
    out = {"size": size, "kind": kind, "python_loop_s": python_loop_s()}
    stolen = stolen_cpu_s()
    t0 = time.perf_counter()
    deck = read_deck(deck_path)
    out["read_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    # first, as a user's process would: on a virtual machine the first touch of memory a process has not used
    # costs about 1 ms a megabyte, and an assembly before it would hand its freed memory to the modes
    modes = compute_modes(deck, configuration=kind, structure_file=folder / "tower.toml")
    out["deck_to_modes_s"] = time.perf_counter() - t0 + out["read_s"]
    if stolen is not None:  # over the read and the modes: the host's share of the cores
        out["stolen_s"] = stolen_cpu_s() - stolen
    out["modes"] = len(modes.modes)
    out["f1_hz"] = float(modes.frequencies_hz[0])
    out["dofs"] = modes.model.dofs.size
    t0 = time.perf_counter()  # the assembly alone, after the modes (its memory used before: warm)
    assemble(deck)
    out["assemble_s"] = time.perf_counter() - t0
    if volts:
        from mace_fmu.iomodel.volts import volts_model

        t0 = time.perf_counter()  # volts_model alone, on the modes just computed
        model = volts_model(modes)
        out["volts_s"] = time.perf_counter() - t0
        out["states"] = model.system.nstates
    out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    out.update(fill_of(deck, kind))
    return out


def deck_to_fmu(size: str) -> dict:
    """``mace-fmu export 0g`` of the deck of ``size`` in its own process: wall time [s] and peak memory [MB]."""
    folder = Path(tempfile.mkdtemp())
    deck_path = write_deck(size, "0g", folder)
    cmd = ["/usr/bin/time", "-v", sys.executable, "-m", "mace_fmu.cli", "export", "0g", "--deck", str(deck_path),
           "--structure", str(folder / "tower.toml"), "--out", str(folder / "fmus")]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    peak = [line for line in proc.stderr.splitlines() if "Maximum resident set size" in line]
    if proc.returncode != 0 or not peak:
        return {"failed": (proc.stderr.strip().splitlines() or ["?"])[-1]}
    return {"fmu_s": wall, "fmu_peak_mb": int(peak[0].split(":")[1]) / 1024}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--sizes", nargs="*", default=["1k", "10k", "30k", "100k"])
    parser.add_argument("--preload-sizes", nargs="*", default=["1k", "3k", "10k"])
    parser.add_argument("--one", nargs=2, help=argparse.SUPPRESS)  # (size, kind): run in this process
    parser.add_argument("--volts", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--ordering", choices=["chosen", "rcm"], default="chosen",
                        help="rcm: reverse Cuthill-McKee whatever the matrix (before issue 35)")
    parser.add_argument("--fmu", action="store_true", help="also time deck -> FMU (mace-fmu export 0g)")
    parser.add_argument("--runs", type=int, default=1, help="runs of each size (each in a new process)")
    args = parser.parse_args()
    if args.one:
        if args.ordering == "rcm":
            rcm_only()
        print(json.dumps(run_one(args.one[0], args.one[1], args.volts)))
        return
    from common import print_run_header

    print_run_header(ordering=args.ordering)
    print("| deck | grids x levels | DOFs | structure | read [s] | assemble, warm [s] | deck -> 50 modes [s] "
          "| volts model [s] "
          "| peak memory [MB] | ordering | factor entries per DOF (RCM / ND / AMD) | deck -> FMU [s] | its peak [MB] | "
          "load | Python loop [s] | CPU taken by the host [s] |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    jobs = [(s, "0g") for s in args.sizes] + [(s, "1g") for s in args.preload_sizes]
    for size, kind in jobs:
        for _ in range(args.runs):
            load = os.getloadavg()[0]
            cmd = [sys.executable, str(Path(__file__).resolve()), "--one", size, kind, "--ordering", args.ordering]
            proc = subprocess.run(cmd + (["--volts"] if kind == "0g" else []), capture_output=True, text=True, cwd=HERE,
                                  check=False)
            if proc.returncode != 0:
                print(f"| {size} | - | - | {kind} | failed: {proc.stderr.strip().splitlines()[-1]} |")
                continue
            r = json.loads(proc.stdout.strip().splitlines()[-1])
            volts = f"{r['volts_s']:.2f}" if "volts_s" in r else "-"
            fill = " / ".join(str(r["fill"].get(name, "-")) for name in
                              ("reverse Cuthill-McKee", "nested dissection (METIS)", "approximate minimum degree (CHOLMOD)"))
            fmu = deck_to_fmu(size) if args.fmu and kind == "0g" and args.ordering == "chosen" else {}
            to_fmu = (f"{fmu['fmu_s']:.1f} | {fmu['fmu_peak_mb']:.0f}" if "fmu_s" in fmu
                      else f"{fmu.get('failed', '-')} | -")
            nx, ny, levels = SIZES[size]
            stolen = f"{r['stolen_s']:.2f}" if "stolen_s" in r else "-"
            print(f"| {'wide' if size.startswith('wide') else 'tower'} {size.removeprefix('wide')} | {nx * ny} x {levels} | {r['dofs']} | "
                  f"{kind} | {r['read_s']:.2f} | {r['assemble_s']:.2f} | {r['deck_to_modes_s']:.2f} | {volts} | "
                  f"{r['peak_mb']:.0f} | {r['ordering']} | {fill} | {to_fmu} | {load:.1f} | {r['python_loop_s']:.3f} | "
                  f"{stolen} |", flush=True)


if __name__ == "__main__":
    main()
