"""Many independent model runs side by side on Dask: local processes by default, any cluster by address.

The updating engine takes a ``runner``: any function with the signature of the builtin ``map``
(``runner(fn, items) -> iterable of fn(item)``, in order). ``map`` itself runs serially; a
:class:`DaskRunner` spreads the calls over the workers of a ``dask.distributed`` cluster, so the
same code runs on a laptop's cores or on a user's cluster (``scheduler="tcp://host:8786"``).
The functions and items must be picklable (cloudpickle: closures and lambdas are fine).
"""

from __future__ import annotations

import os
from typing import Any, Callable, Iterable

from mace_fmu.errors import MaceError
from mace_fmu.util.progress import ProgressCallback, Step


class DaskRunner:
    """``runner(fn, items)`` on a dask.distributed cluster, results in the order of ``items``.

    Without ``scheduler`` or ``client`` a LocalCluster of ``workers`` single-threaded processes
    (default: the machine's cores) is started and closed with the runner (use it as a context
    manager). One numerical thread per worker: the workers are the parallelism, and a fixed
    thread count keeps every result bit for bit what a serial run gives.
    """

    def __init__(self, *, scheduler: str | None = None, client: Any = None, workers: int | None = None,
                 progress: ProgressCallback | None = None, task: str = "model runs", connect_timeout_s: float = 10.0):
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError as exc:  # dask[distributed] is a dependency; say what is missing if it is not there
            raise MaceError(f"the Dask runner needs dask[distributed]: {exc}") from None
        self._own_cluster = None
        self._own_client = client is None
        if client is not None:
            self.client = client
        elif scheduler is not None:
            try:
                self.client = Client(scheduler, timeout=f"{connect_timeout_s}s")
            except (OSError, TimeoutError) as exc:
                raise MaceError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
        else:
            n = workers or os.cpu_count() or 1
            if n < 1:
                raise MaceError(f"workers must be >= 1, got {n}")
            self._own_cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                             dashboard_address=None, silence_logs=40,
                                             env={"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
                                                  "MKL_NUM_THREADS": "1"})
            self.client = Client(self._own_cluster)
        self.progress = progress
        self.task = task

    def __call__(self, fn: Callable[[Any], Any], items: Iterable[Any]) -> list[Any]:
        """[fn(item) for item in items], computed on the cluster; the first failure is raised."""
        from dask.distributed import as_completed

        items = list(items)
        futures = self.client.map(fn, items, pure=False)
        index = {f.key: k for k, f in enumerate(futures)}
        results: list[Any] = [None] * len(items)
        for done, future in enumerate(as_completed(futures), start=1):
            results[index[future.key]] = future.result()  # re-raises the worker's exception here
            if self.progress is not None:
                self.progress(Step(self.task, done, len(items)))
        return results

    @property
    def workers(self) -> int:
        """Number of workers the cluster has now."""
        return len(self.client.scheduler_info()["workers"])

    def close(self) -> None:
        if self._own_client:
            self.client.close()
        if self._own_cluster is not None:
            self._own_cluster.close()

    def __enter__(self) -> DaskRunner:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
