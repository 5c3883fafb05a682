"""What our own FMI 2.0 host loops share: status names, callbacks that keep an FMU's messages instead of
printing, and the repair of fmpy's logger proxy after a simulation with a logger of our own."""

from __future__ import annotations

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
