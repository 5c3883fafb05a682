"""How much LQG performance a wrong model costs (thesis Appendix A.1), through the library.
========================================================================================

    python examples/lqg_model_error.py

Designs the moderate-authority LQG compensator of the two-mass system on the actual stiffnesses
and on models with k2 off by -20 %, -10 %, +10 % and +20 %, closes each around the actual system
and prints J / J_optimal (1 is the best any compensator can do; inf is an unstable loop).
``model_error_costs`` is used by the tests.
"""

from __future__ import annotations

from mace_fmu.control_studies.lqg import closed_loop_cost, design_lqg
from mace_fmu.control_studies.stiffness_sensitivity import AUTHORITIES
from mace_fmu.updating.sample.two_mass import TwoMassSystem


def model_error_costs(*, k2_factors: tuple[float, ...] = (0.8, 0.9, 1.0, 1.1, 1.2),
                      authority: str = "moderate") -> dict[float, float]:
    """J / J_optimal for design models whose k2 is ``factor`` times the actual one."""
    actual = TwoMassSystem()
    plant = actual.state_space(force_on=1, measured=2)  # force on mass 1, displacement of mass 2
    weights = AUTHORITIES[authority]
    best = closed_loop_cost(plant, design_lqg(plant, weights))
    costs = {}
    for factor in k2_factors:
        model = TwoMassSystem(k1=actual.k1, k2=factor * actual.k2).state_space(force_on=1, measured=2)
        costs[factor] = closed_loop_cost(plant, design_lqg(model, weights)) / best
    return costs


if __name__ == "__main__":
    for factor, cost in model_error_costs().items():
        print(f"design k2 = {factor:.1f} x actual: J / J_optimal = {cost:.3f}")
