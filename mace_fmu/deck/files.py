"""Deck files as text: reading a deck file, repeated BEGIN BULK lines, and INCLUDE files expanded into cards.

Every card keeps the file and line it came from, so that later errors can point at an INCLUDEd file too.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from mace_fmu.deck.fields import Lines, RawCard, check_text, split_cards
from mace_fmu.errors import DeckError

_BEGIN_BULK = re.compile(r"BEGIN\s*BULK", re.IGNORECASE)
_INCLUDE = re.compile(r"^\s*INCLUDE\s*'([^']+)'\s*$", re.IGNORECASE)


def deck_file_text(path: str | os.PathLike[str]) -> str:
    """The text of the deck file ``path``.

    Parameters
    ----------
    path : str or path-like
        The deck file.

    Returns
    -------
    str
        Its text, decoded as UTF-8.

    Raises
    ------
    DeckError
        No such file, a file that cannot be read, or a byte that is not text (with its line and column).
    """
    name = os.fspath(path)
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        raise DeckError("no such file", file=name, line=0) from None
    except OSError as exc:
        raise DeckError(f"cannot read the deck file ({exc.strerror})", file=name, line=0) from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line_start = data.rfind(b"\n", 0, exc.start) + 1
        raise DeckError(f"byte 0x{data[exc.start]:02x} at column {exc.start - line_start + 1} is not text (expected "
                        "an ASCII or UTF-8 text file)", file=name, line=data.count(b"\n", 0, exc.start) + 1) from None


def without_begin_bulk(bulk: Lines) -> Lines:
    """The bulk-data lines without any further BEGIN BULK line.

    Parameters
    ----------
    bulk : list of (int, str)
        Numbered lines of the bulk-data section.

    Returns
    -------
    list of (int, str)
        The same lines without those that repeat BEGIN BULK.
    """
    # A second BEGIN BULK line repeats the section's start; NASTRAN reads past it (bah_plane.bdf and
    # ha144ds.bdf of tests/data/nastran have one and ran), and so does this reader.
    return [(number, text) for number, text in bulk
            if text.lstrip()[:1] not in ("B", "b") or not _BEGIN_BULK.fullmatch(text.split("$", 1)[0].strip())]


def cards_with_includes(lines: Lines, file: str, *, stack: tuple[str, ...]) -> list[RawCard]:
    """The bulk cards of ``lines`` with each ``INCLUDE 'path'`` replaced by the cards of that file.

    Parameters
    ----------
    lines : list of (int, str)
        Numbered bulk-data lines of ``file``.
    file : str
        The file the lines are from; an INCLUDE path is relative to its folder (nested INCLUDEs too).
    stack : tuple of str
        Absolute paths of the files being read, outermost first (an INCLUDE of one of them is circular).

    Returns
    -------
    list of RawCard
        The cards in file order, each with its own file and line.

    Raises
    ------
    DeckError
        A malformed, circular, missing or unreadable INCLUDE, or a malformed card.
    """
    out: list[RawCard] = []
    segment: Lines = []

    def flush() -> None:
        for raw in split_cards(segment, file):
            raw.file = file
            out.append(raw)
        segment.clear()

    for number, text in lines:
        head = text.split("$", 1)[0]
        if not head.strip().upper().startswith("INCLUDE"):
            segment.append((number, text))
            continue
        match = _INCLUDE.match(head)
        if not match:
            raise DeckError("expected INCLUDE 'path' (the path in single quotes on one line)", file=file, line=number,
                            card="INCLUDE")
        flush()
        target = Path(match.group(1))
        if not target.is_absolute():
            target = Path(file).parent / target
        resolved = os.path.abspath(target)
        if resolved in stack:
            raise DeckError(f"INCLUDE {match.group(1)!r} is circular: {' -> '.join(stack)} -> {resolved}", file=file,
                            line=number, card="INCLUDE")
        try:
            included = target.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise DeckError(f"INCLUDE {match.group(1)!r}: no such file ({target})", file=file, line=number,
                            card="INCLUDE") from None
        except (OSError, UnicodeDecodeError) as exc:
            raise DeckError(f"INCLUDE {match.group(1)!r}: cannot read {target} ({exc})", file=file, line=number,
                            card="INCLUDE") from None
        physical = included.removeprefix("\ufeff").split("\n")
        numbered = [(k, line.rstrip("\r")) for k, line in enumerate(physical, start=1)]
        check_text(numbered, str(target))
        out += cards_with_includes(numbered, str(target), stack=stack + (resolved,))
    flush()
    return out
