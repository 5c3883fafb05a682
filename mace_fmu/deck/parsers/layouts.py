"""Field layouts that cards of several families share: three reals in a row, and up to two four-field groups."""

from __future__ import annotations

from mace_fmu.deck.fields import Fields


def vec(f: Fields, d: int, names: tuple[str, str, str]) -> tuple[float, float, float]:
    """Data fields ``d`` to ``d + 2`` as a vector of reals (blank fields are 0.0).

    Parameters
    ----------
    f : Fields
        The card's fields.
    d : int
        Data field of the first component.
    names : tuple of str
        The three fields' names, for messages.

    Returns
    -------
    tuple of float
        The three values.
    """
    return (f.real(d, names[0], 0.0), f.real(d + 1, names[1], 0.0), f.real(d + 2, names[2], 0.0))


def two_groups(f: Fields, expected: str, first_name: str) -> list[tuple[int, int]]:
    """The four-field groups present on a card that carries up to two of them (CORD1R, PELAS, ...).

    Parameters
    ----------
    f : Fields
        The card's fields.
    expected : str
        What the first group holds, for the message when it is blank.
    first_name : str
        Name of the first group's first field.

    Returns
    -------
    list of (int, int)
        (group number 1 or 2, its first data field) of each group present; the first is required.
    """
    present = [(k, d) for k, d in ((1, 1), (2, 5)) if any(f.text(d + i) for i in range(4))]
    if not present or present[0][0] != 1:
        raise f.error(f"required field is blank (expected {expected})", 1, first_name)
    return present
