"""A seeded mutator of deck files: the ways people break decks, for the reader's fuzz test.

Each mutation takes the deck as bytes and a ``random.Random`` and returns (kind, new bytes). Lines
are deleted, duplicated, swapped or truncated; fields are swapped or blanked; characters (printable,
control, non-ASCII, invalid UTF-8) are injected; numbers change value, sign or type.
"""

from __future__ import annotations

import random
import re
from typing import Callable

_NUMBER = re.compile(rb"[+-]?(?:\d+\.\d*|\.\d+|\d+)(?:[EeDd][+-]?\d+|[+-]\d+)?")
_NUMBERS = [b"0", b"1", b"-1", b"7", b"999", b"0.0", b"-0.0", b"1.0", b"-1.0", b"1.0E30", b"1.0E-30", b"1.0E999",
            b"-1.0E999", b"0.5", b"0.6", b"-2.0", b"2147483648", b"99999999", b"1.5+3", b".", b"1.2.3", b"NaN",
            b"INF", b"-"]
_CHARACTERS = [b"$", b",", b"*", b"+", b" ", b"\t", b"\x00", b"\x07", b"\x0c", b"\x1b", b"\x7f", b"\xc3\xa9",
               b"\xe2\x80\x8b", b"\xff", b"\xc3", b"\x80", b"\r", b"\n", b"=", b"A", b"x", b"9", b"."]


def _lines(deck: bytes) -> list[bytes]:
    return deck.split(b"\n")


def _join(lines: list[bytes]) -> bytes:
    return b"\n".join(lines)


def _card_line(rng: random.Random, lines: list[bytes]) -> int:
    """A random line, preferring card lines (not comments) since comments are ignored anyway."""
    for _ in range(20):
        i = rng.randrange(len(lines))
        if lines[i] and not lines[i].startswith(b"$"):
            return i
    return rng.randrange(len(lines))


def delete_line(rng: random.Random, deck: bytes) -> bytes:
    lines = _lines(deck)
    del lines[_card_line(rng, lines)]
    return _join(lines)


def duplicate_line(rng: random.Random, deck: bytes) -> bytes:
    lines = _lines(deck)
    i = _card_line(rng, lines)
    lines.insert(rng.randrange(len(lines) + 1), lines[i])
    return _join(lines)


def swap_lines(rng: random.Random, deck: bytes) -> bytes:
    lines = _lines(deck)
    i, j = _card_line(rng, lines), _card_line(rng, lines)
    lines[i], lines[j] = lines[j], lines[i]
    return _join(lines)


def truncate_line(rng: random.Random, deck: bytes) -> bytes:
    lines = _lines(deck)
    i = _card_line(rng, lines)
    lines[i] = lines[i][:rng.randrange(len(lines[i]) + 1)]
    return _join(lines)


def _fields(line: bytes) -> list[bytes]:
    padded = line.ljust(80)
    return [padded[k:k + 8] for k in range(0, 80, 8)]


def swap_fields(rng: random.Random, deck: bytes) -> bytes:
    lines = _lines(deck)
    i = _card_line(rng, lines)
    fields = _fields(lines[i])
    a, b = rng.randrange(10), rng.randrange(10)
    fields[a], fields[b] = fields[b], fields[a]
    lines[i] = b"".join(fields).rstrip()
    return _join(lines)


def blank_field(rng: random.Random, deck: bytes) -> bytes:
    lines = _lines(deck)
    i = _card_line(rng, lines)
    fields = _fields(lines[i])
    fields[rng.randrange(10)] = b" " * 8
    lines[i] = b"".join(fields).rstrip()
    return _join(lines)


def inject_character(rng: random.Random, deck: bytes) -> bytes:
    lines = _lines(deck)
    i = _card_line(rng, lines)
    at = rng.randrange(len(lines[i]) + 1)
    char = rng.choice(_CHARACTERS) if rng.random() < 0.8 else bytes([rng.randrange(256)])
    replace = rng.random() < 0.5
    lines[i] = lines[i][:at] + char + lines[i][at + (1 if replace else 0):]
    return _join(lines)


def change_number(rng: random.Random, deck: bytes) -> bytes:
    """Replace one number of a card line: a new value, its sign flipped, scaled, or its type changed."""
    lines = _lines(deck)
    i = _card_line(rng, lines)
    found = list(_NUMBER.finditer(lines[i]))
    if not found:
        return _join(lines)
    m = rng.choice(found)
    old = m.group(0)
    how = rng.randrange(4)
    if how == 0:
        new = rng.choice(_NUMBERS)
    elif how == 1:
        new = old[1:] if old[:1] in b"+-" else b"-" + old
    elif how == 2:
        new = old.replace(b".", b"") if b"." in old else old + b"."
    else:
        new = str(rng.choice([0, 1, 2, 3, 10, 100, 1000, 5, 50])).encode() + (b"." if b"." in old else b"")
    lines[i] = lines[i][:m.start()] + new + lines[i][m.end():]
    return _join(lines)


MUTATIONS: dict[str, Callable[[random.Random, bytes], bytes]] = {
    f.__name__: f for f in (delete_line, duplicate_line, swap_lines, truncate_line, swap_fields, blank_field,
                           inject_character, change_number)}


def mutate(deck: bytes, *, seed: int, rounds: int = 1) -> tuple[str, bytes]:
    """(names of the mutations applied, mutated deck): ``rounds`` random mutations chosen by ``seed``."""
    rng = random.Random(seed)
    names = []
    for _ in range(rounds):
        name = rng.choice(sorted(MUTATIONS))
        deck = MUTATIONS[name](rng, deck)
        names.append(name)
    return "+".join(names), deck
