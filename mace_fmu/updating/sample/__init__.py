"""The automated-updating sample problem of thesis 4.3: the two-mass system, its parametrised family
and the cases of Tables 4.2 and 4.3. Its public names are also on :mod:`mace_fmu.updating`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.updating.sample.problem import run_sample_problem
    from mace_fmu.updating.sample.two_mass import TwoMassSystem

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "run_sample_problem": "problem",
    "TwoMassSystem": "two_mass",
})
