"""Closed-loop poles of a volts-volts model, each labelled by the states it lives in.

Participation factors p_k = |v_k w_k| (right and left eigenvector components, Verghese,
Perez-Arriaga and Schweppe 1982) say which states a pole lives in; unlike eigenvector magnitudes
they do not depend on how filter or delay states are scaled. States are grouped by open-loop
structural mode and by block, and the group with the largest share names the pole ("1st Z
bending", "time delay (gimbal_primary_x)"). The servos mix open-loop bending modes, so bending
poles are renumbered by frequency within their family (Y or Z) among the closed-loop poles:
the closed-loop pole made mostly of the open-loop 4th Z mode becomes the 3rd Z bending mode,
as the thesis counts them (Table 4.7).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from mace_fmu.fe.labels import ordinal
from mace_fmu.iomodel.volts import VoltsModel

_MODE_STATE = re.compile(r"^structure\.mode(\d+)_(?:disp|vel)$")
_BENDING = re.compile(r"^\d+(?:st|nd|rd|th) ([YZ]) bending$")


@dataclass(frozen=True)
class ClosedLoopPole:
    """One pole (of a complex pair, the one with positive imaginary part)."""

    frequency_hz: float  #: |lambda| / (2 pi)
    damping: float  #: -Re(lambda) / |lambda|
    label: str
    share: float  #: participation of the naming group (0-1)
    eigenvalue: complex


def _group(state: str, model: VoltsModel) -> str:
    """Label of the group a state belongs to: a structural mode's label or a block's role."""
    match = _MODE_STATE.match(state)
    if match:
        return model.plant.labels[int(match.group(1)) - 1]
    block = state.split(".", 1)[0]
    if block.startswith("delay_"):
        return f"time delay ({block[len('delay_'):]})"
    if block == "bessel":
        return "Bessel filter"
    return block


def closed_loop_poles(model: VoltsModel, *, max_hz: float | None = None) -> list[ClosedLoopPole]:
    """Poles with Im >= 0 sorted by frequency [Hz], labelled; up to ``max_hz`` when given."""
    lam, v = sla.eig(model.system.A)
    w = sla.inv(v)  # rows: left eigenvectors normalised so that w v = I
    part = np.abs(v * w.T)  # (state, pole)
    groups = [_group(s, model) for s in model.system.state_labels]
    names = sorted(set(groups))
    share = np.zeros((len(names), len(lam)))
    np.add.at(share, np.array([names.index(g) for g in groups]), part)
    share /= share.sum(axis=0, keepdims=True)
    keep = np.flatnonzero(lam.imag >= -1e-9 * np.maximum(np.abs(lam), 1.0))
    keep = keep[np.argsort(np.abs(lam[keep]))]
    poles, counters = [], {"Y": 0, "Z": 0}
    for k in keep:
        mag = abs(lam[k])
        top = int(np.argmax(share[:, k]))
        label = names[top]
        bending = _BENDING.match(label)
        if bending:
            counters[bending.group(1)] += 1
            label = f"{ordinal(counters[bending.group(1)])} {bending.group(1)} bending"
        poles.append(ClosedLoopPole(frequency_hz=float(mag / (2 * np.pi)), damping=float(-lam[k].real / mag)
                                    if mag > 0 else 0.0, label=label, share=float(share[top, k]),
                                    eigenvalue=complex(lam[k])))
    return [p for p in poles if max_hz is None or p.frequency_hz <= max_hz]
