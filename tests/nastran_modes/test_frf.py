"""The FRF between two grids from the modes we read equals the modal superposition written here from numbers
read by other means: pyNastran's reading of the same OP2 (to 1e-9: the same 32-bit numbers), and NASTRAN's
.f06 printout (to what its 7 printed digits allow)."""

from __future__ import annotations

import numpy as np
import pytest
from support.f06_modes import read_f06_modes
from support.nastran_results import (
    MODELS,
    NASTRAN,
    op2_path,
    pynastran_eigenvalues,
    pynastran_vectors,
)

from mace_fmu.nastran_modes import read_nastran_modes

DAMPING = 0.02  #: modal damping ratio of every mode
COMPONENT_COLUMNS = {1: "t1", 2: "t2", 3: "t3", 4: "r1", 5: "r2", 6: "r3"}
#: model -> (output grid, component), (input grid, component): grids that move in most modes
PAIRS = {
    "solid_shell_bar": ((7, 2), (11, 3)),
    "gpsc1": ((3, 3), (40, 1)),
    "plate_py": ((1, 3), (231, 3)),
    "beam_modes_op2": ((11, 3), (6, 3)),
}


def superposition(eigenvalues: np.ndarray, out: np.ndarray, into: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """Receptance sum_k phi_out,k phi_in,k / (lambda_k - w^2 + 2 i zeta sqrt|lambda_k| w), mass-normalised phi."""
    lam = eigenvalues[:, None]
    return np.sum((out * into)[:, None] / (lam - omega[None] ** 2 + 2j * DAMPING * np.sqrt(np.abs(lam)) * omega[None]),
                  axis=0)


def ours(model: str, omega: np.ndarray) -> np.ndarray:
    """The FRF from the NastranModes we read (basic shapes, frequencies in Hz)."""
    read = read_nastran_modes(op2_path(model))
    (g_out, c_out), (g_in, c_in) = PAIRS[model]
    w = 2 * np.pi * read.modes.frequencies_hz
    return superposition(np.sign(w) * w ** 2, read.modes.shape(g_out, c_out), read.modes.shape(g_in, c_in), omega)


def frequencies(eigenvalues: np.ndarray) -> np.ndarray:
    """Angular frequencies [rad/s] spanning the modes, with points on every resonance."""
    top = np.sqrt(np.abs(eigenvalues).max())
    return np.unique(np.concatenate([np.linspace(0.0, 1.3 * top, 400), np.sqrt(np.abs(eigenvalues))]))


@pytest.mark.parametrize("model", sorted(PAIRS))
def test_frf_equals_the_superposition_of_pynastrans_numbers(model):
    """1e-9 of the FRF's largest magnitude, at 400+ frequencies including each resonance."""
    ref = pynastran_vectors(model)
    _, eigenvalues, masses = pynastran_eigenvalues(model)
    eigenvalues = np.float32(eigenvalues).astype(float)
    scale = 1.0 / np.sqrt(np.float32(masses).astype(float)) if masses is not None else 1.0
    (g_out, c_out), (g_in, c_in) = PAIRS[model]

    def column(grid: int, component: int) -> np.ndarray:
        rows = ref["grid"] == grid
        return np.float32(ref[f"basic_{COMPONENT_COLUMNS[component]}" if "basic_t1" in ref
                              else f"cd_{COMPONENT_COLUMNS[component]}"][rows]).astype(float) * scale

    omega = frequencies(eigenvalues)
    expected = superposition(eigenvalues, column(g_out, c_out), column(g_in, c_in), omega)
    got = ours(model, omega)
    assert np.abs(got - expected).max() <= 1e-9 * np.abs(expected).max()
    assert np.abs(expected).max() > 0


@pytest.mark.parametrize("model", [m for m, (_, f06) in MODELS.items() if f06])
def test_frf_equals_the_superposition_of_the_f06_printout(model):
    """The vectors and eigenvalues as NASTRAN printed them (7 digits): the FRF agrees to 2e-5 of its largest
    magnitude, the printing's 5e-7 amplified at a resonance by 1 / (2 zeta) = 25. beam_modes' .f06 is another
    run than its OP2 with other vectors within each repeated root, which the FRF does not see."""
    printed = read_f06_modes(NASTRAN / model / MODELS[model][1])
    (g_out, c_out), (g_in, c_in) = PAIRS[model]
    scale = 1.0 / np.sqrt(printed.generalized_masses)
    out = np.array([printed.vectors[m][g_out][c_out - 1] for m in printed.modes]) * scale
    into = np.array([printed.vectors[m][g_in][c_in - 1] for m in printed.modes]) * scale
    omega = frequencies(printed.eigenvalues)
    expected = superposition(printed.eigenvalues, out, into, omega)
    got = ours(model, omega)
    assert np.abs(got - expected).max() <= 2e-5 * np.abs(expected).max()
