"""Exceptions raised by mace-fmu itself (as opposed to numpy/scipy failures)."""

from __future__ import annotations


class MaceError(ValueError):
    """Base class of mace-fmu's own errors."""


class DeckError(MaceError):
    """A deck that cannot be read or is inconsistent, located at ``file:line`` (and card, field).

    ``str(e)`` is one line, e.g.
    ``deck.bdf:123: CBAR 41, field 5 (GB): grid 999 is not defined (expected a GRID ID)``;
    line 0 means the file as a whole: ``deck.bdf: no such file``.
    """

    def __init__(self, message: str, *, file: str, line: int, card: str | None = None,
                 field: str | None = None, details: tuple[str, ...] = ()) -> None:
        self.message = message
        self.file = str(file)
        self.line = line
        self.card = card  #: card name and ID when known, e.g. "CBAR 41"
        self.field = field  #: field position and name, e.g. "field 5 (GB)"
        #: the whole story behind a message that had to be short, one line each (the CLI shows it with --verbose)
        self.details = tuple(details)
        super().__init__(str(self))

    def __str__(self) -> str:
        where = ", ".join(part for part in (self.card, self.field) if part)
        at = f"{self.file}:{self.line}: " if self.line > 0 else f"{self.file}: "  # line 0: the file as a whole
        text = at + (f"{where}: " if where else "") + self.message
        # One line, whatever the message or a card field dragged in.
        return " ".join(text.splitlines())

    def __reduce__(self):  # keep keyword-only arguments picklable (multiprocessing, pytest-xdist)
        return (_rebuild, (self.message, self.file, self.line, self.card, self.field, self.details))


def _rebuild(message: str, file: str, line: int, card: str | None, field: str | None,
             details: tuple[str, ...] = ()) -> DeckError:
    return DeckError(message, file=file, line=line, card=card, field=field, details=details)
