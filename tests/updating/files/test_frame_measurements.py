"""The three-storey frame's measured FRFs (examples/three_storey_frame/data, real data of a laboratory rig), read
as the update reads them, and what they say about themselves, independently of any model:

* the unit is (m/s^2)/N: above the last resonance a driving-point accelerance tends to one over the driven
  floor's mass (5.201 kg stated), in phase with the force; in g/N it would be 9.81 times smaller;
* the force acts on floor 1, 2 and 3 in Experimental.csv, test_2.csv and test_3.csv (the source's README says
  floor 1 for all three): the mass line is in that column;
* reciprocity: H_21 of the first file is H_12 of the second, and H_31 is H_13 of the third, at the resonances.
"""

from __future__ import annotations

import numpy as np
import pytest
from support.paths import EXAMPLES

from mace_fmu.updating.files import read_frequency_response

DATA = EXAMPLES / "three_storey_frame" / "data"
FILES = {"Experimental.csv": "force_floor_1", "test_2.csv": "force_floor_2", "test_3.csv": "force_floor_3"}
FLOOR_KG = 5.201


@pytest.fixture(scope="module")
def frfs():
    return {name: read_frequency_response(DATA / name) for name in FILES}


def test_the_files_read_as_one_force_and_three_accelerations_in_si_units(frfs):
    for name, frd in frfs.items():
        assert frd.inputs == (FILES[name],) and frd.outputs == ("acc_floor_1", "acc_floor_2", "acc_floor_3")
        assert frd.units == {FILES[name]: "N", "acc_floor_1": "m/s^2", "acc_floor_2": "m/s^2", "acc_floor_3": "m/s^2"}
        assert frd.frequencies_hz.size == 4096 and np.allclose(np.diff(frd.frequencies_hz), 0.03125)


@pytest.mark.parametrize("name", list(FILES))
def test_the_mass_line_is_in_the_driven_floor_s_column_in_m_per_s2_per_newton(frfs, name):
    frd = frfs[name]
    high = (frd.frequencies_hz >= 100) & (frd.frequencies_hz <= 128)
    driven = int(FILES[name][-1]) - 1
    line = frd.response[high, :, 0]
    assert abs(np.median(np.abs(line[:, driven])) * FLOOR_KG - 1) < 0.1  # (m/s^2)/N, not g/N
    assert abs(np.median(np.angle(line[:, driven], deg=True))) < 5  # acceleration in phase with the force
    others = [k for k in range(3) if k != driven]
    assert np.median(np.abs(line[:, others])) < 0.05 * np.median(np.abs(line[:, driven]))


@pytest.mark.parametrize("other, floor", [("test_2.csv", 2), ("test_3.csv", 3)])
def test_reciprocity_between_the_files_at_the_second_and_third_resonances(frfs, other, floor):
    first, second = frfs["Experimental.csv"], frfs[other]
    for hz in (17.46875, 26.5):
        k = int(np.argmin(np.abs(first.frequencies_hz - hz)))
        h_floor_from_1 = first.response[k, floor - 1, 0]
        h_1_from_floor = second.response[k, 0, 0]
        assert abs(abs(h_1_from_floor) / abs(h_floor_from_1) - 1) < 0.05
        assert abs(np.angle(h_1_from_floor / h_floor_from_1, deg=True)) < 5


#: ±0.1 Hz about each resonance: where each mode dominates and the frame's 1 dB FRF goal is measured
NARROW_BANDS_HZ = ((6.4, 6.6), (17.35, 17.6), (26.4, 26.6))


def _reciprocal_modal_fit(frfs) -> np.ndarray:
    """Three modes (frequency [Hz], damping ratio, mass-normalised shape at the three floors [kg^-1/2]) fitted
    by least squares on the log of all nine measured FRFs over the narrow bands: the best any linear,
    reciprocal, lumped three-mode model does on these data, free of the FE model's assumptions."""
    from scipy.optimize import least_squares

    data = []
    for name, frd in frfs.items():
        keep = np.any([(frd.frequencies_hz >= lo) & (frd.frequencies_hz <= hi) for lo, hi in NARROW_BANDS_HZ], axis=0)
        data.append((frd.frequencies_hz[keep], frd.response[keep, :, 0], int(FILES[name][-1]) - 1))

    def residual(p: np.ndarray) -> np.ndarray:
        parts = []
        for f, measured, driven in data:
            error = np.log(_modal_accelerance(p, f)[:, :, driven]) - np.log(measured)
            parts += [error.real.ravel(), np.angle(np.exp(1j * error.imag)).ravel()]
        return np.concatenate(parts)

    shapes = np.array([[0.19, 0.33, 0.25], [0.33, 0.07, -0.3], [0.39, -0.25, 0.15]])  # a shear chain's, roughly
    start = np.concatenate([[6.51, 17.46, 26.5], [0.0016, 0.0024, 0.0022], shapes.ravel()])
    return least_squares(residual, start, x_scale="jac", max_nfev=20000).x


def _modal_accelerance(p: np.ndarray, f: np.ndarray) -> np.ndarray:
    """(frequencies, floor, driven floor) accelerance [(m/s^2)/N] of the modal model ``p``."""
    w, wr, zeta, phi = 2 * np.pi * f[:, None], 2 * np.pi * p[:3][None, :], p[3:6][None, :], p[6:15].reshape(3, 3)
    return np.einsum("fr,ir,jr->fij", -w**2 / (wr**2 - w**2 + 2j * zeta * wr * w), phi, phi)


def test_what_a_reciprocal_modal_model_reaches_on_all_three_files(frfs):
    """A second route to the 1 dB goal (FRFs within 1 dB over the half-power bands), independent of the FE model: one reciprocal three-mode model
    fitted to all nine FRFs. Modes 2 and 3 then agree within 0.45 dB over their half-power bands on every
    file, so a model can meet the goal there; mode 1 keeps 1.1 dB or more on Experimental.csv, whose peak
    heights break reciprocity (data/README.md). The stiffness matrix this lumped model implies,
    K = Phi^-T Lambda Phi^-1, couples floor 1 to floor 3 by +1.5 to +3.5 kN/m (a storey's stiffness is
    about 45 kN/m), which a shear chain cannot (its K_13 is zero), while its inverse mass matrix Phi Phi^T is
    diagonal within 6 %: either the structure couples those floors or the accelerometers see more than their
    floor's translation; either way the FE model's sway chain misses the shapes, not only the parameters."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("frame_example", EXAMPLES / "three_storey_frame" /
                                                  "update_three_storey_frame.py")
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    p = _reciprocal_modal_fit(frfs)
    np.testing.assert_allclose(p[:3], [6.512, 17.461, 26.503], atol=0.003)
    errors = {}
    for name, frd in frfs.items():
        keep = (frd.frequencies_hz >= 4.0) & (frd.frequencies_hz <= 32.0)
        f = frd.frequencies_hz[keep]
        band = type(frd)(f, frd.inputs, frd.outputs, frd.response[keep], source=frd.source, units=frd.units)
        model = _modal_accelerance(p, f)[:, :, int(FILES[name][-1]) - 1]
        errors[name] = example.half_power_error_db(band, model, example.resonances_hz(frd), p[3:6])
    assert all(max(e[1:]) < 0.45 for e in errors.values()), errors
    assert errors["Experimental.csv"][0] > 1.1, errors
    phi = p[6:15].reshape(3, 3)
    stiffness = np.linalg.inv(phi).T @ np.diag((2 * np.pi * p[:3]) ** 2) @ np.linalg.inv(phi)  # [N/m]
    assert 1.5e3 < stiffness[0, 2] < 3.5e3 and 40e3 < -stiffness[0, 1] < 50e3, stiffness
    inverse_mass = phi @ phi.T
    off = inverse_mass - np.diag(np.diag(inverse_mass))
    assert np.abs(off).max() < 0.06 * np.diag(inverse_mass).min(), inverse_mass
