"""Seeded fuzz test: the bundled deck broken in thousands of ways reads as a model or fails with a located DeckError.

Every mutated deck (tests/support/deck_mutations.py: lines deleted, duplicated, swapped or truncated, fields
swapped or blanked, characters injected, numbers changed in value, sign or type) must either read
and give both structures, or raise a DeckError that names the file and a line of it. Any other
exception is a defect. A few of each kind also go through the command line (status 2, one line)
and through the whole 0-g modal analysis.
"""

from __future__ import annotations

import collections
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from support.deck_mutations import MUTATIONS, mutate
from support.paths import DOCS

from mace_fmu.cli import main
from mace_fmu.deck import DeckError, read_deck
from mace_fmu.structure.build import build_structure
from mace_fmu.structure.file import bundled_deck_path

pytestmark = pytest.mark.slow  # thousands of mutated decks

SEEDS = range(2000)


def _outcome(path: Path) -> tuple[str, DeckError | None]:
    """'valid' (read, and both structures built) or 'DeckError'; anything else propagates."""
    try:
        deck = read_deck(path)
        for kind in ("1g", "0g"):
            build_structure(deck, configuration=kind)
    except DeckError as exc:
        return "DeckError", exc
    return "valid", None


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory: pytest.TempPathFactory) -> dict[int, tuple[str, str, Path]]:
    """seed -> (mutations applied, outcome class, path of the mutated deck), for every seed."""
    folder = tmp_path_factory.mktemp("fuzz")
    base = bundled_deck_path().read_bytes()
    results = {}
    for seed in SEEDS:
        kinds, deck = mutate(base, seed=seed, rounds=1 + seed % 3)
        path = folder / f"mutant_{seed}.bdf"
        path.write_bytes(deck)
        outcome, error = _outcome(path)
        if error is not None:
            message = str(error)
            assert error.file == str(path) and error.line >= 1, f"seed {seed} ({kinds}): {message}"
            assert message.startswith(f"{path}:{error.line}: ") and "\n" not in message, message
            assert len(error.message) > 15, message  # says what was expected, not just "bad"
            if error.line > 0:
                n_lines = deck.count(b"\n") + 1
                assert error.line <= n_lines, f"seed {seed}: line {error.line} of {n_lines}: {message}"
        results[seed] = (kinds, outcome, path)
    return results


def test_every_mutant_is_a_model_or_a_located_deck_error(outcomes) -> None:
    classes = collections.Counter(outcome for _, outcome, _ in outcomes.values())
    assert sum(classes.values()) == len(SEEDS)
    assert set(classes) == {"valid", "DeckError"}
    # The mutator must exercise both outcomes, or the test says little.
    assert classes["valid"] >= 0.05 * len(SEEDS) and classes["DeckError"] >= 0.5 * len(SEEDS), classes
    used = collections.Counter(k for kinds, _, _ in outcomes.values() for k in kinds.split("+"))
    assert set(used) == set(MUTATIONS)


def test_the_outcome_counts_the_reference_page_gives_are_these_runs(outcomes) -> None:
    """docs/reference/tests_and_benchmarks.md gives the split of the 2000 mutants: held to this run's, which
    the seeds fix (a change of the reader that moves one mutant from one class to the other changes them)."""
    page = " ".join((DOCS / "reference" / "tests_and_benchmarks.md").read_text().split())
    stated = re.search(r"mutated (\d+) ways .* reads as a model \((\d+)\) or fails with a DeckError naming a line "
                       r"\((\d+)\)", page)
    assert stated is not None, "the page no longer gives the split"
    classes = collections.Counter(outcome for _, outcome, _ in outcomes.values())
    assert tuple(map(int, stated.groups())) == (len(SEEDS), classes["valid"], classes["DeckError"]), classes


def test_deck_errors_end_the_command_line_with_status_2(outcomes, capsys: pytest.CaptureFixture[str]) -> None:
    broken = [(seed, path) for seed, (_, outcome, path) in outcomes.items() if outcome == "DeckError"][:40]
    for seed, path in broken:
        assert main(["modes", "0g", "--deck", str(path)]) == 2, seed
        err = capsys.readouterr().err
        assert err.startswith(f"mace-fmu: error: {path}:") and err.count("\n") == 1, err


def test_deck_error_exit_status_of_the_installed_command(outcomes) -> None:
    seed, path = next((s, p) for s, (_, outcome, p) in outcomes.items() if outcome == "DeckError")
    run = subprocess.run([sys.executable, "-m", "mace_fmu.cli", "modes", "0g", "--deck", str(path)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 2, run.stderr
    assert run.stderr.startswith(f"mace-fmu: error: {path}:") and "Traceback" not in run.stderr


def test_valid_mutants_give_modes(outcomes) -> None:
    """The first few mutants that read go through the whole 0-g analysis: finite frequencies or a MaceError."""
    from mace_fmu.errors import MaceError
    from mace_fmu.fe.modes import compute_modes

    valid = [path for _, outcome, path in outcomes.values() if outcome == "valid"][:6]
    assert len(valid) == 6
    for path in valid:
        try:
            modes = compute_modes(path, configuration="0g")
        except MaceError as exc:  # e.g. a mechanism the mutation freed: a modelling error, stated
            assert str(exc)
            continue
        assert modes.frequencies_hz.size > 0 and np.all(np.isfinite(modes.frequencies_hz))
