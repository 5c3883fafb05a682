"""Bar strain gauges declared in a structure file read a cantilever's strain as beam theory gives it.

A cantilever of CBARs along X, clamped at grid 1, loaded at its tip. The static gain of the volts
model from a tip force to a gauge (all modes kept, so the modal sum is the static solution) must be
the strain of the statics: axial P / (E A), bending -/+ c M / (E I) with M = P (L - x) at distance x from
the clamp, on Euler-Bernoulli and on shear-flexible (Timoshenko) sections alike.
"""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest
from support.decks import line_of_bars

from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.volts import volts_model

E, NU, RHO, L, N = 7.0e10, 0.33, 2700.0, 2.0, 8
D = 0.03
AREA, INERTIA = math.pi * D**2 / 4, math.pi * D**4 / 64
C = D / 2  # the outer fibre [m]
P_PER_V, V_PER_STRAIN = 2.0, 500.0

STRUCTURE = """
[[actuators]]
name = "tip_force_y"
description = "force along basic Y at the tip"
dofs = [[{tip}, 2, 1.0]]
gain = 2.0   # N per V

[[actuators]]
name = "tip_force_x"
description = "force along the beam (basic X) at the tip"
dofs = [[{tip}, 1, 1.0]]
gain = 2.0   # N per V

[[sensors]]
name = "root_minus_y"
description = "gauge at the clamp on the fibre at basic -Y (element +z: the orientation vector is basic Z)"
kind = "bar_strain"
bar = 100
position = 0.0
fiber = [0.0, {c}]
gain = 500.0   # V per strain

[[sensors]]
name = "third_plus_y"
description = "gauge 0.35 along the third bar, on the fibre at basic +Y"
kind = "bar_strain"
bar = 102
position = 0.35
fiber = [0.0, -{c}]
gain = 500.0

[[sensors]]
name = "neutral"
description = "gauge on the neutral axis of the second bar: axial strain only"
kind = "bar_strain"
bar = 101
fiber = [0.0, 0.0]
gain = 500.0
"""


def _model(tmp_path, *, shear_factor: float | None):
    bulk = line_of_bars(n=N, length=L, e=E, nu=NU, rho=RHO, area=AREA, i=INERTIA, shear_factor=shear_factor)
    # every mode (EIGRL ND above the DOFs with mass): the modal sum is then the static solution
    deck = tmp_path / "cantilever.bdf"
    deck.write_text("SOL 103\nCEND\nSPC = 7\nMETHOD = 1\nBEGIN BULK\n" + "\n".join(
        bulk + ["SPC1,7,123456,1", "EIGRL,1,,,100"]) + "\nENDDATA\n")
    spec = tmp_path / "cantilever.toml"
    spec.write_text(STRUCTURE.format(tip=N + 1, c=C))
    return volts_model(compute_modes(read_deck(deck), configuration="0g", structure_file=spec))


@pytest.mark.parametrize("shear_factor", [None, 0.9], ids=["euler_bernoulli", "timoshenko"])
def test_gauges_read_the_strain_of_the_cantilevers_statics(tmp_path, shear_factor):
    model = _model(tmp_path, shear_factor=shear_factor)
    # every mode: lumped mass leaves the rotations massless (condensed exactly), 3 translations x 8 grids
    assert model.structure_modes.frequencies_hz.size == 3 * N
    gain = ct.dcgain(model.system) / (P_PER_V * V_PER_STRAIN)  # strain per newton
    outputs, inputs = list(model.system.output_labels), list(model.system.input_labels)

    def strain(sensor: str, force: str) -> float:
        return float(gain[outputs.index(sensor), inputs.index(force)])

    bar = L / N
    # bending: M = P (L - x); the fibre at basic -Y is stretched by a +Y tip force, the one at +Y compressed
    np.testing.assert_allclose(strain("root_minus_y", "tip_force_y"), C * L / (E * INERTIA), rtol=1e-8)
    x = 2 * bar + 0.35 * bar
    np.testing.assert_allclose(strain("third_plus_y", "tip_force_y"), -C * (L - x) / (E * INERTIA), rtol=1e-8)
    # axial force: the same strain on every fibre; bending puts none on the neutral axis
    for sensor in ("root_minus_y", "third_plus_y", "neutral"):
        np.testing.assert_allclose(strain(sensor, "tip_force_x"), 1.0 / (E * AREA), rtol=1e-8)
    assert abs(strain("neutral", "tip_force_y")) <= 1e-8 * C * L / (E * INERTIA)
    sensor = next(s for s in model.instruments.sensors if s.name == "root_minus_y")
    assert sensor.unit == "strain" and {g for g, _, _ in sensor.dofs} == {1, 2}


@pytest.mark.parametrize("edit, message", [
    (("bar = 102", "bar = 999"), "sensor third_plus_y: bar 999 is not a CBAR of .*cantilever.bdf"),
    (("position = 0.35", "position = 1.5"), "sensor third_plus_y: position must be in \\[0, 1\\]"),
    (("fiber = [0.0, 0.0]", "fiber = 0.0"), "sensor neutral: fiber must be \\[y, z\\]"),
    (('kind = "bar_strain"\nbar = 101', 'kind = "strain"\nbar = 101'), "sensor neutral: kind must be one of"),
])
def test_a_bad_gauge_names_the_file_the_sensor_and_what_was_expected(tmp_path, edit, message):
    _model(tmp_path, shear_factor=None)  # the deck and structure file, valid
    spec = tmp_path / "cantilever.toml"
    text = spec.read_text()
    assert edit[0] in text
    spec.write_text(text.replace(edit[0], edit[1]))
    with pytest.raises(MaceError, match=f"cantilever.toml.*{message}"):
        volts_model(compute_modes(read_deck(tmp_path / "cantilever.bdf"), configuration="0g", structure_file=spec))
