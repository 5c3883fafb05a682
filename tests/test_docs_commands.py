"""Every ``mace-fmu`` command the README and the documentation pages show is one the parser accepts.

The commands are taken from the fenced ``bash`` and ``console`` blocks (and from inline code in the
README's table of commands) and from the tutorials, the gallery's examples (their docstrings' command lines); each is parsed by ``mace_fmu.cli.build_parser()`` exactly as the shell
would pass it, so a renamed option or subcommand fails here. Running them is left to the tests of each
command (most need minutes or files a user brings); this checks that the text is still true.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
from support.paths import ROOT
from support.printed import NUMBER, printed_in, unit_of_last_digit

#: pages the docs build writes from the code (listed in docs/.gitignore): left out, so that the tests are the
#: same before and after a build (CI runs the suite before the docs build; they added 5 tests after it)
GENERATED = {ROOT / "docs" / line.strip().rstrip("/")
             for line in (ROOT / "docs" / ".gitignore").read_text().splitlines() if line.strip() and line[0] != "#"}
PAGES = [ROOT / "README.md", *sorted(p for p in (ROOT / "docs").rglob("*.md")
                                     if not any(p == g or g in p.parents for g in GENERATED))]


def _commands(path: Path) -> list[tuple[str, str]]:
    """(where, command) for each ``mace-fmu`` command of a page's shell blocks and README table cells."""
    found, block = [], None
    lines = path.read_text().replace("\\\n", " ").splitlines()  # shell line continuations
    for number, line in enumerate(lines, start=1):
        if line.startswith("```"):
            block = line[3:].strip() if block is None else None
            continue
        text = line
        if block in ("bash", "console", "sh", "shell"):
            text = re.sub(r"^\$ ", "", line)
        elif block is None and path.name == "README.md" and line.startswith("|"):
            text = " ".join(re.findall(r"`(mace-fmu [^`]*)`", line))
        else:
            continue
        for part in re.split(r"&&|\|\||;", text.split(" #")[0]):
            part = part.strip()
            if part.startswith("mace-fmu "):
                found.append((f"{path.relative_to(ROOT)}:{number}", part))
    return found


#: the tutorials: the gallery's examples (their docstrings are the tutorial pages' text) and its header
EXAMPLES = sorted((ROOT / "examples").rglob("*.py")) + [ROOT / "examples" / "GALLERY_HEADER.rst"]


def _example_commands(path: Path) -> list[tuple[str, str]]:
    """(where, command) for each whole ``mace-fmu`` command of an example: an indented command line of its
    docstring or comments, or an inline literal (````mace-fmu ...````); fragments with ``...`` are left out."""
    found = []
    lines = path.read_text().splitlines()
    for number, line in enumerate(lines, start=1):
        while line.rstrip().endswith("\\") and number < len(lines):  # a shell continuation ("\\" in a docstring)
            line = line.rstrip().rstrip("\\").rstrip() + " " + lines[number].strip()
            lines[number] = ""
            number += 1
        shown = re.findall(r"``(mace-fmu [^`]*)``", line)
        bare = line.strip().lstrip("# ")
        if not shown and bare.startswith("mace-fmu ") and line.startswith(" "):
            shown = [bare]
        for command in shown:
            command = command.split(" #")[0].strip()
            if "..." not in command:
                found.append((f"{path.relative_to(ROOT)}:{number}", command))
    return found


COMMANDS = [c for page in PAGES for c in _commands(page)] + [c for path in EXAMPLES for c in _example_commands(path)]


def test_the_pages_show_commands():
    assert len(COMMANDS) >= 40
    assert {where.split(":")[0] for where, _ in COMMANDS} >= {"README.md", "docs/guide/fmus.md",
                                                               "docs/howto/animate_a_response.md",
                                                               "examples/own_structure/own_structure.py"}


@pytest.mark.parametrize("where, command", COMMANDS, ids=[w for w, _ in COMMANDS])
def test_every_shown_command_parses(where, command):
    from mace_fmu.cli import build_parser

    # usage-style optional parts ("[--json]") are checked as given
    argv = [a.strip("[]") for a in shlex.split(command)[1:] if a not in (">", "2>")]
    argv = [a for a in argv if not re.match(r"^[0-9]?>", a)]  # redirections
    try:
        build_parser().parse_args(argv)
    except SystemExit as exc:
        if exc.code != 0:  # --help exits 0
            pytest.fail(f"{where}: `{command}` is not a valid command line")


def test_the_api_reference_covers_every_package():
    """docs/_ext/generated.py writes one API page per name of its PACKAGES (the data-flow order): a new
    package must be added there, or the reference would silently leave it out."""
    import importlib.util
    import pkgutil

    import mace_fmu

    spec = importlib.util.spec_from_file_location("docs_generated", ROOT / "docs" / "_ext" / "generated.py")
    generated = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generated)
    found = {"mace_fmu"} | {m.name for m in pkgutil.walk_packages(mace_fmu.__path__, "mace_fmu.") if m.ispkg}
    assert sorted(generated.PACKAGES) == sorted(found)
    assert len(set(generated.PACKAGES)) == len(generated.PACKAGES)


def test_readme_headline_numbers_are_on_the_pages_it_links():
    """Each headline number of the README appears on the page its bullet links to (where it is measured)."""
    readme = (ROOT / "README.md").read_text()
    section = readme[readme.index("## Headline numbers"):readme.index("\n## ", readme.index("## Headline numbers") + 1)]
    checked = 0
    for bullet in re.split(r"\n- ", section)[1:]:
        numbers = [a or b for a, b in re.findall(r"(\d+(?:\.\d+)?) ?%|(\d(?:\.\d+)?e-\d+)", bullet)]
        pages = re.findall(r"\]\(((?:docs|benchmarks)/[^)#]+)\)", bullet)
        text = "".join((ROOT / page).read_text() for page in pages)
        on_pages = [float(n) for n in NUMBER.findall(text)]
        for number in numbers:  # as a number, within the README's last printed digit
            assert any(abs(float(number) - n) <= unit_of_last_digit(number) for n in on_pages), \
                f"README headline {number!r} is not on {pages}"
            checked += 1
    assert checked >= 12


@pytest.mark.slow
def test_the_first_model_notebook_runs_and_its_jupytext_pair_agrees(tmp_path):
    """docs/getting_started/first_model.py (a script in cells) runs, its FMU equals the exact zero-order hold,
    and first_model.ipynb holds the same cells (jupytext pairing: people who work in notebooks start there)."""
    import subprocess
    import sys

    import jupytext

    script = ROOT / "docs" / "getting_started" / "first_model.py"
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert printed_in("2.100 Hz  1st Z bending", run.stdout)
    difference = float(re.search(r"exact zero-order hold: ([0-9.e+-]+) of", run.stdout).group(1))
    assert difference <= 1e-10
    cells = [(c.cell_type, c.source) for c in jupytext.read(script).cells]
    paired = [(c.cell_type, c.source) for c in jupytext.read(script.with_suffix(".ipynb")).cells]
    assert cells == paired, "run: jupytext --sync docs/getting_started/first_model.py"


@pytest.mark.slow
def test_the_uff_how_to_runs_on_the_example_s_own_files(tmp_path):
    """docs/howto/read_a_uff_file.md's commands, run as shown in an empty folder: the example writes its files, the
    MACE 1-g FMU is exported and updated on the example's UFF 58 file, whose six-digit frequencies the update puts
    back on the analyser's grid, as the page says it does (about 1 min on 2 cores)."""
    import os
    import subprocess
    import sys

    page = (ROOT / "docs" / "howto" / "read_a_uff_file.md").read_text()
    block = page[page.index("```console"):page.index("```", page.index("```console") + 3)]
    commands = [shlex.split(line[2:]) for line in block.splitlines() if line.startswith("$ ")]
    assert [c[0] for c in commands] == ["python", "mace-fmu", "mace-fmu"]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    for argv in commands:
        one_worker = ["--workers", "1"] if argv[1] == "update" else []  # the machine's other users keep a core
        argv = ([sys.executable, str(ROOT / argv[1]), *argv[2:]] if argv[0] == "python"
                else [sys.executable, "-m", "mace_fmu.cli", *argv[1:], *one_worker])
        run = subprocess.run(argv, capture_output=True, text=True, timeout=900, cwd=tmp_path, env=env, check=False)
        assert run.returncode == 0, f"{' '.join(argv)}: {run.stderr[-2000:]}"
    said = re.search(r"`(data/run_h1\.uff: .* put on the grid .*)`", page).group(1)
    assert printed_in(said, run.stderr), run.stderr[-2000:]
    assert (tmp_path / "updated" / "parameters.toml").is_file()
