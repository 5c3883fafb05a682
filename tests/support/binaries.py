"""Read what a shared library exports and which CPU it is for, from its bytes (ELF, PE, Mach-O, fat Mach-O).

Written from the formats' specifications (System V gABI ``elf.h``, Microsoft's PE/COFF specification,
Apple's ``<mach-o/loader.h>``, ``<mach-o/nlist.h>``, ``<mach-o/fat.h>``), independently of the exporter
and of any toolchain, so that the checks of the FMUs' binaries need no tool for foreign platforms.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass

ELF_MACHINES = {62: "x86_64", 183: "aarch64"}  #: e_machine EM_X86_64, EM_AARCH64
PE_MACHINES = {0x8664: "x86_64", 0xAA64: "aarch64"}  #: IMAGE_FILE_MACHINE_AMD64, _ARM64
MACHO_CPUS = {0x01000007: "x86_64", 0x0100000C: "aarch64"}  #: CPU_TYPE_X86_64, CPU_TYPE_ARM64


@dataclass(frozen=True)
class Library:
    """What a (thin) shared library is: its format, CPU and the names of the symbols it exports."""

    kind: str  #: "elf", "pe" or "macho"
    cpu: str  #: "x86_64" or "aarch64"
    exports: frozenset[str]  #: exported names, C spelling (Mach-O's leading underscore removed)


def _cstring(data: bytes, offset: int) -> str:
    return data[offset:data.index(b"\0", offset)].decode()


def read_elf(data: bytes) -> Library:
    """The dynamic symbols an ELF64 little-endian shared object defines with default or protected visibility."""
    assert data[:4] == b"\x7fELF" and data[4] == 2 and data[5] == 1, "not an ELF64 little-endian file"
    machine = struct.unpack_from("<H", data, 18)[0]
    shoff, = struct.unpack_from("<Q", data, 0x28)
    shentsize, shnum = struct.unpack_from("<HH", data, 0x3A)
    sections = [struct.unpack_from("<IIQQQQIIQQ", data, shoff + k * shentsize) for k in range(shnum)]
    names = set()
    for _, sh_type, _, _, offset, size, link, _, _, entsize in sections:
        if sh_type != 11:  # SHT_DYNSYM
            continue
        strtab = sections[link][4]
        for k in range(size // entsize):
            st_name, st_info, st_other, st_shndx, _, _ = struct.unpack_from("<IBBHQQ", data, offset + k * entsize)
            binding, visibility = st_info >> 4, st_other & 3
            if st_shndx != 0 and binding in (1, 2) and visibility in (0, 3):  # defined, GLOBAL/WEAK, DEFAULT/PROTECTED
                names.add(_cstring(data, strtab + st_name))
    return Library("elf", ELF_MACHINES.get(machine, hex(machine)), frozenset(names))


def read_pe(data: bytes) -> Library:
    """The names in a PE32+ DLL's export directory."""
    assert data[:2] == b"MZ", "not a PE file"
    pe, = struct.unpack_from("<I", data, 0x3C)
    assert data[pe:pe + 4] == b"PE\0\0"
    machine, n_sections = struct.unpack_from("<HH", data, pe + 4)
    optional_size, = struct.unpack_from("<H", data, pe + 20)
    optional = pe + 24
    assert struct.unpack_from("<H", data, optional)[0] == 0x20B, "not PE32+"
    export_rva, export_size = struct.unpack_from("<II", data, optional + 112)
    sections = [struct.unpack_from("<8sIIII", data, optional + optional_size + 40 * k) for k in range(n_sections)]

    def offset(rva: int) -> int:
        for _, virtual_size, address, raw_size, raw in sections:
            if address <= rva < address + max(virtual_size, raw_size):
                return rva - address + raw
        raise AssertionError(f"RVA {rva:#x} in no section")

    names = set()
    if export_size:
        directory = offset(export_rva)
        n_names, _, names_rva = struct.unpack_from("<III", data, directory + 24)
        table = offset(names_rva)
        for k in range(n_names):
            names.add(_cstring(data, offset(struct.unpack_from("<I", data, table + 4 * k)[0])))
    return Library("pe", PE_MACHINES.get(machine, hex(machine)), frozenset(names))


def _uleb(data: bytes, offset: int) -> tuple[int, int]:
    value, shift = 0, 0
    while True:
        byte = data[offset]
        offset += 1
        value |= (byte & 0x7F) << shift
        shift += 7
        if byte < 0x80:
            return value, offset


def _trie(data: bytes, start: int, node: int, prefix: str, out: set[str]) -> None:
    """The names of dyld's export trie below ``node`` (what dlsym finds), appended to ``out``."""
    terminal, at = _uleb(data, start + node)
    if terminal:
        out.add(prefix)
    at += terminal
    children, at = data[at], at + 1
    for _ in range(children):
        end = data.index(b"\0", at)
        edge = data[at:end].decode()
        child, at = _uleb(data, end + 1)
        _trie(data, start, child, prefix + edge, out)


def _trie_names(data: bytes, start: int) -> set[str]:
    out: set[str] = set()
    _trie(data, start, 0, "", out)
    return out


def read_macho(data: bytes) -> tuple[Library, frozenset[str]]:
    """A thin 64-bit Mach-O image: (its CPU and external defined symbols of LC_SYMTAB, the names of its export
    trie). The two lists must agree: the symbol table is what linkers read, the trie what dyld's dlsym reads."""
    magic, cputype, _, _, ncmds, _, _, _ = struct.unpack_from("<IiiIIIII", data, 0)
    assert magic == 0xFEEDFACF, "not a thin 64-bit little-endian Mach-O image"
    at, symbols, trie = 32, set(), set()
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<II", data, at)
        if cmd == 0x2:  # LC_SYMTAB
            symoff, nsyms, stroff, _ = struct.unpack_from("<IIII", data, at + 8)
            for k in range(nsyms):
                strx, n_type, _, _, _ = struct.unpack_from("<IBBHQ", data, symoff + 16 * k)
                stab, private, kind, external = n_type & 0xE0, n_type & 0x10, n_type & 0x0E, n_type & 0x01
                if not stab and external and not private and kind == 0x0E:  # N_EXT, N_SECT
                    symbols.add(_cstring(data, stroff + strx).removeprefix("_"))
        elif cmd in (0x80000022, 0x22):  # LC_DYLD_INFO(_ONLY): export_off, export_size at +40
            export_off, export_size = struct.unpack_from("<II", data, at + 40)
            if export_size:
                trie |= _trie_names(data, export_off)
        elif cmd == 0x80000033:  # LC_DYLD_EXPORTS_TRIE
            dataoff, datasize = struct.unpack_from("<II", data, at + 8)
            if datasize:
                trie |= _trie_names(data, dataoff)
        at += size
    library = Library("macho", MACHO_CPUS.get(cputype, hex(cputype)), frozenset(symbols))
    return library, frozenset(name.removeprefix("_") for name in trie)


@dataclass(frozen=True)
class FatSlice:
    """One architecture of a universal Mach-O file (a ``fat_arch`` record and its bytes)."""

    cputype: int
    cpusubtype: int
    offset: int
    align: int  #: log2 of the slice's alignment
    image: bytes


def read_fat(data: bytes) -> list[FatSlice]:
    """The slices of a universal (fat) Mach-O file (big-endian ``fat_header`` + ``fat_arch`` records)."""
    magic, count = struct.unpack_from(">II", data, 0)
    assert magic == 0xCAFEBABE, "not a universal Mach-O file"
    out = []
    for k in range(count):
        cputype, subtype, offset, size, align = struct.unpack_from(">iiIII", data, 8 + 20 * k)
        out.append(FatSlice(cputype, subtype, offset, align, data[offset:offset + size]))
    return out


def read_library(data: bytes) -> Library:
    """Any thin library this module reads (ELF, PE, Mach-O; for Mach-O the symbol table's exports)."""
    if data[:4] == b"\x7fELF":
        return read_elf(data)
    if data[:2] == b"MZ":
        return read_pe(data)
    return read_macho(data)[0]


def declared_fmi_functions(text: str) -> dict[str, set[str]]:
    """The functions an FMI header (its text) declares for export, by section ("common", "model exchange",
    "co-simulation", "scheduled execution"), from the header's own section banners."""
    sections: dict[str, set[str]] = {}
    parts = re.split(r"/\*{10,}\s*\n(.*?)\n\*{10,}/", text)
    for title, body in zip(parts[1::2], parts[2::2]):
        lower = title.lower()
        key = ("model exchange" if "model exchange" in lower else "co-simulation" if "co-simulation" in lower
               else "scheduled execution" if "scheduled execution" in lower else "common")
        found = set(re.findall(r"FMI[23]_Export\s+fmi[23]\w+TYPE\s+(fmi[23]\w+)\s*;", body))
        if found:
            sections.setdefault(key, set()).update(found)
    return sections
