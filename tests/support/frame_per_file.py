"""The three-storey frame's FMU updated on each of its three measured FRF files alone, with the intervals each
update reports (do the three estimates of each parameter agree within their intervals?).

The update is the example's (``examples/three_storey_frame/update_three_storey_frame.py``: storey moduli,
floor masses and modal damping ratios, 0.6 Hz about each resonance, log-FRF cost), one file at a time; the
intervals are those ``mace-fmu update fmu`` reports (``_write_fmu_update``): the files carry no coherence, so
their lines are compared unweighted and the verdict is "untested", and the covariance then comes from the
residuals (the sandwich over lines). The noise's covariance (the final cost / (m - n), what was reported
before the sandwich) is kept beside it.
"""

from __future__ import annotations

import importlib.util
import itertools
import math
from dataclasses import dataclass
from pathlib import Path

from support.paths import EXAMPLES

FRAME = EXAMPLES / "three_storey_frame"


def example():
    """The example's module (its files, bands and parameters)."""
    spec = importlib.util.spec_from_file_location("frame_example", FRAME / "update_three_storey_frame.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@dataclass(frozen=True)
class FileFit:
    """One file's update: its estimates [SI] and standard deviations [% of the value] by each covariance."""

    file: str
    values: dict
    sd_percent: dict  #: "reported" (what the update reports), "sandwich", "noise" -> name -> sd [%]
    verdict: str
    method: str  #: the reported covariance's method ("residuals" or "noise")
    seconds: float


def per_file_fits(folder: Path, updates: dict | None = None) -> dict[str, FileFit]:
    """The frame's 1-g FMU exported into ``folder`` and updated on each file: file name -> its fit. ``updates``
    (file name -> (cost, result), e.g. the example's own, ``example_run``) stand for the updates when given."""
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.updating.fmu.problem import fmu_problem
    from mace_fmu.updating.fmu.update import update_fmu

    ex = example()
    if updates is None:
        model = volts_model(compute_modes(read_deck(ex.DECK), configuration="1g", structure_file=ex.STRUCTURE))
        fmu = export_fmu(model, out_dir=folder, name="frame_1g_native")
        updates = {}
        for name in ex.FILES:
            problem = fmu_problem(fmu=fmu, data=[ex.DATA / name], names=ex.UPDATE, cost="log-frf",
                                  bands_hz=ex.BANDS_HZ)
            updates[name] = (problem.cost, update_fmu(family=problem.family, cost=problem.cost, start=problem.start,
                                                      stages=[ex.UPDATE]))
    return {name: _file_fit(name, *updates[name], ex.UPDATE) for name in ex.FILES}


def _file_fit(name: str, cost, result, names) -> FileFit:
    """One file's fit from its update's cost and result, as ``_write_fmu_update`` reports it."""
    from mace_fmu.updating.engine.convergence import blocks_with_noise, convergence_report, missing_noise_floor
    from mace_fmu.updating.engine.uncertainty import stage_uncertainty

    # as _write_fmu_update: no noise floor for FRF files; the sandwich unless the model explains the data
    report = convergence_report(result, noise_floor=None, cost=cost, missing_floor=missing_noise_floor(cost))
    from_residuals = report.verdict != "explained" or (report.residuals is not None and not report.residuals.white)
    blocks = blocks_with_noise(cost, None)
    sandwich = stage_uncertainty(result, residual_blocks=blocks)[0]
    noise = stage_uncertainty(result)[0]
    reported = sandwich if from_residuals else noise
    return FileFit(file=name, values={n: float(result.values[n]) for n in names},
                   sd_percent={"reported": dict(reported.standard_deviation_percent),
                               "sandwich": dict(sandwich.standard_deviation_percent),
                               "noise": dict(noise.standard_deviation_percent)},
                   verdict=report.verdict, method=reported.method, seconds=result.seconds)


_EXAMPLE_RUN: dict = {}


def example_run(folder: Path) -> tuple[Path, dict, dict]:
    """(its folder, its summary, file name -> (cost, result) of its updates) of the example's ``main``, run once
    per process (into ``folder`` the first time): the example's test and the per-file intervals' share its
    three updates, which are ``per_file_fits``'s (the same FMU, files, parameters, bands and starts)."""
    if "run" not in _EXAMPLE_RUN:
        import mace_fmu.updating.fmu.update as module

        ex = example()
        original, calls = module.update_fmu, []

        def recording(**kwargs):
            assert kwargs["stages"] == [ex.UPDATE], kwargs["stages"]
            result = original(**kwargs)
            calls.append((kwargs["cost"], result))
            return result

        module.update_fmu = recording
        try:
            summary = ex.main(folder)
        finally:
            module.update_fmu = original
        assert len(calls) == len(ex.FILES)  # the fitted file's update, then the other files' in order
        _EXAMPLE_RUN["run"] = (folder, summary, dict(zip(ex.FILES, calls)))
    return _EXAMPLE_RUN["run"]


def pairwise_gaps(fits: dict[str, FileFit], method: str) -> dict[str, list[float]]:
    """Parameter -> |a - b| / sqrt(sd_a^2 + sd_b^2) for every pair of files (at most 1.96: they agree)."""
    names = next(iter(fits.values())).values
    out = {}
    for n in names:
        gaps = []
        for a, b in itertools.combinations(fits.values(), 2):
            sa, sb = (f.values[n] * f.sd_percent[method][n] / 100 for f in (a, b))
            gaps.append(abs(a.values[n] - b.values[n]) / math.hypot(sa, sb))
        out[n] = gaps
    return out
