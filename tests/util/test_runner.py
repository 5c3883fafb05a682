"""Runs spread over a real dask.distributed LocalCluster give the serial answer, bit for bit."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from support.sockets import GARBAGE, SSH_GREETING, not_a_scheduler

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
    with pytest.raises(MaceError, match=r"^tcp://127.0.0.1:9: no Dask scheduler answered \(cannot connect"):
        DaskRunner(scheduler="tcp://127.0.0.1:9", connect_timeout_s=1.0)


@pytest.mark.parametrize("greeting, why", [
    (SSH_GREETING, "what answered does not speak Dask's protocol: MemoryError"),  # Dask's 2.8 EiB allocation
    (GARBAGE, "what answered does not speak Dask's protocol: ValueError"),
    (b"", "no answer in Dask's protocol within 2 s"),  # Client(timeout=...) alone waited for ever
], ids=["an SSH server", "garbage", "silence"])
def test_an_address_where_another_service_answers_is_one_error_within_the_timeout(greeting, why):
    outcome: list[BaseException | DaskRunner] = []

    def connect(address: str) -> None:
        try:
            outcome.append(DaskRunner(scheduler=address, connect_timeout_s=1.0))
        except BaseException as exc:
            outcome.append(exc)

    with not_a_scheduler(greeting) as address:
        # in a thread of its own, so that a runner that hangs (as Client did) fails the test instead of hanging it
        attempt = threading.Thread(target=connect, args=(address,), daemon=True)
        attempt.start()
        attempt.join(1.0 + 6.0)  # the bound: the timeout, a second's grace, the check's own margin
    assert outcome, "DaskRunner still waiting after 7 s"
    assert isinstance(outcome[0], MaceError), repr(outcome[0])
    assert str(outcome[0]) == f"{address}: no Dask scheduler answered ({why})"


def test_a_scheduler_passes_the_check_and_a_worker_is_named_for_what_it_is(runner):
    from mace_fmu.util.runner import check_scheduler

    check_scheduler(runner.client.scheduler.address, timeout_s=5.0)
    with DaskRunner(scheduler=runner.client.scheduler.address, connect_timeout_s=5.0) as by_address:
        assert by_address(lambda x: x + 1, [1, 2]) == [2, 3]
    worker = next(iter(runner.client.scheduler_info()["workers"]))
    with pytest.raises(MaceError, match=r": no Dask scheduler answered \(a Dask Worker answered; give the scheduler's"):
        check_scheduler(worker, timeout_s=5.0, name=f"--scheduler {worker}")
    with pytest.raises(MaceError, match=r"^http://host:8786: not a Dask address \(unknown address scheme 'http'"):
        check_scheduler("http://host:8786")


@pytest.mark.slow  # a local cluster started in a subprocess
def test_a_second_cluster_on_the_machine_prints_no_port_warning():
    """Dask's dashboard port, 8787, held (by another engineer's update, or here by a socket): the runner's local
    cluster starts without Dask's "Port 8787 is already in use" warning reaching the user (the
    dashboard is off and the scheduler's HTTP routes take a free port)."""
    import contextlib
    import os
    import socket
    import subprocess
    import sys

    from support.paths import ROOT

    script = ("from mace_fmu.util.runner import DaskRunner\n"
              "with DaskRunner(workers=1) as run:\n"
              "    assert list(run(abs, [-1, -2])) == [1, 2]\n")
    with contextlib.ExitStack() as held:
        try:  # Dask binds the dashboard on every interface
            server = held.enter_context(socket.create_server(("", 8787)))
            server.listen()
        except OSError:
            pass  # already held by someone else on this machine: the condition itself
        run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=180, cwd=ROOT,
                             env={**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT),
                                                                              os.environ.get("PYTHONPATH", "")])})
    assert run.returncode == 0, run.stderr
    assert "8787" not in run.stderr and "already in use" not in run.stderr, run.stderr
