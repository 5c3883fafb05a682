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
    w = reference_model.mass[rows_ref][:, rows_ref]  # sparse: a mass matrix is mostly its diagonal
    a = reference.shapes[rows_ref]
    b = other.shapes[rows_other]
    wa, wb = w @ a, w @ b
    cross = wa.T @ b
    norm_a = np.sum(a * wa, axis=0)
    norm_b = np.sum(b * wb, axis=0)
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


def continue_modes(reference: Modes, reference_model: FEModel, other: Modes, *, zero_hz: float) -> Modes:
    """The modes of ``other`` (a re-solve with more modes than ``reference``) that continue ``reference``'s, in
    its order and with its labels: mode k of the result is the physical mode reference mode k became.

    The zero-frequency cluster (rigid bodies, mechanisms: a basis of their span, labelled by motion, whatever
    the stiffness) is the re-solve's own, each of its motions in the place of the reference's it resembles
    most; each flexible mode is the re-solve's mode of the one-to-one pairing with the largest total MAC
    (mass-weighted by the reference). An FMU's parameter route pairs its re-analysed
    modes the same way (:func:`~mace_fmu.iomodel.reanalysis.ritz_reanalysis`), and keys its per-mode data
    (damping ratios, frequency scales) by the index of the mode continued: a re-solve in frequency order with
    fresh labels handed them to other modes wherever two modes crossed (a violin and a bending mode, two
    bending modes renamed 3rd and 4th).

    Parameters
    ----------
    reference : Modes
        The modes to continue (the nominal structure's).
    reference_model : FEModel
        Their model (its mass weights the MAC).
    other : Modes
        The re-solve's modes, enough of them that every reference mode's continuation is among them.
    zero_hz : float
        Modes below this [Hz] form the zero-frequency cluster.

    Returns
    -------
    Modes
        ``len(reference)`` modes of ``other``: its zero cluster, then the continuations, in the reference's order.

    Raises
    ------
    MaceError
        When the two zero-frequency clusters differ in size (a parameter that frees or holds a mechanism).
    """
    import dataclasses

    from scipy.optimize import linear_sum_assignment

    from mace_fmu.errors import MaceError

    zero_ref = np.abs(reference.frequencies_hz) < zero_hz
    zero_other = np.abs(other.frequencies_hz) < zero_hz
    if zero_ref.sum() != zero_other.sum():
        raise MaceError(f"the re-solve has {int(zero_other.sum())} zero-frequency modes, the nominal structure "
                        f"{int(zero_ref.sum())}: a parameter value that frees or holds a rigid-body motion or a "
                        "mechanism")
    flex_ref, flex_other = np.flatnonzero(~zero_ref), np.flatnonzero(~zero_other)
    if len(flex_other) < len(flex_ref):
        raise MaceError(f"the re-solve found {len(flex_other)} flexible modes, fewer than the {len(flex_ref)} it "
                        "must continue")
    mac = mac_matrix(reference, reference_model, other)
    order = np.empty(len(reference), dtype=int)
    # each cluster paired within itself: the zero cluster's named motions (a reaction wheel's spin) in the
    # reference's places, the flexible modes by the largest total MAC
    for ref, oth in ((np.flatnonzero(zero_ref), np.flatnonzero(zero_other)), (flex_ref, flex_other)):
        rows, cols = linear_sum_assignment(-mac[np.ix_(ref, oth)])
        order[ref[rows]] = oth[cols]
    labels = list(other.labels[k] for k in order) if other.labels else [""] * len(order)
    for i in flex_ref:
        labels[i] = reference.labels[i] if reference.labels else labels[i]
    return dataclasses.replace(other, frequencies_hz=other.frequencies_hz[order], shapes=other.shapes[:, order],
                               labels=tuple(labels))
