"""Native FMUs for every desktop: the platform folders, the universal darwin64 binary, each binary's
CPU and exports, the build record, ``--platforms`` and a missing toolchain.

The binaries are read by tests/support/binaries.py, written from the file formats' specifications and
checked here against llvm's tools where they are installed. Running them (wine, qemu-user, a plain cc
build of sources/) is in tests/fmu/test_native_fmu.py, with the plant FMUs.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import warnings
import zipfile

import numpy as np
import pytest
from support.binaries import read_fat, read_macho
from support.platform_checks import check_binaries, require_tool

from mace_fmu.cli import main as cli_main
from mace_fmu.errors import MaceError
from mace_fmu.fmu.controller import DiscreteController, export_controller_fmu
from mace_fmu.fmu.native import compile as runtime
from mace_fmu.fmu.native.macho import universal_binary
from mace_fmu.fmu.native.platforms import AARCH64_DARWIN, PLATFORMS, X86_64_DARWIN, select_platforms


def _controller() -> DiscreteController:
    return DiscreteController(a=np.array([[0.5, 0.1], [0.0, 0.9]]), b=np.array([[1.0], [0.5]]),
                              c=np.array([[2.0, -1.0]]), d=np.array([[0.1]]), sample_time_s=0.01, inputs=("u",),
                              outputs=("y",))


@pytest.fixture(scope="module")
def controllers(tmp_path_factory):
    """The controller FMU, FMI 2 and FMI 3, with every platform's binary."""
    out = tmp_path_factory.mktemp("platforms")
    return {v: export_controller_fmu(_controller(), out_dir=out, name=f"ctl{v}", fmi_version=v) for v in (2, 3)}


@pytest.mark.slow
@pytest.mark.parametrize("version", [2, 3])
def test_every_platform_binary_is_for_its_cpu_and_exports_the_fmi_functions(controllers, version):
    check_binaries(controllers[version])


@pytest.mark.slow
def test_the_symbol_reader_agrees_with_llvm(controllers, tmp_path):
    """The test's own readers of ELF, PE and Mach-O against llvm-nm and llvm-objdump (where installed; not a
    CI dependency): the same exported names for every binary."""
    nm, objdump = shutil.which("llvm-nm"), shutil.which("llvm-objdump")
    if nm is None or objdump is None:
        pytest.skip("llvm-nm / llvm-objdump are not installed (the readers are checked against them where they are)")
    from support.binaries import read_library

    with zipfile.ZipFile(controllers[3]) as z:
        for name in [n for n in z.namelist() if n.startswith("binaries/")]:
            path = tmp_path / name.replace("/", "_")
            path.write_bytes(z.read(name))
            if name.endswith(".dll"):  # the export table's "ordinal RVA name" rows
                table = subprocess.run([objdump, "-p", str(path)], capture_output=True, text=True, check=True).stdout
                rows = table.split("Ordinal      RVA  Name")[1].split("\n\n")[0].splitlines()
                found = {row.split()[-1] for row in rows if len(row.split()) == 3}
            else:
                dynamic = ["--dynamic"] if name.endswith(".so") else []
                listed = subprocess.run([nm, *dynamic, "--extern-only", "--defined-only", str(path)],
                                        capture_output=True, text=True, check=True).stdout
                found = {line.split()[-1] for line in listed.splitlines() if line.strip()}
                if name.endswith(".dylib"):
                    found = {n.removeprefix("_") for n in found}
            assert len(found) > 70 and read_library(path.read_bytes()).exports == found, name  # FMI 3's 75 and more


@pytest.mark.slow
def test_macos_binaries_rebuild_byte_for_byte_from_the_fmus_sources_and_recorded_command(controllers, tmp_path):
    """The macOS binaries cannot run here: they are the bytes the recorded command makes from the FMU's own
    sources/ (the same flags as every other platform, checked in check_binaries)."""
    zig = runtime.zig_command()
    if zig is None:
        require_tool(None, "zig (the ziglang package)")
    sources = tmp_path / "sources"
    with zipfile.ZipFile(controllers[2]) as z:
        for name in z.namelist():
            if name.startswith("sources/"):
                z.extract(name, tmp_path)
        fat = read_fat(z.read("binaries/darwin64/ctl2.dylib"))
    info = json.loads((sources / "build_info.json").read_text())
    rebuilt = {}
    for entry in info["binaries"]:
        if entry["platform"] not in (X86_64_DARWIN.name, AARCH64_DARWIN.name):
            continue
        subprocess.run([*zig, *entry["command"][1:]], cwd=sources, check=True, capture_output=True)
        rebuilt[entry["platform"]] = (sources / entry["output"]).read_bytes()
    assert {read_macho(s.image)[0].cpu: s.image for s in fat} == {"x86_64": rebuilt["x86_64-darwin"],
                                                                  "aarch64": rebuilt["aarch64-darwin"]}


def test_universal_binary_holds_each_slice_at_its_page_alignment():
    """The fat writer against the test's own reader of <mach-o/fat.h>: slices unchanged, 4 KiB / 16 KiB aligned."""
    def thin(cputype: int, size: int) -> bytes:
        header = np.array([0xFEEDFACF, cputype, 3 if cputype == X86_64_DARWIN.macho_cpu else 0, 6, 0, 0, 0, 0],
                          dtype="<u4").tobytes()
        return header + bytes(range(256)) * (size // 256)

    x86, arm = thin(X86_64_DARWIN.macho_cpu, 5000), thin(AARCH64_DARWIN.macho_cpu, 7000)
    fat = read_fat(universal_binary({AARCH64_DARWIN.macho_cpu: arm, X86_64_DARWIN.macho_cpu: x86}))
    assert [(s.cputype, s.cpusubtype, s.offset, s.align) for s in fat] == [
        (X86_64_DARWIN.macho_cpu, 3, 4096, 12), (AARCH64_DARWIN.macho_cpu, 0, 16384, 14)]
    assert [s.image for s in fat] == [x86, arm]
    with pytest.raises(MaceError, match="CPU type 0x100000c is of CPU type 0x1000007"):
        universal_binary({AARCH64_DARWIN.macho_cpu: x86})


def test_platform_names_are_checked():
    assert select_platforms(None) == PLATFORMS
    assert [p.name for p in select_platforms(["x86_64-windows", " x86_64-linux"])] == ["x86_64-linux", "x86_64-windows"]
    assert select_platforms("x86_64-windows, x86_64-linux") == select_platforms(["x86_64-linux", "x86_64-windows"])
    with pytest.raises(MaceError, match="unknown 'win64'; expected some of x86_64-linux, aarch64-linux"):
        select_platforms(["win64"])


def test_cli_platforms_option_refuses_an_unknown_name_in_one_line(capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli_main(["export-controller", "--lqg", "--platforms", "x86_64-linux,sparc-solaris"])
    assert exit_info.value.code == 2
    assert "unknown 'sparc-solaris'" in capsys.readouterr().err


@pytest.mark.slow
def test_a_subset_of_platforms_carries_only_those_and_a_thin_darwin64(tmp_path):
    fmu = export_controller_fmu(_controller(), out_dir=tmp_path, name="ctl", platforms=["aarch64-darwin", "x86_64-linux"])
    with zipfile.ZipFile(fmu) as z:
        binaries = sorted(n for n in z.namelist() if n.startswith("binaries/"))
        assert binaries == ["binaries/darwin64/ctl.dylib", "binaries/linux64/ctl.so"]
        assert read_macho(z.read("binaries/darwin64/ctl.dylib"))[0].cpu == "aarch64"
        info = json.loads(z.read("sources/build_info.json"))
    assert [b["platform"] for b in info["binaries"]] == ["x86_64-linux", "aarch64-darwin"]


def test_a_missing_toolchain_is_one_warning_line_or_an_error_when_asked_for(tmp_path, monkeypatch):
    """Without zig the default export says so in one line and ships sources/ only; a platform named is an error."""
    monkeypatch.setattr(runtime, "zig_command", lambda: None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fmu = export_controller_fmu(_controller(), out_dir=tmp_path, name="ctl")
    lines = [str(w.message) for w in caught]
    assert len(lines) == 1 and "\n" not in lines[0]
    assert lines[0].startswith("no C toolchain for x86_64-linux, aarch64-linux, x86_64-windows, x86_64-darwin, "
                               "aarch64-darwin: zig is not installed (pip install ziglang)")
    with zipfile.ZipFile(fmu) as z:
        assert not [n for n in z.namelist() if n.startswith("binaries/")]
        assert "sources/fmi2_api.c" in z.namelist() and "sources/fmi3_api.c" not in z.namelist()
    with pytest.raises(MaceError, match="^no C toolchain for x86_64-windows: zig is not installed"):
        export_controller_fmu(_controller(), out_dir=tmp_path, name="ctl", platforms=["x86_64-windows"])


def test_the_command_line_says_a_missing_toolchain_in_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(runtime, "zig_command", lambda: None)
    npz = _controller().write_npz(tmp_path / "ctl.npz")
    assert cli_main(["export-controller", "--npz", str(npz), "-o", str(tmp_path)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [("mace-fmu: warning: no C toolchain for x86_64-linux, aarch64-linux, x86_64-windows, x86_64-darwin, "
                    "aarch64-darwin: zig is not installed (pip install ziglang); the FMU carries sources/ for them")]
    refused = tmp_path / "refused"
    assert cli_main(["export-controller", "--npz", str(npz), "-o", str(refused), "--platforms", "x86_64-linux"]) == 2
    assert capsys.readouterr().err.strip() == ("mace-fmu: error: no C toolchain for x86_64-linux: zig is not installed "
                                               "(pip install ziglang)")
    assert not (refused / "controller.fmu").exists()


@pytest.mark.slow
def test_export_platforms_option_chooses_the_binaries_of_a_plant_fmu(tmp_path, capsys):
    assert cli_main(["export", "0g", "-o", str(tmp_path), "--max-hz", "20", "--fmi-version", "3",
                     "--platforms", "aarch64-linux,x86_64-windows"]) == 0
    (fmu,) = tmp_path.glob("*.fmu")
    with zipfile.ZipFile(fmu) as z:
        binaries = sorted(n.split("/")[1] for n in z.namelist() if n.startswith("binaries/"))
    assert binaries == ["aarch64-linux", "x86_64-windows"]
    capsys.readouterr()
    assert cli_main(["export", "0g", "-o", str(tmp_path), "--runtime", "pythonfmu", "--platforms", "x86_64-linux"]) == 2
    assert capsys.readouterr().err.strip() == ("mace-fmu: error: --platforms needs --runtime native (a pythonfmu FMU "
                                               "has no binaries of its own)")
