"""Small decks written as text for analytic checks (they go through the real reader)."""

from __future__ import annotations


def r(x: float) -> str:
    """A NASTRAN real field (always with a decimal point)."""
    return f"{x:.10e}"


def line_of_bars(*, n: int, length: float, e: float, nu: float, rho: float, area: float, i: float,
                 j: float | None = None, shear_factor: float | None = None, direction=(1.0, 0.0, 0.0),
                 orientation=(0.0, 0.0, 1.0), ps: str = "", first_grid: int = 1) -> list[str]:
    """GRID/CBAR/PBAR/MAT1 cards of a straight beam of ``n`` bars from the origin (free field)."""
    j = 2 * i if j is None else j
    cards = [f"MAT1,1,{r(e)},,{r(nu)},{r(rho)}"]
    pbar = f"PBAR,1,1,{r(area)},{r(i)},{r(i)},{r(j)}"
    if shear_factor is not None:
        # K1/K2 sit on the second continuation (fields 17-18), after the stress points
        pbar += f"\n,,,,,,,,\n,{r(shear_factor)},{r(shear_factor)}"
    cards.append(pbar)
    for k in range(n + 1):
        s = length * k / n
        cards.append(f"GRID,{first_grid + k},,{r(direction[0] * s)},{r(direction[1] * s)},{r(direction[2] * s)},,{ps}")
    for k in range(n):
        cards.append(f"CBAR,{100 + k},1,{first_grid + k},{first_grid + k + 1},"
                     f"{r(orientation[0])},{r(orientation[1])},{r(orientation[2])}")
    return cards


def deck_text(bulk: list[str], *, case: str = "") -> str:
    """A complete deck: optional case control, BEGIN BULK, the cards, ENDDATA."""
    head = f"SOL 103\nCEND\n{case}\nBEGIN BULK\n" if case else "BEGIN BULK\n"
    return head + "\n".join(bulk) + "\nENDDATA\n"
