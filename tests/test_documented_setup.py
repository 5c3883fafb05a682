"""What the README and the pages say a user needs, and the figures they give of the tests, are the project's.

The set-up a new user reads (the README's first lines, "Getting started") is checked against what the project
declares (``requires-python``, the dependency that compiles the native FMUs); the figures the pages give of
the test suite are either read from the tests themselves (the broken decks) or not given (a test count and a
run time change with every test added and every machine: their dated measurements are kept in
``benchmarks/RESULTS.md``).
"""

from __future__ import annotations

import importlib.util
import re
import tomllib

import pytest
from support.paths import DOCS, ROOT, TESTS

#: pages a user or contributor reads (the site includes CONTRIBUTING.md as its contributor guide)
PAGES = [ROOT / "README.md", ROOT / "CONTRIBUTING.md",
         *sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts)]


def _python_floor() -> str:
    """The lowest Python the package installs on, from ``requires-python = ">=3.11"``."""
    spec = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["requires-python"]
    (floor,) = re.fullmatch(r">=\s*(\d+\.\d+)", spec.strip()).groups()
    return floor


def test_the_readme_opens_with_its_two_commands_then_says_which_python_and_a_venv():
    """The README's first lines stay the two set-up commands (install and the main job; the tests); the Python
    version and the virtual environment are a note below them, not a third command."""
    readme = (ROOT / "README.md").read_text()
    first = readme.index("```bash\n") + len("```bash\n")
    block = readme[first:readme.index("```", first)]
    commands = [line.split("  #")[0].strip() for line in block.splitlines() if line.strip()]
    assert commands == ['pip install -e ".[test]" && mace-fmu build', "python -m pytest -q -n auto"], commands
    note = readme[readme.index("```", first) + 3:].lstrip().split("\n\n")[0]
    assert f"Python {_python_floor()} or later" in note, note
    assert "-m venv .venv" in note and ". .venv/bin/activate" in note, note


def test_getting_started_names_the_same_python_and_what_compiles_the_native_fmus():
    """The page said the native FMUs need gcc: zig compiles them (the ``ziglang`` dependency), so a machine
    without a C compiler exports them."""
    from mace_fmu.fmu.native.compile import build_command
    from mace_fmu.fmu.native.platforms import PLATFORMS

    page = (DOCS / "getting_started" / "index.md").read_text()
    needs = page[page.index("On a fresh machine"):page.index("```")]
    assert f"Python {_python_floor()} or later" in needs and "-m venv" in needs, needs
    compiler = build_command(PLATFORMS[0], ("mace_model.c",))[0]
    assert compiler == "zig" and "compiled by zig" in needs and "gcc" not in needs, needs
    dependencies = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    assert any(d.startswith("ziglang") for d in dependencies)


def test_the_data_files_page_states_the_unit_rule_the_update_enforces():
    """Data are in the FMU's units (a force input in N, an accelerometer in m/s^2), not volts always: the
    page said "the unit must be V"."""
    from mace_fmu.errors import MaceError
    from mace_fmu.updating.fmu.model import FmuInterface

    interface = FmuInterface(path="frame.fmu", guid="", model_identifier="frame", generation_tool="",
                             inputs=("force_floor_1",), outputs=("acc_floor_1",), parameters={}, references={},
                             units={"force_floor_1": "N", "acc_floor_1": "m/s^2"})
    interface.check_signals(inputs=["force_floor_1"], outputs=["acc_floor_1"], where="test.csv",
                            units={"force_floor_1": "N", "acc_floor_1": "m/s^2"})
    with pytest.raises(MaceError, match="the data must be in the FMU's units"):
        interface.check_signals(inputs=["force_floor_1"], outputs=[], where="test.csv", units={"force_floor_1": "V"})
    page = " ".join((DOCS / "reference" / "data_files.md").read_text().split())
    assert "Data are in the model's units at its boundary, the units the FMU declares" in page
    assert not re.search(r"unit must be V\b|must be in volts", page), "the page still asks for volts"


def test_no_page_gives_a_test_count_or_the_suites_run_time():
    """"1067 passed, 5 skipped", "runs in 8 min 30 s", "53 s": true on one day on one machine."""
    for page in PAGES:
        text = page.read_text()
        for pattern in (r"\d+ passed", r"\d+ skipped", r"(suite|pytest[^`\n]*`|quick loop)[^.\n]* runs in \d",
                        r"not slow\"[^\n]*\(\d+ s"):
            found = re.search(pattern, text)
            assert found is None, f"{page.relative_to(ROOT)}: {found.group(0)!r}"


def test_the_broken_deck_count_the_pages_give_is_the_tests():
    spec = importlib.util.spec_from_file_location("deck_errors", TESTS / "deck" / "test_deck_errors.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    stated = {page.relative_to(ROOT): int(n) for page in PAGES
              for n in re.findall(r"(\d+) broken decks", page.read_text())}
    assert len(stated) >= 2, stated  # the contributor guide and the tests' reference page
    assert set(stated.values()) == {len(module.BROKEN)}, stated
