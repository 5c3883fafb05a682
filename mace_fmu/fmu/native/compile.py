"""Compile the C runtime of native FMUs into a shared library for a platform (gcc, mingw-w64).

The runtime does not depend on the model (the model is data), so one compilation serves every
FMU a process exports; it is cached per platform and source digest. The flags are portable:
no -march=native and no -ffast-math (the exact zero-order hold relies on IEEE arithmetic).
"""

from __future__ import annotations

import functools
from concurrent.futures import ThreadPoolExecutor
import hashlib
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from mace_fmu.errors import MaceError

SOURCE_DIR = Path(__file__).with_name("c")
#: the runtime's C files, in link order; the FMI headers and their licence go into sources/ too
C_FILES = ("mace_linalg.c", "mace_data.c", "mace_zoh.c", "mace_model.c", "mace_instance.c", "fmi2_api.c",
           "fmi3_api.c")
CFLAGS = ("-std=c99", "-O3", "-fPIC", "-shared", "-fvisibility=hidden")


@dataclass(frozen=True)
class Platform:
    """A target of the runtime: its compiler and where FMI 2 and FMI 3 put its binary."""

    name: str
    compiler: str
    suffix: str
    fmi2_folder: str
    fmi3_folder: str
    extra_flags: tuple[str, ...] = ()


LINUX64 = Platform("linux64", "gcc", ".so", "linux64", "x86_64-linux", ("-lm",))
WIN64 = Platform("win64", "x86_64-w64-mingw32-gcc", ".dll", "win64", "x86_64-windows",
                 ("-static-libgcc", "-lm"))


def source_files() -> list[Path]:
    """Every file of the runtime that an FMU's sources/ folder carries (C files, headers, licence)."""
    return sorted(p for p in SOURCE_DIR.iterdir() if p.suffix in (".c", ".h") or p.name.startswith("LICENSE"))


def _digest() -> str:
    h = hashlib.sha256()
    for path in source_files():
        h.update(path.name.encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


def available(platform: Platform) -> bool:
    """Whether this machine has the platform's compiler."""
    return shutil.which(platform.compiler) is not None


@functools.lru_cache(maxsize=4)
def _compile_cached(platform: Platform, digest: str) -> bytes:
    with tempfile.TemporaryDirectory(prefix="mace_fmu_cc_") as tmp:
        out = Path(tmp) / f"runtime{platform.suffix}"
        command = [platform.compiler, *CFLAGS, "-o", str(out), *(str(SOURCE_DIR / f) for f in C_FILES),
                   *platform.extra_flags]
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            raise MaceError(f"compiling the native FMU runtime for {platform.name} failed:\n{done.stderr.strip()}")
        return out.read_bytes()


def compile_runtime(platform: Platform = LINUX64) -> bytes:
    """The runtime's shared library for ``platform`` (compiled once per process and source version)."""
    if not available(platform):
        raise MaceError(f"no C compiler for {platform.name}: {platform.compiler} is not installed")
    return _compile_cached(platform, _digest())


def compile_runtimes(platforms: list[Platform]) -> dict[Platform, bytes]:
    """The runtime for each of ``platforms``, the compilers running side by side."""
    with ThreadPoolExecutor(max_workers=max(1, len(platforms))) as pool:
        return dict(zip(platforms, pool.map(compile_runtime, platforms)))
