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
    with pytest.raises(MaceError, match=r"not whole multiples of 0.1 Hz: no periodic signal has all of them"):
        multisine_probe(np.array([1.0, 1.1, 1.25]))
