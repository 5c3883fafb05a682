"""Both modal sources, a deck's modes and NASTRAN's, answer every question of the one protocol the model, the FMU
writers and the viewer ask (mace_fmu.iomodel.source): none of them switches on which source it holds."""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path

import pytest

import mace_fmu
from mace_fmu.fe.modes import StructureModes
from mace_fmu.iomodel.modal_source import ModalStructure
from mace_fmu.iomodel.source import ModalSource

ROOT = Path(mace_fmu.__file__).parent


def _members() -> list[str]:
    return [name for name in vars(ModalSource) if not name.startswith("_")]


@pytest.mark.parametrize("source", [StructureModes, ModalStructure])
def test_each_source_has_every_member_of_the_protocol(source):
    fields = {f.name for f in dataclasses.fields(source)}
    missing = [name for name in _members() if name not in fields and not hasattr(source, name)]
    assert missing == []
    assert len(_members()) >= 15


def test_no_module_after_the_fe_switches_on_the_sources_type():
    """isinstance(x, StructureModes) or isinstance(x, ModalStructure) past the FE (which makes the deck's modes):
    the question belongs to the source."""
    found = []
    paths = [p for p in ROOT.rglob("*.py") if p.parent.name != "fe"] + list((ROOT.parent / "viewer").rglob("*.py"))
    for path in paths:
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "isinstance" and len(node.args) == 2:
                named = {n.id for n in ast.walk(node.args[1]) if isinstance(n, ast.Name)}
                if named & {"ModalStructure", "StructureModes"}:
                    found.append(f"{path.relative_to(ROOT.parent)}:{node.lineno}")
    assert found == []
