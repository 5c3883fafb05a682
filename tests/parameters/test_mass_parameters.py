"""Concentrated masses as parameters (``m_<name>``) in the full re-solve: a scaled body, checked in closed form.

A CONM2 on a translational and a rotational spring (every other DOF held) has two modes, sqrt(k / m) and
sqrt(k_r / I11): a mass parameter f x m must move both by 1 / sqrt(f), the second only if the inertia scales
with the mass (a scaled body, mace_fmu.parameters.sets.fe_overrides). The mass matrix one CONM2 with an offset
adds (mace_fmu.fe.assembly.conm2_mass) is held to the parallel-axis theorem.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.decks import deck_text, r

from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.assembly import assemble, conm2_mass
from mace_fmu.fe.modes import compute_modes
from mace_fmu.parameters.sets import ParameterSet

MASS, INERTIA, K, K_R = 2.5, 0.04, 4.0e4, 900.0  # kg, kg m^2, N/m, N m/rad
CONM2_INERTIA = f",{r(INERTIA)},,{r(INERTIA)},,,{r(INERTIA)}"  #: the CONM2's continuation: I11, I22, I33


def _oscillator(tmp_path, masses: str = '{ "2" = "payload" }'):
    """(deck, structure file) of a CONM2 on springs along X and about X."""
    deck = tmp_path / "oscillator.bdf"
    deck.write_text(deck_text(["GRID,1,,0.0,0.0,0.0", f"CONM2,2,1,,{r(MASS)},,,,", CONM2_INERTIA, f"CELAS2,3,{r(K)},1,1", f"CELAS2,4,{r(K_R)},1,4", "SPC1,7,2356,1",
                               "EIGRL,1,,,2"], case="SPC = 7\nMETHOD = 1\n"))
    spec = tmp_path / "oscillator.toml"
    spec.write_text(f"[components]\nmass = [1]\n[parameters]\nmasses = {masses}\n")
    return read_deck(deck), spec


@pytest.mark.parametrize("factor", [0.7, 1.5])
def test_a_mass_parameter_scales_the_body_mass_and_inertia_alike(tmp_path, factor):
    deck, spec = _oscillator(tmp_path)
    modes = compute_modes(deck, configuration="0g", structure_file=spec,
                          parameters=ParameterSet({"m_payload": MASS * factor}))
    expected = sorted([math.sqrt(K / (MASS * factor)) / (2 * math.pi), math.sqrt(K_R / (INERTIA * factor)) / (2 * math.pi)])
    assert np.sort(modes.frequencies_hz) == pytest.approx(expected, rel=1e-10)


def test_a_mass_name_of_no_conm2_is_refused_naming_the_file_and_key(tmp_path):
    deck, spec = _oscillator(tmp_path, masses='{ "9" = "payload" }')
    with pytest.raises(MaceError, match=r"oscillator\.toml: \[parameters\] masses: key '9' \('payload'\) is no CONM2"):
        compute_modes(deck, configuration="0g", structure_file=spec, parameters=ParameterSet({"m_payload": 3.0}))


def test_an_unnamed_mass_is_refused_with_the_names_there_are(tmp_path):
    deck, spec = _oscillator(tmp_path)
    with pytest.raises(MaceError, match=r"'m_floor': no such mass; known: m_payload"):
        compute_modes(deck, configuration="0g", structure_file=spec, parameters=ParameterSet({"m_floor": 3.0}))


def test_one_conm2s_mass_matrix_is_the_parallel_axis_theorem_and_the_assemblys_share(tmp_path):
    """A 2 kg CONM2 0.1 m above its grid (inertia diag(0.01, 0.02, 0.03) kg m^2 about its c.g.): m on the
    translations, m d coupling X with rotation about Y (and -m d Y with X), I11 + m d^2 and I22 + m d^2; and it is
    what the CONM2 adds to the assembled model."""
    m, d = 2.0, 0.1
    bulk = ["GRID,1,,0.0,0.0,0.0", "GRID,2,,1.0,0.0,0.0", "MAT1,1,7.0e10,,0.33,2700.0", "PBAR,1,1,1.0e-4,1.0e-9,1.0e-9,2.0e-9",
            "CBAR,1,1,1,2,0.0,0.0,1.0", f"CONM2,5,2,,{r(m)},0.0,0.0,{r(d)},", f",{r(0.01)},,{r(0.02)},,,{r(0.03)}"]
    path = tmp_path / "offset.bdf"
    path.write_text(deck_text(bulk))
    deck = read_deck(path)
    model = assemble(deck)
    block = conm2_mass(deck, model.dofs, 5).toarray()[np.ix_(model.dofs.indices(2), model.dofs.indices(2))]
    expected = np.diag([m, m, m, 0.01 + m * d**2, 0.02 + m * d**2, 0.03])
    expected[0, 4] = expected[4, 0] = m * d
    expected[1, 3] = expected[3, 1] = -m * d
    assert block == pytest.approx(expected, abs=1e-15)
    without = tmp_path / "without.bdf"
    without.write_text(deck_text(bulk[:-2]))
    share = (model.mass - assemble(read_deck(without)).mass).toarray()
    assert share == pytest.approx(conm2_mass(deck, model.dofs, 5).toarray(), abs=1e-15)


def test_a_mass_that_moves_in_a_rigid_body_mode_is_refused_as_an_fmu_parameter(tmp_path):
    """Without the translational spring the CONM2 moves freely along X: a rigid-body mode, reduced once at export
    with the nominal mass, which no FMU could then correct: the export refuses the mass, naming it."""
    from mace_fmu.iomodel.model_options import ModelledElectronics
    from mace_fmu.iomodel.parametric_data import parametric_arrays
    from mace_fmu.iomodel.volts import volts_model

    deck = tmp_path / "free.bdf"
    deck.write_text(deck_text(["GRID,1,,0.0,0.0,0.0", f"CONM2,2,1,,{r(MASS)},,,,", CONM2_INERTIA, f"CELAS2,4,{r(K_R)},1,4", "SPC1,7,2356,1",
                               "EIGRL,1,,,2"],
                              case="SPC = 7\nMETHOD = 1\n"))
    spec = tmp_path / "free.toml"
    spec.write_text('[components]\nmass = [1]\n[parameters]\nmasses = { "2" = "payload" }\n'
                    '[[actuators]]\nname = "force"\ndescription = "force along X"\ndofs = [[1, 1, 1.0]]\n'
                    '[[sensors]]\nname = "acc"\ndescription = "acceleration along X"\nkind = "acceleration"\n'
                    'dofs = [[1, 1, 1.0]]\n')
    model = volts_model(compute_modes(read_deck(deck), configuration="0g", structure_file=spec),
                        electronics=ModelledElectronics(servos=False, bessel="none", delays=False))
    with pytest.raises(MaceError, match=r"mass parameter\(s\) m_payload: the mass moves in a rigid-body"):
        parametric_arrays(model)


def test_parameter_names_takes_the_path_of_a_structure_file_or_none(tmp_path):
    from mace_fmu.parameters.sets import parameter_names

    deck, spec = _oscillator(tmp_path)
    assert parameter_names(deck, spec).masses == {"payload": 2}
    assert parameter_names(deck, str(spec)).masses == {"payload": 2}
    named = parameter_names(deck)  # no structure file: every card by its ID, no masses
    assert (named.springs, named.masses) == ({"celas3": 3, "celas4": 4}, {})
