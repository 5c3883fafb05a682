"""Measured data files: a lab's time-history CSV through a channel map, an H1 estimate, a UFF 58 file.
===================================================================================================

The 'test article' is one lightly damped mode (12 Hz, 2 %) from the secondary Z gimbal command
to the payload Z gyro, sampled at 200 Hz; the logger names its channels ai0, ai3, ai7 and adds a
temperature. Run ``python examples/measured_data.py [FOLDER]``: it writes the files there and
prints the H1 estimate's largest error against the exact response, away from the mode.
"""

from __future__ import annotations

import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import signal

from mace_fmu.updating.files import (
    h1_estimate, read_channel_map, read_frequency_response, read_time_history, write_frequency_response)

FS_HZ = 200.0
MODE_HZ, ZETA = 12.0, 0.02
CHANNEL_MAP = """channel,signal,role,unit
ai0,gimbal_secondary_z,input,V
ai3,gyro_payload_z,output,V
ai7,,ignore,degC
"""


@dataclass(frozen=True)
class ExampleResult:
    """What the example wrote and how close its H1 estimate is to the exact response."""

    folder: Path
    max_error_away_from_mode: float  #: largest |H1 - H| / |H| more than 2 Hz from the mode, 1-60 Hz
    source: str  #: the H1 estimate's source, stating segment length, window and overlap
    uff_frequency_error: float  #: largest relative change of a frequency through the UFF file


def _article() -> tuple:
    w = 2 * np.pi * MODE_HZ
    a = np.array([[0.0, 1.0], [-w * w, -2 * ZETA * w]])
    return signal.cont2discrete((a, np.array([[0.0], [w * w]]), np.array([[1.0, 0.0]]), np.zeros((1, 1))),
                                1 / FS_HZ, method="zoh")[:4]


def write_lab_files(folder: Path, *, samples: int = 2**15, seed: int = 7) -> None:
    """A logger's CSV export (time, ai0, ai3, ai7) and the channel map that names its channels."""
    ad, bd, cd, dd = _article()
    rng = np.random.default_rng(seed)
    u = 0.5 * rng.standard_normal(samples)
    b, a = signal.ss2tf(ad, bd, cd, dd)
    y = signal.lfilter(b[0], a, u) + 1e-3 * rng.standard_normal(samples)
    table = np.column_stack([np.arange(samples) / FS_HZ, u, y, 21.5 + 0.01 * rng.standard_normal(samples)])
    header = "# logger export, 200 Hz\ntime [s],ai0 [V],ai3 [V],ai7 [degC]"
    np.savetxt(folder / "run.csv", table, fmt="%.10g", delimiter=",", header=header, comments="")
    (folder / "channels.csv").write_text(CHANNEL_MAP)


def main(folder: Path) -> ExampleResult:
    folder.mkdir(parents=True, exist_ok=True)
    write_lab_files(folder)
    run = read_time_history(folder / "run.csv", channel_map=read_channel_map(folder / "channels.csv"),
                            sample_time_s=1 / FS_HZ)
    h1 = h1_estimate(run, segment_length=1024, window="hann", overlap=0.5, band_hz=(1.0, 60.0))
    write_frequency_response(h1, folder / "run_h1.uff")
    back = read_frequency_response(folder / "run_h1.uff")
    ad, bd, cd, dd = _article()
    z = np.exp(2j * np.pi * h1.frequencies_hz / FS_HZ)
    exact = np.array([(cd @ np.linalg.solve(zk * np.eye(2) - ad, bd) + dd)[0, 0] for zk in z])
    away = np.abs(h1.frequencies_hz - MODE_HZ) > 2.0
    error = np.abs(h1.response[:, 0, 0] - exact) / np.abs(exact)
    return ExampleResult(folder=folder, max_error_away_from_mode=float(error[away].max()), source=h1.source,
                         uff_frequency_error=float(np.max(np.abs(back.frequencies_hz / h1.frequencies_hz - 1))))


if __name__ == "__main__":
    target = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="mace_measured_"))
    result = main(target)
    print(f"wrote {result.folder}/run.csv, channels.csv, run_h1.uff")
    print(result.source)
    print(f"H1 against the exact response, 1-60 Hz, more than 2 Hz from the mode: at most "
          f"{100 * result.max_error_away_from_mode:.2f} %")
    print(f"frequencies through UFF 58 (six digits): at most {result.uff_frequency_error:.1e} relative change")
