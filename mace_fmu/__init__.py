"""mace-fmu: a NASTRAN deck of a flexible, actively controlled structure to modes, volts-volts models and FMUs.

The names a user starts with, in the order of the data flow (imported on first use, so that
``import mace_fmu`` stays cheap)::

    deck = mace_fmu.read_deck("my.bdf")                           # the deck as NASTRAN reads it
    modes = mace_fmu.compute_modes(deck, configuration="0g")      # modes.frequencies_hz, modes.labels
    model = mace_fmu.volts_model("0g", structure_file="my.toml",  # volts in, volts out
                                 electronics=mace_fmu.ModelledElectronics(servos=False),
                                 signals=mace_fmu.SignalSelection(outputs=["tip_z"]))
    mace_fmu.export_fmu(model, out_dir="fmus")                    # an FMU (native: FMI 2 or 3; or kind="pythonfmu")

The packages follow the same flow, each with its own ``__all__``: :mod:`mace_fmu.deck` (the deck),
:mod:`mace_fmu.structure` (the structure file; 1-g and 0-g structures), :mod:`mace_fmu.parameters`
(parameter kinds and sets), :mod:`mace_fmu.fe` (finite elements to labelled modes),
:mod:`mace_fmu.iomodel` (volts-volts state-space models), :mod:`mace_fmu.fmu` and :mod:`mace_fmu.ssp`
(FMUs and SSP packages), :mod:`mace_fmu.updating` (models updated from test data), :mod:`mace_fmu.zero_g`
(the 0-g prediction and its robustness), :mod:`mace_fmu.control_studies` (thesis Appendix A),
:mod:`mace_fmu.cli` (the ``mace-fmu`` command); :mod:`mace_fmu.util` holds what they share.
"""

from __future__ import annotations

from mace_fmu.util.lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "read_deck": "mace_fmu.deck.reader",
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
    "fmu_problem": "mace_fmu.updating.fmu_problem",
    "update_fmu": "mace_fmu.updating.fmu_update",
    "MaceError": "mace_fmu.errors",
})
