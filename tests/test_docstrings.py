"""The examples in the public API's docstrings run and print what they say (doctest)."""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import mace_fmu

PACKAGES = ["mace_fmu"] + [m.name for m in pkgutil.walk_packages(mace_fmu.__path__, "mace_fmu.") if m.ispkg]
EXAMPLES = sorted({f"{name}.{public}" for name in PACKAGES for public in importlib.import_module(name).__all__
                   if ">>>" in (getattr(importlib.import_module(name), public).__doc__ or "")})


def test_the_api_shows_examples():
    assert {"mace_fmu.compute_modes", "mace_fmu.volts_model"} <= set(EXAMPLES)


def test_every_docstring_example_runs():
    failures = []
    for dotted in EXAMPLES:
        package, public = dotted.rsplit(".", 1)
        obj = getattr(importlib.import_module(package), public)
        finder, runner = doctest.DocTestFinder(), doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
        for test in finder.find(obj, dotted, globs={}):
            result = runner.run(test)
            if result.failed:
                failures.append(dotted)
    assert failures == []
