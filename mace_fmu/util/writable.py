"""Whether an output can be written, asked before the work that makes it.

A command that computes for a minute and then finds its output folder uncreatable loses that minute
and, for an update, its results. These checks answer at once: a folder that can be made (or is
there and takes files), a file whose folder can be made and which, if it exists, may be replaced.
They try what the write will do (make the folders, create a file in them) and undo it, because
the permission bits say nothing to root, a read-only file system or ``/proc``; nothing stays behind.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

from mace_fmu.errors import MaceError

__all__ = ["check_output_file", "check_output_folder"]

_PROBE = ".mace-fmu-probe-"


def _folder_problem(folder: Path, *, called: str) -> str | None:
    """Why files cannot be written into ``folder`` (made with its parents if missing), or None when they can.

    ``called`` is how the reason names the folder ("the folder", "its folder /x"). The missing folders are
    made and removed again; an existing one gets a temporary file, removed again.
    """
    missing = []
    for part in (folder, *folder.parents):
        if os.path.exists(part):  # False, not an exception, below a folder it may not search
            break
        missing.append(part)
    if not os.path.isdir(part):
        return f"{called} is a file" if part == folder else f"cannot create {called} ({part} is a file)"
    if missing:
        made = []
        try:
            for new in reversed(missing):  # outermost first, as mkdir(parents=True) would
                os.mkdir(new)
                made.append(new)
        except OSError as exc:
            return f"cannot create {called} ({exc.strerror or exc})"
        finally:
            for new in reversed(made):
                with contextlib.suppress(OSError):  # another process wrote into it meanwhile: it is theirs now
                    os.rmdir(new)
        return None
    try:
        handle, probe = tempfile.mkstemp(dir=folder, prefix=_PROBE)
    except OSError as exc:
        return f"cannot write into {called} ({exc.strerror or exc})"
    os.close(handle)
    with contextlib.suppress(OSError):
        os.unlink(probe)
    return None


def check_output_folder(folder: str | os.PathLike, *, name: str | None = None) -> None:
    """Raise a MaceError unless files can be written into ``folder`` (created with its parents if missing).

    Parameters
    ----------
    folder : path
        The output folder a command will write into.
    name : str, optional
        How the message names it, e.g. ``"-o /proc/x"`` (default: the path).

    Raises
    ------
    MaceError
        One line: the name and why, e.g. ``-o /proc/x: cannot create the folder (No such file or directory)``
        or ``-o out.txt/x: cannot create the folder (out.txt is a file)``. Nothing is left on disk either way.
    """
    folder = Path(folder)
    problem = _folder_problem(folder, called="the folder")
    if problem == "the folder is a file":
        problem = "is a file, not a folder (outputs go into a folder)"
    if problem is not None:
        raise MaceError(f"{name or folder}: {problem}")


def check_output_file(path: str | os.PathLike, *, name: str | None = None) -> None:
    """Raise a MaceError unless ``path`` can be written: its folder can be made and written into, and what
    is there already is a writable regular file (the write replaces it).

    Parameters
    ----------
    path : path
        The output file a command will write.
    name : str, optional
        How the message names it, e.g. ``"--html /proc/page.html"`` (default: the path).

    Raises
    ------
    MaceError
        One line: the name and why, e.g. ``--html /proc/page.html: cannot write into its folder /proc (No such
        file or directory)``. Nothing is left on disk either way.
    """
    path = Path(path)
    name = name or str(path)
    if os.path.isdir(path):
        raise MaceError(f"{name}: is a folder; give the file to write")
    # a device or a pipe (/dev/null): the rename that ends an atomic write would replace it by a file
    if os.path.exists(path) and not os.path.isfile(path):
        raise MaceError(f"{name}: exists and is not a regular file")
    if os.path.isfile(path) and not os.access(path, os.W_OK):
        raise MaceError(f"{name}: the file is read-only")
    problem = _folder_problem(path.parent, called=f"its folder {path.parent}")
    if problem is not None:
        raise MaceError(f"{name}: {problem}")
