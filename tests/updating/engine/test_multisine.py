"""The multisine probe: a simulated model's frequency response at the lines of a measured FRF, against the exact
frequency response of the same model's state space (an independent route: no simulation, no hold, no DFT).

The model is the three-storey frame's (examples/three_storey_frame): force inputs [N], accelerometers [m/s^2],
whose direct feedthrough (the mass line) the probe must not mistake for a delay.
"""

from __future__ import annotations

import numpy as np
import pytest
from support.paths import EXAMPLES

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.multisine import multisine_probe

FRAME = EXAMPLES / "three_storey_frame"


@pytest.fixture(scope="module")
def frame(tmp_path_factory):
    """(volts model, its native FMU as an update model) of the frame's 1-g configuration."""
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.updating.fmu.model import fmu_family

    model = volts_model(compute_modes(read_deck(FRAME / "frame.bdf"), configuration="1g",
                                      structure_file=FRAME / "frame.toml"))
    fmu = export_fmu(model, out_dir=tmp_path_factory.mktemp("frame"), name="frame_1g")
    return model, fmu_family(fmu).full({})


def test_the_probe_gives_the_state_space_response_at_every_line(frame):
    model, fmu = frame
    f = np.arange(128, 1025) * 0.03125  # 4-32 Hz on the analyser's grid of the frame's data
    probe = multisine_probe(f, samples_per_cycle=40)
    outputs = ["acc_floor_1", "acc_floor_2", "acc_floor_3"]
    h = probe.response(fmu, inputs=["force_floor_2"], outputs=outputs)
    exact = model.frequency_response(f)[:, :3, 1:2]
    error = np.abs(h / exact - 1)
    peaks = [int(np.argmin(np.abs(f - hz))) for hz in model.plant.frequencies_hz[:3]]
    assert error[peaks].max() < 1e-6  # where a measured FRF says most
    assert np.median(error) < 1e-5
    assert error.max() < 2e-3  # at the antiresonances: the hold's images, folded back by the sampling
    assert probe._periods[0] >= 4  # 0.2 % damping: the free response needed more than the first two periods


def test_frequencies_no_period_holds_are_refused():
    with pytest.raises(MaceError, match=r"not whole multiples of one spacing \(the smallest gap 0.1 Hz, nor any "
                                        r"fraction of it down to .* Hz\): no periodic signal has all of them"):
        multisine_probe(np.array([1.0, 1.1, 1.2 + 0.01 * np.sqrt(2.0)]))


@pytest.mark.parametrize("precision", [0.0, 5e-6])
def test_lines_whose_smallest_gap_is_several_steps_are_a_multisine_of_the_finer_step(precision):
    """A 10 Hz multisine's lines at 100, 120 and 150 Hz: multiples of 10 Hz, two and three steps apart;
    the old code took the smallest gap, 20 Hz, for the step and refused 150 Hz. 1.0, 1.1 and 1.25 Hz likewise
    are multiples of 0.05 Hz (a 20 s period)."""
    for lines, step in (([100.0, 120.0, 150.0], 10.0), ([1.0, 1.1, 1.25], 0.05)):
        probe = multisine_probe(np.array(lines), precision=precision)
        assert probe.period_s == pytest.approx(1.0 / step, rel=1e-9)
        np.testing.assert_array_equal(probe.bins, np.rint(np.array(lines) / step).astype(int))
        np.testing.assert_allclose(probe.frequencies_hz, lines, rtol=1e-12)


def test_an_h1_estimate_read_back_from_uff_58_is_probed_on_the_analyser_s_grid(tmp_path):
    """UFF 58 keeps six digits of each frequency (E13.5), so an H1 estimate read back from the file has its lines
    up to 5e-6 off the analyser's grid, fs / N: the probe finds each line's bin on that grid (the truth: the bins
    the estimate was computed at) and runs at the lines put back on it; the cost then takes the file's data."""
    from mace_fmu.updating.engine.measured import TimeHistory
    from mace_fmu.updating.engine.multisine import ProbedFrequencyResponseCost
    from mace_fmu.updating.files import (
        h1_estimate,
        read_frequency_response,
        write_frequency_response,
    )

    fs_hz, segment = 200.0, 1024
    rng = np.random.default_rng(3)
    u = rng.standard_normal(16 * segment)
    history = TimeHistory(np.arange(u.size) / fs_hz, {"force": u}, {"acc": np.convolve(u, [0.5, 0.3, 0.2])[:u.size]},
                          units={"force": "N", "acc": "m/s^2"}, source="shaker run")
    h1 = h1_estimate(history, segment_length=segment, band_hz=(1.0, 60.0))
    back = read_frequency_response(write_frequency_response(h1, tmp_path / "h1.uff"))
    moved = np.abs(back.frequencies_hz / h1.frequencies_hz - 1)
    assert 1e-7 < moved.max() <= 5e-6 and back.frequency_precision == 5e-6  # what the six digits did
    probe = multisine_probe(back.frequencies_hz, precision=back.frequency_precision)
    np.testing.assert_array_equal(probe.bins, np.rint(h1.frequencies_hz * segment / fs_hz).astype(int))
    assert probe.period_s == pytest.approx(segment / fs_hz, rel=1e-6)
    np.testing.assert_allclose(probe.frequencies_hz, h1.frequencies_hz, rtol=1e-6)
    assert "put on the grid" in probe.note and "within the 5e-06 the data state them to" in probe.note
    cost = ProbedFrequencyResponseCost(data=back, probe=probe)
    assert cost.pairs == (("force", "acc"),)


def test_lines_off_the_grid_by_more_than_their_precision_are_still_refused():
    grid = np.arange(6, 308) * 0.1953125
    stated = np.array([float(f"{x:13.5e}") for x in grid])
    stated[150] *= 1 + 2e-5  # four times what six digits can do
    with pytest.raises(MaceError, match=r"not whole multiples of one spacing \(the smallest gap 0.19\d* Hz, nor any "
                                        r"fraction .*\): no periodic signal has all of them "
                                        r"\(.*more than its precision 5e-06 allows; give the data on a uniform grid\)"):
        multisine_probe(stated, precision=5e-6)
    assert multisine_probe(grid).note == ""  # lines on the grid are taken as they are
