"""The modal-test route (thesis 4.2.1's first technique): modes identified from measured FRFs, paired with a
deck's modes by MAC, and the update of a structure file's parameters against them. Its public names are also on
:mod:`mace_fmu.updating`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.updating.modal.correlation import Correlation, correlate
    from mace_fmu.updating.modal.family import StructureFamily
    from mace_fmu.updating.modal.identify import Identification, IdentifiedMode, identify_modes
    from mace_fmu.updating.modal.modes_file import ModesFile, read_modes_file, write_modes_file
    from mace_fmu.updating.modal.update import ModalUpdate, run_modal_update, select_and_update

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "Identification": "identify",
    "IdentifiedMode": "identify",
    "identify_modes": "identify",
    "Correlation": "correlation",
    "correlate": "correlation",
    "StructureFamily": "family",
    "ModesFile": "modes_file",
    "read_modes_file": "modes_file",
    "write_modes_file": "modes_file",
    "ModalUpdate": "update",
    "run_modal_update": "update",
    "select_and_update": "update",
})
