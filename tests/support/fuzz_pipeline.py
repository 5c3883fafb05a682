"""By hand: mutated decks that read go through the whole modal analysis (0-g and 1-g, linear preload).

``python tests/support/fuzz_pipeline.py FIRST_SEED COUNT`` prints the outcome classes (a model whose 0-g
frequencies equal the bundled deck's, another valid model, a MaceError, or an exception class,
which would be a defect) and every non-model outcome. Seeds are those of tests/deck/test_deck_fuzz.py.
"""

from __future__ import annotations

import collections
import sys
import tempfile
import traceback
from pathlib import Path

import numpy as np
from deck_mutations import mutate

from mace_fmu.deck import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.structure.file import bundled_deck_path


def main(first: int, count: int) -> None:
    base = bundled_deck_path().read_bytes()
    nominal = compute_modes(configuration="0g").modes.frequencies_hz
    outcomes, notes = collections.Counter(), []
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "mutant.bdf"
        for seed in range(first, first + count):
            kinds, deck = mutate(base, seed=seed, rounds=1 + seed % 3)
            path.write_bytes(deck)
            try:
                parsed = read_deck(path)
            except MaceError:
                continue  # the reader's outcome; tests/deck/test_deck_fuzz.py checks those
            try:
                f = compute_modes(parsed, configuration="0g").modes.frequencies_hz
                compute_modes(parsed, configuration="1g", preload="linear")
                same = len(f) == len(nominal) and np.allclose(f, nominal, rtol=1e-6, atol=1e-3)
                outcomes["model, same 0-g modes" if same else "model, changed"] += 1
            except MaceError as exc:
                outcomes["MaceError"] += 1
                notes.append(f"{seed} {kinds}: {exc}")
            except Exception as exc:  # noqa: BLE001 - a defect: report it with its traceback
                outcomes[type(exc).__name__] += 1
                notes.append(f"{seed} {kinds}: {traceback.format_exc()}")
    print(dict(outcomes))
    print("\n".join(notes))


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]))
