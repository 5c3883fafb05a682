"""The command-line spellings removed before the first release, each refused by name.

``docs/reference/renamed.md`` promises that an earlier spelling is never refused generically ("unrecognized
arguments") nor read as something else: the command names it and says what to write instead.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence


@dataclass(frozen=True)
class RemovedSpelling:
    """An option of an earlier development version that is gone."""

    command: str  #: the subcommand it belonged to, e.g. "export"
    spelling: str  #: the option, e.g. "--kind"
    now: str  #: what to write instead
    #: only as the first argument after the command: ``update -o DIR`` is gone, ``update mace -o DIR`` is not
    first_only: bool = False


#: every removed spelling of the command line (docs/reference/renamed.md, CHANGELOG.md)
REMOVED = (
    RemovedSpelling("export", "--kind", "--runtime native|pythonfmu"),
    RemovedSpelling("predict-0g", "--kind", "--runtime native|pythonfmu"),
    RemovedSpelling("update", "--fmu", "mace-fmu update fmu FILE ...", first_only=True),
    RemovedSpelling("update", "--sample-problem", "mace-fmu update sample-problem", first_only=True),
    RemovedSpelling("update", "-o", "mace-fmu update mace -o DIR", first_only=True),
    RemovedSpelling("update", "--out", "mace-fmu update mace -o DIR", first_only=True),
)


def removed_spelling(argv: Sequence[str]) -> tuple[str, str] | None:
    """The command and the message for a removed spelling in ``argv`` (the arguments after ``mace-fmu``).

    Parameters
    ----------
    argv : sequence of str
        The command line after ``mace-fmu``.

    Returns
    -------
    tuple of (str, str) or None
        (the subcommand, e.g. "update"; one sentence naming the spelling and what to write now), or None when
        ``argv`` has no removed spelling.
    """
    argv = list(argv)
    command = next((k for k, token in enumerate(argv) if not token.startswith("-")), None)
    if command is None:
        return None
    rest = argv[command + 1:]
    for removed in REMOVED:
        if removed.command != argv[command]:
            continue
        tokens = rest[:1] if removed.first_only else rest
        if any(token == removed.spelling or token.startswith(removed.spelling + "=") for token in tokens):
            return removed.command, (f"{removed.spelling} was removed before the first release; write "
                                     f"{removed.now} (docs/reference/renamed.md)")
    return None
