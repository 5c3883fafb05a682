"""Packages that re-export their modules' public names without importing them all up front.

``import mace_fmu`` (or ``mace_fmu.fe``) must stay cheap and free of import cycles between stages,
yet a user should reach the names a stage offers from the stage itself (``mace_fmu.fe.compute_modes``).
A package lists its public names and the module of each; a name is imported on first access
(PEP 562 module ``__getattr__``).
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(package: str, public: Mapping[str, str]
                 ) -> tuple[list[str], Callable[[str], Any], Callable[[], list[str]]]:
    """``__all__``, ``__getattr__`` and ``__dir__`` of a package whose public names live in its modules.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    public : Mapping[str, str]
        Public name -> the module that defines it, relative to the package (``"modal"``) or absolute.

    Returns
    -------
    tuple
        ``(__all__, __getattr__, __dir__)``, assigned at the package's top level.
    """
    def module_of(name: str) -> str:
        module = public[name]
        return module if module.startswith("mace_fmu") else f"{package}.{module}"

    def __getattr__(name: str) -> Any:
        if name not in public:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(module_of(name)), name)

    names = sorted(public)
    # where each is defined (the API reference), as the function's attribute ``modules``
    __getattr__.__dict__["modules"] = {name: module_of(name) for name in names}

    def __dir__() -> list[str]:
        return sorted(set(names) | set(vars(sys.modules[package])))

    return names, __getattr__, __dir__
