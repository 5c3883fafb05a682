"""mace-fmu: a NASTRAN deck of a flexible, actively controlled structure to modes, volts-volts models and FMUs.

Each stage takes the object of the stage before it (the names are imported on first use, so that
``import mace_fmu`` stays cheap). On the bundled MACE deck:

>>> import tempfile
>>> import mace_fmu
>>> deck = mace_fmu.read_deck(mace_fmu.bundled_deck_path())           # the deck as NASTRAN reads it
>>> modes = mace_fmu.compute_modes(deck, configuration="0g", max_hz=5.0)  # labelled modes [Hz]
>>> [f"{hz:.2f} Hz {label}" for hz, label in zip(modes.frequencies_hz, modes.labels) if hz > 1]
['2.10 Hz 1st Z bending', '3.07 Hz 1st Y bending']
>>> model = mace_fmu.volts_model(modes, signals=mace_fmu.SignalSelection(  # volts in, volts out
...     inputs=["gimbal_secondary_z"], outputs=["gyro_payload_z"]))
>>> list(model.system.input_labels), list(model.system.output_labels)
(['gimbal_secondary_z'], ['gyro_payload_z'])
>>> with tempfile.TemporaryDirectory() as folder:                     # an FMU: native C, FMI 2.0
...     print(mace_fmu.export_fmu(model, out_dir=folder).name)
MACE_0g.fmu

Another structure's deck needs a structure file that names its actuators and sensors:
``compute_modes(read_deck("my.bdf"), configuration="0g", structure_file="my.toml")`` (see
:mod:`mace_fmu.structure.file`); the stages after it are the same.

The packages follow the same flow, each with its own ``__all__``: :mod:`mace_fmu.deck` (the deck),
:mod:`mace_fmu.structure` (the structure file; 1-g and 0-g structures), :mod:`mace_fmu.parameters`
(parameter kinds and sets), :mod:`mace_fmu.fe` (finite elements to labelled modes),
:mod:`mace_fmu.iomodel` (volts-volts state-space models), :mod:`mace_fmu.fmu` and :mod:`mace_fmu.ssp`
(FMUs and SSP packages), :mod:`mace_fmu.updating` (models updated from test data), :mod:`mace_fmu.zero_g`
(the 0-g prediction and its robustness), :mod:`mace_fmu.control_studies` (thesis Appendix A),
:mod:`mace_fmu.cli` (the ``mace-fmu`` command); :mod:`mace_fmu.sparse` is the sparse solver (linear algebra
only: factors and the lowest eigenpairs of large matrices) and :mod:`mace_fmu.util` holds what they share.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.errors import MaceError
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.controller import DiscreteController, export_controller_fmu
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.model_options import ModelledElectronics, SignalSelection
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.parameters.sets import ParameterSet
    from mace_fmu.ssp.package import write_ssp
    from mace_fmu.structure.file import bundled_deck_path, load_structure_file
    from mace_fmu.updating.fmu.problem import fmu_problem
    from mace_fmu.updating.fmu.update import update_fmu

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "read_deck": "mace_fmu.deck.reader",
    "bundled_deck_path": "mace_fmu.structure.file",
    "load_structure_file": "mace_fmu.structure.file",
    "compute_modes": "mace_fmu.fe.modes",
    "volts_model": "mace_fmu.iomodel.volts",
    "ModelledElectronics": "mace_fmu.iomodel.model_options",
    "SignalSelection": "mace_fmu.iomodel.model_options",
    "ParameterSet": "mace_fmu.parameters.sets",
    "export_fmu": "mace_fmu.fmu.export",
    "export_controller_fmu": "mace_fmu.fmu.controller",
    "DiscreteController": "mace_fmu.fmu.controller",
    "write_ssp": "mace_fmu.ssp.package",
    "fmu_problem": "mace_fmu.updating.fmu.problem",
    "update_fmu": "mace_fmu.updating.fmu.update",
    "MaceError": "mace_fmu.errors",
})
