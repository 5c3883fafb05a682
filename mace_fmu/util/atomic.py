"""Write files so that an interrupted run never leaves a half-written file under the final name."""

from __future__ import annotations

import contextlib
import os
import secrets
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from mace_fmu.errors import MaceError

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def output_folder(folder: str | os.PathLike, *, create: bool = True) -> Path:
    """``folder``, created with its parents when missing (``create=False``: only checked, before any work); a
    MaceError naming it when a file stands where a folder must go (``-o`` naming an existing file) or it
    cannot be created."""
    folder = Path(folder)
    for part in (folder, *folder.parents):
        if part.exists() and not part.is_dir():
            where = "" if part == folder else f"{folder}: "
            raise MaceError(f"{where}{part} exists and is not a folder (outputs go into a folder)")
    if create:
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise MaceError(f"{folder}: cannot create the folder ({exc.strerror or exc})") from None
    return folder


@contextlib.contextmanager
def atomic_path(final: str | os.PathLike) -> Iterator[Path]:
    """A temporary path next to ``final``; renamed onto ``final`` only when the block succeeds.

    The temporary file sits in the same folder (same file system), so the rename is atomic: a
    reader sees the previous file or the new one, never a part of it, and an exception, Ctrl-C
    or a full disk leaves the previous file untouched and removes the temporary one.
    """
    final = Path(final)
    output_folder(final.parent)
    # The name is chosen before the file exists, so that an interrupt arriving the moment it is
    # created still finds it in the cleanup below (mkstemp would return it only afterwards).
    tmp_path = final.parent / f".{final.name}.{secrets.token_hex(6)}.part"
    try:
        try:
            os.close(os.open(tmp_path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
        except OSError as exc:  # a folder that takes no files (read-only, /proc): one line, not a traceback
            raise MaceError(f"{final}: cannot write into its folder {final.parent} ({exc.strerror or exc})") from None
        yield tmp_path
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp_path, 0o666 & ~mask)  # the 0600 it was created with would make every output private
        os.replace(tmp_path, final)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()


@contextlib.contextmanager
def atomic_zip(final: str | os.PathLike) -> Iterator[zipfile.ZipFile]:
    """A deflated ZIP archive written to a temporary file and renamed onto ``final`` when the block succeeds.

    The archive is finished (its central directory written) only when every entry was: a ``SIGTERM`` or
    Ctrl-C arriving while an entry is being written leaves the interrupt to propagate and the temporary
    file to :func:`atomic_path`'s cleanup. Closing a ``ZipFile`` on the way out, as its own context
    manager does, would replace the interrupt by ``ValueError: Can't close the ZIP file while there is an
    open writing handle``.
    """
    with atomic_path(final) as part, open(part, "wb") as handle:
        archive = zipfile.ZipFile(handle, "w", zipfile.ZIP_DEFLATED)
        try:
            yield archive
        except BaseException:
            archive.fp = None  # abandoned: the state close() leaves, so that __del__ does not finish it either
            raise
        archive.close()


def save_figure_atomic(figure: Figure, path: str | os.PathLike, **savefig_options) -> Path:
    """Save a matplotlib figure to ``path`` atomically (format from the suffix, PNG without one); returns the path."""
    path = Path(path)
    with atomic_path(path) as tmp:
        figure.savefig(tmp, format=path.suffix.lstrip(".").lower() or "png", **savefig_options)
    return path


def write_text_atomic(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; returns the path.

    Parameters
    ----------
    path : path
        The file to write (its folder must exist).
    text : str
        The content.

    Returns
    -------
    Path
        ``path``. A reader never sees half a file: the text goes to a temporary file beside it, which
        replaces ``path`` when complete.
    """
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)
