"""An FMU update as a user states it: an FMU file, measured-data files, parameter names, a cost; checked before any run.

Everything that can be wrong with the request (files, parameter names, channels the FMU lacks,
a frequency response without the time history it needs) is found here, before the first FMU
simulation, and reported as one :class:`~mace_fmu.errors.MaceError`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

from mace_fmu.errors import MaceError
from mace_fmu.updating.costs import Cost
from mace_fmu.updating.data import FrequencyResponseData, TimeHistory
from mace_fmu.updating.fmu_model import FmuFamily, read_fmu_interface
from mace_fmu.updating.fmu_update import COST_KINDS, CostKind, Weighting, fmu_cost
from mace_fmu.updating.simulated_frf import H1Estimator


@dataclass(frozen=True)
class FmuProblem:
    """A checked FMU update: the FMU, what it starts from, the measured data and the cost."""

    family: FmuFamily  #: the FMU with every start value from the start file set on each run
    names: tuple[str, ...]  #: parameters to update
    start: Mapping[str, float]  #: their start values [FMU units]
    history: TimeHistory
    frequency_data: FrequencyResponseData | None
    cost: Cost
    data_files: tuple[str, ...]


def fmu_problem(*, fmu: str | os.PathLike, data: Sequence[str | os.PathLike], names: Sequence[str],
                cost: CostKind, start: Mapping[str, float] | None = None, channel_map: str | os.PathLike | None = None,
                segment_s: float = 2.0, weighting: Weighting = "noise",
                held_inputs: Sequence[str] = ()) -> FmuProblem:
    """Read and check everything an FMU update needs; no simulation runs.

    ``data``: one time history (CSV/npz: the measured inputs and outputs) and, for the log-FRF cost,
    optionally one frequency response (UFF 58/CSV) to compare with instead of the H1 of the time
    history; ``start``: values [FMU units] set on every run (default: the FMU's own start values);
    ``segment_s``: H1 segment length [s]; ``held_inputs``: FMU inputs the data lack that are to be held at
    0 (any other input the data lack is an error: a silently grounded input biases every parameter).
    """
    from mace_fmu.updating.files import read_channel_map, read_measured_data

    if cost not in COST_KINDS:
        raise MaceError(f"cost must be one of {', '.join(COST_KINDS)}, got {cost!r}")
    interface = read_fmu_interface(fmu)
    names = tuple(dict.fromkeys(names))
    if not names:
        raise MaceError("name at least one FMU parameter to update")
    interface.check_parameters(names)
    start = dict(start or {})
    interface.check_parameters(list(start))
    mapping = read_channel_map(channel_map) if channel_map is not None else None
    histories, responses = [], []
    for path in data:
        if not Path(path).is_file():
            raise MaceError(f"{path}: no such measured-data file")
        item = read_measured_data(path, channel_map=mapping)
        interface.check_signals(inputs=list(item.inputs), outputs=list(item.outputs), where=os.fspath(path))
        (histories if isinstance(item, TimeHistory) else responses).append(item)
    if len(histories) != 1 or len(responses) > 1:
        raise MaceError(f"give one time history (the measured inputs drive the FMU) and at most one frequency "
                        f"response; got {len(histories)} time histories and {len(responses)} frequency responses")
    if responses and cost != "log-frf":
        raise MaceError(f"{responses[0].source}: a frequency response is compared by the log-frf cost only "
                        f"(--cost log-frf), not by {cost!r}")
    history, frd = histories[0], (responses[0] if responses else None)
    missing = [i for i in (frd.inputs if frd is not None else ()) if i not in history.inputs]
    if missing:
        raise MaceError(f"{frd.source}: input(s) {', '.join(missing)} are not in the time history "
                        f"{history.source}, which drives the FMU")
    if not history.inputs:
        raise MaceError(f"{history.source}: no input channels: the FMU must be driven by the measured inputs")
    unknown_held = [i for i in held_inputs if i not in interface.inputs]
    if unknown_held:
        raise MaceError(f"--hold-input: {', '.join(unknown_held)} is not an input of {interface.path} "
                        f"(its inputs: {', '.join(interface.inputs)})")
    absent = [i for i in interface.inputs if i not in history.inputs and i not in held_inputs]
    if absent:
        raise MaceError(f"{history.source}: no channel for the FMU input(s) {', '.join(absent)}; record them, or "
                        "hold each at 0 explicitly (--hold-input NAME=0)")
    estimator = H1Estimator(segment_length=int(round(segment_s / history.sample_time_s)),
                            band_hz=(float(frd.frequencies_hz[0]), float(frd.frequencies_hz[-1])) if frd is not None
                            else None)
    if cost == "log-frf" and frd is None:
        estimator = H1Estimator(segment_length=estimator.segment_length, band_hz=_default_band(history))
    the_cost = fmu_cost(cost, history=history, frequency_data=frd, estimator=estimator,
                        weighting=weighting if frd is None or _same_bins(frd, history, estimator) else "none")
    values = {n: start.get(n, interface.parameters[n]) for n in names}
    return FmuProblem(family=FmuFamily(interface=interface, fixed=start), names=names, start=values, history=history,
                      frequency_data=frd, cost=the_cost, data_files=tuple(os.fspath(p) for p in data))


def _default_band(history: TimeHistory) -> tuple[float, float]:
    """0.5 Hz to 60 Hz (thesis 4.5), cut to what the sampling allows."""
    return 0.5, min(60.0, 0.4 / history.sample_time_s)


def _same_bins(frd: FrequencyResponseData, history: TimeHistory, estimator: H1Estimator) -> bool:
    """Whether ``frd`` sits on the estimator's bins (the noise weights are computed there)."""
    import numpy as np

    spacing = 1.0 / (estimator.segment_length * history.sample_time_s)
    k = frd.frequencies_hz / spacing
    return bool(np.allclose(k, np.round(k), atol=1e-6))
