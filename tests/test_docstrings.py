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


def test_the_package_docstring_walks_the_stages_on_the_bundled_deck():
    """The example ``help(mace_fmu)`` shows runs: deck, 0-g modes (Table 5.1's 2.10 and 3.07 Hz), a
    one-channel volts-volts model and its native FMU."""
    finder, runner = doctest.DocTestFinder(), doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    (test,) = [t for t in finder.find(mace_fmu, "mace_fmu", globs={}) if t.name == "mace_fmu"]
    assert len(test.examples) >= 6
    assert runner.run(test).failed == 0


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


def _documented_in_docstring(doc: str) -> set[str]:
    """Names a numpydoc Parameters/Attributes list documents ("name : type" or "a, b : type" lines)."""
    import re

    names: set[str] = set()
    for line in doc.splitlines():
        match = re.match(r"^([A-Za-z_][\w]*(?:, [A-Za-z_][\w]*)*) :", line)
        if match:
            names.update(match.group(1).split(", "))
    return names


def _documented_parameters(doc: str) -> set[str] | None:
    """The names a numpydoc ``Parameters`` section lists (both of ``a, b : type``; ``*args`` and ``**options``
    without their stars), or None for a docstring without one."""
    import re

    start = re.search(r"^Parameters\n-{3,}\n", doc, re.M)
    if start is None:
        return None
    body = doc[start.end():]
    end = re.search(r"^\S.*\n-{3,}$", body, re.M)  # the next section's title
    names: set[str] = set()
    for line in (body[:end.start()] if end else body).splitlines():
        if line and not line[0].isspace():  # an entry; its description is indented
            names.update(part.strip().lstrip("*") for part in line.split(" : ")[0].split(","))
    return names


def _public_callables():
    """(dotted name, callable) of every public function, every public class (its constructor's parameters) and
    every public method of a public class that a package's ``__all__`` names, once each."""
    import inspect

    yield from _public_functions()
    seen = set()
    for name in PACKAGES:
        package = importlib.import_module(name)
        for public in package.__all__:
            cls = getattr(package, public)
            if not inspect.isclass(cls) or id(cls) in seen:
                continue
            seen.add(id(cls))
            yield f"{name}.{public}", cls
            for attr, value in vars(cls).items():
                value = value.__func__ if isinstance(value, (staticmethod, classmethod)) else value
                if not attr.startswith("_") and inspect.isfunction(value):
                    yield f"{name}.{public}.{attr}", value


#: public methods that take arguments and document them in a sentence, without a Parameters section: the
#: baseline of the test below, which fails for a new one and for one that gets its section (then
#: remove it here)
METHODS_WITHOUT_PARAMETERS = frozenset({
    "mace_fmu.DiscreteController.from_statespace", "mace_fmu.DiscreteController.read_npz",
    "mace_fmu.DiscreteController.write_npz", "mace_fmu.fe.Constraints.reduce",
    "mace_fmu.fe.Constraints.reduce_sparse", "mace_fmu.fe.DofMap.grid_index", "mace_fmu.fe.DofMap.grid_indices",
    "mace_fmu.fe.DofMap.index", "mace_fmu.fe.DofMap.indices", "mace_fmu.fe.DofMap.label", "mace_fmu.fe.Modes.shape",
    "mace_fmu.fe.Modes.grid_motion", "mace_fmu.iomodel.Instruments.actuator", "mace_fmu.iomodel.Instruments.sensor",
    "mace_fmu.iomodel.ParametricSystem.parameter_problems", "mace_fmu.iomodel.ParametricSystem.parameter_problem",
    "mace_fmu.iomodel.ParametricSystem.index", "mace_fmu.iomodel.ParametricSystem.relative_changes",
    "mace_fmu.iomodel.ParametricSystem.modes", "mace_fmu.iomodel.ParametricSystem.structure",
    "mace_fmu.iomodel.ParametricSystem.build", "mace_fmu.iomodel.VoltsModel.frequency_response",
    "mace_fmu.updating.FrequencyResponseData.lines", "mace_fmu.updating.FrequencyResponseData.unit",
    "mace_fmu.updating.ModelFamily.full", "mace_fmu.updating.ModelFamily.basis", "mace_fmu.updating.TimeHistory.unit",
    "mace_fmu.updating.TimeHistory.head", "mace_fmu.updating.TwoMassSystem.state_space",
    "mace_fmu.updating.files.ChannelMap.find", "mace_fmu.updating.files.ChannelMap.where",
    "mace_fmu.updating.modal.StructureFamily.physical_values", "mace_fmu.updating.modal.StructureFamily.check_names",
    "mace_fmu.updating.modal.StructureFamily.solve", "mace_fmu.updating.modal.StructureFamily.full",
    "mace_fmu.updating.modal.StructureFamily.basis", "mace_fmu.updating.modal.StructureFamily.current_values",
    "mace_fmu.updating.modal.StructureFamily.fresh_labels", "mace_fmu.zero_g.BoundRule.bound",
    "mace_fmu.zero_g.robust.ParameterBox.label", "mace_fmu.zero_g.robust.SweepResult.costs",
    "mace_fmu.zero_g.robust.SweepResult.stable"
})


def test_every_parameter_is_documented_and_every_documented_parameter_exists():
    """Per argument, as python-control's docstrings_test.py: each parameter of a public function's, class's or
    method's signature has its entry in the numpydoc Parameters section, and each entry there is a parameter (a
    renamed or removed argument leaves none behind). Classes without the section document their fields instead
    (test_every_public_dataclass_documents_its_fields); methods without it are the listed baseline."""
    import inspect

    offenders, checked, without = [], 0, set()
    for dotted, obj in _public_callables():
        documented = _documented_parameters(inspect.getdoc(obj) or "")
        if documented is None:  # functions: test_every_public_function_has_numpydoc_parameters_and_returns
            if not inspect.isclass(obj) and set(inspect.signature(obj).parameters) - {"self", "cls"}:
                without.add(dotted)
            continue
        try:
            signature = inspect.signature(obj)
        except ValueError:  # a class without a signature of its own
            continue
        parameters = {p.name for p in signature.parameters.values() if p.name not in ("self", "cls")}
        missing, unknown = parameters - documented, documented - parameters
        if missing or unknown:
            offenders.append(f"{dotted}: not documented {sorted(missing)}, not a parameter {sorted(unknown)}")
        checked += 1
    assert checked > 100
    assert offenders == [], "\n".join(offenders)
    functions = {dotted for dotted, _ in _public_functions()}
    assert sorted(without - functions - METHODS_WITHOUT_PARAMETERS) == []  # a new method: give it the section
    assert sorted(METHODS_WITHOUT_PARAMETERS - without) == []  # it has one now (or is gone): off the list


def test_every_public_dataclass_documents_its_fields():
    """The API reference lists each field of a public record with what it is (units where physical): a ``#:``
    comment on the field's line or the line above, or an entry of the class's numpydoc list."""
    import dataclasses
    import inspect

    offenders, seen = [], set()
    for name in PACKAGES:
        package = importlib.import_module(name)
        for public in package.__all__:
            cls = getattr(package, public)
            if not (inspect.isclass(cls) and dataclasses.is_dataclass(cls)) or id(cls) in seen:
                continue
            seen.add(id(cls))
            lines = inspect.getsource(cls).splitlines()
            in_doc = _documented_in_docstring(inspect.getdoc(cls) or "")
            for f in dataclasses.fields(cls):
                at = next((i for i, line in enumerate(lines) if line.strip().startswith(f.name + ":")), None)
                if at is None or f.name in in_doc:
                    continue
                if "#:" not in lines[at] and not (at and lines[at - 1].strip().startswith("#:")):
                    offenders.append(f"{name}.{public}.{f.name}")
    assert len(seen) > 50
    assert offenders == [], "\n".join(offenders)


def test_no_docstring_has_a_bare_uri_that_the_api_pages_would_link_to_nowhere():
    """docutils turns a bare ``scheme:rest`` in reStructuredText into a hyperlink: the Deck page linked
    ``file:line`` to nowhere. Docstrings and ``#:`` comments write such text as a literal."""
    import re
    from pathlib import Path

    bare = re.compile(r"(?<![`\w/.])(file|mailto|ftp):[^\s`]")
    found = []
    for path in sorted(Path(mace_fmu.__file__).parent.rglob("*.py")):
        in_docstring = False
        for number, line in enumerate(path.read_text().splitlines(), start=1):
            quotes = line.count('"""')
            shown = in_docstring or quotes or line.lstrip().startswith("#:")
            if shown and bare.search(_outside_literals(line)):
                found.append(f"{path.name}:{number}: {line.strip()}")
            if quotes % 2:
                in_docstring = not in_docstring
    assert found == []


def _outside_literals(line: str) -> str:
    """``line`` without its ``literal`` spans."""
    import re

    return re.sub(r"``.*?``", "", line)
