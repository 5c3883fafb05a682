"""The element library against closed-form solutions, through reader, assembly and solvers."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sla
from support.decks import deck_text, line_of_bars, r

from mace_fmu.deck.reader import read_deck_text
from mace_fmu.fe.assembly import assemble
from mace_fmu.fe.constraints import build_constraints
from mace_fmu.fe.modal import solve_modes
from mace_fmu.fe.modes import compute_modes, gravity_load
from mace_fmu.fe.preload import geometric_stiffness

# Steel-like solid round bar, 1 m
E, NU, RHO, L = 2.0e11, 0.3, 7800.0, 1.0
D = 0.02
AREA, INERTIA = math.pi * D**2 / 4, math.pi * D**4 / 64


def modes_of(text: str, *, spc: int | None = None, max_hz: float | None = None, mass: str = "lumped"):
    deck = read_deck_text(text)
    model = assemble(deck, mass=mass)
    cons = build_constraints(deck, model.dofs, model.cd_frames, spc_set=spc, mpc_set=None)
    return solve_modes(model.stiffness, model.mass, cons, model.dofs, model.cd_frames, max_hz=max_hz)


@pytest.mark.parametrize(("mass", "rtol"), [("consistent", 5e-3), ("lumped", 1e-2)])
def test_cantilever_bending_frequencies_euler_bernoulli(mass, rtol):
    """beta_n L = 1.875104, 4.694091, 7.854757 (Euler-Bernoulli cantilever), 20 bars.

    Consistent mass: within 0.5 %. NASTRAN's lumped bar mass (no rotary inertia) converges as
    (n pi / N)^2 from below: the third mode is 0.65 % low with 20 bars, hence 1 %.
    """
    # in-plane (x-y) motion only: translations along z and rotations about x, y fixed
    bulk = line_of_bars(n=20, length=L, e=E, nu=NU, rho=RHO, area=AREA, i=INERTIA, ps="345")
    bulk.append("SPC1,1,123456,1")
    modes = modes_of(deck_text(bulk), spc=1, mass=mass)
    bending = modes.frequencies_hz[:3]  # the axial mode is far higher
    exact = np.array([1.875104, 4.694091, 7.854757]) ** 2 * math.sqrt(E * INERTIA / (RHO * AREA * L**4)) / (2 * math.pi)
    np.testing.assert_allclose(bending, exact, rtol=rtol)


def test_short_thick_beam_matches_timoshenko_not_euler_bernoulli():
    """Simply supported, L/D = 5, shear factor 0.9: f_n from the Timoshenko equation without
    rotary inertia (lumped mass has none): w^2 = (EI k^4 / rho A) / (1 + EI k^2 / (kappa G A))."""
    length, kappa = 0.1, 0.9
    # bending in the x-y plane only (axial motion fixed too: it decouples and is not tested here)
    bulk = line_of_bars(n=40, length=length, e=E, nu=NU, rho=RHO, area=AREA, i=INERTIA, shear_factor=kappa, ps="1345")
    bulk += ["SPC1,1,12,1", "SPC1,1,2,41"]
    f = modes_of(deck_text(bulk), spc=1).frequencies_hz
    g = E / (2 * (1 + NU))
    k = np.array([1, 2]) * math.pi / length
    euler = np.sqrt(E * INERTIA * k**4 / (RHO * AREA)) / (2 * math.pi)
    timoshenko = euler / np.sqrt(1 + E * INERTIA * k**2 / (kappa * g * AREA))
    bending = np.sort(f[f < 1.2 * euler[1]])[:2]
    np.testing.assert_allclose(bending, timoshenko, rtol=1e-2)
    assert np.all(np.abs(bending / euler - 1) > 0.02), "shear must matter for this beam, or the test proves nothing"


def _hanging_spec_deck(bulk: list[str], *, static_spc: int, modal_spc: int) -> str:
    case = (f"SUBCASE 1\n  SPC = {static_spc}\n  LOAD = 10\n  NLPARM = 1\nSUBCASE 2\n  SPC = {modal_spc}\n")
    bulk = bulk + ["GRAV,10,,9.81,0.0,-1.0,0.0", "NLPARM,1,5"]
    return deck_text(bulk, case=case)


@pytest.mark.parametrize("preload", ["large", "linear"])
def test_taut_string_violin_frequencies_from_geometric_stiffness(preload):
    """A light vertical string tensioned by a 50 kg mass that may only move vertically:
    f_n = n / (2 L) sqrt(T / mu) for the transverse modes, within 1 %."""
    length, mass_end = 2.0, 50.0
    d = 0.002
    # negligible bending stiffness: sqrt(EI / T) / L = 1e-3 (a real 2 mm wire would add 0.9 %)
    area, inertia = math.pi * d**2 / 4, 1.0e-14
    rho = 1000.0
    # stiff (static strain 8e-4), so the length and mu hardly change under the preload
    bulk = line_of_bars(n=40, length=length, e=2.0e11, nu=0.3, rho=rho, area=area, i=inertia,
                        direction=(0.0, -1.0, 0.0), ps="345")
    bulk += [f"CONM2,900,41,,{r(mass_end)}", "SPC1,1,123456,1", "SPC1,1,1,41"]
    result = compute_modes(read_deck_text(_hanging_spec_deck(bulk, static_spc=1, modal_spc=1)), configuration="1g",
                           preload=preload, max_hz=400.0)
    mu = rho * area
    tension = mass_end * 9.81 + 0.5 * mu * length * 9.81  # mean tension along the string
    exact = np.arange(1, 4) / (2 * length) * math.sqrt(tension / mu)
    f = result.frequencies_hz
    transverse = f[(f > 0.5 * exact[0]) & (f < 1.1 * exact[2])]  # the bounce of the mass is at 6 Hz
    np.testing.assert_allclose(transverse, exact, rtol=1e-2)


@pytest.mark.parametrize("preload", ["large", "linear"])
def test_pendulum_frequency_from_gravity_preload(preload):
    """Point mass on a light stiff rod, pinned at the top: f = sqrt(g / L) / (2 pi) within 1 %."""
    length = 0.75
    bulk = line_of_bars(n=4, length=length, e=2.0e11, nu=0.3, rho=0.0, area=1.0e-4, i=1.0e-8,
                        direction=(0.0, -1.0, 0.0), ps="345")
    # the pin is locked for the static preload (as MACE's gimbals are) and released for the modes
    bulk += ["CONM2,900,5,,2.0", "SPC1,1,123456,1", "SPC1,2,123,1"]
    result = compute_modes(read_deck_text(_hanging_spec_deck(bulk, static_spc=1, modal_spc=2)), configuration="1g",
                           preload=preload, max_hz=50.0)
    assert result.frequencies_hz[0] == pytest.approx(math.sqrt(9.81 / length) / (2 * math.pi), rel=1e-2)


def test_euler_column_buckling_load_from_geometric_stiffness():
    """Pinned-pinned column under a top mass: lambda * M g = pi^2 E I / L^2 within 1 % (20 bars)."""
    mass_top = 100.0
    bulk = line_of_bars(n=20, length=L, e=E, nu=NU, rho=0.0, area=AREA, i=INERTIA, direction=(0.0, 1.0, 0.0), ps="345")
    bulk += [f"CONM2,900,21,,{r(mass_top)}", "GRAV,10,,9.81,0.0,-1.0,0.0", "SPC1,1,123,1", "SPC1,1,1,21"]
    deck = read_deck_text(deck_text(bulk))
    model = assemble(deck)
    cons = build_constraints(deck, model.dofs, model.cd_frames, spc_set=1, mpc_set=None)
    k_sigma = geometric_stiffness(model, cons, gravity_load(deck, model, 10))
    lam = sla.eigvals(cons.reduce(model.stiffness), -cons.reduce(k_sigma)).real
    critical = np.min(lam[lam > 0]) * mass_top * 9.81
    assert critical == pytest.approx(math.pi**2 * E * INERTIA / L**2, rel=1e-2)
