"""The worker plugin that carries a file's bytes to every worker of a Dask cluster (see
:mod:`mace_fmu.util.shipping`; a module of its own because it imports Dask)."""

from __future__ import annotations

from distributed.diagnostics.plugin import WorkerPlugin

from mace_fmu.errors import MaceError
from mace_fmu.util.atomic import atomic_path
from mace_fmu.util.shipping import copy_path, sha256_of


class ShippedFile(WorkerPlugin):
    """A file's bytes, written by every worker into its local directory under their SHA-256 (see the module).

    Parameters
    ----------
    data : bytes
        The file's contents.
    name : str
        The file's name (no folder).
    """

    idempotent = True  # a second registration under the same name (the same runner, the same file) is a no-op

    def __init__(self, data: bytes, *, name: str):
        self.data = data
        self.name_of_file = name
        self.sha256 = sha256_of(data)

    def setup(self, worker) -> None:
        """Write the bytes into ``worker``'s local directory (atomically), then drop them from its memory."""
        target = copy_path(worker.local_directory, sha256=self.sha256, name=self.name_of_file)
        if not target.is_file():
            if sha256_of(self.data) != self.sha256:  # pickled on the client, read here: a damaged copy fails now
                raise MaceError(f"{self.name_of_file}: the bytes that reached this worker are not the client's")
            with atomic_path(target) as tmp:
                tmp.write_bytes(self.data)
        self.data = b""  # the copy on disk is what tasks read; the scheduler keeps the bytes for workers to come
