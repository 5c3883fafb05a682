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


def _public_functions():
    """(dotted name, function) of every function a package's ``__all__`` names, once each."""
    import inspect

    seen = set()
    for name in PACKAGES:
        package = importlib.import_module(name)
        for public in package.__all__:
            obj = getattr(package, public)
            if inspect.isfunction(obj) and id(obj) not in seen:
                seen.add(id(obj))
                yield f"{name}.{public}", obj


def test_every_public_function_has_numpydoc_parameters_and_returns():
    """The API reference is generated from these docstrings: every public function that takes arguments says
    what each is (numpydoc Parameters, units where physical), and every one that returns something what."""
    import inspect

    offenders = []
    for dotted, function in _public_functions():
        doc = inspect.getdoc(function) or ""
        signature = inspect.signature(function)
        if signature.parameters and "Parameters\n----------" not in doc:
            offenders.append(f"{dotted}: no Parameters section")
        returns_nothing = signature.return_annotation in (None, "None")
        if not returns_nothing and "Returns\n-------" not in doc:
            offenders.append(f"{dotted}: no Returns section")
    assert offenders == [], "\n".join(offenders)
