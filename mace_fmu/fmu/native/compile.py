"""Compile the C runtime of native FMUs into a shared library for each platform with zig's C compiler.

The ``ziglang`` package (a dependency, so ``pip install`` brings it) cross-compiles for every target of
:mod:`mace_fmu.fmu.native.platforms` from any machine, with its own libc headers and import stubs: one
compiler, one flag set, five targets. The runtime does not depend on the model (the model is data), so
one compilation per platform, runtime variant and source version serves every FMU, under a key of the
sources, flags, target and zig version. The package build compiles every variant for every platform
into the package (``PREBUILT_DIR``, by :func:`prebuild`, run from ``setup.py``), so that an export on a
fresh machine compiles nothing: zig's first build for a target makes its C libraries (the mingw-w64 C
runtime for Windows takes minutes). Binaries the package lacks (sources changed since the build, another
zig) are compiled at first use, the targets side by side, reported step by step to a progress callback,
and kept on disk (``cache_dir``). There are four variants (``VARIANTS``), the plant and the controller
each for FMI 2 and FMI 3 (``C_FILES``, ``CONTROLLER_C_FILES``): an FMU links only its own FMI version's
entry points, so that its binaries export that version's functions and nothing of the other. The flags
are portable: no -march=native and no -ffast-math, and -ffp-contract=off so that no target fuses
a*b+c into one rounding (ARM would by default), keeping the exact zero-order hold's IEEE arithmetic
the same on every platform.

Each platform is compiled in a folder laid out as the FMU's ``sources/`` (the C files flat), with relative
paths, so the command recorded in the FMU's ``sources/build_info.json`` rebuilds the same binary there.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Sequence
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from importlib import metadata
from pathlib import Path

from mace_fmu.errors import MaceError
from mace_fmu.fmu.native.platforms import PLATFORMS, Platform, entry_path
from mace_fmu.util.progress import ProgressCallback, Step

SOURCE_DIR = Path(__file__).with_name("c")
#: the FMI entry points of each FMI version; fmi2_api.c also holds maceRunRecord, the updating engine's call
API_C_FILES = {2: "fmi2_api.c", 3: "fmi3_api.c"}
_PLANT_LAYERS = ("mace_linalg.c", "mace_data.c", "mace_zoh.c", "mace_resolve.c", "mace_model.c", "mace_instance.c")
#: the sampled-data controller's layers: another implementation of mace_model.h under the same FMI layers
_CONTROLLER_LAYERS = ("mace_linalg.c", "mace_data.c", "controller/mace_discrete.c", "mace_instance.c")
#: FMI version -> the plant runtime's C files, in link order; its headers and their licence go into sources/ too
C_FILES = {v: (*_PLANT_LAYERS, api) for v, api in API_C_FILES.items()}
#: FMI version -> the controller runtime's C files, in link order
CONTROLLER_C_FILES = {v: (*_CONTROLLER_LAYERS, api) for v, api in API_C_FILES.items()}
#: every runtime variant by what it is: the package build compiles each for every platform
VARIANTS = {"plant, FMI 2": C_FILES[2], "plant, FMI 3": C_FILES[3],
            "controller, FMI 2": CONTROLLER_C_FILES[2], "controller, FMI 3": CONTROLLER_C_FILES[3]}
#: the binaries compiled when the package was built (setup.py), named as in the cache
PREBUILT_DIR = Path(__file__).with_name("prebuilt")
#: while a compilation runs, a progress step at least this often [s]: the first one on a machine takes minutes
HEARTBEAT_S = 15.0
#: the runtime's optimisation level (zig builds a target's C library once per installation and level: the tests'
#: hosts use this one, so that they share it with the runtime's compilations)
OPTIMISATION = "-O3"
#: every target gets these (the C standard, optimisation, exports only what the FMI headers mark)
CFLAGS = ("-std=c99", OPTIMISATION, "-fPIC", "-shared", "-fvisibility=hidden", "-ffp-contract=off", "-g0")
#: the library file each platform's compilation writes (its name inside the FMU is the model identifier's)
OUTPUT_STEM = "mace_runtime"
BUILD_INFO = "build_info.json"


def source_files(c_files: tuple[str, ...] = C_FILES[2]) -> list[Path]:
    """Every file of a runtime that an FMU's sources/ folder carries (its C files, the headers, the licence).

    A host that builds from sources compiles every C file there, so each FMU carries exactly the C
    files of its own runtime variant (``C_FILES[v]`` for plants, ``CONTROLLER_C_FILES[v]`` for controllers
    of FMI version v), and the FMI headers of that version only.
    """
    names = {Path(f).name for f in c_files}

    def carried(path: Path) -> bool:
        if path.name.startswith("LICENSE"):
            return True
        version = next((v for v in API_C_FILES if path.name.startswith(f"fmi{v}")), None)
        return path.suffix == ".h" and (version is None or API_C_FILES[version] in names)

    shared = [p for p in SOURCE_DIR.iterdir() if carried(p)]
    return sorted(shared + [SOURCE_DIR / f for f in c_files], key=lambda p: p.name)


def sources_digest(files: Sequence[Path]) -> str:
    """SHA-256 over the names and contents of ``files`` in name order (the FMU's sources/, read back in tests)."""
    h = hashlib.sha256()
    for path in sorted(files, key=lambda p: p.name):
        h.update(path.name.encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


def zig_command() -> list[str] | None:
    """The command that runs zig: the ``ziglang`` package's, else a ``zig`` on PATH, else None."""
    if importlib.util.find_spec("ziglang") is not None:
        return [sys.executable, "-m", "ziglang"]
    zig = shutil.which("zig")
    return [zig] if zig else None


@functools.lru_cache(maxsize=1)
def zig_version() -> str:
    """zig's version (the package's metadata when it is the ``ziglang`` package: no process started)."""
    if importlib.util.find_spec("ziglang") is not None:
        return metadata.version("ziglang")
    command = zig_command()
    if command is None:
        raise MaceError("zig is not installed (pip install ziglang)")
    return subprocess.run([*command, "version"], capture_output=True, text=True, check=True).stdout.strip()


def available(platform: Platform) -> bool:
    """Whether this machine can build ``platform``'s binary (zig targets every platform from any host)."""
    return zig_command() is not None


def cache_dir() -> Path:
    """Where compiled runtimes are kept: $MACE_FMU_CACHE_DIR, else $XDG_CACHE_HOME/mace-fmu, else ~/.cache/mace-fmu."""
    if os.environ.get("MACE_FMU_CACHE_DIR"):
        return Path(os.environ["MACE_FMU_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "mace-fmu"


def build_command(platform: Platform, c_files: tuple[str, ...]) -> list[str]:
    """The compile command of ``platform``'s binary, run in the FMU's sources/ folder (``zig`` = zig's command)."""
    return ["zig", "cc", "-target", platform.target, *CFLAGS, "-I.", "-o", f"{OUTPUT_STEM}{platform.suffix}",
            *(Path(f).name for f in c_files), "-lm"]


def _cache_key(platform: Platform, c_files: tuple[str, ...], digest: str) -> str:
    """The binary's cache key from the toolchain, its command and ``digest``, the runtime's sources_digest."""
    h = hashlib.sha256(json.dumps([zig_version(), build_command(platform, c_files)]).encode())
    h.update(digest.encode())
    return h.hexdigest()[:24]


def _compile(platform: Platform, c_files: tuple[str, ...]) -> bytes:
    command = zig_command()
    if command is None:
        raise MaceError("compiling the native FMU runtime needs zig (the ziglang package, a dependency of mace-fmu, "
                        "or a zig on PATH)")
    with tempfile.TemporaryDirectory(prefix="mace_fmu_cc_") as tmp:
        for path in source_files(c_files):
            shutil.copyfile(path, Path(tmp) / path.name)
        argv = [*command, *build_command(platform, c_files)[1:]]
        done = subprocess.run(argv, capture_output=True, text=True, cwd=tmp, check=False)
        if done.returncode != 0:
            raise MaceError(f"compiling the native FMU runtime for {platform.name} failed:\n{done.stderr.strip()}")
        return (Path(tmp) / f"{OUTPUT_STEM}{platform.suffix}").read_bytes()


def _file_name(platform: Platform, key: str) -> str:
    """A binary's file name in the cache and in the package's prebuilt binaries."""
    return f"{OUTPUT_STEM}-{key}-{platform.name}{platform.suffix}"


#: (platform, key) -> binary, read or compiled by this process
_MEMORY: dict[tuple[Platform, str], bytes] = {}


def _stored(platform: Platform, key: str) -> bytes | None:
    """The binary of ``key`` from this process's memory, the package's prebuilt binaries or the cache; None if
    it has to be compiled."""
    if (platform, key) in _MEMORY:
        return _MEMORY[platform, key]
    for folder in (PREBUILT_DIR, cache_dir()):
        path = folder / _file_name(platform, key)
        if path.is_file():
            _MEMORY[platform, key] = binary = path.read_bytes()
            return binary
    return None


def _write(path: Path, binary: bytes) -> None:
    """Write ``binary`` to ``path`` atomically: parallel exports (pytest-xdist) never read half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile(dir=path.parent, delete=False, prefix=".tmp-") as f:
        f.write(binary)
    os.replace(f.name, path)


def _compile_and_keep(platform: Platform, c_files: tuple[str, ...], key: str) -> bytes:
    binary = _compile(platform, c_files)
    _MEMORY[platform, key] = binary
    try:  # an unwritable cache costs a compilation per process, nothing else
        _write(cache_dir() / _file_name(platform, key), binary)
    except OSError:
        pass
    return binary


def _variant_name(c_files: tuple[str, ...]) -> str:
    return next((name for name, files in VARIANTS.items() if files == tuple(c_files)), "custom")


def _compile_side_by_side(platforms: Sequence[Platform], c_files: tuple[str, ...], keys: dict[Platform, str],
                          progress: ProgressCallback | None) -> dict[Platform, bytes]:
    """Compile ``platforms`` at once, reporting the start, each platform done and, while none finishes, a
    step every ``HEARTBEAT_S`` seconds (the first compilation on a machine is minutes long)."""
    def report(done: int, detail: str) -> None:
        if progress is not None:
            progress(Step(f"native FMU runtime ({_variant_name(c_files)})", done, len(platforms), detail))

    report(0, f"compiling for {', '.join(p.name for p in platforms)} with zig {zig_version()}: seconds per "
              "platform once zig's own cache holds its C libraries, minutes the first time on a machine")
    start = time.monotonic()
    binaries: dict[Platform, bytes] = {}
    with ThreadPoolExecutor(max_workers=len(platforms)) as pool:
        futures = {pool.submit(_compile_and_keep, p, c_files, keys[p]): p for p in platforms}
        pending = set(futures)
        while pending:
            finished, pending = wait(pending, timeout=HEARTBEAT_S, return_when=FIRST_COMPLETED)
            for future in finished:
                platform = futures[future]
                binaries[platform] = future.result()  # a failure is raised here, in one MaceError
                report(len(binaries), f"{platform.name} compiled ({time.monotonic() - start:.0f} s)")
            if not finished:
                still = [p.name for p in platforms if any(futures[f] == p for f in pending)]
                report(len(binaries), f"still compiling for {', '.join(still)} ({time.monotonic() - start:.0f} s)")
    return binaries


def compile_runtime(platform: Platform = PLATFORMS[0], *, c_files: tuple[str, ...] = C_FILES[2]) -> bytes:
    """A runtime's shared library for ``platform`` (compiled once per source version and platform, then cached).

    Parameters
    ----------
    platform : Platform
        Target and binary folder names (default: x86_64 Linux).
    c_files : tuple of str
        The runtime's C sources, in link order (default: the FMI 2 plant's, ``C_FILES[2]``).

    Returns
    -------
    bytes
        The shared library (.so, .dll or .dylib).

    Raises
    ------
    MaceError
        zig is missing or fails (its messages included).
    """
    return compile_runtimes([platform], c_files=c_files, requested=True)[platform]


class MissingToolchainWarning(UserWarning):
    """A platform of the default set left out of an FMU's binaries for want of a toolchain (its sources/ stay)."""


def compile_runtimes(platforms: Sequence[Platform], *, c_files: tuple[str, ...] = C_FILES[2],
                     requested: bool = False, progress: ProgressCallback | None = None) -> dict[Platform, bytes]:
    """The runtime (the FMI 2 plant's by default) for each of ``platforms``: the package's prebuilt binary or
    the cached one, else compiled, the platforms side by side.

    A platform without a toolchain is an error when the caller ``requested`` it by name, and one warning
    line otherwise (the FMU then carries sources/ for it, which a host can compile).

    Parameters
    ----------
    platforms : sequence of Platform
        The targets.
    c_files : tuple of str
        The runtime variant's C sources, in link order (default: the FMI 2 plant's, ``C_FILES[2]``).
    requested : bool
        Whether the caller named these platforms (a missing toolchain is then an error).
    progress : callable, optional
        Called with a :class:`~mace_fmu.util.progress.Step` when compiling starts, as each platform is
        done, and every ``HEARTBEAT_S`` seconds in between; never when every binary is prebuilt or cached.

    Returns
    -------
    dict
        Platform -> the shared library's bytes, in the order of ``platforms``.

    Raises
    ------
    MaceError
        A requested platform without zig, or a compiler failure (its messages included).
    """
    missing = [p for p in platforms if not available(p)]
    if missing:
        line = f"no C toolchain for {', '.join(p.name for p in missing)}: zig is not installed (pip install ziglang)"
        if requested:
            raise MaceError(line)
        warnings.warn(line + "; the FMU carries sources/ for them", MissingToolchainWarning, stacklevel=3)
    todo = [p for p in platforms if p not in missing]
    if not todo:
        return {}
    digest = sources_digest(source_files(c_files))  # once for every platform (and every in-memory cache hit)
    keys = {p: _cache_key(p, c_files, digest) for p in todo}
    binaries = {p: b for p in todo if (b := _stored(p, keys[p])) is not None}
    missing = [p for p in todo if p not in binaries]
    if missing:
        binaries.update(_compile_side_by_side(missing, c_files, keys, progress))
    return {p: binaries[p] for p in todo}


def prebuild(folder: str | os.PathLike[str] = PREBUILT_DIR, *, progress: ProgressCallback | None = None) -> list[Path]:
    """Compile every runtime variant for every platform into ``folder`` (what the package build ships).

    Run by ``setup.py`` when the package is built (a wheel, or ``pip install -e .``): an export then finds
    its binaries there and compiles nothing. Binaries of other source versions in ``folder`` are removed.

    Parameters
    ----------
    folder : path
        Where to write them (default: the package's ``PREBUILT_DIR``).
    progress : callable, optional
        Progress steps of the compilations (see :func:`compile_runtimes`).

    Returns
    -------
    list of Path
        The binaries, four variants of five platforms.

    Raises
    ------
    MaceError
        zig is missing or fails.
    """
    folder = Path(folder)
    written = []
    for c_files in VARIANTS.values():
        digest = sources_digest(source_files(c_files))
        for platform, binary in compile_runtimes(PLATFORMS, c_files=c_files, requested=True,
                                                 progress=progress).items():
            path = folder / _file_name(platform, _cache_key(platform, c_files, digest))
            if not path.is_file():
                _write(path, binary)
            written.append(path)
    for old in folder.glob(f"{OUTPUT_STEM}-*"):
        if old not in written:
            old.unlink()
    return written


def build_info(binaries: dict[Platform, bytes], *, c_files: tuple[str, ...], fmi_version: int, name: str) -> bytes:
    """sources/build_info.json: the toolchain, the sources' digest and, per platform, the command, the
    SHA-256 of the binary it made and the archive entry holding it (in FMI 2 the macOS binaries are the
    slices of the one universal ``darwin64`` file)."""
    info = {"toolchain": f"zig {zig_version()} (PyPI package ziglang)" if binaries else None,
            "sources_sha256": sources_digest(source_files(c_files)),
            "binaries": [{"platform": p.name, "archive_entry": entry_path(p, fmi_version=fmi_version, name=name),
                          "command": build_command(p, c_files), "output": f"{OUTPUT_STEM}{p.suffix}",
                          "sha256": hashlib.sha256(b).hexdigest()} for p, b in binaries.items()]}
    return (json.dumps(info, indent=1) + "\n").encode()
