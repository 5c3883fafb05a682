"""Make the pictures of the README and the site's front page from the code (run by hand, commit the PNGs).

    python docs/make_figures.py

``docs/_static/mode_and_bode.png``: a still of the 0-g structure's first Z bending mode (the viewer,
through headless Chromium) beside the Bode plot of the 1-g and 0-g models from the secondary Z gimbal
command to the payload Z gyro (``mace-fmu report``).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

from mace_fmu.cli import main  # noqa: E402

STATIC = Path(__file__).resolve().parent / "_static"


def make() -> Path:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        if main(["view", "modes", "0g", "--mode", "1st Z bending", "--camera", "iso", "--html", str(tmp / "m.html"),
                 "--png", str(tmp / "mode.png")]) != 0:
            sys.exit("the viewer's still failed (is chromium installed?)")
        if main(["report", "--out", str(tmp / "report")]) != 0:
            sys.exit("mace-fmu report failed")
        bode = sorted((tmp / "report").glob("bode_gimbal_secondary_z_to_gyro_payload_z*.png"))
        bode = bode[0] if bode else sorted((tmp / "report").glob("bode_*.png"))[0]
        fig, axes = plt.subplots(1, 2, figsize=(14, 5.2), gridspec_kw={"width_ratios": [1.1, 1]})
        for ax, path, title in ((axes[0], tmp / "mode.png", "0-g structure, 1st Z bending mode"),
                                (axes[1], bode, "")):
            ax.imshow(mpimg.imread(path))
            ax.set_axis_off()
            if title:
                ax.set_title(title)
        fig.tight_layout()
        STATIC.mkdir(exist_ok=True)
        out = STATIC / "mode_and_bode.png"
        fig.savefig(out, dpi=90)
        return out


if __name__ == "__main__":
    print(f"wrote {make()}")
