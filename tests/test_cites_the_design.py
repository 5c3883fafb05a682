"""Code, tests and documentation cite the design (what the code does and why), never a tracker's issue number:
the number means nothing to a reader without the tracker, and the design is what a change must keep."""

from __future__ import annotations

import re

from support.paths import ROOT

#: "issue 51", "Issue 23 section 4", "(issue: 1 %)"; another project's bug is cited as theirs, "pythonfmu issue #229"
CITATION = re.compile(r"\bissues? ?(?:\d+|:)", re.IGNORECASE)
WHERE = ("mace_fmu", "tests", "docs", "examples")
SUFFIXES = {".py", ".md", ".toml", ".rst", ".txt", ".c", ".h", ".js", ".ipynb"}


def test_no_file_cites_an_issue_number():
    files = [ROOT / "README.md", ROOT / "CONTRIBUTING.md"]
    for top in WHERE:
        files += [p for p in sorted((ROOT / top).rglob("*")) if p.suffix in SUFFIXES and "_build" not in p.parts
                  and p.is_file()]
    found = [f"{p.relative_to(ROOT)}:{n}" for p in files
             for n, line in enumerate(p.read_text(encoding="utf-8", errors="replace").splitlines(), start=1)
             if CITATION.search(line) and p != ROOT / "tests" / "test_cites_the_design.py"]
    assert found == []
