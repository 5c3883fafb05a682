"""Time to write the 0-g mode animation HTML for every mode up to 60 Hz, and its size.

Run: python benchmarks/bench_viewer.py   (goal: under 2 s, modes computed beforehand)
"""

from __future__ import annotations

import importlib.metadata
import os
import tempfile

from common import machine_line, timed

from mace_fmu.fe.modes import compute_modes
from mace_fmu.viewer import animate_modes, write_animation_html


def main(repeats: int = 7) -> None:
    modes = compute_modes(configuration="0g", max_hz=60.0)
    indices = list(range(1, modes.frequencies_hz.size + 1))
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "modes.html")
        median, fastest, size = timed(lambda: write_animation_html(animate_modes(modes, indices), path,
                                                              title="MACE 0g modes"), repeats)
    solve, _, _ = timed(lambda: compute_modes(configuration="0g", max_hz=60.0), 1)
    print(machine_line(meshcat=importlib.metadata.version("meshcat")))
    print(f"0-g, {len(indices)} modes <= 60 Hz: HTML written in {median:.3f} s "
          f"(median of {repeats}; min {fastest:.3f}), {size / 1e6:.1f} MB; eigen-solution {solve:.3f} s")


if __name__ == "__main__":
    main()
