"""Text layer of a deck: sections, case-control selections, bulk lines to cards, typed fields.

Data fields are numbered from 1 in NASTRAN's positional sense: fields 2-9 of a card's first line
are data fields 1-8, fields 2-9 of its first continuation are data fields 9-16, and so on. A
large-field line carries 4 data fields, so two large-field lines make one such logical line.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from mace_fmu.deck.cards import Source, Subcase
from mace_fmu.errors import DeckError

Lines = list[tuple[int, str]]
REQUIRED: Any = object()  #: default meaning "a blank field is an error"

_INT = re.compile(r"[+-]?\d+")
# NASTRAN reals need a decimal point; the exponent may be E/D or implicit ("4.99-12").
_REAL = re.compile(r"([+-]?(?:\d+\.\d*|\.\d+))(?:[EeDd]([+-]?\d+)|([+-]\d+))?")
_WORD = re.compile(r"[A-Z][A-Z0-9]*")


def parse_int(text: str) -> int | None:
    """The integer written in ``text``, or None when it is not a NASTRAN integer."""
    if text.isdecimal():  # the usual unsigned ID, without the regular expression (the same digits as \d)
        return int(text)
    return int(text) if _INT.fullmatch(text) else None


#: deletes the characters of a real written as Python reads it too ("1.5e-3"); what is left is not one
_PLAIN_REAL = str.maketrans("", "", "0123456789.+-eE")


def parse_real(text: str) -> float | None:
    """The real written in ``text`` (decimal point required), or None when it is not one."""
    if "." in text and not text.translate(_PLAIN_REAL):
        # digits, signs, a point and an E: the forms Python's float reads are the same numbers in NASTRAN, and
        # the others ("1.5-3", "1.5e") fail there and are read below (a large deck has hundreds of thousands)
        try:
            return float(text)
        except ValueError:
            pass
    m = _REAL.fullmatch(text)
    if m is None:
        return None
    return float(f"{m.group(1)}e{m.group(2) or m.group(3) or '0'}")


def describe(d: int, name: str, last: int | None = None) -> str:
    """Position of data field ``d`` (to ``last``) in NASTRAN's numbering, e.g. 'field 5 (GB)'."""
    line, col = divmod(d - 1, 8)
    where = (f"continuation {line} " if line else "") + f"field {col + 2}"
    if last is not None:
        line2, col2 = divmod(last - 1, 8)
        where = (where.replace("field", "fields") + f"-{col2 + 2}" if line2 == line
                 else f"{where} to continuation {line2} field {col2 + 2}")
    return f"{where} ({name})"


def _code(text: str) -> str:
    return text.split("$", 1)[0].strip()


_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f\u2028\u2029\ufeff\ufffe\uffff]")


def check_text(lines: Lines, file: str) -> None:
    """Control characters (other than tab) are no deck's content: reject them with their line and column."""
    if not lines:
        raise DeckError("the file is empty (expected bulk data cards)", file=file, line=1)
    if not _CONTROL.search("\n".join(text for _, text in lines)):  # one search; the line only for a message
        return
    for number, text in lines:
        if m := _CONTROL.search(text):
            raise DeckError(f"control character U+{ord(m.group()):04X} at column {m.start() + 1} (expected text)",
                            file=file, line=number)


def split_sections(lines: Lines, file: str) -> tuple[Lines | None, Lines]:
    """(case-control lines or None, bulk-data lines up to ENDDATA)."""
    begin = next((i for i, (_, t) in enumerate(lines) if re.fullmatch(r"BEGIN\s*BULK", _code(t), re.I)), None)
    cend = next((i for i, (_, t) in enumerate(lines[:begin]) if _code(t).upper() == "CEND"), None)
    if begin is None:
        if cend is not None:
            raise DeckError("CEND but no BEGIN BULK (expected BEGIN BULK after the case control)", file=file,
                            line=lines[cend][0])
        case, bulk = None, lines
    else:
        case, bulk = lines[(cend if cend is not None else -1) + 1:begin], lines[begin + 1:]
    end = next((i for i, (_, t) in enumerate(bulk)
                if t.lstrip()[:1] in ("E", "e") and re.match(r"ENDDATA\b", _code(t), re.I)), None)
    if end is None and begin is not None:
        raise DeckError(f"BEGIN BULK at line {lines[begin][0]} has no ENDDATA (expected ENDDATA after the "
                        "bulk data)", file=file, line=lines[-1][0])
    return case, bulk[:end]


SELECTIONS = ("SPC", "MPC", "LOAD", "NLPARM", "METHOD")
#: the selections key of a case control's material temperature set (TEMP(MATERIAL) or TEMP(BOTH))
TEMPERATURE = "TEMP(MATERIAL)"
Selections = dict[int, dict[str, tuple[Any, int]]]  #: case ID -> key -> (value, line written)


def case_control(lines: Lines, file: str) -> tuple[Subcase, dict[int, Subcase], Selections]:
    """Global case, subcases with inherited selections resolved, and where each selection is written."""
    start = lines[0][0] - 1 if lines else 1
    blocks: dict[int, tuple[int, dict[str, tuple[Any, int]]]] = {0: (max(start, 1), {})}
    current = 0
    for number, text in lines:
        code = _code(text)
        label = f"SUBCASE {current}" if current else "global case control"
        if m := re.match(r"SUBCASE\b\s*=?\s*(.*)", code, re.I):  # "SUBCASE = 1": MSC.NASTRAN 2006 took it
            sid = parse_int(m.group(1))
            if sid is None or sid < 1:
                raise DeckError(f"expected a positive subcase ID, got {m.group(1)!r}", file=file, line=number,
                                card="SUBCASE")
            if sid in blocks:
                raise DeckError(f"SUBCASE {sid} defined twice: line {blocks[sid][0]} and line {number}",
                                file=file, line=number, card=f"SUBCASE {sid}")
            blocks[sid] = (number, {})
            current = sid
        elif m := re.match(r"(SUBCOM|SUBSEQ|SYMCOM|SYMSEQ|SYM|REPCASE)\b", code, re.I):
            raise DeckError(f"{m.group(1).upper()} is not supported by mace-fmu (expected SUBCASE)",
                            file=file, line=number, card=label)
        elif m := re.fullmatch(r"TEMP(?:ERATURE)?\s*(?:\(\s*([A-Za-z]+)\s*\))?\s*=\s*(.*)", code, re.I):
            # which temperatures set the materials (MATERIAL or BOTH, the default): the deck's check refuses
            # them where a MATT1 would make its material depend on them
            if (m.group(1) or "BOTH").upper() in ("MATERIAL", "BOTH"):
                blocks[current][1][TEMPERATURE] = (m.group(2).strip(), number)
        elif (m := re.fullmatch(r"([A-Za-z]+)\s*=\s*(.*)", code)) and m.group(1).upper() in (*SELECTIONS, "LABEL"):
            key, raw = m.group(1).upper(), m.group(2).strip()
            value: Any = raw if key == "LABEL" else parse_int(raw)
            if key != "LABEL" and (value is None or value < 1):
                raise DeckError(f"expected a set ID (positive integer), got {raw!r}", file=file, line=number,
                                card=label, field=key)
            own = blocks[current][1]
            if key in own:
                raise DeckError(f"{key} selected twice: line {own[key][1]} and line {number}", file=file,
                                line=number, card=label, field=key)
            own[key] = (value, number)
    selections: Selections = {}
    cases: dict[int, Subcase] = {}
    for cid, (line, own) in blocks.items():
        values = {**blocks[0][1], **own}
        selections[cid] = values
        get = {k: values.get(k, (None, 0))[0] for k in SELECTIONS}
        cases[cid] = Subcase(id=cid, spc=get["SPC"], mpc=get["MPC"], load=get["LOAD"], nlparm=get["NLPARM"],
                             method=get["METHOD"], label=values.get("LABEL", ("", 0))[0], source=Source(file, line))
    global_case = cases.pop(0)
    return global_case, cases, selections


@dataclass
class RawCard:
    """One bulk-data card as text: its name and its data fields across all its lines."""

    name: str  #: upper case, without the large-field '*'
    line: int  #: 1-based line of the card's first physical line
    fields: list[str] = field(default_factory=list)  #: stripped text of data fields 1, 2, ...
    lines: list[int] = field(default_factory=list)  #: physical line of each data field
    file: str = ""  #: the file the card is in (an INCLUDEd file's own name; "" for the deck's)


def _physical(text: str) -> tuple[str, list[str], bool]:
    """(field 1, data fields, free field?) of one non-blank line without its comment."""
    if "," in text:
        items = [item.strip() for item in text.split(",")]
        return items[0], items[1:], True
    text = text.expandtabs(8)
    head = text[:8].strip()
    width = 16 if head.startswith("*") or head.endswith("*") else 8
    # Columns 73-80 hold the continuation marker, which modern NASTRAN does not need.
    return head, [text[col:col + width].strip() for col in range(8, 72, width)], False


def split_cards(lines: Iterable[tuple[int, str]], file: str) -> list[RawCard]:
    """Group numbered bulk-data lines into cards (comments and blank lines dropped)."""
    cards: list[RawCard] = []
    for number, text in lines:
        text = (text.split("$", 1)[0] if "$" in text else text).rstrip()
        if not text:
            continue
        head, data, free = _physical(text)
        continuation = head == "" or head[0] in "+*"
        if continuation and not cards:
            raise DeckError(f"continuation line {head or '(blank field 1)'!r} has no card before it "
                            "(expected a card name in field 1)", file=file, line=number)
        large = head.startswith("*") if continuation else head.endswith("*")
        # "GRID   *": NASTRAN's own punch files put the large-field '*' at the end of field 1
        card = cards[-1] if continuation else RawCard(head.rstrip("*").strip().upper(), number)
        capacity = 4 if large else 8
        if not large and len(card.fields) % 8:
            raise DeckError("small-field continuation after an odd number of large-field lines (expected a '*' "
                            "continuation to complete the logical line)", file=file, line=number, card=card.name)
        if free and len(data) > capacity:
            data = _free_field_images(data, capacity, file=file, line=number, card=card.name)
        if not continuation:
            cards.append(card)
        # Short lines are padded so that each continuation starts at its positional data field.
        padded = -(-max(len(data), 1) // capacity) * capacity
        card.fields += data + [""] * (padded - len(data))
        card.lines += [number] * padded
    return cards


def _free_field_images(items: list[str], capacity: int, *, file: str, line: int, card: str) -> list[str]:
    """The data fields of a free-field line longer than one card image.

    NASTRAN converts a free-field line into fixed-field card images of ten fields (NASTRAN-95 User's Manual
    2.4.1.2; field 10 of an image is its continuation field): the items after the card name fill fields 2-9
    (``capacity`` data fields, 4 in large field), then field 10, and the items after that continue on implicit
    continuation images, each a field 1 (the continuation's marker), its data fields and its field 10. So the
    data go on at the next logical line's first data field; a field 10 or field 1 must hold a continuation
    marker (blank, or starting with + or *), and a datum written there is refused rather than shifted."""
    data = list(items[:capacity])
    rest = items[capacity:]
    image = 1
    while rest:
        for k, marker in enumerate(rest[:2]):  # field 10 of this image, field 1 of the next
            if marker and marker[0] not in "+*":
                where = f"field 10 of card image {image}" if k == 0 else f"field 1 of card image {image + 1}"
                raise DeckError(f"free-field line: {marker!r} (item {len(items) - len(rest) + k + 2} of the line) "
                                f"falls in {where}, a continuation field (NASTRAN reads a free-field line as card "
                                f"images of 10 fields: fields 2-{capacity + 1} data, fields 10 and 1 continuation "
                                "markers; expected a blank or a marker such as '+' there)",
                                file=file, line=line, card=card)
        rest = rest[2:]
        if rest:
            chunk = rest[:capacity]
            data += chunk + [""] * (capacity - len(chunk))
            rest = rest[capacity:]
            image += 1
    return data


def _bound(minimum: float | None, above: float | None) -> str:
    """The range a real field expects, for its messages: " >= 0.0", " > 0.0" or ""."""
    return (f" >= {minimum}" if minimum is not None else "") + (f" > {above}" if above is not None else "")


class Fields:
    """Typed, checked access to the data fields of one card; errors carry ``file:line`` and field."""

    def __init__(self, raw: RawCard, file: str) -> None:
        self.raw = raw
        self.file = raw.file or file
        self.label = raw.name  #: becomes "NAME ID" once the ID is read
        self._fields, self._count = raw.fields, len(raw.fields)  # read millions of times in a large deck

    def __len__(self) -> int:
        return self._count

    def text(self, d: int) -> str:
        """Stripped text of data field ``d`` ('' when blank or beyond the card)."""
        return self._fields[d - 1] if d <= self._count else ""

    def error(self, message: str, d: int | None = None, name: str = "", last: int | None = None) -> DeckError:
        """A DeckError at the line holding field ``d`` (the card's first line when absent)."""
        line = self.raw.lines[d - 1] if d is not None and d <= len(self.raw.lines) else self.raw.line
        return DeckError(message, file=self.file, line=line, card=self.label,
                         field=describe(d, name, last) if d is not None else None)

    def _blank(self, d: int, name: str, default: Any, expected: str) -> Any:
        if default is REQUIRED:
            raise self.error(f"required field is blank (expected {expected})", d, name)
        return default

    def integer(self, d: int, name: str, default: Any = REQUIRED, minimum: int | None = None) -> Any:
        """Integer field; a real or a word is an error."""
        text = self.text(d)
        value = parse_int(text) if text else None
        if value is not None and (minimum is None or value >= minimum):
            return value
        # the messages are built only for a field that needs one: a large deck reads millions of fields
        expected = "an integer" if minimum is None else f"an integer >= {minimum}"
        if not text:
            return self._blank(d, name, default, expected)
        raise self.error(f"expected {expected}, got {text!r}", d, name)

    def ident(self, d: int, name: str) -> int:
        """The card's required positive ID; later errors name the card with it."""
        value: int = self.integer(d, name, minimum=1)
        self.label = f"{self.raw.name} {value}"
        return value

    def real(self, d: int, name: str, default: Any = REQUIRED, minimum: float | None = None,
             above: float | None = None) -> Any:
        """Real field (decimal point required, as in NASTRAN), optionally >= ``minimum`` or > ``above``."""
        text = self.text(d)
        if not text:
            return self._blank(d, name, default, f"a real number{_bound(minimum, above)}")
        value = parse_real(text)
        if value is None:
            hint = " with a decimal point" if parse_int(text) is not None else ""
            raise self.error(f"expected a real number{hint}, got {text!r}", d, name)
        if not math.isfinite(value):
            raise self.error(f"real number {text!r} is out of range (expected a finite value)", d, name)
        if (minimum is not None and value < minimum) or (above is not None and value <= above):
            expected = f"a real number{_bound(minimum, above)}"
            raise self.error(f"value {text!r} is out of range (expected {expected})", d, name)
        return value

    def word(self, d: int, name: str, default: Any = REQUIRED, allowed: Iterable[str] | None = None) -> Any:
        """Character field (upper case), optionally one of ``allowed``."""
        text = self.text(d).upper()
        if not text:
            return self._blank(d, name, default, "a character value")
        choices = tuple(allowed) if allowed is not None else None
        if not _WORD.fullmatch(text) or (choices is not None and text not in choices):
            expected = "one of " + ", ".join(choices) if choices else "a character value"
            raise self.error(f"expected {expected}, got {text!r}", d, name)
        return text

    def components(self, d: int, name: str, default: Any = REQUIRED) -> str:
        """Component list such as '123456' or '2', normalised to sorted unique digits."""
        text = self.text(d)
        if not text:
            blank: str = self._blank(d, name, default, "components (digits 1-6)")
            return blank
        if not re.fullmatch(r"[1-6]+", text):
            raise self.error(f"expected components (digits 1-6), got {text!r}", d, name)
        return "".join(sorted(set(text)))

    def component(self, d: int, name: str) -> int:
        """A single required component 1-6 of a grid."""
        text = self.text(d)
        if text == "0":
            raise self.error("component 0 (scalar point) is not supported by mace-fmu "
                             "(expected a single digit 1-6)", d, name)
        if not text:
            blank: int = self._blank(d, name, REQUIRED, "a single component digit 1-6")  # raises
            return blank
        if not re.fullmatch(r"[1-6]", text):
            raise self.error(f"expected a single component digit 1-6, got {text!r}", d, name)
        return int(text)

    def blank(self, d: int, name: str) -> None:
        """Field that must be blank (unused by NASTRAN or by mace-fmu)."""
        if self.text(d):
            raise self.error(f"expected a blank field, got {self.text(d)!r}", d, name)

    def end(self, last: int) -> None:
        """No data beyond field ``last``."""
        for d in range(last + 1, len(self) + 1):
            if self.text(d):
                raise self.error(f"unexpected value {self.text(d)!r} (the card has {last} data fields)",
                                 d, "unused")
