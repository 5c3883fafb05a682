"""The tip-mass cantilever of the own-deck tests: its SOL 103 deck and its closed-form frequencies.

Shared by tests/structure/test_own_deck.py and tests/iomodel/test_acceleration_sensors.py.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.optimize

from support.decks import line_of_bars, r

E, NU, RHO, L, N = 7.0e10, 0.33, 2700.0, 2.0, 20
D = 0.03
AREA, INERTIA = math.pi * D**2 / 4, math.pi * D**4 / 64
TIP_MASS = 0.6 * RHO * AREA * L  # kg: 60 % of the beam's mass


def beam_deck(*, first_grid: int = 1, mass_id: int = 22, eigrl: str = "EIGRL,1,,,4", method: bool = True,
              length: float = L) -> str:
    """A cantilever along X, bending in the x-y plane only, with a tip mass (60 % of the beam's), as a SOL 103 deck."""
    bulk = line_of_bars(n=N, length=length, e=E, nu=NU, rho=RHO, area=AREA, i=INERTIA, ps="345",
                        first_grid=first_grid)
    if first_grid != 1:  # renumber the bars too: no ID in common with the first beam
        bulk = [c.replace("CBAR,1", "CBAR,5") if c.startswith("CBAR,1") else c for c in bulk]
    tip = first_grid + N
    bulk += [f"CONM2,{mass_id},{tip},,{r(TIP_MASS * length / L)}", f"SPC1,7,123456,{first_grid}", eigrl]
    case = "SPC = 7\n" + ("METHOD = 1\n" if method else "")
    return f"SOL 103\nCEND\n{case}BEGIN BULK\n" + "\n".join(bulk) + "\nENDDATA\n"


def tip_mass_cantilever_hz(count: int) -> np.ndarray:
    """Roots of 1 + cos(bL) cosh(bL) + mu bL (cos(bL) sinh(bL) - sin(bL) cosh(bL)) = 0, mu = M / (rho A L)."""
    mu = TIP_MASS / (RHO * AREA * L)

    def g(x: float) -> float:
        return 1 + math.cos(x) * math.cosh(x) + mu * x * (math.cos(x) * math.sinh(x) - math.sin(x) * math.cosh(x))

    grid = np.linspace(0.1, 15.0, 3000)
    values = [g(x) for x in grid]
    roots = [scipy.optimize.brentq(g, a, b) for a, b, ga, gb in zip(grid, grid[1:], values, values[1:]) if ga * gb < 0]
    beta = np.array(roots[:count]) / L
    return beta**2 * math.sqrt(E * INERTIA / (RHO * AREA)) / (2 * math.pi)
