"""What a control designer does next: a compensator checked over the 0-g model's bounds
=======================================================================================

An LQG compensator designed on the nominal 0-g model, closed around the 0-g FMU over Table 5.3's
frequency bounds, on a local Dask cluster.

    python examples/robust_lqg_0g.py [OUT_DIR]

Builds the updated nominal 0-g model and its bounds (``predict_zero_g``, about a minute), exports
it as a native FMU whose ``frequency_scale_mode_<k>`` span the bounds, designs the compensator
(gimbal_primary_z from gyro_payload_z, LQG rho = 0.01, theta = 0.1 on a 30-state balanced
truncation), and runs it at the nominal point, each bound alone, the corners of the four most
critical modes and 100 seeded Monte Carlo samples on two Dask workers. Writes robust_0g.png and
prints the summary. ``study_on_dask`` is used by the tests, with bounds given directly.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Mapping

from mace_fmu.iomodel.volts import VoltsModel
from mace_fmu.util.runner import DaskRunner
from mace_fmu.zero_g.robust.study import RobustStudy, format_cross_checks, prediction_bounds, robust_0g_study
from mace_fmu.zero_g.robust.summary import format_summary, sweep_figure


def study_on_dask(model: VoltsModel, *, frequency_bounds: Mapping[int, float], out_dir: str | Path,
                  samples: int = 100, seed: int = 1, workers: int = 2) -> RobustStudy:
    """The study of ``model`` over ``frequency_bounds`` (1-based mode -> relative bound) on a local cluster."""
    with DaskRunner(workers=workers, task="closed-loop runs") as runner:
        return robust_0g_study(model, frequency_bounds=frequency_bounds, out_dir=out_dir, samples=samples, seed=seed,
                               runner=runner)


def main() -> None:
    from mace_fmu.zero_g.nominal import predict_zero_g

    out = Path(sys.argv[1] if len(sys.argv) > 1 else "robust_0g")
    prediction = predict_zero_g()
    study = study_on_dask(prediction.model, frequency_bounds=prediction_bounds(prediction), out_dir=out)
    print(f"wrote {sweep_figure(study.sweep, path=out / 'robust_0g.png')}")
    print(format_summary(study.sweep, study.design))
    print(format_cross_checks(study.cross_checks, study.sweep))


if __name__ == "__main__":
    main()
