"""The sparse solver of large symmetric matrices: factored in the ordering that fills least (CHOLMOD's supernodal
Cholesky, two substructures on two cores, or SuperLU) and the lowest eigenpairs by block shift-invert Lanczos.

Linear algebra only: it knows nothing of decks, elements or DOF names, and the other stages reach it through
the names below (``factorize`` and ``lowest_modes``), never through its modules.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.sparse.factor import factorize
    from mace_fmu.sparse.lanczos import LanczosModes, lowest_modes

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "factorize": "factor",
    "lowest_modes": "lanczos",
    "LanczosModes": "lanczos",
})
