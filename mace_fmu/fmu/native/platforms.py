"""The platforms a native FMU carries binaries for, and the folders FMI 2 and FMI 3 give them.

Five targets, named by their FMI 3 platform tuples (``--platforms`` takes these names):

==============  ======================  ====================  ==============
platform        zig target              FMI 2 folder          FMI 3 folder
==============  ======================  ====================  ==============
x86_64-linux    x86_64-linux-gnu.2.17   linux64               x86_64-linux
aarch64-linux   aarch64-linux-gnu.2.17  aarch64-linux         aarch64-linux
x86_64-windows  x86_64-windows-gnu      win64                 x86_64-windows
x86_64-darwin   x86_64-macos.11.0       darwin64 (universal)  x86_64-darwin
aarch64-darwin  aarch64-macos.11.0      darwin64 (universal)  aarch64-darwin
==============  ======================  ====================  ==============

FMI 2 names no folder for ARM Linux: ``aarch64-linux``, the FMI 3 tuple, is the one a reader recognises
(FMPy 0.3 loads FMI 2 binaries from ``linux64`` on any 64-bit Linux, so on ARM it needs ``libraryPath``).
FMI 2's ``darwin64`` holds one file, so both macOS slices go into it as one universal (fat) Mach-O
(:mod:`mace_fmu.fmu.native.macho`), the form Apple's loader picks the running architecture from.
glibc 2.17 and macOS 11 are the oldest systems the binaries ask for.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from mace_fmu.errors import MaceError
from mace_fmu.fmu.native.macho import universal_binary


@dataclass(frozen=True)
class Platform:
    """A target of the runtime: its zig target triple and where FMI 2 and FMI 3 put its binary."""

    name: str  #: the FMI 3 platform tuple, e.g. "x86_64-windows"
    target: str  #: zig's -target, with the oldest libc / OS version the binary needs
    suffix: str  #: shared-library file suffix (".so", ".dll", ".dylib")
    fmi2_folder: str  #: binaries/<folder> in an FMI 2 FMU
    fmi3_folder: str  #: binaries/<folder> in an FMI 3 FMU
    macho_cpu: int | None = None  #: Mach-O CPU type of a macOS slice (mach/machine.h), None elsewhere


X86_64_LINUX = Platform("x86_64-linux", "x86_64-linux-gnu.2.17", ".so", "linux64", "x86_64-linux")
AARCH64_LINUX = Platform("aarch64-linux", "aarch64-linux-gnu.2.17", ".so", "aarch64-linux", "aarch64-linux")
X86_64_WINDOWS = Platform("x86_64-windows", "x86_64-windows-gnu", ".dll", "win64", "x86_64-windows")
X86_64_DARWIN = Platform("x86_64-darwin", "x86_64-macos.11.0", ".dylib", "darwin64", "x86_64-darwin",
                         macho_cpu=0x01000007)  # CPU_TYPE_X86_64
AARCH64_DARWIN = Platform("aarch64-darwin", "aarch64-macos.11.0", ".dylib", "darwin64", "aarch64-darwin",
                          macho_cpu=0x0100000C)  # CPU_TYPE_ARM64
#: every platform, in the order the FMU lists them
PLATFORMS = (X86_64_LINUX, AARCH64_LINUX, X86_64_WINDOWS, X86_64_DARWIN, AARCH64_DARWIN)
BY_NAME = {p.name: p for p in PLATFORMS}


def select_platforms(names: Iterable[str] | None) -> tuple[Platform, ...]:
    """The platforms named (FMI 3 tuples, e.g. ``["x86_64-linux", "x86_64-windows"]`` or that comma-separated), or
    all of them for None.

    Raises
    ------
    MaceError
        An unknown or empty list of names (the message lists the known ones).
    """
    if names is None:
        return PLATFORMS
    if isinstance(names, str):  # "x86_64-linux,x86_64-windows", as on the command line
        names = names.split(",")
    names = [n.strip() for n in names if n.strip()]
    unknown = [n for n in names if n not in BY_NAME]
    if unknown or not names:
        raise MaceError(f"platforms: unknown {', '.join(map(repr, unknown)) or 'empty list'}; expected some of "
                        f"{', '.join(BY_NAME)}")
    return tuple(p for p in PLATFORMS if p.name in names)


def entry_path(platform: Platform, *, fmi_version: int, name: str) -> str:
    """The archive entry of ``platform``'s binary in an FMI ``fmi_version`` FMU of model identifier ``name``
    (FMI 2's macOS slices share ``binaries/darwin64``)."""
    folder = platform.fmi2_folder if fmi_version == 2 else platform.fmi3_folder
    return f"binaries/{folder}/{name}{platform.suffix}"


def binary_entries(binaries: Mapping[Platform, bytes], *, fmi_version: int, name: str) -> dict[str, bytes]:
    """The ``binaries/...`` archive entries of an FMU from each platform's shared library.

    FMI 3 gives each platform its folder; FMI 2 puts the macOS slices into one universal ``darwin64``
    binary (a single slice stays thin).
    """
    grouped: dict[str, dict[Platform, bytes]] = {}
    for platform, binary in binaries.items():
        grouped.setdefault(entry_path(platform, fmi_version=fmi_version, name=name), {})[platform] = binary
    return {path: next(iter(group.values())) if len(group) == 1
            else universal_binary({p.macho_cpu: b for p, b in group.items() if p.macho_cpu is not None})
            for path, group in grouped.items()}
