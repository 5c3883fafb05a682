"""A universal (fat) Mach-O file from thin 64-bit slices: FMI 2's single ``darwin64`` binary for Intel and ARM Macs.

The zig distribution has no ``lipo``; the format is small (``<mach-o/fat.h>``): a big-endian header,
``magic = FAT_MAGIC, nfat_arch``, one ``fat_arch`` record per slice ``(cputype, cpusubtype, offset, size,
align)``, then each slice unchanged at an offset aligned to its page size (``2**align``), as ``lipo -create``
lays it out: x86_64 on 4 KiB pages, arm64 on 16 KiB.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping

from mace_fmu.errors import MaceError

FAT_MAGIC = 0xCAFEBABE
MH_MAGIC_64 = 0xFEEDFACF
CPU_SUBTYPE_MASK = 0xFF000000  #: capability bits of cpusubtype, not part of the subtype
#: log2 of the page size of each CPU type (lipo's alignment of a slice)
PAGE_ALIGN = {0x01000007: 12, 0x0100000C: 14}


def thin_header(binary: bytes) -> tuple[int, int]:
    """(cputype, cpusubtype) of a thin little-endian 64-bit Mach-O image; MaceError if it is not one."""
    if len(binary) < 32 or struct.unpack_from("<I", binary, 0)[0] != MH_MAGIC_64:
        raise MaceError("not a thin 64-bit Mach-O image (magic 0xfeedfacf expected)")
    cputype, cpusubtype = struct.unpack_from("<ii", binary, 4)
    return cputype, cpusubtype & ~CPU_SUBTYPE_MASK


def universal_binary(slices: Mapping[int, bytes]) -> bytes:
    """One fat Mach-O file holding each of ``slices`` (CPU type -> thin image), as ``lipo -create`` writes it.

    Raises
    ------
    MaceError
        A slice that is not a thin 64-bit Mach-O of the CPU type it is filed under.
    """
    records, body = [], []
    ordered = sorted(slices.items(), key=lambda item: (PAGE_ALIGN.get(item[0], 14), item[0]))
    offset = 8 + 20 * len(ordered)
    for cputype, image in ordered:
        found, subtype = thin_header(image)
        if found != cputype:
            raise MaceError(f"Mach-O slice filed as CPU type {cputype:#x} is of CPU type {found:#x}")
        align = PAGE_ALIGN.get(cputype, 14)
        start = -(-offset // (1 << align)) << align
        body.append(b"\0" * (start - offset) + image)
        records.append(struct.pack(">iiIII", cputype, subtype, start, len(image), align))
        offset = start + len(image)
    return struct.pack(">II", FAT_MAGIC, len(ordered)) + b"".join(records) + b"".join(body)
