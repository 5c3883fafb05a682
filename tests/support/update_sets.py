"""Parameter sets as ``mace-fmu update fmu`` writes them, for the tests of the flows that read them (the
three-storey frame's: tests/parameters/test_per_mode_names.py, tests/cli/test_parameter_round_trips.py)."""

from __future__ import annotations

from pathlib import Path


def write_as_fmu_update(path: str | Path, values: dict[str, float]) -> Path:
    """``values`` written by ``update fmu``'s own writer (FmuParameters: [provenance] and [values] by the FMU's
    names), as an update of the frame's FMU against its measured FRFs would write them."""
    from mace_fmu.parameters.sets import Provenance
    from mace_fmu.updating.fmu.update import FmuParameters

    provenance = Provenance(created="2026-12-01T00:00:00+00:00", tool="mace-fmu test", fitted_to="frame_1g_native.fmu",
                            data="Experimental.csv", cost="log-FRF")
    return FmuParameters(values=values, units={}, provenance=provenance).write(path)
