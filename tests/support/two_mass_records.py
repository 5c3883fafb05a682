"""Records of the thesis's two-mass system with known white measurement noise (updating tests)."""

from __future__ import annotations

import numpy as np

from mace_fmu.updating.engine.linear_model import simulate_discrete, zoh_transition
from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.sample.two_mass import TwoMassSystem

STEP_S = 0.5


def two_mass_record(*, samples: int, noise: float, seed: int, band_limited: bool = False) -> TimeHistory:
    """Force on mass 1 (white, or band-limited to 0.5 Hz of the 1 Hz Nyquist band), displacement of mass 1
    plus white noise of ``noise`` times the noise-free output's RMS."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(samples)
    if band_limited:
        spectrum = np.fft.rfft(u)
        spectrum[np.fft.rfftfreq(samples, STEP_S) > 0.5] = 0.0
        u = np.fft.irfft(spectrum, samples)
    plant = TwoMassSystem().state_space(force_on=1, measured=1)
    phi, gamma = zoh_transition(plant.A, plant.B, STEP_S)
    y = simulate_discrete(phi, gamma, plant.C, plant.D, u[:, None])[:, 0]
    y = y + noise * np.sqrt(np.mean(y**2)) * rng.standard_normal(samples)
    return TimeHistory(STEP_S * np.arange(samples), {"force_1": u}, {"displacement_1": y}, source="test")


def true_damping() -> list[float]:
    """Modal damping ratios of the actual system, lower mode first."""
    eig = np.linalg.eigvals(TwoMassSystem().state_space().A)
    eig = eig[eig.imag > 0]
    eig = eig[np.argsort(np.abs(eig))]
    return list(-eig.real / np.abs(eig))
