"""What our own FMI 2.0 host loops share: status names, and callbacks that keep an FMU's messages instead of printing."""

from __future__ import annotations

from typing import Any

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
