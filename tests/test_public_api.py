"""The package's front door: the names a user starts with, each documented, none costly to import."""

from __future__ import annotations

import subprocess
import sys


def test_every_public_name_resolves_and_is_documented():
    import mace_fmu

    for name in mace_fmu.__all__:
        obj = getattr(mace_fmu, name)
        assert obj.__doc__ and obj.__doc__.strip(), name


def test_importing_the_package_loads_no_heavy_dependency():
    code = "import sys, mace_fmu; print(sorted(m for m in ('control', 'fmpy', 'scipy') if m in sys.modules))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


#: the packages in the order of the data flow: each may import only from packages before it (the
#: command line, last, from all). util and errors are shared by every stage; sparse, the sparse solver, is
#: linear algebra that needs neither decks nor elements; the viewer draws modes and FMU runs and is drawn
#: by the command line only (which imports it lazily: `mace-fmu --help` does not load meshcat).
STAGES = ("errors", "util", "sparse", "deck", "structure", "parameters", "fe", "nastran_modes", "iomodel", "thesis",
          "fmu", "viewer", "ssp", "updating", "control_studies", "zero_g", "cli")


def _imports_between_stages() -> list[tuple[str, str, str]]:
    """(importing module, imported module, the two stages) for every ``from mace_fmu.X import`` in the package."""
    import ast
    from pathlib import Path

    import mace_fmu

    root = Path(mace_fmu.__file__).parent
    found = []
    for path in sorted(root.rglob("*.py")):
        module = ".".join(path.relative_to(root.parent).with_suffix("").parts)
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("mace_fmu."):
                found.append((module, node.module))
    return found


def _stage(module: str) -> str:
    return module.split(".")[1]


def test_every_stage_imports_only_earlier_stages():
    """The layout reads like the data flow: deck -> structure -> parameters -> fe -> iomodel -> fmu -> ...;
    an import against that order (a later stage's name used by an earlier one) is a design error."""
    edges = _imports_between_stages()
    assert len(edges) > 300  # the walk saw the package
    backwards = [(a, b) for a, b in edges if _stage(a) != "__init__" and STAGES.index(_stage(b)) > STAGES.index(_stage(a))]
    assert backwards == []


def test_the_sparse_solver_is_reached_through_its_public_names_only():
    """mace_fmu.sparse is a boundary: the other stages import what its ``__all__`` declares (``factorize``,
    ``lowest_modes``) from the package, never one of its modules, so that its inside (CHOLMOD's structures,
    the orderings, the substructures) can change without them."""
    import mace_fmu.sparse

    edges = [(a, b) for a, b in _imports_between_stages() if _stage(b) == "sparse" and _stage(a) != "sparse"]
    assert {a for a, _ in edges} >= {"mace_fmu.fe.modal", "mace_fmu.fe.preload"}
    assert [(a, b) for a, b in edges if b != "mace_fmu.sparse"] == []
    assert set(mace_fmu.sparse.__all__) == {"factorize", "lowest_modes", "LanczosModes"}


def test_every_package_lists_its_public_names_and_each_resolves():
    import importlib
    import pkgutil

    import mace_fmu

    packages = ["mace_fmu"] + [m.name for m in pkgutil.walk_packages(mace_fmu.__path__, "mace_fmu.") if m.ispkg]
    assert {"mace_fmu.fe", "mace_fmu.sparse", "mace_fmu.updating", "mace_fmu.zero_g.robust",
            "mace_fmu.fmu.native"} <= set(packages)
    for name in packages:
        package = importlib.import_module(name)
        assert package.__doc__ and package.__all__, name
        for public in package.__all__:
            assert getattr(package, public) is not None, f"{name}.{public}"


def test_no_public_name_is_shadowed_by_a_module_of_its_package():
    """``package.name`` must be the public object: once a submodule of that name is imported, Python binds
    the module to the package's attribute and the lazy re-export is never asked."""
    import importlib
    import pkgutil

    import mace_fmu

    packages = ["mace_fmu"] + [m.name for m in pkgutil.walk_packages(mace_fmu.__path__, "mace_fmu.") if m.ispkg]
    for name in packages:
        package = importlib.import_module(name)
        modules = {m.name for m in pkgutil.iter_modules(package.__path__)}
        assert not modules & set(package.__all__), name


def test_the_spellings_removed_before_the_first_release_are_refused_by_name():
    """0.1 is unreleased: the earlier spellings are gone (CHANGELOG.md), and each is refused in one line that names
    it, never read silently as something else."""
    import pytest

    from mace_fmu import compute_modes, volts_model
    from mace_fmu.cli import main
    from mace_fmu.errors import MaceError
    from mace_fmu.parameters import ParameterSet

    with pytest.raises(TypeError, match="structure"):
        compute_modes(structure="0g", max_hz=3.5)
    with pytest.raises(TypeError, match="servos"):
        volts_model(compute_modes(configuration="0g"), servos=False)
    head = '[provenance]\ncreated = "2026-11-24T00:00:00+00:00"\ntool = "mace-fmu"\n'
    with pytest.raises(MaceError, match=r"\[provenance\] has unknown key\(s\) \['structure'\]"):
        ParameterSet.from_toml(head + 'structure = "0g"\n\n[values]\nE_lexan_center = 2.4e9\n')
    with pytest.raises(SystemExit) as stopped:
        main(["update", "--sample-problem"])
    assert stopped.value.code == 2


def test_every_lazy_package_shows_its_names_to_type_checkers():
    """A package's ``if TYPE_CHECKING:`` imports (what editors and type checkers follow) are exactly its lazy
    table: every public name, from the module that defines it at run time."""
    import ast
    import importlib
    import inspect
    import pkgutil

    import mace_fmu

    packages = ["mace_fmu"] + [m.name for m in pkgutil.walk_packages(mace_fmu.__path__, "mace_fmu.") if m.ispkg]
    checked = 0
    for name in packages:
        package = importlib.import_module(name)
        table = getattr(getattr(package, "__getattr__", None), "modules", None)
        if table is None:  # a package that imports its names eagerly
            continue
        tree = ast.parse(inspect.getsource(package))
        guarded = [node for node in tree.body
                   if isinstance(node, ast.If) and getattr(node.test, "id", "") == "TYPE_CHECKING"]
        assert len(guarded) == 1, f"{name}: no `if TYPE_CHECKING:` block"
        shown = {alias.name: node.module for node in guarded[0].body if isinstance(node, ast.ImportFrom)
                 for alias in node.names}
        assert shown == dict(table), name
        checked += 1
    assert checked >= 12


#: updating's sub-packages by use, and which of them each may import (besides itself): the engine knows
#: nothing of the modal update, the MACE update, the FMU update or the sample problem; the MACE update is the modal
#: route on the bundled deck
UPDATING_LAYERS = {"engine": set(), "files": {"engine"}, "modal": {"engine"}, "mace": {"engine", "modal"},
                   "fmu": {"engine", "files"}, "sample": {"engine", "files"}}


def test_updating_is_layered_by_use():
    import ast
    from pathlib import Path

    import mace_fmu.updating

    root = Path(mace_fmu.updating.__file__).parent
    assert {p.name for p in root.iterdir() if (p / "__init__.py").exists()} == set(UPDATING_LAYERS)
    offenders = []
    for sub, allowed in UPDATING_LAYERS.items():
        for path in (root / sub).glob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("mace_fmu.updating."):
                    other = node.module.split(".")[2]
                    if other != sub and other not in allowed:
                        offenders.append(f"{sub}/{path.name} imports {node.module}")
    assert offenders == []
