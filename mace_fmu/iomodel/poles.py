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
from typing import Sequence

import numpy as np
import scipy.linalg as sla
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from mace_fmu.fe.labels import ordinal
from mace_fmu.iomodel.volts import VoltsModel
from modelica_like.filters import LOWPASS_KINDS

_MODE_STATE = re.compile(r"^structure\.mode(\d+)_(?:disp|vel)$")
_BENDING = re.compile(r"^\d+(?:st|nd|rd|th) ([YZ]) bending$")


@dataclass(frozen=True)
class ClosedLoopPole:
    """One pole (of a complex pair, the one with positive imaginary part)."""

    frequency_hz: float  #: ``|lambda| / (2 pi)``
    damping: float  #: ``-Re(lambda) / |lambda|``
    label: str  #: the mode it belongs to, e.g. "1st Z bending"
    share: float  #: participation of the naming group (0-1)
    eigenvalue: complex  #: the pole [rad/s]
    #: 0-based index into the mode labels of the open-loop structural mode that participates most (None: none does)
    mode: int | None = None


def _group(state: str, mode_labels: Sequence[str]) -> str:
    """Label of the group a state belongs to: a structural mode's label or a block's role."""
    match = _MODE_STATE.match(state)
    if match:
        return mode_labels[int(match.group(1)) - 1]
    block = state.split(".", 1)[0]
    if block.startswith("delay_"):
        return f"time delay ({block[len('delay_'):]})"
    if block in LOWPASS_KINDS:  # the anti-aliasing filter block is named after its family
        return f"{block.capitalize()} filter"
    return block


def closed_loop_poles(model: VoltsModel, *, max_hz: float | None = None) -> list[ClosedLoopPole]:
    """Poles with Im >= 0 sorted by frequency [Hz], labelled; up to ``max_hz`` when given.

    Parameters
    ----------
    model : VoltsModel
        The volts-volts model (servos closed).
    max_hz : float, optional
        Keep the poles up to this frequency [Hz].

    Returns
    -------
    list of ClosedLoopPole
        Frequency [Hz], damping ratio, label and the participating open-loop mode of each pole.
    """
    return label_poles(model.system.A, state_names=model.system.state_labels, mode_labels=model.plant.labels,
                       max_hz=max_hz)


def _eigen_participation(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues of ``a`` and participation factors |v_k w_k| (state, pole), block by block.

    The states are split into the strongly connected components of A's coupling graph, which
    puts A in block-triangular form (filters and delays on the outputs sit downstream of every
    loop). The eigenvalues are those of the diagonal blocks, and a pole's right and left
    eigenvectors overlap only on its own block, so its participation factors are those of the
    block alone: exact, cheaper than one eigen-solution of A, and free of the ill-conditioning
    that identical output filters give the eigenvectors of the whole.
    """
    n = a.shape[0]
    n_comp, comp = connected_components(csr_matrix(a != 0.0), directed=True, connection="strong")
    lam = np.empty(n, dtype=complex)
    part = np.zeros((n, n))
    at = 0
    for c in range(n_comp):
        idx = np.flatnonzero(comp == c)
        block_lam, v = sla.eig(a[np.ix_(idx, idx)])
        w = sla.inv(v)  # rows: left eigenvectors normalised so that w v = I
        cols = np.arange(at, at + len(idx))
        lam[cols] = block_lam
        part[np.ix_(idx, cols)] = np.abs(v * w.T)
        at += len(idx)
    return lam, part


def label_poles(a: np.ndarray, *, state_names: Sequence[str], mode_labels: Sequence[str],
                max_hz: float | None = None) -> list[ClosedLoopPole]:
    """Poles of ``a`` with Im >= 0 sorted by frequency [Hz], each labelled by the states it lives in.

    ``state_names`` are "block.state" (the structure's "structure.mode<k>_disp|vel", k 1-based
    into ``mode_labels``).
    """
    lam, part = _eigen_participation(a)
    groups = [_group(s, mode_labels) for s in state_names]
    names = sorted(set(groups))
    share = np.zeros((len(names), len(lam)))
    np.add.at(share, np.array([names.index(g) for g in groups]), part)
    share /= share.sum(axis=0, keepdims=True)
    mode_of = [int(m.group(1)) - 1 if (m := _MODE_STATE.match(s)) else -1 for s in state_names]
    structural = np.flatnonzero(np.array(mode_of) >= 0)
    by_mode = np.zeros((len(mode_labels), len(lam)))
    np.add.at(by_mode, np.array(mode_of, dtype=int)[structural], part[structural])
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
                                    eigenvalue=complex(lam[k]),
                                    mode=int(np.argmax(by_mode[:, k])) if by_mode[:, k].any() else None))
    return [p for p in poles if max_hz is None or p.frequency_hz <= max_hz]
