"""The native runtime's binaries on a fresh machine: compiled when the package is built,
taken from there by an export that then compiles nothing, and a compilation at first use (sources changed
since the build) reported as it goes: its start, each platform, and a line at least every 15 s.

The wheel's own binaries and a ``mace-fmu build`` with zig's cache empty are in tests/test_packaging.py.
"""

from __future__ import annotations

import time

import pytest
from support.cli import run_cli

from mace_fmu.fmu.native import compile as runtime
from mace_fmu.fmu.native.platforms import PLATFORMS, X86_64_LINUX, X86_64_WINDOWS


@pytest.fixture
def fresh_machine(tmp_path, monkeypatch):
    """No binary anywhere: an empty package folder, an empty cache, nothing in this process's memory."""
    monkeypatch.setattr(runtime, "PREBUILT_DIR", tmp_path / "prebuilt", raising=False)
    monkeypatch.setenv("MACE_FMU_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(runtime, "_MEMORY", {}, raising=False)
    return tmp_path


def _key(platform, c_files=runtime.C_FILES[2]) -> str:
    return runtime._cache_key(platform, c_files, runtime.sources_digest(runtime.source_files(c_files)))


def test_an_export_takes_the_binaries_built_with_the_package_and_compiles_nothing(fresh_machine, monkeypatch):
    for platform in PLATFORMS:
        (fresh_machine / "prebuilt").mkdir(exist_ok=True)
        (fresh_machine / "prebuilt" / runtime._file_name(platform, _key(platform))).write_bytes(platform.name.encode())

    def no_compiler(platform, c_files):
        raise AssertionError(f"compiled {platform.name} although the package has its binary")

    monkeypatch.setattr(runtime, "_compile", no_compiler)
    steps = []
    binaries = runtime.compile_runtimes(PLATFORMS, progress=steps.append)
    assert {p: b.decode() for p, b in binaries.items()} == {p: p.name for p in PLATFORMS}
    assert steps == []  # nothing to report: nothing took time
    assert not (fresh_machine / "cache").exists()


def test_a_compilation_says_when_it_starts_each_platform_done_and_still_running_every_heartbeat(fresh_machine,
                                                                                                monkeypatch):
    seconds = {X86_64_LINUX: 0.1, X86_64_WINDOWS: 1.2}  # Windows the slow one, as zig's mingw-w64 build is

    def compiler(platform, c_files):
        time.sleep(seconds[platform])
        return platform.name.encode()

    monkeypatch.setattr(runtime, "_compile", compiler)
    monkeypatch.setattr(runtime, "HEARTBEAT_S", 0.4)
    steps = []
    binaries = runtime.compile_runtimes([X86_64_LINUX, X86_64_WINDOWS], progress=steps.append)
    assert binaries == {X86_64_LINUX: b"x86_64-linux", X86_64_WINDOWS: b"x86_64-windows"}
    assert {s.task for s in steps} == {"native FMU runtime (plant, FMI 2)"} and {s.total for s in steps} == {2}
    assert steps[0].done == 0 and steps[0].detail.startswith(
        f"compiling for x86_64-linux, x86_64-windows with zig {runtime.zig_version()}: seconds per platform")
    assert "minutes the first time on a machine" in steps[0].detail
    assert (steps[1].done, steps[1].detail.split(" (")[0]) == (1, "x86_64-linux compiled")
    heartbeats = [s for s in steps[2:-1] if s.detail.startswith("still compiling for x86_64-windows (")]
    assert len(heartbeats) == len(steps) - 3 >= 2 and all(s.done == 1 for s in heartbeats)
    assert (steps[-1].done, steps[-1].detail.split(" (")[0]) == (2, "x86_64-windows compiled")
    kept = sorted(p.name for p in (fresh_machine / "cache").iterdir())
    assert kept == sorted(runtime._file_name(p, _key(p)) for p in binaries)
    steps.clear()
    runtime.compile_runtimes([X86_64_LINUX, X86_64_WINDOWS], progress=steps.append)
    assert steps == []  # compiled once: the next export reads them


@pytest.mark.slow
def test_export_with_nothing_compiled_yet_says_so_on_stderr_line_by_line(fresh_machine, capsys):
    """zig itself, for one platform (seconds with zig's own cache filled, as the suite leaves it)."""
    code, out, err = run_cli(capsys, ["export", "0g", "--max-hz", "20", "--platforms", "x86_64-linux",
                                      "-o", str(fresh_machine / "out")])
    assert code == 0, err
    lines = [line for line in err.splitlines() if "native FMU runtime" in line]
    assert lines, err
    assert lines[0].startswith("  native FMU runtime (plant, FMI 2): compiling for x86_64-linux with zig ")
    assert lines[-1].startswith("  native FMU runtime (plant, FMI 2): x86_64-linux compiled (")
    # between them, on a loaded machine, a line every 15 s
    assert all(" still compiling for x86_64-linux (" in line for line in lines[1:-1])
    assert out.startswith("wrote ")


@pytest.mark.slow
def test_prebuild_writes_every_variant_for_every_platform_and_removes_other_versions(tmp_path):
    """What setup.py runs: four variants of five binaries under the keys an export looks for."""
    folder = tmp_path / "prebuilt"
    folder.mkdir()
    (folder / f"{runtime.OUTPUT_STEM}-0123456789abcdef01234567-x86_64-linux.so").write_bytes(b"an older runtime")
    written = runtime.prebuild(folder)
    expected = {runtime._file_name(p, _key(p, c_files)) for c_files in runtime.VARIANTS.values() for p in PLATFORMS}
    assert len(expected) == 20 and sorted(p.name for p in folder.iterdir()) == sorted(expected)
    assert sorted(p.name for p in written) == sorted(expected)
    for c_files in runtime.VARIANTS.values():
        for platform, binary in runtime.compile_runtimes(PLATFORMS, c_files=c_files).items():
            assert (folder / runtime._file_name(platform, _key(platform, c_files))).read_bytes() == binary
