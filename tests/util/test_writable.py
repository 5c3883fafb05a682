"""An output is found unwritable before the work: the folder a command writes into, or the file it writes.

The tests run as root in CI's containers, where permission bits stop nothing: what cannot be written
there is a path below a regular file, or ``/proc``.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from mace_fmu.errors import MaceError
from mace_fmu.util.writable import check_output_file, check_output_folder

LINUX_PROC = pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux's /proc")
NOT_ROOT = pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0,
                              reason="root writes whatever the permission bits say")


def _everything(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def test_a_folder_that_can_be_made_or_written_into_passes_and_nothing_stays(tmp_path):
    (tmp_path / "there").mkdir()
    before = _everything(tmp_path)
    for folder in (tmp_path / "there", tmp_path / "new", tmp_path / "new" / "deeper" / "still"):
        check_output_folder(folder)
    assert _everything(tmp_path) == before  # the folders tried were removed, the probe file too


@pytest.mark.parametrize("below", ["", "out", "out/deeper"])
def test_a_folder_where_a_file_stands_is_refused_by_name(tmp_path, below):
    taken = tmp_path / "file.txt"
    taken.write_text("a file\n")
    folder = taken / below if below else taken
    with pytest.raises(MaceError) as refused:
        check_output_folder(folder, name=f"-o {folder}")
    expected = (f"-o {folder}: is a file, not a folder (outputs go into a folder)" if not below
                else f"-o {folder}: cannot create the folder ({taken} is a file)")
    assert str(refused.value) == expected
    assert _everything(tmp_path) == ["file.txt"]


@LINUX_PROC
def test_a_folder_the_system_refuses_is_refused_with_its_reason():
    with pytest.raises(MaceError, match=r"^-o /proc/mace-fmu-out: cannot create the folder \(.+\)$"):
        check_output_folder("/proc/mace-fmu-out", name="-o /proc/mace-fmu-out")
    with pytest.raises(MaceError, match=r"^/proc: cannot write into the folder \(.+\)$"):
        check_output_folder("/proc")


@NOT_ROOT
def test_a_read_only_folder_is_refused(tmp_path):
    (tmp_path / "locked").mkdir(mode=0o500)
    with pytest.raises(MaceError, match="cannot write into the folder .Permission denied"):
        check_output_folder(tmp_path / "locked")
    with pytest.raises(MaceError, match="cannot create the folder .Permission denied"):
        check_output_folder(tmp_path / "locked" / "new")


def test_a_file_that_can_be_written_passes_and_nothing_stays(tmp_path):
    (tmp_path / "old.toml").write_text("x = 1\n")
    before = _everything(tmp_path)
    for path in (tmp_path / "old.toml", tmp_path / "new.toml", tmp_path / "a" / "b" / "new.toml"):
        check_output_file(path)
    assert _everything(tmp_path) == before and (tmp_path / "old.toml").read_text() == "x = 1\n"


def test_a_file_that_cannot_be_written_is_refused_by_name(tmp_path):
    taken = tmp_path / "file.txt"
    taken.write_text("a file\n")
    cases = {tmp_path: f"--npz {tmp_path}: is a folder; give the file to write",
             taken / "page.html": f"--npz {taken / 'page.html'}: its folder {taken} is a file",
             taken / "a" / "page.html": f"--npz {taken / 'a' / 'page.html'}: cannot create its folder {taken / 'a'} "
                                        f"({taken} is a file)"}
    for path, message in cases.items():
        with pytest.raises(MaceError) as refused:
            check_output_file(path, name=f"--npz {path}")
        assert str(refused.value) == message
    assert _everything(tmp_path) == ["file.txt"]


@LINUX_PROC
def test_a_file_where_the_system_refuses_it_is_refused_with_its_reason():
    with pytest.raises(MaceError, match=r"^--html /proc/page.html: cannot write into its folder /proc \(.+\)$"):
        check_output_file("/proc/page.html", name="--html /proc/page.html")
    with pytest.raises(MaceError, match=r"^/dev/null: exists and is not a regular file$"):
        check_output_file("/dev/null")  # the rename of an atomic write would put a file in its place


@NOT_ROOT
def test_a_read_only_file_is_refused(tmp_path):
    path = tmp_path / "kept.toml"
    path.write_text("x = 1\n")
    path.chmod(0o444)
    with pytest.raises(MaceError, match="kept.toml: the file is read-only"):
        check_output_file(path)
