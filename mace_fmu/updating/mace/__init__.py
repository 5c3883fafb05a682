"""The MACE update of thesis 4.5: the volts-volts model as a parametrised family, the update from the
pre-update moduli, and what it writes (parameter set, report, figures). Its public names are also on
:mod:`mace_fmu.updating`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.updating.mace.update import MaceUpdate, run_mace_update

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "MaceUpdate": "update",
    "run_mace_update": "update",
})
