"""Stills of a page: headless Chromium renders the standalone HTML and saves a PNG."""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

from mace_fmu.errors import MaceError
from mace_fmu.util.atomic import atomic_path

#: Executable names of Chromium, in the order they are looked up on PATH (Debian: chromium).
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome")


def chromium_executable() -> str | None:
    """Path of a Chromium on PATH, or None.

    Returns
    -------
    str or None
        The first of ``CHROMIUM_NAMES`` found on PATH.
    """
    return next((found for name in CHROMIUM_NAMES if (found := shutil.which(name))), None)


def render_page(page: str | os.PathLike[str], *, png: str | os.PathLike[str], width_px: int = 1200,
                height_px: int = 800, virtual_time_s: float = 1.0, timeout_s: float = 240.0) -> str:
    """Render ``page`` in headless Chromium (software WebGL), write ``png`` and return the page's DOM.

    The picture and the DOM are taken in one Chromium run after ``virtual_time_s`` [s] of Chromium's
    virtual time, page loading included (a 1-g page is drawn well within 1 s of it), so the animation
    has played a little and the DOM shows what the picture shows (for example which legend row is
    marked). Each virtual second costs about 7-8 s of real time at 1200 x 800 on a 2-core machine
    (software WebGL draws every frame): 1.0 s took 6.8 s, 3.0 s (the default until 2026-11-25) 35 s.

    Parameters
    ----------
    page : path
        The standalone HTML page (:func:`~mace_fmu.viewer.html.write_animation_html`).
    png : path
        The picture to write (replaced atomically).
    width_px, height_px : int
        Window size [pixels].
    virtual_time_s : float
        Chromium's virtual time before the picture [s].
    timeout_s : float
        Real time Chromium may take [s].

    Returns
    -------
    str
        The serialised DOM at the moment of the picture.

    Raises
    ------
    MaceError
        No Chromium on PATH, or Chromium could not render the page.
    """
    chromium = chromium_executable()
    if chromium is None:
        raise MaceError(f"a PNG still needs headless Chromium, and none of {', '.join(CHROMIUM_NAMES)} is on PATH "
                        "(Debian: apt-get install chromium)")
    page = Path(page).resolve()
    with tempfile.TemporaryDirectory(prefix="mace_fmu_chromium_") as profile, atomic_path(png) as part:
        shot = Path(profile) / "still.png"  # then moved onto the temporary name next to ``png``
        done = subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
                               "--use-angle=swiftshader", "--disable-quic", "--no-first-run",
                               "--disable-background-networking", "--disable-component-update", "--disable-sync",
                               f"--user-data-dir={profile}/user", f"--window-size={width_px},{height_px}",
                               f"--virtual-time-budget={int(round(1000 * virtual_time_s))}", f"--screenshot={shot}",
                               "--dump-dom", page.as_uri()], capture_output=True, text=True, timeout=timeout_s)
        if done.returncode != 0 or not shot.exists():
            raise MaceError(f"Chromium could not render {page} (exit status {done.returncode}): "
                            f"{done.stderr.strip()[-1000:]}")
        shutil.move(shot, part)
    return done.stdout


def write_still(page: str | os.PathLike[str], png: str | os.PathLike[str], *, width_px: int = 1200,
                height_px: int = 800, virtual_time_s: float = 1.0, timeout_s: float = 240.0) -> Path:
    """Render ``page`` in headless Chromium (software WebGL) and write ``png`` (see :func:`render_page`).

    Parameters
    ----------
    page, png : path
        The standalone HTML page and the picture to write.
    width_px, height_px, virtual_time_s, timeout_s
        As for :func:`render_page`: the window [pixels], Chromium's virtual time before the picture [s]
        and the real time it may take [s].

    Returns
    -------
    pathlib.Path
        ``png``.
    """
    render_page(page, png=png, width_px=width_px, height_px=height_px, virtual_time_s=virtual_time_s,
                timeout_s=timeout_s)
    return Path(png)
