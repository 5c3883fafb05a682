"""Nothing lost: every file the CLI writes appears whole under its final name or not at all.

A failed write (a full disk, an exception, Ctrl-C) keeps the previous file and removes the
temporary one; a build killed mid-way leaves the previous FMU byte for byte; two builds into one
folder at once leave a valid FMU.
"""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from mace_fmu.cli import main
from mace_fmu.util.atomic import atomic_path, atomic_zip, save_figure_atomic, write_text_atomic

pytestmark = pytest.mark.slow  # each test builds FMUs in subprocesses and kills them

PREVIOUS = b"the previous good file\n"


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".part"))


def _full_disk(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


def test_failed_write_keeps_the_previous_file_and_removes_the_temporary(tmp_path: Path) -> None:
    final = tmp_path / "out.fmu"
    final.write_bytes(PREVIOUS)
    with pytest.raises(OSError, match="No space left"):
        with atomic_path(final) as tmp:
            tmp.write_bytes(b"half of a new fi")
            _full_disk()
    assert final.read_bytes() == PREVIOUS and _leftovers(tmp_path) == []
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(final) as tmp:
            tmp.write_bytes(b"half")
            raise KeyboardInterrupt
    assert final.read_bytes() == PREVIOUS and _leftovers(tmp_path) == []
    write_text_atomic(final, "new\n")
    assert final.read_text() == "new\n" and _leftovers(tmp_path) == []
    assert oct(final.stat().st_mode & 0o777) == oct(0o666 & ~_umask())  # not mkstemp's private 0600


def test_an_interrupt_while_an_archive_entry_is_open_stays_the_interrupt(tmp_path: Path) -> None:
    """SIGTERM (SystemExit 143 from the CLI's handler) arriving inside an entry's write: the exit status
    stays 143 and the previous FMU stays. ``with ZipFile(...)`` turned it into a ValueError traceback
    ("Can't close the ZIP file while there is an open writing handle") and exit 1."""
    final = tmp_path / "MACE_0g_native.fmu"
    final.write_bytes(PREVIOUS)
    with pytest.raises(SystemExit) as stopped:
        with atomic_zip(final) as archive:
            # the signal arrives while the entry is still open (inside its own close, in the export)
            entry = archive.open("binaries/linux64/MACE_0g_native.so", "w")
            entry.write(b"\x7fELF half of a shared object")
            raise SystemExit(128 + signal.SIGTERM)
    assert stopped.value.code == 143
    assert final.read_bytes() == PREVIOUS and _leftovers(tmp_path) == []
    with atomic_zip(final) as archive:
        archive.writestr("modelDescription.xml", "<fmiModelDescription/>")
    with zipfile.ZipFile(final) as written:
        assert written.testzip() is None and written.read("modelDescription.xml") == b"<fmiModelDescription/>"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_figures_and_pages_are_written_atomically(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from matplotlib.figure import Figure

    from mace_fmu.viewer.html import write_html

    fig = Figure()
    fig.subplots().plot([0, 1], [1, 0])
    png = save_figure_atomic(fig, tmp_path / "plot.png", dpi=50)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and _leftovers(tmp_path) == []
    png.write_bytes(PREVIOUS)
    monkeypatch.setattr(Figure, "savefig", _full_disk)
    with pytest.raises(OSError):
        save_figure_atomic(fig, png)
    assert png.read_bytes() == PREVIOUS and _leftovers(tmp_path) == []

    page = tmp_path / "page.html"
    page.write_bytes(PREVIOUS)
    monkeypatch.setattr(Path, "write_text", _full_disk)
    with pytest.raises(OSError):
        write_html(page, [], title="t")
    assert page.read_bytes() == PREVIOUS and _leftovers(tmp_path) == []
    monkeypatch.undo()
    assert write_html(page, [], title="t") == page.stat().st_size and b"<html" in page.read_bytes()


def test_model_npz_and_modelica_outputs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["model", "0g", "--no-servos", "--bessel", "none", "--npz", "m", "--modelica", "m.mo"]) == 0
    capsys.readouterr()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.mo", "m.npz"]  # np.savez's own .npz rule kept
    with np.load(tmp_path / "m.npz") as data:
        assert data["A"].shape[0] == data["A"].shape[1] == len(data["states"]) and len(data["inputs"]) == 9
    source = (tmp_path / "m.mo").read_text()
    assert source.startswith("model MACE_0g_volts") and source.rstrip().endswith("end MACE_0g_volts;")


def _export(folder: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "mace_fmu.cli", "export", "0g", "-o", str(folder), *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _kill_while_writing(folder: Path, signum: int) -> subprocess.Popen:
    """Start an export and send ``signum`` once its temporary FMU exists; None if it finished first (an export
    that failed on its own is an error, with its message)."""
    proc = _export(folder)
    while proc.poll() is None:
        if _leftovers(folder):
            proc.send_signal(signum)
            _, proc.stderr_text = proc.communicate(timeout=120)  # kept for the failure message
            return proc
        time.sleep(0.002)
    _, stderr = proc.communicate()
    assert proc.returncode == 0, stderr[-2000:]
    return None


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT, signal.SIGKILL], ids=["TERM", "INT", "KILL"])
def test_a_build_killed_mid_way_keeps_the_previous_fmu(tmp_path: Path, signum: int) -> None:
    """The temporary FMU exists for about 0.2 s; a signal sent while it does can land after the rename on
    a loaded machine. Whenever it lands, the final name holds the previous file or a whole new FMU, never
    part of one; the attempts go on until one lands mid-way, which must keep the previous file."""
    final = tmp_path / "MACE_0g_native.fmu"
    missed = []
    for _attempt in range(10):
        final.write_bytes(PREVIOUS)
        proc = _kill_while_writing(tmp_path, signum)
        if proc is None:  # finished before its temporary file was seen
            missed.append("finished before its temporary FMU was seen")
            continue
        if final.read_bytes() == PREVIOUS:
            break
        with zipfile.ZipFile(final) as archive:  # the signal came after the rename: a whole FMU
            assert archive.testzip() is None and "modelDescription.xml" in archive.namelist()
        missed.append(f"the signal landed after the rename (exit status {proc.returncode})")
        for leftover in _leftovers(tmp_path):
            (tmp_path / leftover).unlink()
    else:
        pytest.fail("ten exports ended before a signal landed while their temporary FMU existed: " + "; ".join(missed))
    if signum == signal.SIGKILL:  # no chance to clean up: a hidden temporary file may stay, never the final name
        assert proc.returncode == -signal.SIGKILL
        assert all(name.startswith(".MACE_0g_native.fmu.") for name in _leftovers(tmp_path))
    else:
        assert proc.returncode == (128 + signum if signum == signal.SIGTERM else 130), proc.stderr_text[-2000:]
        assert _leftovers(tmp_path) == []


def test_two_builds_into_one_folder_leave_a_valid_fmu(tmp_path: Path) -> None:
    from fmpy import read_model_description

    first, second = _export(tmp_path), _export(tmp_path)
    for proc in (first, second):
        _, err = proc.communicate(timeout=600)
        assert proc.returncode == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["MACE_0g_native.fmu"]
    with zipfile.ZipFile(tmp_path / "MACE_0g_native.fmu") as archive:
        assert archive.testzip() is None
    description = read_model_description(str(tmp_path / "MACE_0g_native.fmu"))
    assert description.modelName == "MACE_0g_native" and sum(v.causality == "input" for v in description.modelVariables) == 9
