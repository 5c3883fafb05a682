"""Many independent model runs side by side on Dask: local processes by default, any cluster by address.

The updating engine takes a ``runner``: any function with the signature of the builtin ``map``
(``runner(fn, items) -> iterable of fn(item)``, in order). ``map`` itself runs serially; a
:class:`DaskRunner` spreads the calls over the workers of a ``dask.distributed`` cluster, so the
same code runs on a laptop's cores or on a user's cluster (``scheduler="tcp://host:8786"``).
The functions and items must be picklable (cloudpickle: closures and lambdas are fine). A file the
runs read goes to the workers as bytes (:meth:`DaskRunner.ship`, :mod:`mace_fmu.util.shipping`): the
workers of a cluster need not see the client's files.
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import sys
import threading
import uuid
import warnings
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

from mace_fmu.errors import MaceError
from mace_fmu.util.progress import ProgressCallback, Step

#: how long a scheduler address is given to answer [s]: a cluster's scheduler answers in milliseconds, a
#: loaded one in seconds; what does not answer by then is not going to
DEFAULT_CONNECT_TIMEOUT_S = 20.0

#: longest wait for an interrupted run's workers to close [s]; a worker inside a long task is then terminated
#: by its nanny, and Ctrl-C answers within seconds, not after the task
_INTERRUPTED_CLOSE_S = 5.0

#: the exchange after the connection gets this much longer than the connection [s], so that when the
#: connection is the problem, Dask's own timeout fires first with its reason (refused, unresolvable)
_GRACE_S = 1.0


def _why_no_scheduler(exc: BaseException, *, timeout_s: float) -> str:
    """The reason, in words, that an address gave no Dask scheduler's answer."""
    from distributed.comm import CommClosedError

    if isinstance(exc, TimeoutError) and not str(exc):  # the bound of check_scheduler: connected, then nothing
        return f"no answer in Dask's protocol within {timeout_s + _GRACE_S:g} s"
    if isinstance(exc, CommClosedError):
        return "the other end closed the connection"
    if isinstance(exc, OSError):  # refused, unreachable: the system's words, under Dask's wrappers
        root: BaseException = exc
        while root.__cause__ is not None:
            root = root.__cause__
        strerror = getattr(root, "strerror", None)
        if strerror:
            return f"cannot connect: {strerror}"
        return f"cannot connect within {timeout_s:g} s" if root is not exc else str(exc)
    # a service that speaks first (SSH, SMTP) has its greeting read as a Dask frame length: an exabyte
    # allocation (MemoryError) or a dimension beyond numpy's (ValueError); other garbage fails in msgpack
    # named by the builtin class it is (numpy's _ArrayMemoryError is a MemoryError, msgpack's ExtraData a ValueError)
    builtin = next(c for c in type(exc).__mro__ if c.__module__ == "builtins")
    return f"what answered does not speak Dask's protocol: {builtin.__name__}"


def check_scheduler(address: str, *, timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S, name: str | None = None) -> None:
    """Raise a MaceError unless a Dask scheduler answers at ``address`` within ``timeout_s``.

    ``dask.distributed.Client(address, timeout=...)`` bounds the TCP connection only: a service that
    accepts and stays silent keeps it waiting for the handshake for ever, and one that speaks first
    has its bytes read as a frame length (Dask then allocates exabytes). This asks the address for
    its identity, the whole exchange bounded by ``timeout_s`` (and a second), and says in one line what
    went wrong.

    Parameters
    ----------
    address : str
        The scheduler's address, e.g. ``tcp://host:8786``.
    timeout_s : float
        Longest wait for the connection (Dask's ``timeout``) [s]; the answer must come within a second more.
    name : str, optional
        How the message names the address, e.g. ``"--scheduler tcp://host:8786"`` (default: the address).

    Raises
    ------
    MaceError
        ``<name>: no Dask scheduler answered (<why>)``, or ``<name>: not a Dask address (...)``.
    """
    import asyncio
    import threading

    from distributed.comm import connect
    from distributed.comm.addressing import parse_address
    from distributed.comm.registry import get_backend

    name = name or address
    try:
        get_backend(parse_address(address)[0])
    except (ValueError, TypeError) as exc:
        raise MaceError(f"{name}: not a Dask address ({exc}); expected e.g. tcp://host:8786") from None

    async def identity():
        comm = await connect(address, timeout=timeout_s)
        try:
            await comm.write({"op": "identity"})
            return await comm.read()
        finally:
            comm.abort()

    outcome: list = []

    def ask() -> None:
        try:
            outcome.append(asyncio.run(asyncio.wait_for(identity(), timeout_s + _GRACE_S)))
        except Exception as exc:
            outcome.append(exc)

    # a loop of its own in a daemon thread: the caller may be inside an event loop (a notebook), and a
    # connection that ignores its cancellation keeps neither the caller nor the interpreter's exit waiting
    thread = threading.Thread(target=ask, name="mace-fmu scheduler check", daemon=True)
    thread.start()
    thread.join(timeout_s + 5.0 + _GRACE_S)
    answer = outcome[0] if outcome else TimeoutError()
    if isinstance(answer, Exception):
        raise MaceError(f"{name}: no Dask scheduler answered ({_why_no_scheduler(answer, timeout_s=timeout_s)})")
    kind = answer.get("type") if isinstance(answer, dict) else None
    if kind != "Scheduler":
        what = f"a Dask {kind}" if isinstance(kind, str) else "something that is not Dask"
        raise MaceError(f"{name}: no Dask scheduler answered ({what} answered; give the scheduler's address)")


class DaskRunner:
    """``runner(fn, items)`` on a dask.distributed cluster, results in the order of ``items``.

    Without ``scheduler`` or ``client`` a LocalCluster of ``workers`` single-threaded processes
    (default: the machine's cores) is started and closed with the runner (use it as a context
    manager). One numerical thread per worker: the workers are the parallelism, and a fixed
    thread count keeps every result bit for bit what a serial run gives.

    With ``scheduler``, the address must answer as a Dask scheduler within ``connect_timeout_s``
    seconds (:func:`check_scheduler`), else a MaceError says so in one line.

    The workers need the same mace-fmu and Python packages as the client, not its files: a file the runs
    read is sent with :meth:`ship`.
    """

    def __init__(self, *, scheduler: str | None = None, client: Any = None, workers: int | None = None,
                 progress: ProgressCallback | None = None, task: str = "model runs",
                 connect_timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S):
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError as exc:  # dask[distributed] is a dependency; say what is missing if it is not there
            raise MaceError(f"the Dask runner needs dask[distributed]: {exc}") from None
        self._own_cluster = None
        self._stderr: _WorkersStderr | None = None
        self.client: Any = None  # a distributed.Client once connected
        self._shipped: dict[str, str] = {}  # SHA-256 -> the name of the plugin that ships it
        self._id = uuid.uuid4().hex[:12]  # plugin names of this runner's own: closing it leaves other clients' alone
        self._own_client = client is None
        if client is not None:
            self.client = client
        elif scheduler is not None:
            check_scheduler(scheduler, timeout_s=connect_timeout_s)  # Client alone can hang or allocate exabytes
            try:
                self.client = Client(scheduler, timeout=f"{connect_timeout_s}s")
            except Exception as exc:  # it answered a moment ago: whatever stops the client now, in one line
                raise MaceError(f"{scheduler}: the Dask client could not connect ({type(exc).__name__}: {exc})") \
                    from None
        else:
            n = workers or os.cpu_count() or 1
            if n < 1:
                raise MaceError(f"workers must be >= 1, got {n}")
            self._stderr = _WorkersStderr.made()
            started_before = set(_started_clusters())
            try:
                with self._stderr.given_to_new_processes() if self._stderr else contextlib.nullcontext():
                    # no dashboard; the scheduler's HTTP routes on a free port: the default 8787 taken by
                    # another cluster printed a three-line warning into every run
                    self._own_cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                                     dashboard_address=None, silence_logs=40,
                                                     scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                                                     preload=[__name__],
                                                     env={"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
                                                          "MKL_NUM_THREADS": "1"})
                    self.client = Client(self._own_cluster)
            except (KeyboardInterrupt, SystemExit):  # Ctrl-C while the workers started: nothing left, nothing shown
                # the cluster whose constructor was interrupted: closed here, else Dask's exit handler tries
                # again and prints its half-started workers' AssertionError
                self._own_cluster = next((c for c in _started_clusters() if c not in started_before), None)
                self.close(quiet=True)
                raise
            except BaseException:
                if self._stderr:
                    self._stderr.release()  # why the workers did not start
                self.close(quiet=True)
                raise
            if self._stderr:
                self._stderr.release()
        self.progress = progress
        self.task = task

    def ship(self, path: str | os.PathLike, *, sha256: str | None = None) -> str:
        """Send the bytes of the file at ``path`` to every worker of the cluster, now and joining later, once.

        Each worker keeps them in its local directory under their SHA-256 until it stops; a task finds
        them with :func:`mace_fmu.util.shipping.shipped_copy`. A file already shipped by this runner is
        not sent again; closing the runner frees the scheduler's copy.

        Parameters
        ----------
        path : path
            The file, as this process names it (relative to this process's folder).
        sha256 : str, optional
            The digest the file was read with: a file changed since is a MaceError.

        Returns
        -------
        str
            The file's SHA-256 (hex), by which the workers find it.

        Raises
        ------
        MaceError
            The file cannot be read, changed since it was read (``sha256``), or a worker cannot store it.
        """
        from mace_fmu.util.shipped_file import ShippedFile
        from mace_fmu.util.shipping import sha256_of

        try:
            data = Path(path).read_bytes()
        except OSError as exc:
            raise MaceError(f"{path}: cannot read the file to send to the Dask workers "
                            f"({exc.strerror or exc})") from None
        digest = sha256_of(data)
        if sha256 is not None and digest != sha256:
            raise MaceError(f"{path}: the file changed while in use (SHA-256 {digest[:12]}..., read as "
                            f"{sha256[:12]}...)")
        if digest not in self._shipped:
            name = f"mace-fmu-file-{digest[:16]}-{self._id}"
            try:
                self.client.register_plugin(ShippedFile(data, name=Path(path).name), name=name)
            except Exception as exc:  # a worker's full or read-only disk: in one line, with the worker's words
                raise MaceError(f"{path}: the Dask workers could not store it ({type(exc).__name__}: {exc})") \
                    from None
            self._shipped[digest] = name
        return digest

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

    def close(self, *, quiet: bool = False) -> None:
        """Free the scheduler's copies of the shipped files and close the client and the cluster this runner
        started (a given client or cluster stays open).

        Parameters
        ----------
        quiet : bool
            For a run that is being interrupted (Ctrl-C, SIGTERM): Dask's loggers are silenced and the workers
            are given :data:`_INTERRUPTED_CLOSE_S` seconds, so that the interruption ends in the caller's one
            line and not in the cancelled tasks' tracebacks; a second Ctrl-C meanwhile is ignored (the close is
            bounded) rather than leaving workers behind.
        """
        if not quiet:
            self._close()
            return
        if self._stderr:
            self._stderr.mute()
        self._loop_errors_dropped()
        with _dask_silenced(), _interrupts_ignored():
            try:
                self._close(timeout_s=_INTERRUPTED_CLOSE_S)
            except Exception:  # noqa: BLE001 - an interrupted run's cluster may be half started or half gone
                pass
            # what could not be closed is left to the worker processes' own finalisers, not to Dask's exit
            # handler, which would print the same failure again
            if self._own_cluster is not None:
                _started_clusters().discard(self._own_cluster)

    def _loop_errors_dropped(self) -> None:
        """The event loop of this runner's own cluster drops the errors nobody retrieved from then on.

        A start interrupted while a worker was still importing leaves the nanny's start task failed
        ("Nanny failed to start"); asyncio reports such a task when it is collected, which may be after
        the command's own line, as the process exits. Only this loop's reports are dropped: another
        loop of the process reports as before.
        """
        loop = getattr(getattr(self._own_cluster, "loop", None), "asyncio_loop", None)
        if loop is not None:
            loop.set_exception_handler(lambda _loop, _context: None)

    def _close(self, *, timeout_s: float | None = None) -> None:
        for name in self._shipped.values():
            try:  # the workers keep their copies until they stop; a cluster already gone needs nothing freed
                self.client.unregister_worker_plugin(name)
            except Exception:  # noqa: BLE001
                pass
        self._shipped.clear()
        bounded = {} if timeout_s is None else {"timeout": timeout_s}  # else Dask's own defaults
        if self._own_client and self.client is not None:
            self.client.close(**bounded)
        if self._own_cluster is not None:
            self._own_cluster.close(**bounded)

    def __enter__(self) -> DaskRunner:
        return self

    def __exit__(self, exc_type, exc, traceback) -> None:
        self.close(quiet=exc_type is not None and issubclass(exc_type, (KeyboardInterrupt, SystemExit)))


def _started_clusters():
    """Dask's registry of the clusters this process started (closed by its exit handler if still open)."""
    from distributed.deploy.spec import SpecCluster

    return SpecCluster._instances


class _WorkersStderr:
    """The standard error of the processes a local cluster starts: a pipe this process forwards to its own.

    Ctrl-C signals the terminal's whole process group, Dask's worker processes included, and each printed the
    KeyboardInterrupt of its event loop (35-68 lines of tracebacks before the command's own line). A worker
    ignores SIGINT from its start on (:func:`dask_setup`); what one prints before that, while Python and Dask
    are being imported, is held here until the cluster has started (then shown) or the start was interrupted
    (then dropped), and what the workers print while an interrupted run closes them is dropped too.
    Processes started later (a worker restarted after a crash) write to this process's stderr directly.
    """

    @classmethod
    def made(cls) -> _WorkersStderr | None:
        """One, or None where fd 2 cannot be passed on so (Windows; a process without a stderr)."""
        if os.name != "posix":
            return None
        try:
            return cls()
        except OSError:
            return None

    def __init__(self) -> None:
        self._target = os.dup(2)
        read, self._write = os.pipe()
        self._lock = threading.Lock()
        self._held: list[bytes] | None = []  # None once released: forwarded as it comes
        self._muted = False
        threading.Thread(target=self._forward, args=(read,), name="mace-fmu workers' stderr", daemon=True).start()

    @contextlib.contextmanager
    def given_to_new_processes(self) -> Iterator[None]:
        """fd 2 is the pipe meanwhile: processes started now inherit it (this process's own lines pass too)."""
        sys.stderr.flush()
        saved = os.dup(2)
        os.dup2(self._write, 2)
        try:
            yield
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
            os.close(self._write)  # the children hold theirs: the pipe ends when the last of them has exited

    def release(self) -> None:
        """Show what was held, and from now on what comes."""
        with self._lock:
            held, self._held = self._held or [], None
            if not self._muted:
                self._write_all(b"".join(held))

    def mute(self) -> None:
        """Drop what was held and whatever comes."""
        with self._lock:
            self._muted, self._held = True, None

    def _forward(self, read: int) -> None:
        with os.fdopen(read, "rb", buffering=0) as pipe:
            while chunk := pipe.read(65536):
                with self._lock:
                    if self._muted:
                        continue
                    if self._held is not None:
                        self._held.append(chunk)
                    else:
                        self._write_all(chunk)
        os.close(self._target)

    def _write_all(self, data: bytes) -> None:
        while data:
            try:
                data = data[os.write(self._target, data):]
            except OSError:  # stderr closed: nothing left to show it on
                return


def dask_setup(worker: Any) -> None:
    """Dask's preload hook of the local cluster's workers: SIGINT ignored in the worker process.

    Ctrl-C is for the process that started the cluster, which closes the workers: a worker interrupted by the
    terminal printed its event loop's traceback and died under its nanny. Runs in the worker process's main
    thread (its event loop's), before the worker registers with the scheduler, so every worker of a started
    cluster ignores SIGINT.
    """
    del worker  # the hook's argument; nothing of the worker is needed
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def _interrupts_ignored() -> Iterator[None]:
    """SIGINT ignored meanwhile (main thread only: elsewhere Python does not deliver it)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def _dask_silenced() -> Iterator[None]:
    """Dask's (and its event loop's) log records and warnings dropped meanwhile: the cancelled tasks and closing
    comms of an interrupted run are the interruption itself, not news."""
    loggers = [logging.getLogger(name) for name in ("distributed", "tornado", "asyncio")]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL + 1)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            yield
    finally:
        for logger, level in zip(loggers, levels):
            logger.setLevel(level)
