"""Thesis A.2's aluminium cantilever (Figure A.5) from our FE core, as a modal state-space model.

A 1 in x 1/8 in aluminium bar, clamped at one end, bending in its stiff-less plane (the force is
across the 1/8 in thickness). The deck (CBAR elements, consistent mass) goes through the same
reader, assembly and eigen-solver as the MACE deck. Euler-Bernoulli bars give frequencies that
scale exactly as 1/L^2, so the length for the thesis's 27.8 Hz fundamental follows from one
solve. Unstated in the thesis, chosen here: E = 69 GPa, rho = 2700 kg/m^3 (nominal aluminium; the
length, 0.305 m = 12.0 in, absorbs them), 20 elements (mode 5 within 0.1 % of Euler-Bernoulli).
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np

from mace_fmu.deck.reader import read_deck_text
from mace_fmu.errors import MaceError
from mace_fmu.fe.assembly import assemble
from mace_fmu.fe.constraints import build_constraints
from mace_fmu.fe.modal import Modes, solve_modes

INCH = 0.0254  # [m]


@dataclass(frozen=True)
class CantileverSpec:
    """Section, material, target fundamental, mesh and modal model of the A.2 cantilever (SI)."""

    width: float = 1.0 * INCH  #: [m], along the force's normal
    thickness: float = 0.125 * INCH  #: [m], along the force
    youngs_modulus: float = 69.0e9  #: [Pa]
    density: float = 2700.0  #: [kg/m^3]
    fundamental_hz: float = 27.8  #: the thesis's first bending frequency [Hz]
    elements: int = 20  #: CBARs along the length
    modes: int = 5  #: modes kept in the model
    damping_ratio: float = 0.01  #: of every mode

    @property
    def area(self) -> float:
        """Cross-section area [m^2]."""
        return self.width * self.thickness

    @property
    def bending_inertia(self) -> float:
        """Second moment of area for bending across the thickness [m^4]."""
        return self.width * self.thickness**3 / 12.0


@dataclass(frozen=True)
class CantileverModel:
    """Length, FE modes and the modal model tip force [N] -> tip displacement [m]."""

    spec: CantileverSpec
    length: float  #: [m]
    frequencies_hz: np.ndarray  #: of the kept modes
    tip_shapes: np.ndarray  #: mass-normalised tip displacement per kept mode [m/sqrt(kg)]
    system: ct.StateSpace  #: x = [eta; eta'] of the kept modes


def _r(x: float) -> str:
    return f"{x:.10e}"


def cantilever_deck_text(*, spec: CantileverSpec, length: float) -> str:
    """Bulk data of the cantilever along basic x, grid 1 clamped, bending in the x-y plane only.

    Every grid keeps T2 and R3 (the PS field fixes axial, out-of-plane and torsion motion), so
    all modes are bending across the thickness (the force's direction, basic y).
    """
    if not (length > 0.0 and spec.elements >= 1):
        raise MaceError(f"cantilever: expected a positive length and at least one element, got {length}, "
                        f"{spec.elements}")
    i_thin, i_wide = spec.bending_inertia, spec.thickness * spec.width**3 / 12.0
    # Poisson's ratio only sets G, which no kept DOF feels (torsion is fixed, the bars have no shear factor)
    cards = [f"MAT1,1,{_r(spec.youngs_modulus)},,{_r(0.33)},{_r(spec.density)}",
             # I1 bends in the element x-y plane (orientation vector along basic y)
             f"PBAR,1,1,{_r(spec.area)},{_r(i_thin)},{_r(i_wide)},{_r(i_thin + i_wide)}"]
    n = spec.elements
    for k in range(n + 1):
        cards.append(f"GRID,{k + 1},,{_r(length * k / n)},0.0,0.0,,1345")
    cards += [f"CBAR,{100 + k},1,{k + 1},{k + 2},0.0,1.0,0.0" for k in range(n)]
    cards.append("SPC1,1,123456,1")
    return "BEGIN BULK\n" + "\n".join(cards) + "\nENDDATA\n"


def tip_grid(spec: CantileverSpec) -> int:
    """ID of the free-end grid."""
    return spec.elements + 1


def cantilever_modes(*, spec: CantileverSpec, length: float) -> Modes:
    """All bending modes of the FE cantilever of ``length`` [m] (consistent mass)."""
    deck = read_deck_text(cantilever_deck_text(spec=spec, length=length), name="<cantilever>")
    model = assemble(deck, mass="consistent")
    cons = build_constraints(deck, model.dofs, model.cd_frames, spc_set=1, mpc_set=None)
    return solve_modes(model.stiffness, model.mass, cons, model.dofs, model.cd_frames)


def length_for_fundamental(spec: CantileverSpec) -> float:
    """Length [m] whose FE fundamental is ``spec.fundamental_hz`` (f scales as 1/L^2)."""
    f_at_1m = cantilever_modes(spec=spec, length=1.0).frequencies_hz[0]
    return float(np.sqrt(f_at_1m / spec.fundamental_hz))


def cantilever_model(spec: CantileverSpec = CantileverSpec()) -> CantileverModel:
    """The modal model of the first ``spec.modes`` modes, tip force [N] in, tip displacement [m] out.

    Parameters
    ----------
    spec : CantileverSpec
        Beam section [m], material [Pa, kg/m^3], the fundamental frequency it is tuned to [Hz], elements,
        retained modes and their damping ratio (default: Appendix A's beam).

    Returns
    -------
    CantileverModel
        The beam's length [m], the kept modes' frequencies [Hz] and tip shapes, and their state space.
    """
    length = length_for_fundamental(spec)
    modes = cantilever_modes(spec=spec, length=length)
    if len(modes) < spec.modes:
        raise MaceError(f"cantilever: {spec.elements} elements give {len(modes)} modes, fewer than the "
                        f"{spec.modes} asked for")
    freq = modes.frequencies_hz[:spec.modes]
    phi = modes.shape(tip_grid(spec), 2)[:spec.modes]
    omega = 2.0 * np.pi * freq
    n = spec.modes
    a = np.block([[np.zeros((n, n)), np.eye(n)],
                  [-np.diag(omega**2), -np.diag(2.0 * spec.damping_ratio * omega)]])
    b = np.concatenate([np.zeros(n), phi])[:, None]
    c = np.concatenate([phi, np.zeros(n)])[None, :]
    states = [f"eta_{k + 1}" for k in range(n)] + [f"eta_{k + 1}_dot" for k in range(n)]
    system = ct.ss(a, b, c, np.zeros((1, 1)), inputs=["tip_force"], outputs=["tip_displacement"], states=states,
                   name="cantilever")
    return CantileverModel(spec=spec, length=length, frequencies_hz=freq, tip_shapes=phi, system=system)
