"""Model updating on the MACE model: the whole update, and what each inclusion method costs.

Run by hand: ``python benchmarks/bench_update.py [--compare]``; results go into benchmarks/RESULTS.md.

1. The MACE update of ``mace-fmu update`` (selection on 13 candidates, then two rounds of
   physical parameters, servo delays and damping ratios, cost-sensitivity method), end to end,
   with the share of each stage.
2. Per evaluation of a perturbed model on the MACE 1-g model: a full re-solve, reanalysis and
   modal sensitivities (after their set-up), and the set-up costs themselves.
3. ``--compare``: the physical stage alone (frequency cost, the parameters the selection kept)
   by each method, how long it takes and where it ends.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from common import machine_line
from mace_fmu.updating.engine.bounds import default_bounds
from mace_fmu.updating.engine.costs import ModalCost
from mace_fmu.updating.engine.inclusion import modal_sensitivity
from mace_fmu.updating.mace.family import MaceFamily
from mace_fmu.updating.mace.update import (format_mode_rows, measured_modes, mode_rows, pre_update_parameters,
                                           run_mace_update, scores)
from mace_fmu.updating.engine.solve import Stage, UpdateSettings, update


def _time(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def whole_update() -> list[str]:
    seconds, outcome = _time(lambda: run_mace_update())
    s = scores(mode_rows(outcome))
    res = outcome.result
    lines = [f"| MACE update end to end (selection + 2 rounds) | {seconds:.1f} | cost {res.initial_cost:.4g} -> "
             f"{res.final_cost:.4g} ({100 * res.reduction:.0f} % lower), RMS (zeta < 10 %) {s.rms_light_before:.2f} -> "
             f"{s.rms_light_after:.2f} %, {outcome.family.solves} FE solves |"]
    for stage, t in outcome.seconds.items():
        lines.append(f"| - {stage} | {t:.1f} | {100 * t / seconds:.0f} % of the total |")
    print(format_mode_rows(mode_rows(outcome)))
    return lines


def _difference(cost: ModalCost, j: np.ndarray, j_full: np.ndarray) -> str:
    """Largest |j - j_full| over the frequency entries and over the damping entries, with the worst entry."""
    labels = cost.entry_labels()
    parts = []
    for kind in ("f", "zeta"):
        rows = [k for k, label in enumerate(labels) if label.split()[0] == kind]
        k = rows[int(np.argmax(np.abs(j[rows] - j_full[rows])))]
        parts.append(f"{kind}: max |j - j_full| {abs(j[k] - j_full[k]):.1e} ({labels[k]})")
    return "; ".join(parts)


def per_evaluation() -> list[str]:
    family = MaceFamily(base=pre_update_parameters())
    names = ("E_lexan_center", "E_active_strut_piezo", "E_cable_1")
    base = family.current_values(names)
    cost = ModalCost(measured=measured_modes())
    lines = []
    point = {**base, "E_lexan_center": base["E_lexan_center"] * 1.02}
    t_full, m_full = _time(lambda: cost.residual(family.full(point)))
    lines.append(f"| full re-solve (FE, preload, modes, volts model) + cost | {t_full:.2f} | one new physical point |")
    basis = family.basis(base)
    t_basis, _ = _time(lambda: basis.model(base))  # the stiffness sensitivities are computed on first use
    lines.append(f"| reanalysis set-up (stiffness sensitivities projected on 80 modes) | {t_basis:.2f} | once per "
                 "base point |")
    t_re, m_re = _time(lambda: cost.residual(basis.model(point)))
    lines.append(f"| reanalysis evaluation + cost | {t_re:.2f} | {_difference(cost, m_re, m_full)} |")
    t_ms_setup, sens = _time(lambda: modal_sensitivity(family.basis(base), base, names, relative_step=1e-2))
    lines.append(f"| modal-sensitivity set-up ({len(names)} parameters: one FE modal solve each) | {t_ms_setup:.2f} | "
                 "once per base point |")
    t_ms, m_ms = _time(lambda: cost.residual(sens(point)))
    lines.append(f"| modal-sensitivity evaluation + cost | {t_ms:.2f} | {_difference(cost, m_ms, m_full)} |")
    return lines


def compare_methods() -> list[str]:
    lines = []
    kept = ("E_lexan_end", "E_lexan_center", "E_active_strut_end", "E_active_strut_piezo",
            "E_active_strut_center")  # what the selection of `mace-fmu update` keeps
    for method, perturbation in (("cost-sensitivity", "reanalysis"), ("cost-sensitivity", "full"),
                                 ("reanalysis", "reanalysis"), ("modal-sensitivity", "full"), ("full", "full")):
        family = MaceFamily(base=pre_update_parameters())
        start = family.current_values(kept)
        cost = ModalCost(measured=measured_modes(), damping_weight=0.0)
        settings = UpdateSettings(method=method, perturbation=perturbation, max_outer=4)
        t, res = _time(lambda: update(family, cost, start=start, stages=[Stage("physical", kept)],
                                      bounds=default_bounds(kept, start), settings=settings))
        moduli = ", ".join(f"{n.removeprefix('E_')} {100 * (res.values[n] / start[n] - 1):+.1f}" for n in kept)
        lines.append(f"| physical stage, {method} ({perturbation}) | {t:.1f} | cost {res.initial_cost:.5f} -> "
                     f"{res.final_cost:.5f}, {family.solves} FE solves; changes %: {moduli} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--compare", action="store_true", help="also run the physical stage by every method")
    args = parser.parse_args()
    import control as ct
    import scipy

    print(machine_line(numpy=np.__version__, scipy=scipy.__version__, control=ct.__version__))
    print(f"- date: {time.strftime('%Y-%m-%d')}\n")
    print("| case | wall time [s] | notes |")
    print("|---|---|---|")
    rows = per_evaluation() + whole_update() + (compare_methods() if args.compare else [])
    print("\n".join(rows))


if __name__ == "__main__":
    main()
