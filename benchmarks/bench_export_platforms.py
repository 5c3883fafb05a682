"""Export time of a native FMU with every platform's binary (issue 37), against the export before it.

Each run is a fresh process, as a ``mace-fmu export`` is: it builds the 1-g volts-volts model (not timed)
and times one ``export_fmu`` (FMI 2 native), the binaries' compilation included. Cases:

- before: the code of another checkout (``--before DIR``, e.g. ``git archive HEAD`` unpacked before the
  change): gcc for linux64 and mingw-w64 for win64, compiled in every new process;
- after, warm: this checkout, five platforms from the on-disk cache (the usual case);
- after, cold runtime cache: an empty ``MACE_FMU_CACHE_DIR`` (a new source version), zig's own cache warm;
- after, cold: both caches empty (a fresh machine: zig builds its libc stubs and mingw-w64 CRT first).

Run by hand: ``python benchmarks/bench_export_platforms.py --before /tmp/mace_head [--runs 3] [--cold]``;
results go into RESULTS.md.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from common import machine_line

HERE = Path(__file__).resolve().parents[1]


def one_export() -> None:
    """In the child: build the model, time the export, print JSON."""
    import time

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model

    model = volts_model(compute_modes(configuration="1g"))
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        fmu = export_fmu(model, out_dir=out, name="MACE_1g_native")
        seconds = time.perf_counter() - t0
        import zipfile

        with zipfile.ZipFile(fmu) as z:
            folders = sorted({n.split("/")[1] for n in z.namelist() if n.startswith("binaries/")})
    print(json.dumps({"seconds": seconds, "folders": folders}))


def run(code: Path, runs: int, env: dict[str, str]) -> tuple[list[float], list[str]]:
    times, folders = [], []
    for _ in range(runs):
        done = subprocess.run([sys.executable, __file__, "--child"], capture_output=True, text=True, check=True,
                              env={**os.environ, **env, "PYTHONPATH": f"{code}{os.pathsep}{HERE / 'benchmarks'}"})
        result = json.loads(done.stdout.strip().splitlines()[-1])
        times.append(result["seconds"])
        folders = result["folders"]
    return times, folders


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--child", action="store_true")
    parser.add_argument("--before", type=Path, help="a checkout of the code before the change")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--cold", action="store_true", help="also time an export with zig's cache empty (minutes)")
    args = parser.parse_args()
    if args.child:
        one_export()
        return
    from importlib import metadata

    print(machine_line(ziglang=metadata.version("ziglang")))
    print(f"- load before: {os.getloadavg()[0]:.1f}")
    rows = []
    if args.before:
        rows.append(("before (gcc linux64 + mingw-w64 win64, per process)", *run(args.before, args.runs, {})))
    run(HERE, 1, {})  # fills the runtime cache if this source version is new
    rows.append(("after, warm cache (5 platforms)", *run(HERE, args.runs, {})))
    with tempfile.TemporaryDirectory() as empty:
        rows.append(("after, cold runtime cache, zig's cache warm", *run(HERE, 1, {"MACE_FMU_CACHE_DIR": empty})))
    if args.cold:
        with tempfile.TemporaryDirectory() as empty, tempfile.TemporaryDirectory() as zig:
            rows.append(("after, cold (both caches empty)",
                         *run(HERE, 1, {"MACE_FMU_CACHE_DIR": empty, "ZIG_GLOBAL_CACHE_DIR": zig})))
    print(f"- load after: {os.getloadavg()[0]:.1f}")
    print("\n| case | median [s] | min [s] | runs | binaries/ |\n|---|---|---|---|---|")
    for name, times, folders in rows:
        print(f"| {name} | {statistics.median(times):.2f} | {min(times):.2f} | {len(times)} | {', '.join(folders)} |")


if __name__ == "__main__":
    main()
