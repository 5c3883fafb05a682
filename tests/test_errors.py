"""A bad input to the library is a MaceError (a ValueError, so callers that catch ValueError still do): the
CLI shows it as one line with status 2. Plain ValueErrors are left only where a caller broke an internal
contract (no user input reaches them)."""

from __future__ import annotations

import re

import pytest
from support.paths import ROOT

from mace_fmu.deck.sections import section_properties
from mace_fmu.errors import MaceError
from mace_fmu.fe.dofs import DofMap
from mace_fmu.parameters.kinds import DAMPING, MODULUS, mode_number
from mace_fmu.updating.sample.problem import run_case

#: file -> plain ValueErrors kept: the sweep's array and factor kind (CHOLMOD's contract), a stressed
#: bar's energy asked without its state (the assembly's contract)
INTERNAL = {"mace_fmu/sparse/cholmod.py": 2, "mace_fmu/fe/corotational.py": 1}


def test_plain_value_errors_are_only_internal_contracts():
    found = {}
    for path in sorted((ROOT / "mace_fmu").rglob("*.py")):
        count = len(re.findall(r"raise ValueError\b", path.read_text(encoding="utf-8")))
        if count:
            found[path.relative_to(ROOT).as_posix()] = count
    assert found == INTERNAL


@pytest.mark.parametrize("call, message", [
    (lambda: section_properties("TUBE", (0.01, 0.02)), r"DIM2 \(inner radius 0.02\) is not below DIM1"),
    (lambda: section_properties("ROD", (0.01, 0.02)), "ROD has 1 dimension"),
    (lambda: DofMap((1, 2)).index(1, 7), "component must be 1-6, got 7"),
    (lambda: MODULUS.fmu_name(3), "modulus parameters are not per mode"),
    (lambda: DAMPING.named("x"), "not named after an element"),
    (lambda: mode_number("E_lexan"), "'E_lexan' is not a per-mode FMU parameter name"),
    (lambda: run_case("9z", None), "sample problem case must be one of"),
])
def test_a_bad_argument_is_a_mace_error_with_its_message(call, message):
    with pytest.raises(MaceError, match=message):
        call()
