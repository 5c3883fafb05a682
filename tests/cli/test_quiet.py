"""A library does not print, and leaves no temporary folders behind."""

from __future__ import annotations

import tempfile

import pytest
from support.paths import EXAMPLES

from mace_fmu.errors import MaceError


@pytest.fixture
def private_tmp(tmp_path, monkeypatch):
    """A fresh temporary-files folder for this process and its children (TMPDIR)."""
    folder = tmp_path / "tmp"
    folder.mkdir()
    monkeypatch.setenv("TMPDIR", str(folder))
    monkeypatch.setattr(tempfile, "tempdir", None)  # re-read TMPDIR
    return folder


@pytest.mark.parametrize("in_subprocess", [True, False])
def test_simulation_removes_its_unpacked_fmu_even_when_the_fmu_fails(motion_fmu_0g, private_tmp, in_subprocess):
    from mace_fmu.fmu.simulate import simulate_input_response

    _, fmu, _ = motion_fmu_0g
    run = simulate_input_response(fmu, input_name="rwa_z", signal="impulse", duration_s=0.01,
                                  outputs=["tach_z"], in_subprocess=in_subprocess)
    assert run.outputs["tach_z"].shape == (6,)
    assert list(private_tmp.iterdir()) == []
    with pytest.raises(Exception) as failure:  # a NaN input ends the FMU's step with fmi2Error
        simulate_input_response(fmu, input_name="rwa_z", signal="step", amplitude_v=float("nan"), duration_s=0.01,
                                outputs=["tach_z"], in_subprocess=in_subprocess)
    assert not in_subprocess or isinstance(failure.value, MaceError)
    assert list(private_tmp.iterdir()) == []


def test_compute_modes_reports_progress_only_to_its_callback_and_the_log(capfd, caplog):
    """From Python nothing reaches stdout or stderr; the 20 preload increments go to the callback and the log."""
    import logging

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.util.progress import Step

    steps: list[Step] = []
    with caplog.at_level(logging.DEBUG, logger="mace_fmu"):
        compute_modes(configuration="1g", max_hz=3.0, progress=steps.append)
        compute_modes(configuration="1g", max_hz=3.0)
    assert capfd.readouterr() == ("", "")
    assert [(s.task, s.done, s.total) for s in steps] == [("gravity preload", k, 20) for k in range(1, 21)]
    assert "work ratio" in steps[-1].detail
    increments = [r for r in caplog.records if r.name == "mace_fmu.fe.preload"]
    assert len(increments) == 40 and all(r.levelno == logging.DEBUG for r in increments)


class _Terminal:
    """A text stream that says it is a terminal (tqdm draws only on terminals)."""

    def __init__(self):
        self.parts: list[str] = []

    def write(self, text: str) -> int:
        self.parts.append(text)
        return len(text)

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return True


def test_cli_shows_one_progress_bar_on_a_terminal_and_nothing_in_a_pipe(monkeypatch, capsys):
    import sys

    from mace_fmu.cli import main

    assert main(["modes", "1g", "--max-hz", "3"]) == 0
    out, err = capsys.readouterr()
    assert err == "" and "1st Z bending" in out  # stderr is not a terminal here: no bar, no lines
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    assert main(["modes", "1g", "--max-hz", "3"]) == 0
    drawn = "".join(terminal.parts)
    frames = [f for f in drawn.split("\r") if f.strip()]
    assert frames and all(f.startswith("gravity preload:") for f in frames)  # one bar, redrawn in place
    assert "20/20" in frames[-1] and "\n" not in drawn  # and cleared when done (leave=False)


def test_stage_lines_are_written_once_per_stage_in_a_pipe_too(capsys):
    """progress_bar(task_lines=True), as predict-0g and update mace use it: a log shows which stage a long run is
    in (one line as each stage begins, none per step), and no bar where stderr is no terminal."""
    from mace_fmu.cli.common import progress_bar
    from mace_fmu.util.progress import Step, begin_stage

    with progress_bar(task_lines=True) as bar:
        begin_stage(bar, "first stage", number=1, stages=2)
        for k in range(5):
            bar(Step("cost sensitivities", k + 1, 5, detail=f"E_{k}"))
        begin_stage(bar, "second stage", number=2, stages=2)
    out, err = capsys.readouterr()
    assert out == "" and err == "  first stage\n  cost sensitivities\n  second stage\n"


@pytest.mark.slow
def test_examples_are_quiet_and_leave_no_unpacked_fmu(motion_fmu_0g, private_tmp):
    """libcosim's FMI Library debug lines only with --verbose; cosimulate removes its unpacked FMU."""
    import os
    import subprocess
    import sys

    _, fmu, _ = motion_fmu_0g
    examples = EXAMPLES
    env = {**os.environ, "TMPDIR": str(private_tmp)}
    libcosim = subprocess.run([sys.executable, str(examples / "libcosim_import.py"), str(fmu)], env=env,
                              capture_output=True, text=True, timeout=300, check=True)
    lines = libcosim.stdout.splitlines()
    assert len(lines) == 20 and all(line.startswith("t = ") for line in lines), libcosim.stdout[:500]
    assert libcosim.stderr == ""
    cosim = subprocess.run([sys.executable, str(examples / "cosimulate.py"), str(fmu)], env=env,
                           capture_output=True, text=True, timeout=300, check=True)
    assert cosim.stdout.count("payload Z gyro RMS") == 2 and cosim.stderr == ""
    assert list(private_tmp.iterdir()) == []


def test_the_measurement_model_fit_draws_no_dependency_bar(capfd):
    """sdypy-EMA's pole selection draws a tqdm bar of its own; the sample problem's fit must not let it out
    (it reached redirected stderr as `0%| | 0/30 ... 100%| 30/30`)."""
    from mace_fmu.updating.sample.problem import generate_data

    data = generate_data()
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    assert len(data.measurement_model.frequencies_hz) == 2
