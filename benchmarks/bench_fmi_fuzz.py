"""The long state-machine fuzz of the native FMUs (issue 23, section 3): seeded random call sequences
of FMI 2 co-simulation, FMI 2 model exchange and FMI 3 co-simulation against the reference model of
the standard's state tables (tests/support/fmi_fuzz.py), in worker subprocesses so that a crash or a hang
is reported with its seeds instead of ending the run.

Run: python benchmarks/bench_fmi_fuzz.py [--sequences 3000] [--length 40] [--chunk 100] [--model 0g]
(sequences are counted over the three interfaces: 3,000 = 1,000 seeds x 3).
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import fmpy

from common import machine_line
from mace_fmu.fe.modes import compute_modes
from mace_fmu.fmu.export import export_fmu
from mace_fmu.iomodel.volts import volts_model

WORKER = Path(__file__).resolve().parents[1] / "tests" / "support" / "fmi_fuzz.py"


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--sequences", type=int, default=3000)
    parser.add_argument("--length", type=int, default=40)
    parser.add_argument("--chunk", type=int, default=100, help="seeds per worker process")
    parser.add_argument("--first-seed", type=int, default=1000)
    parser.add_argument("--model", default="0g")
    a = parser.parse_args()
    seeds = a.sequences // 3
    with tempfile.TemporaryDirectory() as tmp:
        model = volts_model(compute_modes(configuration=a.model))
        fmi2 = export_fmu(model, out_dir=tmp, name=f"MACE_{a.model}_fuzz")
        fmi3 = export_fmu(model, out_dir=tmp, name=f"MACE_{a.model}_fuzz3", fmi_version=3)
        folders = [fmpy.extract(str(fmi2), unzipdir=f"{tmp}/fmi2"), fmpy.extract(str(fmi3), unzipdir=f"{tmp}/fmi3")]
        totals = Counter()
        states, mismatches, failures = Counter(), [], []
        t0 = time.perf_counter()
        for first in range(a.first_seed, a.first_seed + seeds, a.chunk):
            n = min(a.chunk, a.first_seed + seeds - first)
            command = [sys.executable, str(WORKER), *folders, str(first), str(n), "--length", str(a.length)]
            try:
                done = subprocess.run(command, capture_output=True, text=True, timeout=60 + 10 * n)
            except subprocess.TimeoutExpired:
                failures.append(f"seeds {first}-{first + n - 1}: hung")
                continue
            if done.returncode != 0:
                failures.append(f"seeds {first}-{first + n - 1}: worker exit {done.returncode}, last "
                                f"{done.stderr.strip().splitlines()[-3:]}")
                continue
            summary = json.loads(done.stdout.strip().splitlines()[-1])
            totals.update({k: summary[k] for k in ("sequences", "calls", "ok", "error")})
            states.update(summary["by_state"])
            mismatches += summary["mismatches"]
        seconds = time.perf_counter() - t0
    print(machine_line(fmpy=importlib.metadata.version("fmpy")))
    print(f"- seeds {a.first_seed}-{a.first_seed + seeds - 1} (x 3 interfaces), {a.length} calls a sequence, "
          f"model {a.model}")
    print(f"- {totals['sequences']} sequences, {totals['calls']} calls ({totals['ok']} OK, {totals['error']} "
          f"errors) in {seconds:.1f} s; {len(mismatches)} status mismatches, {len(failures)} crashes or hangs")
    print("- calls per state: " + ", ".join(f"{k} {v}" for k, v in sorted(states.items())))
    for m in mismatches[:10]:
        print("  mismatch:", json.dumps(m))
    for f in failures:
        print("  failure:", f)
    return 0 if not mismatches and not failures else 1


if __name__ == "__main__":
    sys.exit(main())
