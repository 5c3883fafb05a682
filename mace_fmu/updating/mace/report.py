"""What a MACE update writes: the parameter set, a text report, a summary as data, and figures."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.bode import plot_bode
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.updating.mace.update import (MaceUpdate, cost_history, format_mode_rows, format_moduli, format_table_4_1,
                                           mode_rows, scores, table_4_1_rows, table_4_4_moduli)
from mace_fmu.updating.engine.selection import plot_selection
from mace_fmu.util.atomic import save_figure_atomic, write_text_atomic

#: channels of the update (gimbals to rate gyros, thesis 4.5) drawn before and after
BODE_CHANNELS = (
    ("gimbal_secondary_z", "gyro_payload_z", "secondary Z gimbal -> payload Z gyro (Fig. 4.15)"),
    ("gimbal_secondary_x", "gyro_payload_x", "secondary X gimbal -> payload X gyro (Fig. 4.16)"),
    ("gimbal_primary_x", "gyro_bus_x", "primary X gimbal -> bus X gyro"),
)


def summary(outcome: MaceUpdate) -> dict:
    """The update's numbers as data (what the CLI prints, what tests read)."""
    rows = mode_rows(outcome)
    s = scores(rows)
    res = outcome.result
    return {
        "initial_cost": res.initial_cost, "final_cost": res.final_cost, "reduction": res.reduction,
        "seconds": dict(outcome.seconds),
        "selection": {"candidates": list(outcome.selection.names), "kept": list(outcome.selection.keep),
                      "strength": [float(x) for x in outcome.selection.strength],
                      "reasons": dict(outcome.selection.reasons)},
        "parameters": {"start": dict(res.start), "updated": dict(res.values), "table_4_4": table_4_4_moduli()},
        "rms_light_percent": {"thesis": s.rms_light_thesis, "before": s.rms_light_before, "after": s.rms_light_after},
        "worst_light_bending_percent": {"before": list(s.worst_structural_before),
                                        "after": list(s.worst_structural_after)},
        "modes": [{"label": r.label, "measured_hz": r.measured_hz, "measured_zeta": r.measured_zeta,
                   "thesis_hz": r.thesis_hz, "before_hz": r.before_hz, "before_zeta": r.before_zeta,
                   "after_hz": r.after_hz, "after_zeta": r.after_zeta, "after_label": r.after_label} for r in rows],
        "history": [{"step": step, "cost": before, "predicted": predicted}
                    for step, before, predicted in cost_history(outcome)],
    }


def text_report(outcome: MaceUpdate) -> str:
    """The whole report as plain text."""
    res = outcome.result
    lines = ["MACE 1-g model update (thesis 4.5) from the pre-update moduli", "",
             "The start model against Table 4.1 (after engineering insight, before automated updating):",
             format_table_4_1(table_4_1_rows(outcome.family, res.start)), "",
             "Parameter selection (orthogonality and strength tests, eq. 4.15-4.16):", outcome.selection.table(), "",
             "Modes against Table 4.7's measurement model (closed loop, servos on):", format_mode_rows(mode_rows(outcome)),
             "", "Moduli against Table 4.4:", format_moduli(outcome), "",
             f"Cost j^T j: {res.initial_cost:.6g} -> {res.final_cost:.6g} ({100 * res.reduction:.1f} % lower)", "",
             "Outer iterations (stage, cost of the full model at the base point, predicted for the new point):"]
    lines += [f"  {step:28s} {before:10.6g} {predicted:10.6g}" for step, before, predicted in cost_history(outcome)]
    lines += ["", "Wall time [s]: " + ", ".join(f"{k} {v:.1f}" for k, v in outcome.seconds.items())]
    return "\n".join(lines) + "\n"


def write_report(outcome: MaceUpdate, out_dir: str | Path) -> list[Path]:
    """parameters.toml, report.txt, summary.json and the PNG figures in ``out_dir``; returns the paths."""
    out = Path(out_dir)
    paths = [outcome.parameters.write(out / "parameters.toml"),
             write_text_atomic(out / "report.txt", text_report(outcome)),
             write_text_atomic(out / "summary.json", json.dumps(summary(outcome), indent=1) + "\n")]
    paths += plot_selection(outcome.selection, orthogonality_png=out / "orthogonality.png",
                            strength_png=out / "strength.png", title="MACE 1-g, modal cost")
    paths.append(_plot_history(outcome, out / "cost_history.png"))
    paths += _bode_overlays(outcome, out)
    return paths


def _plot_history(outcome: MaceUpdate, path: Path) -> Path:
    from matplotlib.figure import Figure

    history = cost_history(outcome)
    fig = Figure(figsize=(8, 4))
    ax = fig.add_subplot()
    ax.plot(range(1, len(history) + 1), [h[1] for h in history], "o-", label="full model at the base point")
    ax.plot(range(2, len(history) + 2), [h[2] for h in history], "x", label="predicted by the linearisation")
    ax.set_xticks(range(1, len(history) + 1), [h[0] for h in history], rotation=90, fontsize=6)
    ax.set_ylabel("j^T j")
    ax.set_title("Cost history of the MACE update")
    ax.legend()
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return save_figure_atomic(fig, path, dpi=110)


def _bode_overlays(outcome: MaceUpdate, out: Path) -> list[Path]:
    """Before (pre-update), after (ours) and the bundled deck (the thesis's updated model)."""
    f = np.logspace(np.log10(0.5), np.log10(60.0), 1200)  # the update band
    fam = outcome.family
    models = {"pre-update": fam.volts_model(outcome.result.start), "updated (ours)": fam.volts_model(outcome.result.values),
              "thesis final (bundled deck)": volts_model(compute_modes(fam.deck, configuration="1g",
                                                                       preload=fam.preload))}
    responses = {k: m.frequency_response(f) for k, m in models.items()}
    paths = []
    for u, y, title in BODE_CHANNELS:
        curves = {}
        for k, m in models.items():
            i, o = list(m.system.input_labels).index(u), list(m.system.output_labels).index(y)
            curves[k] = responses[k][:, o, i]
        paths.append(plot_bode(f, curves, title=title, path=out / f"bode_{u}_to_{y}.png"))
    return paths
