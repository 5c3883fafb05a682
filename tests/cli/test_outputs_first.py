"""Every output a command writes, and the Dask scheduler it is sent to, are checked before the work.

Before: ``update fmu -o`` to a folder that cannot be made ended in a traceback after the update
(its results lost), ``update mace`` said so after 14 s of work, ``predict-0g -o`` and ``view --html``
gave tracebacks, and a ``--scheduler`` where another service listens gave a traceback (a 3 EiB
allocation) or hung. Each is now one line, exit 2, before anything is computed.

Tests run as root, where permission bits stop nothing: the unwritable path is one below a regular file
(or in /proc, where even root creates nothing).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import pytest
from support.cli import run_cli
from support.sockets import GARBAGE, SSH_GREETING, not_a_scheduler

import mace_fmu.cli as cli

#: generous: the checks take milliseconds; the work they come before took 5 s to minutes
QUICK_S = 10.0


def _leaves(parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()):
    """(command words, parser) of every command that runs (the leaves of the subcommand tree)."""
    subcommands = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subcommands:
        yield prefix, parser
    for action in subcommands:
        for name, sub in action.choices.items():
            yield from _leaves(sub, (*prefix, name))


@pytest.fixture
def no_work(monkeypatch) -> list[tuple[str, ...]]:
    """Every command's work replaced by a refusal that records it: a command that starts its work fails the test."""
    started: list[tuple[str, ...]] = []
    real = cli.build_parser

    def parser_of_commands_that_must_not_start() -> argparse.ArgumentParser:
        parser = real()
        for words, leaf in _leaves(parser):
            def refuse(args, words=words):
                started.append(words)
                raise AssertionError(f"mace-fmu {' '.join(words)} started its work")
            leaf.set_defaults(func=refuse)
        return parser

    monkeypatch.setattr(cli, "build_parser", parser_of_commands_that_must_not_start)
    return started


@pytest.fixture
def a_file(tmp_path) -> Path:
    """A regular file: no folder can be made below it, whoever asks."""
    path = tmp_path / "file.txt"
    path.write_text("a file, not a folder\n")
    return path


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


# -- the four cases above: no simulation, model or mode computed, one line at once ---------------------------

def _started(monkeypatch, *targets: str) -> list[str]:
    """Replace each ``module.function`` by a refusal that records the call."""
    calls: list[str] = []
    for target in targets:
        def refuse(*args, target=target, **kwargs):
            calls.append(target)
            raise AssertionError(f"{target} ran before the output was checked")
        monkeypatch.setattr(target, refuse)
    return calls


UNWRITABLE = {"below a file": lambda file, leaf: str(file / leaf),
              "in /proc": lambda file, leaf: f"/proc/mace-fmu-test/{leaf}"}


@pytest.fixture(params=list(UNWRITABLE))
def unwritable(request, a_file):
    if request.param == "in /proc" and not Path("/proc/self").is_dir():
        pytest.skip("needs Linux's /proc")
    return lambda leaf: UNWRITABLE[request.param](a_file, leaf)


@pytest.mark.parametrize("command, work", [
    (["update", "fmu", "{tmp}/model.fmu", "--data", "{tmp}/test.csv", "--update", "E_lexan_end", "-o", "{out}"],
     ["mace_fmu.updating.fmu.problem.fmu_problem", "mace_fmu.updating.fmu.update.update_fmu"]),
    (["update", "mace", "-o", "{out}"], ["mace_fmu.updating.mace.update.run_mace_update"]),
    (["predict-0g", "-o", "{out}"], ["mace_fmu.zero_g.nominal.predict_zero_g"]),
], ids=["update fmu", "update mace", "predict-0g"])
def test_an_output_folder_that_cannot_be_made_is_refused_before_the_work(capsys, monkeypatch, tmp_path, unwritable,
                                                                        command, work):
    calls = _started(monkeypatch, *work)
    out = unwritable("out")
    start = time.monotonic()
    code, stdout, err = run_cli(capsys, [w.format(tmp=tmp_path, out=out) for w in command])
    assert time.monotonic() - start < QUICK_S
    assert calls == [] and code == 2 and stdout == ""
    assert _one_line(err).startswith(f"mace-fmu: error: -o {out}: cannot create the folder (")


def test_a_page_that_cannot_be_written_is_refused_before_the_modes_are_computed(capsys, monkeypatch, unwritable):
    calls = _started(monkeypatch, "mace_fmu.fe.modes.compute_modes")
    page = unwritable("modes.html")
    start = time.monotonic()
    code, stdout, err = run_cli(capsys, ["view", "modes", "0g", "--html", page])
    assert time.monotonic() - start < QUICK_S
    assert calls == [] and code == 2 and stdout == ""
    line = _one_line(err)
    assert line.startswith(f"mace-fmu: error: --html {page}: ") and f" its folder {Path(page).parent}" in line, line


# -- every output of every command -----------------------------------------------------------------------------

#: every command's every output: its words with {out} where the output goes ({tmp}: a folder for the inputs, which
#: are never read: the check comes first), the option as messages name it, and whether it is a folder or a file
OUTPUTS = [
    (["build", "-o", "{out}"], "-o", "folder"),
    (["export", "0g", "-o", "{out}"], "-o", "folder"),
    (["export", "0g", "--ssp", "{out}.ssp"], "--ssp", "file"),
    (["export-controller", "--lqg", "-o", "{out}"], "-o", "folder"),
    (["model", "0g", "--npz", "{out}.npz"], "--npz", "file"),
    (["model", "0g", "--modelica", "{out}.mo"], "--modelica", "file"),
    (["report", "-o", "{out}"], "-o", "folder"),
    (["view", "modes", "0g", "--html", "{out}.html"], "--html", "file"),
    (["view", "modes", "0g", "--png", "{out}.png"], "--png", "file"),
    (["view", "pairs", "--html", "{out}.html"], "--html", "file"),
    (["view", "pairs", "--png", "{out}.png"], "--png", "file"),
    (["view", "response", "0g", "--input", "rwa_z", "--html", "{out}.html"], "--html", "file"),
    (["view", "response", "0g", "--input", "rwa_z", "--png", "{out}.png"], "--png", "file"),
    (["update", "mace", "-o", "{out}"], "-o", "folder"),
    (["update", "modal", "--deck", "{tmp}/d.bdf", "--modes", "{tmp}/m.toml", "--update", "E", "-o", "{out}"], "-o",
     "folder"),
    (["ema", "{tmp}/f.csv", "-o", "{out}"], "-o", "folder"),
    (["correlate", "--deck", "{tmp}/d.bdf", "--modes", "{tmp}/m.toml", "-o", "{out}"], "-o", "folder"),
    (["update", "fmu", "{tmp}/m.fmu", "--data", "{tmp}/d.csv", "--update", "E", "-o", "{out}"], "-o", "folder"),
    (["plan-test", "{tmp}/m.fmu", "--tests", "{tmp}/plan.toml", "--update", "E", "-o", "{out}.toml"], "-o", "file"),
    (["predict-0g", "-o", "{out}"], "-o", "folder"),
    (["study", "lqg-sensitivity", "--out", "{out}"], "--out", "folder"),
    (["study", "reduced-order", "--out", "{out}"], "--out", "folder"),
    (["study", "robust-0g", "-o", "{out}"], "-o", "folder"),
    (["data", "h1", "{tmp}/t.csv", "--segment", "64", "-o", "{out}.csv"], "-o", "file"),
    (["params", "to-ssv", "{tmp}/p.toml", "-o", "{out}.ssv"], "-o", "file"),
    (["params", "from-ssv", "{tmp}/p.ssv", "-o", "{out}.toml"], "-o", "file"),
    (["params", "from-ssv", "{tmp}/p.ssv", "--frequency-bounds-out", "{out}.toml"], "--frequency-bounds-out", "file"),
]


def _case_id(words: list[str], option: str) -> str:
    """"view modes --html": the command words (up to the first option or input) and the output's option."""
    command = []
    for word in words:
        if word.startswith(("-", "{")):
            break
        command += [word] if word not in ("0g", "1g") else []
    return " ".join([*command, option])


@pytest.mark.parametrize("words, option, kind", OUTPUTS, ids=[_case_id(w, o) for w, o, _ in OUTPUTS])
def test_every_output_is_checked_before_any_work(capsys, tmp_path, a_file, no_work, words, option, kind):
    out = str(a_file / "out")
    argv = [w.format(tmp=tmp_path, out=out) for w in words]
    path = argv[argv.index(option) + 1]
    code, stdout, err = run_cli(capsys, argv)
    assert no_work == [] and code == 2 and stdout == ""
    why = f"cannot create the folder ({a_file} is a file)" if kind == "folder" else f"its folder {a_file} is a file"
    assert _one_line(err) == f"mace-fmu: error: {option} {path}: {why}"


def test_an_output_named_by_default_after_the_input_is_checked_too(capsys, a_file, no_work):
    """params to-ssv P.toml writes P.ssv beside it when -o is not given."""
    code, _, err = run_cli(capsys, ["params", "to-ssv", str(a_file / "p.toml")])
    assert no_work == [] and code == 2
    assert _one_line(err) == f"mace-fmu: error: -o {a_file / 'p.ssv'}: its folder {a_file} is a file"


def test_an_output_a_command_does_not_write_with_its_options_is_not_checked(capsys, tmp_path, a_file, no_work):
    """export --ssp writes the package, not the -o folder; study robust-0g --serial uses no scheduler."""
    with pytest.raises(AssertionError, match="mace-fmu export started its work"):
        cli.main(["export", "0g", "-o", str(a_file / "out"), "--ssp", str(tmp_path / "plant.ssp")])
    with pytest.raises(AssertionError, match="mace-fmu study robust-0g started its work"):
        cli.main(["study", "robust-0g", "-o", str(tmp_path), "--serial", "--scheduler", "tcp://127.0.0.1:9"])


#: options whose names say output but which name an input: a signal of view response, a controller's arrays
INPUTS_NAMED_LIKE_OUTPUTS = {(("view", "response"), "output"), (("export-controller",), "npz")}


def test_every_output_option_is_declared_and_each_is_tested_above():
    """Each command's outputs are the options declared as outputs; each of them has a case in OUTPUTS. An output
    option added with add_argument instead of output_option, or without a case above, fails here."""
    from mace_fmu.cli.preflight import CHECKS, OutputCheck, SchedulerCheck

    declared = set()
    for words, leaf in _leaves(cli.build_parser()):
        for check in leaf.get_default(CHECKS) or ():
            if isinstance(check, OutputCheck):
                declared.add((" ".join(words), check.option, check.kind))
            else:
                assert isinstance(check, SchedulerCheck)
        names = {a.dest for a in leaf._actions}
        for dest in ("out", "output", "html", "png", "npz", "modelica", "ssp", "frequency_bounds_out"):
            if dest in names and (words, dest) not in INPUTS_NAMED_LIKE_OUTPUTS:
                assert any(getattr(c, "dest", None) == dest for c in leaf.get_default(CHECKS) or ()), (words, dest)
    tested = {(_command_of(words), option, kind) for words, option, kind in OUTPUTS}
    assert tested == declared


def _command_of(words: list[str]) -> str:
    """The command words at the start of an argv (up to the first argument that is no subcommand)."""
    commands = {" ".join(c) for c, _ in _leaves(cli.build_parser())}
    for n in range(len(words), 0, -1):
        if " ".join(words[:n]) in commands:
            return " ".join(words[:n])
    raise AssertionError(f"no command in {words}")


# -- a --scheduler where no Dask scheduler answers ---------------------------------------------------------------

SCHEDULER_COMMANDS = {
    "update fmu": ["update", "fmu", "{tmp}/m.fmu", "--data", "{tmp}/d.csv", "--update", "E", "-o", "{tmp}/out"],
    "plan-test": ["plan-test", "{tmp}/m.fmu", "--tests", "{tmp}/plan.toml", "--update", "E"],
    "study robust-0g": ["study", "robust-0g", "-o", "{tmp}/out", "--bound", "17=2.5"],
}


#: (command, what listens, why): what speaks first, for every command; silence, which takes the timeout, for one
SCHEDULER_CASES = [(command, greeting, why) for command in SCHEDULER_COMMANDS for greeting, why in (
    (SSH_GREETING, "what answered does not speak Dask's protocol: MemoryError"),  # was Dask's 2.8 EiB allocation
    (GARBAGE, "what answered does not speak Dask's protocol: ValueError"))] + [
    ("update fmu", b"", "no answer in Dask's protocol within 2 s")]  # was a hang, whatever Client's timeout said


@pytest.mark.parametrize("command, greeting, why", SCHEDULER_CASES,
                         ids=[f"{c}-{'silence' if not g else 'SSH' if g == SSH_GREETING else 'garbage'}"
                              for c, g, _ in SCHEDULER_CASES])
def test_a_scheduler_address_where_another_service_listens_is_one_line_before_the_work(capsys, tmp_path, no_work,
                                                                                      command, greeting, why):
    argv = [w.format(tmp=tmp_path) for w in SCHEDULER_COMMANDS[command]]
    with not_a_scheduler(greeting) as address:
        start = time.monotonic()
        code, stdout, err = run_cli(capsys, [*argv, "--scheduler", address, "--scheduler-timeout", "1"])
        assert time.monotonic() - start < 1.0 + QUICK_S
    assert no_work == [] and code == 2 and stdout == ""
    assert _one_line(err) == f"mace-fmu: error: --scheduler {address}: no Dask scheduler answered ({why})"
    assert not (tmp_path / "out").exists()


def test_the_scheduler_timeout_is_in_every_scheduler_commands_help(capsys):
    for words in (["update", "fmu"], ["plan-test"], ["study", "robust-0g"]):
        with pytest.raises(SystemExit):
            cli.main([*words, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert "--scheduler-timeout S how long --scheduler is given to answer as a Dask scheduler [s] (default 20)" \
            in text, text
