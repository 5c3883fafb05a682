"""The FMU update's costs over a window of a record: the model driven from the record's first
sample, compared or estimated from the window's start; a record whose time axis does not start at 0 s."""

from __future__ import annotations

import numpy as np
from support.two_mass_records import two_mass_record

from mace_fmu.updating.engine.linear_model import simulate_discrete, zoh_transition
from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.engine.simulated_frf import H1Estimator
from mace_fmu.updating.fmu.update import fmu_cost, record_from
from mace_fmu.updating.sample.two_mass import TwoMassSystem


class _Plant:
    """The two-mass record's own system (force on mass 1 to its displacement), simulated as the record was made:
    a model whose response to the record's force is the noise-free record exactly, from rest at its first sample."""

    def time_response(self, times_s, inputs, *, outputs):
        plant = TwoMassSystem().state_space(force_on=1, measured=1)
        phi, gamma = zoh_transition(plant.A, plant.B, float(times_s[1] - times_s[0]))
        return simulate_discrete(phi, gamma, plant.C, plant.D, np.asarray(inputs["force_1"])[:, None])


def test_a_record_that_does_not_start_at_0_s_is_compared_from_its_first_sample():
    """The old time cost compared "from 0 s" and refused a record starting at 500 s."""
    record = two_mass_record(samples=512, noise=0.0, seed=2)
    shifted = TimeHistory(record.times_s + 500.0, record.inputs, record.outputs, source="late.csv")
    cost = fmu_cost("time", history=shifted)
    assert cost.compare_from_s == 500.0 and np.max(np.abs(cost.residual(_Plant()))) < 1e-9


def test_log_frf_over_a_window_estimates_the_model_simulated_from_the_record_s_start():
    """Noise-free data of the truth: estimated from 600 s on, the model driven from the record's start (at rest,
    as the structure was) gives the data's estimate exactly; the same model driven from 600 s (the record cut
    there, the structure's state at 600 s lost: its modes ring for 500 s) does not."""
    record = two_mass_record(samples=4096, noise=0.0, seed=4)
    estimator = H1Estimator(segment_length=512, band_hz=(0.02, 0.5))
    truth = _Plant()
    windowed = fmu_cost("log-frf", history=record, estimator=estimator, weighting="none", compare_from_s=600.0)
    assert windowed.data.averages == 1 + (record.times_s.size - 1200 - 512) // 256
    assert np.max(np.abs(windowed.residual(truth))) < 1e-9
    cut = fmu_cost("log-frf", history=record_from(record, 600.0), estimator=estimator, weighting="none")
    assert np.max(np.abs(cut.residual(truth))) > 1e-2
