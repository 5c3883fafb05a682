"""Session hooks shared by all tests."""

from __future__ import annotations

import os
import sys

import pytest

# One BLAS thread per xdist worker: the suite runs one worker per core, and a second BLAS thread
# per worker then waits for a busy core (the matrices here are small; mace_fmu/util/threads.py
# measures the same for the model build). Set before numpy or scipy load their OpenBLAS.
if "PYTEST_XDIST_WORKER" in os.environ:
    for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_variable, "1")

_exit_status: list[int] = []


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    _exit_status.append(int(exitstatus))


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config: pytest.Config) -> None:
    """Leave without interpreter finalisation once pythonfmu FMUs were loaded in this process.

    pythonfmu 0.7 keeps every instance's module alive (upstream issue #229); when the interpreter
    finalises, its native wrapper has been seen to corrupt the heap ("corrupted double-linked
    list", SIGABRT) after all tests passed and the summary was printed, on one CI clone and not
    on another. The exit status is pytest's own; only the crash at teardown is skipped.
    """
    if _exit_status and any("pythonfmu" in name or "fmpy" in name for name in sys.modules):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_exit_status[-1])


@pytest.fixture(scope="session")
def motion_fmu_0g(tmp_path_factory):
    """(model, fmu, extracted folder) of the 0-g model with the motion of every grid as outputs.

    Extracted once into a session folder that outlives every simulation (see tests/fmu/test_fmu.py).
    """
    import fmpy

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.model_options import SignalSelection
    from mace_fmu.iomodel.volts import volts_model

    model = volts_model(compute_modes(configuration="0g"), signals=SignalSelection(motion_grids="all"))
    fmu = export_fmu(model, out_dir=tmp_path_factory.mktemp("motion_fmu"), name="MACE_0g_motion", runtime="pythonfmu")
    return model, fmu, fmpy.extract(str(fmu), unzipdir=str(tmp_path_factory.mktemp("motion_unzipped")))


@pytest.fixture(scope="session")
def native_fmu_1g(tmp_path_factory):
    """The 1-g native FMU of the bundled deck at its nominal values (MACE_1g_native.fmu), exported once per process
    for the modules that only read it (the updates' truth and model, the plans' FMU)."""
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model

    return export_fmu(volts_model(compute_modes(configuration="1g")), out_dir=tmp_path_factory.mktemp("native_1g"),
                      name="MACE_1g_native")
