"""What our own FMI 2.0 host loops share: status names, callbacks that keep an FMU's messages instead of
printing, the repair of fmpy's logger proxy after a simulation with a logger of our own, and the release of
the process-wide state a pythonfmu FMU's binary would otherwise write into after freeing it at exit."""

from __future__ import annotations

import ctypes
import os
from contextlib import contextmanager
from typing import Any, Iterator

#: fmi2Status names, by value
STATUS_NAMES = ("OK", "warning", "discard", "error", "fatal", "pending")


def status_name(status: int) -> str:
    """'OK', 'warning', ... for an fmi2Status value (the number itself when it is none of them)."""
    return STATUS_NAMES[status] if 0 <= status < len(STATUS_NAMES) else str(status)


def collecting_callbacks(messages: list[str]) -> Any:
    """fmpy's fmi2CallbackFunctions whose logger appends '<status>: <message>' of warning level and above to
    ``messages`` (fmpy's default logger prints them); keep the returned object alive as long as the instance."""
    from fmpy import calloc, free
    from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                           fmi2CallbackLoggerTYPE)

    def log(component, instance, status, category, message) -> None:
        if status >= 1:
            messages.append(f"{status_name(status)}: {(message or b'').decode('utf-8', 'replace')}")

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(log)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    return callbacks


#: the one logger fmpy's proxy is pointed back at; it must outlive every FMU instance of the process
_LASTING_FMPY_LOGGER: list[Any] = []


@contextmanager
def fmpy_logger_restored() -> Iterator[None]:
    """Run a ``fmpy.simulate_fmu(..., logger=...)`` and leave fmpy's FMI 2 logger proxy pointing at a live logger.

    fmpy formats an FMU's variadic log messages in a small C proxy (``fmpy.logging.addLoggerProxy``)
    that keeps the last Python logger it was given in one global pointer, and its default callbacks,
    used by every ``FMU2Model``/``FMU2Slave`` instantiated without callbacks, go through that proxy.
    ``simulate_fmu`` hands it a logger that is collected when the call returns; the next FMU of the
    process that logs (an error, say) then jumps into freed memory: a segmentation fault, seen in a
    model-exchange instance that refused a directional derivative after a simulation of a failing
    FMU. On the way out, the proxy is given fmpy's own message printer, kept alive here for good.
    """
    try:
        yield
    finally:
        from ctypes import byref

        from fmpy.fmi1 import printLogMessage
        from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

        try:
            from fmpy.logging import addLoggerProxy
        except (ImportError, OSError):  # fmpy without its proxy library: nothing is left dangling
            return
        if not _LASTING_FMPY_LOGGER:
            _LASTING_FMPY_LOGGER.append(fmi2CallbackLoggerTYPE(printLogMessage))
        # a fresh record each time: the proxy takes the record's logger, then puts itself in its place
        callbacks = fmi2CallbackFunctions()
        callbacks.logger = _LASTING_FMPY_LOGGER[0]
        addLoggerProxy(byref(callbacks))


def release_pythonfmu_state(library: ctypes.CDLL | str | os.PathLike) -> bool:
    """Free the interpreter guard a pythonfmu FMU's binary keeps for the process, so that the process can exit.

    pythonfmu's wrapper (0.6.4 on, upstream PR #213; ``PySlaveInstance.cpp`` of 0.7.0) keeps one
    ``std::shared_ptr<PyState>`` in a static that its first ``fmi2Instantiate`` fills (a 128-byte heap block),
    and an ``__attribute__((destructor))`` function, ``onLibraryUnload``, that empties it through the exported
    ``finalizePythonInterpreter`` (``pyState = nullptr``). The wrapper defines ``STB_GNU_UNIQUE`` symbols, so
    the loader never unloads it (fmpy's ``freeLibrary`` leaves it mapped) and the two run only at ``exit()``,
    in the wrong order: the static's destructor, registered with ``__cxa_atexit`` when the binary was loaded,
    runs first and frees the block; ``_dl_fini`` then runs ``onLibraryUnload``, whose assignment decrements the
    reference count in the freed block (offset 8). When glibc has put the block in a bin, offset 8 is its
    ``bk`` link: the next free that consolidates the bin aborts with "corrupted double-linked list". Seen in
    the Dask workers of ``mace-fmu update fmu``, after their results were delivered (status 0, the right
    answer); valgrind reports the access to the freed block in every run (``tests/fmu/test_pythonfmu_exit.py``).

    Called while the interpreter runs, the same function empties the static and frees the block once; the
    destructor and ``onLibraryUnload`` then find it empty and do nothing. In a Python host this is the whole
    effect: the block's thread initialises Python only when no interpreter runs, so it has none to finalise,
    and no instance holds the block (``createInstance`` stores it in its own argument, after the instance has
    copied that argument). An instantiation afterwards fills the static again, so call this after every
    instantiation of the binary, a failed one included, from the thread that instantiated
    (``finalizePythonInterpreter`` takes no lock against ``createInstance``).

    Parameters
    ----------
    library : ctypes.CDLL or path
        The FMU's loaded binary (fmpy's ``FMU2Slave.dll``), or its path; a binary this process has not loaded
        is not loaded by this call.

    Returns
    -------
    bool
        True if the binary is a pythonfmu wrapper and its state was released; False for any other binary
        (a native FMU's, pythonfmu's Windows DLL, which does not export the function) or one not loaded.
    """
    if not isinstance(library, ctypes.CDLL):
        try:  # RTLD_NOLOAD: the handle of the binary fmpy loaded, found by its path even if the file is gone
            library = ctypes.CDLL(os.fspath(library), mode=os.RTLD_NOLOAD | os.RTLD_NOW | os.RTLD_LOCAL)
        except (OSError, AttributeError):  # not loaded here, or a platform without dlopen's flags
            return False
    try:
        release = library.finalizePythonInterpreter
    except AttributeError:
        return False
    release.argtypes, release.restype = [], None
    release()
    return True
