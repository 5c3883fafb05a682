"""Printed text compared as a reader compares it: words as words, numbers as numbers.

A number the documentation (or a test) shows was rounded by a program at some digit. The same
computation on another machine can land on the other side of a rounding edge (``2.215`` printed as
``2.22`` here and ``2.21`` there), so a documented number is held to what the program prints within
one unit of the documented number's last printed digit, never as a string. Everything between the
numbers must be the same text; runs of spaces are one space, because a column's width moves with
the numbers in it.
"""

from __future__ import annotations

import re

#: a number standing on its own: not the digit of a name such as ``strut2`` or ``1st``
NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w])")


def unit_of_last_digit(token: str) -> float:
    """One unit of the last digit printed in ``token`` (``2.22`` -> 0.01, ``1e-12`` -> 1e-12, ``40`` -> 1)."""
    mantissa, _, exponent = token.lower().partition("e")
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    return 10.0 ** (int(exponent or 0) - decimals)


def _split(line: str) -> tuple[list[str], list[str]]:
    """(words between the numbers with spaces collapsed, the numbers as printed)."""
    words = [re.sub(r"\s+", " ", part) for part in NUMBER.split(line)]
    return words, NUMBER.findall(line)


def line_agrees(shown: str, printed: str) -> bool:
    """True when ``printed`` says ``shown``: the same words, each number within one unit of the last digit
    ``shown`` prints (a hair more, so that a binary fraction on the edge is not refused)."""
    shown_words, shown_numbers = _split(shown)
    printed_words, printed_numbers = _split(printed)
    if shown_words != printed_words or len(shown_numbers) != len(printed_numbers):
        return False
    return all(abs(float(a) - float(b)) <= unit_of_last_digit(a) * (1 + 1e-9)
               for a, b in zip(shown_numbers, printed_numbers))


def _lines(text: str) -> list[str]:
    return [line.rstrip() for line in text.strip().splitlines()]


def printed_in(shown: str, text: str) -> bool:
    """True when the lines of ``shown`` appear, one after another, in ``text``, each agreeing as
    :func:`line_agrees` says. A one-line ``shown`` may also be part of a longer line of ``text``."""
    wanted, lines = _lines(shown), _lines(text)
    if len(wanted) == 1:
        return any(_part_agrees(wanted[0], line) for line in lines)
    return any(all(line_agrees(w, p) for w, p in zip(wanted, lines[start:start + len(wanted)]))
               for start in range(len(lines) - len(wanted) + 1))


def _part_agrees(shown: str, line: str) -> bool:
    """A one-line ``shown`` somewhere in ``line``: its words with any number where it shows one."""
    words, numbers = _split(shown)
    escaped = [re.escape(w).replace(r"\ ", r"\s+") for w in words]
    pattern = "".join(w + (NUMBER.pattern if i < len(numbers) else "") for i, w in enumerate(escaped))
    return any(line_agrees(shown, match.group(0)) for match in re.finditer(pattern, line))


def assert_printed_in(shown: str, text: str) -> None:
    """Fail with the documented block and the printed text nearest it when ``shown`` is not in ``text``."""
    assert printed_in(shown, text), f"not printed (numbers compared within their last digit):\n{shown[:600]}"
