"""Full re-solves as the independent reference of the FMUs' parameter route.

A re-solve (the deck with the parameter built in, the FE model, preload and modes solved again) knows
nothing of the reanalysis it checks. Its modes are labelled afresh, and the structure file gives damping
ratios by label, so a stiffness change that renames a mode ("4th Y bending" becoming "3rd Y bending")
would also move a damping ratio to another mode: :func:`held_damping` keeps each physical mode's
nominal damping (modes paired by their mass-weighted MAC), so that the comparison sees the stiffness
alone.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm
from scipy.optimize import linear_sum_assignment
from scipy.signal import butter, lfilter

from mace_fmu.iomodel.parametric import ParametricSystem
from mace_fmu.iomodel.parametric_data import parametric_arrays
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.parameters.sets import ParameterSet

STEP_S = 2e-3  #: the issue's check: 10 s at 2 ms
SAMPLES = 5000


def band_limited_inputs(names: list[str], driven: tuple[str, ...], *, seed: int = 1) -> np.ndarray:
    """(SAMPLES, n_inputs) inputs [V]: independent noise below 20 Hz on the inputs whose names start with one
    of ``driven``, zero elsewhere."""
    rng = np.random.default_rng(seed)
    b, a = butter(4, 20.0 * 2 * STEP_S)
    u = np.zeros((SAMPLES, len(names)))
    for k, name in enumerate(names):
        if name.startswith(driven):
            u[:, k] = lfilter(b, a, rng.standard_normal(SAMPLES))
    return u


def zoh_response(system: tuple[np.ndarray, ...], u: np.ndarray) -> np.ndarray:
    """(SAMPLES, n_outputs) exact zero-order-hold response of (A, B, C, D) from rest."""
    a, b, c, d = system
    n, m = b.shape
    block = expm(np.block([[a, b], [np.zeros((m, n + m))]]) * STEP_S)
    ad, bd = block[:n, :n], block[:n, n:]
    x = np.zeros(n)
    y = np.empty((len(u), c.shape[0]))
    for k, uk in enumerate(u):
        y[k] = c @ x + d @ uk
        x = ad @ x + bd @ uk
    return y


def held_damping(nominal, resolved) -> dict[str, float]:
    """``damping_mode_<k>`` values for ``resolved`` (a VoltsModel) that give each of its modes the damping of the
    nominal mode it continues (largest mass-weighted MAC, one to one)."""
    mass = nominal.structure_modes.model.mass
    a, b = nominal.plant.shapes, resolved.plant.shapes
    mac = (a.T @ (mass @ b)) ** 2 / np.outer(np.einsum("ik,ik->k", a, mass @ a), np.einsum("ik,ik->k", b, mass @ b))
    rows, cols = linear_sum_assignment(-mac)
    return {f"damping_mode_{j + 1}": float(nominal.plant.damping[i]) for i, j in zip(rows, cols)}


def resolved_system(configuration: str, values: dict[str, float], nominal) -> tuple[np.ndarray, ...]:
    """(A, B, C, D) of a full re-solve with moduli and springs ``values`` [Pa, N/m], damping held per mode."""
    model = volts_model(configuration, parameters=ParameterSet(values))
    system = ParametricSystem(parametric_arrays(model, physical=False))
    params = system.nominal.copy()
    for name, value in held_damping(nominal, model).items():
        params[system.index(name)] = value
    return system.build(params)
