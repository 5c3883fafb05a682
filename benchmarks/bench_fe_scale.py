"""Scale of the FE core: time and peak memory from a generated beam-frame deck to its 50 lowest modes,
to a volts-volts model of them, and through the 1-g gravity preload.

Each size runs in its own process, so its peak resident memory (ru_maxrss) is that size's alone.
Run by hand: ``python benchmarks/bench_fe_scale.py [--sizes 1k 10k 30k 100k] [--preload-sizes 1k 3k]``
and paste the table into benchmarks/RESULTS.md with the machine, date and load (``uptime``).
The deck is tests/support/decks.py's ``frame_tower`` (aluminium tube lattice, clamped base, 5 kg masses on
the top level, EIGRL ND = 50).
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
sys.path.insert(0, str(HERE.parent / "tests"))

#: (nx, ny, levels) of each size: 6 nx ny (levels + 1) DOFs
#: from 10k up the same 6 x 6 section, taller: the growth with DOFs is then the solver's, not the shape's
SIZES = {"1k": (3, 3, 18), "3k": (4, 4, 30), "10k": (6, 6, 46), "30k": (6, 6, 138), "100k": (6, 6, 462)}

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


def run_one(size: str, kind: str, volts: bool) -> dict:
    """In this process: the stages for one deck, with their wall times [s] and the peak memory [MB]."""
    from support.decks import frame_tower

    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.assembly import assemble
    from mace_fmu.fe.modes import compute_modes

    nx, ny, levels = SIZES[size]
    folder = Path(tempfile.mkdtemp())
    deck_path = folder / "tower.bdf"
    deck_path.write_text(frame_tower(nx=nx, ny=ny, levels=levels, with_gravity=kind == "1g"))
    top = nx * ny * levels + 1  # the first grid of the top level
    (folder / "tower.toml").write_text(STRUCTURE_FILE.format(top=top))
    out = {"size": size, "kind": kind}
    t0 = time.perf_counter()
    deck = read_deck(deck_path)
    out["read_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    model = assemble(deck)
    out["assemble_s"] = time.perf_counter() - t0
    out["dofs"] = model.dofs.size
    t0 = time.perf_counter()
    modes = compute_modes(deck, configuration=kind, structure_file=folder / "tower.toml")
    out["deck_to_modes_s"] = time.perf_counter() - t0 + out["read_s"]
    out["modes"] = len(modes.modes)
    out["f1_hz"] = float(modes.frequencies_hz[0])
    if volts:
        from mace_fmu.fe.modes import compute_modes
        from mace_fmu.iomodel.volts import volts_model

        t0 = time.perf_counter()
        model = volts_model(compute_modes(deck, configuration=kind, structure_file=folder / "tower.toml"))
        out["volts_s"] = time.perf_counter() - t0
        out["states"] = model.system.nstates
    out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--sizes", nargs="*", default=["1k", "10k", "30k", "100k"])
    parser.add_argument("--preload-sizes", nargs="*", default=["1k", "3k", "10k"])
    parser.add_argument("--one", nargs=2, help=argparse.SUPPRESS)  # (size, kind): run in this process
    parser.add_argument("--volts", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(run_one(args.one[0], args.one[1], args.volts)))
        return
    import numpy
    import scipy
    from common import machine_line

    print(machine_line(numpy=numpy.__version__, scipy=scipy.__version__))
    print(f"date: {time.strftime('%Y-%m-%d %H:%M')}, load: {os.getloadavg()[0]:.2f}")
    print("| deck | DOFs | structure | read [s] | assemble [s] | deck -> 50 modes [s] | volts model [s] | peak memory [MB] |")
    print("|---|---|---|---|---|---|---|---|")
    jobs = [(s, "0g") for s in args.sizes] + [(s, "1g") for s in args.preload_sizes]
    for size, kind in jobs:
        cmd = [sys.executable, str(Path(__file__).resolve()), "--one", size, kind] + (["--volts"] if kind == "0g" else [])
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=HERE)
        if proc.returncode != 0:
            print(f"| {size} | - | {kind} | failed: {proc.stderr.strip().splitlines()[-1]} |")
            continue
        r = json.loads(proc.stdout.strip().splitlines()[-1])
        volts = f"{r['volts_s']:.2f}" if "volts_s" in r else "-"
        print(f"| tower {size} | {r['dofs']} | {kind} | {r['read_s']:.2f} | {r['assemble_s']:.2f} | "
              f"{r['deck_to_modes_s']:.2f} | {volts} | {r['peak_mb']:.0f} |", flush=True)


if __name__ == "__main__":
    main()
