"""Files that Dask workers read, sent to them as bytes: a worker's paths are not the client's.

A worker started in another folder does not resolve the client's relative paths, and a worker on another
machine resolves none of its paths. :meth:`DaskRunner.ship <mace_fmu.util.runner.DaskRunner.ship>` sends a
file's bytes to the cluster once, as a worker plugin (:class:`~mace_fmu.util.shipped_file.ShippedFile`):
every worker there now and every worker that joins later writes them into its own local directory, under
the file's SHA-256, before it runs a task. A task then finds that copy with :func:`shipped_copy` and falls
back to the path where nothing was shipped (a serial run, a runner of another kind). Each worker process
has a folder of its own, written in the plugin's setup before any task of that worker runs, so two tasks
never race for a half-written file. This module does not import Dask: the serial path stays light.
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

#: the folder, inside a worker's local directory, that holds the shipped files: <sha256>/<file name>
FOLDER = "mace_fmu_files"


def sha256_of(data: bytes) -> str:
    """The SHA-256 of ``data``, hex."""
    return hashlib.sha256(data).hexdigest()


def copy_path(local_directory: str | os.PathLike, *, sha256: str, name: str) -> Path:
    """Where a worker whose local directory is ``local_directory`` keeps the shipped file ``name`` of digest
    ``sha256`` (under its own name, so that messages and extraction folders read as the client's)."""
    return Path(local_directory) / FOLDER / sha256 / name


def shipped_copy(*, sha256: str, name: str) -> Path | None:
    """In a Dask worker, its copy of the file of digest ``sha256`` and name ``name`` if one was shipped to it;
    None elsewhere (the client, a serial run) or when none was shipped."""
    if "distributed" not in sys.modules or not sha256:  # not in a worker: no Dask imported, nothing shipped
        return None
    from distributed import get_worker

    try:
        worker = get_worker()
    except ValueError:
        return None
    path = copy_path(worker.local_directory, sha256=sha256, name=name)
    return path if path.is_file() else None
