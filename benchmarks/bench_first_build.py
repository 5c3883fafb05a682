"""The first ``mace-fmu build`` on a fresh machine against a warm one (issue 51, item 8), before and after the
runtime's binaries were compiled when the package is built.

A fresh machine is an empty zig cache (``ZIG_GLOBAL_CACHE_DIR``) and an empty runtime cache
(``MACE_FMU_CACHE_DIR``), both new temporary folders. Every case is a new process running
``python -m mace_fmu.cli build -o <tmp>`` (the README's first command after the install), timed from start to end:

- before (``--before DIR``, e.g. ``git archive HEAD`` unpacked before the change): cold, then warm;
- after: this checkout's files are copied to a temporary folder and installed editable into a new virtual
  environment (``pip install --no-deps -e``, with build isolation, as the README installs; the dependencies
  come from this environment's site-packages), with both caches empty: that install is where zig's first
  build went. Then ``mace-fmu build`` with two new empty caches (the package's own binaries only), then warm.

Each case prints its progress lines' times, so that the longest silence (the gap between two lines of
output, or before the first) is measured too.

Run by hand: ``python benchmarks/bench_first_build.py --before /tmp/mace_head``; results go into RESULTS.md.
The cold cases take minutes each.
"""

from __future__ import annotations

import argparse
import os
import site
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import machine_line

HERE = Path(__file__).resolve().parents[1]


def timed_run(argv: list[str], *, env: dict[str, str], cwd: Path) -> tuple[float, float, list[str]]:
    """Wall time of ``argv`` [s], the longest wait for a line of output [s] (stdout and stderr), and its lines."""
    start = time.monotonic()
    process = subprocess.Popen(argv, cwd=cwd, env={**env, "PYTHONUNBUFFERED": "1"}, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    last, longest, lines = start, 0.0, []
    for line in process.stdout:
        now = time.monotonic()
        longest, last = max(longest, now - last), now
        lines.append(f"{now - start:7.1f} s {line.rstrip()}")
    if process.wait() != 0:
        raise SystemExit(f"{argv} failed:\n" + "\n".join(lines))
    end = time.monotonic()
    return end - start, max(longest, end - last), lines


def build(python: str, *, env: dict[str, str], work: Path) -> tuple[float, float, list[str]]:
    out = tempfile.mkdtemp(dir=work)
    return timed_run([python, "-m", "mace_fmu.cli", "build", "-o", out], env=env, cwd=work)


def empty_caches(root: Path) -> dict[str, str]:
    """A fresh machine's caches: two new empty folders under ``root``."""
    zig, mace = tempfile.mkdtemp(dir=root, prefix="zig-"), tempfile.mkdtemp(dir=root, prefix="mace-")
    return {"ZIG_GLOBAL_CACHE_DIR": zig, "MACE_FMU_CACHE_DIR": mace}


def installed_copy(root: Path) -> tuple[str, Path]:
    """This checkout's files in ``root/src``, and the Python of a new venv to install them into."""
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=HERE, check=True,
                           capture_output=True, text=True).stdout.split()
    src = root / "src"
    for name in files:
        if (HERE / name).is_file():
            (src / name).parent.mkdir(parents=True, exist_ok=True)
            (src / name).write_bytes((HERE / name).read_bytes())
    venv = root / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    python = str(venv / "bin" / "python")
    purelib = subprocess.run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             check=True, capture_output=True, text=True).stdout.strip()
    Path(purelib, "dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    return python, src


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--before", type=Path, help="a checkout of the code before the change")
    args = parser.parse_args()
    from importlib import metadata

    print(machine_line(ziglang=metadata.version("ziglang")))
    print(f"- date: {time.strftime('%Y-%m-%d %H:%M %Z')}, load before: {os.getloadavg()[0]:.1f}")
    rows = []
    with tempfile.TemporaryDirectory(prefix="mace_first_build_") as tmp:
        root = Path(tmp)
        base = {k: v for k, v in os.environ.items() if k not in ("ZIG_GLOBAL_CACHE_DIR", "MACE_FMU_CACHE_DIR")}
        if args.before:
            env = {**base, "PYTHONPATH": str(args.before)}
            rows.append(("before: first build, both caches empty", *build(sys.executable, env={**env,
                                                                                           **empty_caches(root)},
                                                                        work=root)))
            build(sys.executable, env=env, work=root)  # fills the runtime cache if this source version is new
            rows.append(("before: warm build", *build(sys.executable, env=env, work=root)))
        python, src = installed_copy(root)
        env = {k: v for k, v in base.items() if k != "PYTHONPATH"}
        rows.append(("after: pip install -e, both caches empty (zig's first build is here)",
                     *timed_run([python, "-m", "pip", "install", "--no-deps", "-v", "-e", str(src)],
                                env={**env, **empty_caches(root)}, cwd=root)))
        shipped = sorted(p.name for p in (src / "mace_fmu" / "fmu" / "native" / "prebuilt").iterdir())
        print(f"- binaries the install compiled into the package: {len(shipped)}")
        first = empty_caches(root)
        rows.append(("after: first build, both caches empty", *build(python, env={**env, **first}, work=root)))
        print(f"- files in zig's cache after it: {sum(1 for _ in Path(first['ZIG_GLOBAL_CACHE_DIR']).rglob('*'))}")
        build(python, env=env, work=root)
        rows.append(("after: warm build", *build(python, env=env, work=root)))
    print(f"- load after: {os.getloadavg()[0]:.1f}")
    print("\n| case | wall [s] | longest silence [s] |\n|---|---|---|")
    for name, seconds, silence, _ in rows:
        print(f"| {name} | {seconds:.1f} | {silence:.1f} |")
    for name, _, _, lines in rows:
        print(f"\n{name}:")
        print("\n".join(line for line in lines if "mace-fmu:" in line or line[10:12] == "  " or "wrote" in line)
              or "(no lines)")


if __name__ == "__main__":
    main()
