"""A user's text file read with errors that name the file and what it was meant to be."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

from mace_fmu.errors import MaceError


def read_text(path: str | Path, *, what: str | None = None) -> str:
    """The UTF-8 text of ``path``; MaceError '<path>: no such <what> file' or '<path>: cannot read the <what>: ...'."""
    try:
        return Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise MaceError(f"{path}: no such {what + ' ' if what else ''}file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise MaceError(f"{path}: cannot read{' the ' + what if what else ''}: {exc}") from None


def read_toml(path: str | Path, *, what: str) -> dict[str, Any]:
    """The parsed TOML of ``path``; errors as :func:`read_text`'s, or '<path>: not a valid <what> (TOML): ...'.

    Parameters
    ----------
    path : path
        The TOML file.
    what : str
        What kind of file it is, for error messages ("parameter-set", "test-plan", ...).

    Returns
    -------
    dict
        The parsed tables.

    Raises
    ------
    MaceError
        The file is missing, not UTF-8 or not TOML: one line naming it.
    """
    text = read_text(path, what=what)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise MaceError(f"{path}: not a valid {what} (TOML): {exc}") from None
