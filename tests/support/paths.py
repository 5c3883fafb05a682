"""Where things are, for tests in any folder of tests/ (they are laid out like the package)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]  #: the repository
TESTS = ROOT / "tests"
SUPPORT = TESTS / "support"  #: helper programs and C hosts the tests build
DATA = TESTS / "data"  #: test data (public NASTRAN decks with their results, recorded outputs)
EXAMPLES = ROOT / "examples"
DOCS = ROOT / "docs"
