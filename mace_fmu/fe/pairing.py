"""Pair the modes of two structures by shape: mass-weighted modal assurance criterion (MAC)."""

from __future__ import annotations

import numpy as np

from mace_fmu.fe.assembly import FEModel
from mace_fmu.fe.modal import Modes


def mac_matrix(reference: Modes, reference_model: FEModel, other: Modes) -> np.ndarray:
    """(n_ref, n_other) MAC on the grids both structures share, weighted by the reference mass.

    Parameters
    ----------
    reference : Modes
        Modes whose mass weights the MAC.
    reference_model : FEModel
        Their model (its mass matrix).
    other : Modes
        The other structure's modes.

    Returns
    -------
    numpy.ndarray
        (n_ref, n_other) MAC values in [0, 1].
    """
    common = [g for g in reference.dofs.grid_ids if g in set(other.dofs.grid_ids)]
    rows_ref = np.concatenate([reference.dofs.indices(g) for g in common])
    rows_other = np.concatenate([other.dofs.indices(g) for g in common])
    w = reference_model.mass[np.ix_(rows_ref, rows_ref)].toarray()
    a = reference.shapes[rows_ref]
    b = other.shapes[rows_other]
    cross = a.T @ w @ b
    norm_a = np.einsum("im,ij,jm->m", a, w, a)
    norm_b = np.einsum("im,ij,jm->m", b, w, b)
    return cross**2 / np.maximum(np.outer(norm_a, norm_b), 1e-300)


def pair_by_mac(reference: Modes, reference_model: FEModel, other: Modes, indices: list[int]
                ) -> list[tuple[int, int, float]]:
    """For each reference mode index, the other structure's mode with the largest MAC.

    Returns (reference index, other index, MAC); an other mode is used at most once, taken by
    the reference mode that matches it best.

    Parameters
    ----------
    reference : Modes
        The modes to pair.
    reference_model : FEModel
        Their model (its mass matrix).
    other : Modes
        The other structure's modes.
    indices : list of int
        The reference modes to pair (0-based).

    Returns
    -------
    list of tuple
        (reference index, other index, MAC) for each of ``indices``.
    """
    mac = mac_matrix(reference, reference_model, other)
    pairs: dict[int, tuple[int, float]] = {}
    taken: set[int] = set()
    for i in sorted(indices, key=lambda i: -mac[i].max()):
        j = next(int(k) for k in np.argsort(-mac[i]) if int(k) not in taken)
        taken.add(j)
        pairs[i] = (j, float(mac[i, j]))
    return [(i, *pairs[i]) for i in indices]


def carry_labels(reference: Modes, reference_model: FEModel, other: Modes) -> Modes:
    """``other`` with each mode labelled as the reference mode it continues (one-to-one, largest total MAC).

    Energy-based labels are recomputed from scratch for every solution, so a small change of a
    parameter can move a label ("5th Z bending") to another mode when two modes of a family swap
    character; everything keyed by label (damping ratios, pairing with measurements) would jump
    with it. Carried labels follow the physical mode. Modes with no partner keep their own label.
    """
    import dataclasses

    from scipy.optimize import linear_sum_assignment

    mac = mac_matrix(reference, reference_model, other)
    rows, cols = linear_sum_assignment(-mac)
    labels = list(other.labels)
    for i, j in zip(rows, cols):
        labels[j] = reference.labels[i]
    return dataclasses.replace(other, labels=tuple(labels))
