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


def frame_tower(*, nx: int, ny: int, levels: int, bay_m: float = 1.0, storey_m: float = 1.0,
                with_gravity: bool = False, modes: int = 50) -> str:
    """A lattice tower of aluminium tube bars as a deck: ``nx`` x ``ny`` grids per level, ``levels`` storeys
    above a clamped base, bars along every grid line and one diagonal per bay face, a 5 kg CONM2 on every
    grid of the top level, an EIGRL asking for the lowest ``modes``; with a gravity subcase (SUBCASE 1,
    LOAD) for a 1-g preload when ``with_gravity``. 6 nx ny (levels + 1) DOFs; the benchmarks' scalable deck."""
    area, inertia = 2.0e-4, 3.0e-8  # a 40 x 2 mm aluminium tube
    cards = ["MAT1,1,7.0e10,,0.33,2700.0", f"PBAR,1,1,{r(area)},{r(inertia)},{r(inertia)},{r(2 * inertia)}",
             f"EIGRL,1,,,{modes}"]
    grid = {}
    for k in range(levels + 1):
        for j in range(ny):
            for i in range(nx):
                gid = 1 + i + nx * (j + ny * k)
                grid[i, j, k] = gid
                cards.append(f"GRID,{gid},,{r(i * bay_m)},{r(j * bay_m)},{r(k * storey_m)}")
    eid = 1

    def bar(a: int, b: int, v: tuple[float, float, float]) -> None:
        nonlocal eid
        cards.append(f"CBAR,{eid},1,{a},{b},{r(v[0])},{r(v[1])},{r(v[2])}")
        eid += 1

    for (i, j, k), g in grid.items():
        if i + 1 < nx:
            bar(g, grid[i + 1, j, k], (0.0, 0.0, 1.0))
        if j + 1 < ny:
            bar(g, grid[i, j + 1, k], (0.0, 0.0, 1.0))
        if k + 1 <= levels:
            bar(g, grid[i, j, k + 1], (1.0, 0.0, 0.0))
            if i + 1 < nx:
                bar(g, grid[i + 1, j, k + 1], (0.0, 1.0, 0.0))
            if j + 1 < ny:
                bar(g, grid[i, j + 1, k + 1], (1.0, 0.0, 0.0))
    for n, g in enumerate(g for (i, j, k), g in grid.items() if k == levels):
        cards.append(f"CONM2,{100000 + n},{g},,5.0")
    base = [g for (i, j, k), g in grid.items() if k == 0]
    cards += [f"SPC1,1,123456,{g}" for g in base]
    case = "METHOD = 1\nSPC = 1\n"
    if with_gravity:
        cards += ["GRAV,9999,0,9.807,0.0,0.0,-1.0", "LOAD,100,1.0,1.0,9999"]
        case = "METHOD = 1\nSUBCASE 1\n  SPC = 1\n  LOAD = 100\nSUBCASE 2\n  SPC = 1\n"
    return deck_text(cards, case=case)
