"""A process that ran a pythonfmu FMU exits without touching freed memory.

pythonfmu's wrapper frees its process-wide ``PyState`` block with a static's destructor at ``exit()`` and
then, from its ``onLibraryUnload`` destructor, decrements a count inside the freed block; glibc aborted
the Dask workers of ``mace-fmu update fmu`` with "corrupted double-linked list" in some runs of several
(see :func:`mace_fmu.fmu.host.release_pythonfmu_state`). Whether glibc notices depends on the state of
its bins, so the host process runs under valgrind, which reports the access in every run: before the fix,
"Invalid read of size 4 at finalizePythonInterpreter (in .../binaries/linux64/Tiny.so) by _dl_fini",
in a block of 128 bytes allocated by ``pythonfmu::createInstance`` and freed by ``__run_exit_handlers``.

The FMU is a two-variable pythonfmu slave (y = 2 u, computed at each step): the wrapper is the same
binary in every pythonfmu FMU, and a small slave keeps the host quick under valgrind.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import json
import os
import re
import shutil
import subprocess
import sys

import fmpy
import pytest
from support.paths import ROOT, SUPPORT

HOST = SUPPORT / "pythonfmu_exit_host.py"

TINY_SLAVE = '''
from pythonfmu import Fmi2Causality, Fmi2Slave, Real


class Tiny(Fmi2Slave):
    """y = 2 u, y updated by each step from the input held over it."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.u = 0.0
        self.y = 0.0
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.y = 2.0 * self.u
        return True
'''


@pytest.fixture(scope="module")
def tiny_fmu(tmp_path_factory) -> str:
    """A pythonfmu FMU of the two-variable slave above (built by pythonfmu's own builder)."""
    from pythonfmu.builder import FmuBuilder

    folder = tmp_path_factory.mktemp("tiny_pythonfmu")
    script = folder / "tiny_slave.py"
    script.write_text(TINY_SLAVE)
    return str(FmuBuilder.build_FMU(script, dest=folder))


def _binary(folder: str) -> str:
    md = fmpy.read_model_description(folder)
    return os.path.join(os.path.abspath(os.path.join(folder, "binaries", fmpy.platform)),
                        md.coSimulation.modelIdentifier + fmpy.sharedLibraryExtension)


def _mapped(path: str) -> bool:
    with open("/proc/self/maps") as maps:
        return any(line.rstrip().endswith(path) for line in maps)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="pythonfmu's exported release is its Linux binary's")
def test_the_release_finds_a_loaded_pythonfmu_binary_and_loads_none(tiny_fmu, tmp_path):
    """The installed pythonfmu's binary exports the function the release calls (were it renamed, the release
    would silently do nothing); a binary found by its path is one already loaded, never loaded by the release."""
    from fmpy.fmi2 import FMU2Slave

    from mace_fmu.fmu.host import release_pythonfmu_state

    folder = fmpy.extract(tiny_fmu, unzipdir=str(tmp_path / "unzipped"))
    binary = _binary(folder)
    assert not release_pythonfmu_state(binary) and not _mapped(binary)
    md = fmpy.read_model_description(folder)
    # loaded, not instantiated: the wrapper's static stays empty, so nothing of it is left for exit
    slave = FMU2Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier)
    assert _mapped(binary)
    assert release_pythonfmu_state(slave.dll) and release_pythonfmu_state(binary)
    assert not release_pythonfmu_state(ctypes.CDLL(ctypes.util.find_library("m")))  # any other binary: no


def _fmu_binary_errors(log: str) -> list[str]:
    """valgrind's invalid-access and mismatched-free reports whose stacks pass through an FMU's binary."""
    records = re.split(r"\n==\d+== \n", log)
    return [r for r in records if re.search(r"==\d+== (Invalid|Mismatched)", r) and "/binaries/linux64/" in r]


@pytest.mark.slow  # python with numpy under valgrind: about 20 s a pattern
@pytest.mark.skipif(shutil.which("valgrind") is None, reason="needs valgrind")
@pytest.mark.parametrize("pattern", ["update", "simulate"])
def test_a_host_that_ran_a_pythonfmu_fmu_exits_without_touching_freed_memory(tiny_fmu, tmp_path, pattern):
    """update: a Dask worker's instance (two runs, fmi2Reset between); simulate: fmpy.simulate_fmu as
    mace_fmu.fmu.simulate runs it. The host exits normally; memcheck sees every access of the exit handlers.
    PYTHONMALLOC=malloc: Python's own allocator would hide its blocks from memcheck."""
    log = tmp_path / "valgrind.log"
    env = {**os.environ, "PYTHONMALLOC": "malloc",
           "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    done = subprocess.run(["valgrind", "--tool=memcheck", "--error-limit=no", f"--log-file={log}", sys.executable,
                           str(HOST), tiny_fmu, pattern], capture_output=True, text=True, env=env, timeout=900,
                          cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    runs = json.loads(done.stdout.strip().splitlines()[-1])
    # y at t_k is 2 u held over the step before it (u_k = 1 + k), 0 at the start: every run from rest
    assert runs and all(y == [0.0, 2.0, 4.0, 6.0, 8.0] for y in runs), runs
    errors = _fmu_binary_errors(log.read_text())
    assert not errors, "\n\n".join(errors)[:4000]
