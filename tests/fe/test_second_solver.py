"""The cards no public NASTRAN result checks, against a second solver that reads the same decks: MYSTRAN.

tests/data/second_solver holds small decks written for this check (CROD, CELAS1/PELAS, CMASS1/PMASS, RBE3,
CORD1R, PBARL TUBE and BOX) and the .F06 MYSTRAN 17.0.0 printed for each (provenance.toml there says how it was
built and run). MYSTRAN is an independent NASTRAN-compatible solver (its own reader, elements, constraint
processing and Lanczos/Givens eigensolvers); nothing of it is used here but its printed eigenvalues.

* CROD, CELAS1, CMASS1, RBE3, CORD1R: every mode within 1e-6 (MYSTRAN prints 7 significant digits).
* PBARL TUBE and BOX: MYSTRAN gives a PBARL section the A, I1 and I2 of the published formulas but shear factors
  of its own (BD_PBARL.f90), not NASTRAN's (which mace-fmu uses, checked against NASTRAN's message 4379 in
  test_nastran_decks.py). Our CBAR on a PBAR with the published A, I1, I2 and MYSTRAN's factors reproduces
  MYSTRAN's PBARL run to 1e-6 on every mode; the PBARL decks as NASTRAN reads them then differ from MYSTRAN by
  the shear-factor convention alone: within 3e-4 on the first bending mode of each plane (measured 2.1e-4, the
  BOX's plane 1, NASTRAN's K1 0.21 against MYSTRAN's 0.80) and 1e-2 on the eight modes (measured 6.4e-3, the
  BOX's third plane-1 bending mode, where shear matters most).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.paths import DATA

from mace_fmu.deck.reader import read_deck, read_deck_text
from mace_fmu.fe.modes import compute_modes

FOLDER = DATA / "second_solver"
EXACT = 1e-6  #: relative, MYSTRAN printing 7 significant digits (rounding 5e-7 at most)


def mystran_hz(name: str) -> np.ndarray:
    """CYCLES column of the REAL EIGENVALUES table of MYSTRAN's ``name``.F06 [Hz]."""
    lines = (FOLDER / f"{name}.F06").read_text(encoding="latin-1").splitlines()
    start = next(k for k, line in enumerate(lines) if "R E A L   E I G E N V A L U E S" in line)
    cycles = []
    for line in lines[start + 3:]:
        parts = line.split()
        # MODE NUMBER, EXTRACTION ORDER, EIGENVALUE, RADIANS, CYCLES, GENERALIZED MASS, GENERALIZED STIFFNESS
        if len(parts) == 7 and parts[0].isdigit():
            cycles.append(float(parts[4]))
        elif cycles:
            break
    return np.array(cycles)


def ours_hz(text_or_name: str) -> np.ndarray:
    deck = read_deck_text(text_or_name) if "\n" in text_or_name else read_deck(FOLDER / f"{text_or_name}.bdf")
    return compute_modes(deck, configuration="0g").modes.frequencies_hz


@pytest.mark.parametrize("name", ["crod", "scalar_springs_masses", "rbe3", "cord1r"])
def test_every_mode_is_mystrans(name):
    reference = mystran_hz(name)
    assert len(reference) >= 7
    ours = ours_hz(name)
    assert len(ours) == len(reference), f"{len(ours)} modes, MYSTRAN has {len(reference)}"
    np.testing.assert_allclose(ours, reference, rtol=EXACT)


def _tube(outer: float, inner: float) -> tuple[float, float, float, float, float]:
    """A, I1, I2 of a hollow circle (Roark table A.1) and MYSTRAN's K1 = K2: Cowper's hollow-circle shear factor
    with nu = 0, 6 (1 + m^2)^2 / (7 (1 + m^2)^2 + 20 m^2), m = inner / outer (BD_PBARL.f90, SECTION_PROPS_TUBE)."""
    area, inertia = math.pi * (outer**2 - inner**2), math.pi * (outer**4 - inner**4) / 4
    m2 = (inner / outer) ** 2
    k = 6 * (1 + m2) ** 2 / (7 * (1 + m2) ** 2 + 20 * m2)
    return area, inertia, inertia, k, k


def _box(width: float, height: float, t_flange: float, t_web: float) -> tuple[float, float, float, float, float]:
    """A, I1 (about element z: height along y), I2 of a hollow rectangle (Roark table A.1) and MYSTRAN's K1, K2:
    the inner height over the height, the inner width over the width (BD_PBARL.f90, SECTION_PROPS_BOX)."""
    inner_w, inner_h = width - 2 * t_web, height - 2 * t_flange
    return (width * height - inner_w * inner_h, (width * height**3 - inner_w * inner_h**3) / 12,
            (height * width**3 - inner_h * inner_w**3) / 12, inner_h / height, inner_w / width)


PBARL = {"pbarl_tube": _tube(0.03, 0.025), "pbarl_box": _box(0.06, 0.03, 0.003, 0.002)}


def _with_pbar(name: str, area: float, i1: float, i2: float, k1: float | None, k2: float | None) -> str:
    """The deck with its PBARL (a card and one continuation) replaced by a PBAR of these values (K1, K2 None:
    blank, rigid in shear). J does not matter: a CBAR's lumped mass has no torsional inertia, so torsion is not
    among the modes."""
    lines = (FOLDER / f"{name}.bdf").read_text().splitlines()
    at = next(k for k, line in enumerate(lines) if line.startswith("PBARL"))
    pbar = f"PBAR,1,1,{area:.12e},{i1:.12e},{i2:.12e},{(i1 + i2):.12e}"
    if k1 is not None and k2 is not None:
        pbar += f"\n,,,,,,,,\n,{k1:.12e},{k2:.12e}"
    return "\n".join(lines[:at] + [pbar] + lines[at + 2:]) + "\n"


@pytest.mark.parametrize("name", sorted(PBARL))
def test_pbarl_is_mystrans_with_the_published_section_and_mystrans_shear_factors(name):
    reference = mystran_hz(name)
    np.testing.assert_allclose(ours_hz(_with_pbar(name, *PBARL[name])), reference, rtol=EXACT)


@pytest.mark.parametrize("name", sorted(PBARL))
def test_pbarl_as_nastran_reads_it_differs_from_mystran_by_the_shear_factors_alone(name):
    reference, ours = mystran_hz(name), ours_hz(name)
    assert len(ours) == len(reference)
    np.testing.assert_allclose(ours[:2], reference[:2], rtol=3e-4)  # first bending mode of each plane
    np.testing.assert_allclose(ours, reference, rtol=1e-2)
    # and the difference is the shear factors': with MYSTRAN's, the same section gives MYSTRAN's modes (above),
    # with infinite shear stiffness (K blank) it gives modes above both
    area, i1, i2, _, _ = PBARL[name]
    rigid_in_shear = ours_hz(_with_pbar(name, area, i1, i2, None, None))
    assert np.all(rigid_in_shear > ours) and np.all(rigid_in_shear > reference)
