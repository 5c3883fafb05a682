"""Runs spread over a real dask.distributed LocalCluster give the serial answer, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.costs import TimeResponseCost
from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.engine.sensitivity import cost_sensitivities
from mace_fmu.updating.sample.family import TwoMassFamily
from mace_fmu.util.runner import DaskRunner

START = {"k_1": 1.0, "k_2": 1.0, "damping:mode 1": 0.01, "damping:mode 2": 0.01}


@pytest.fixture(scope="module")
def runner():
    with DaskRunner(workers=2) as r:
        yield r


def _failing(x):
    raise ValueError(f"item {x} is bad")


def test_results_come_back_in_order_from_two_worker_processes(runner):
    import os

    assert runner.workers == 2
    out = runner(lambda x: (x * x, os.getpid()), range(20))
    assert [v for v, _ in out] == [x * x for x in range(20)]
    assert os.getpid() not in {pid for _, pid in out}  # computed in the workers, not here


@pytest.mark.slow
def test_cost_sensitivities_on_the_cluster_equal_the_serial_ones_bit_for_bit(runner):
    family = TwoMassFamily()
    t = 0.5 * np.arange(2048)
    u = np.random.default_rng(5).standard_normal(t.size)
    truth = family.full({"k_1": 0.75, "k_2": 1.2, "damping:mode 1": 0.004, "damping:mode 2": 0.008})
    cost = TimeResponseCost(TimeHistory(t, {"force_1": u}, {"displacement_1": truth.time_response(t, {"force_1": u})[:, 0]}))
    kwargs = dict(base_model=family.full(START), perturbed=family.full, base=START, names=list(START),
                  relative_step=1e-3)
    serial = cost_sensitivities(cost, **kwargs)
    spread = cost_sensitivities(cost, runner=runner, **kwargs)
    np.testing.assert_array_equal(spread.matrix, serial.matrix)


def test_a_failing_run_raises_its_own_error(runner):
    with pytest.raises(ValueError, match="item 3 is bad"):
        runner(_failing, [3])


def test_an_unreachable_scheduler_is_a_clear_error():
    with pytest.raises(MaceError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9"):
        DaskRunner(scheduler="tcp://127.0.0.1:9", connect_timeout_s=1.0)
