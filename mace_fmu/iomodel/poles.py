"""Closed-loop poles of a volts-volts model, each labelled by the states it lives in.

A pole's label comes from its participation factors p_k = |v_k w_k| (right and left eigenvector
components, Verghese, Perez-Arriaga and Schweppe 1982). Unlike eigenvector magnitudes they do not
depend on how filter or delay states are scaled. The states are grouped by structural mode and
by block, and the group with the largest share names the pole.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from mace_fmu.iomodel.volts import VoltsModel

_MODE_STATE = re.compile(r"^structure\.mode(\d+)_(?:disp|vel)$")


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
    a = model.system.A
    lam, v = sla.eig(a)
    w = sla.inv(v)  # rows: left eigenvectors normalised so that w v = I
    part = np.abs(v * w.T)  # (state, pole)
    groups = [_group(s, model) for s in model.system.state_labels]
    names = sorted(set(groups))
    index = np.array([names.index(g) for g in groups])
    share = np.zeros((len(names), len(lam)))
    np.add.at(share, index, part)
    share /= share.sum(axis=0, keepdims=True)
    poles = []
    for k in np.flatnonzero(lam.imag >= -1e-9 * np.maximum(np.abs(lam), 1.0)):
        mag = abs(lam[k])
        f = mag / (2 * np.pi)
        if max_hz is not None and f > max_hz:
            continue
        top = int(np.argmax(share[:, k]))
        poles.append(ClosedLoopPole(frequency_hz=float(f), damping=float(-lam[k].real / mag) if mag > 0 else 0.0,
                                    label=names[top], share=float(share[top, k]), eigenvalue=complex(lam[k])))
    return sorted(poles, key=lambda p: p.frequency_hz)
