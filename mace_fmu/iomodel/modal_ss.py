"""Physical modal state-space model (thesis eq. 3.5-3.6): inputs [N m], outputs in physical units.

x = [eta; eta_dot] per retained mode; A = [[0, I], [-Omega^2, -2 zeta Omega]], B = [0; Phi^T b],
C = [c_d Phi, 0; 0, c_r Phi], D = 0. Besides the sensors, the model outputs the displacement
reading (``<name>_angle``) of each rate sensor a gimbal servo integrates (the encoders).

Zero-frequency modes (rigid bodies and mechanisms) obey eta'' = Phi^T b u in any orthonormal
basis of their cluster, so the cluster is rotated (mass normalisation kept) and reduced by rule,
with the reason recorded:
- directions no actuator moves are uncontrollable: all inputs are internal torques, so the
  rigid-body momenta are conserved; both states of these directions go;
- of the rest, displacement directions no output reads (wheel angles: the tachometers sense
  rate) keep only their rate state.
Appendix C (gimcon3) reduces its 0-g cluster by an SVD of the rate outputs in the same spirit.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np

from mace_fmu.fe.modal import Modes
from mace_fmu.iomodel.instruments import Instruments, influence_vector

ZERO_HZ = 0.01
# Relative to the largest modal input/output coefficient. The computed zero cluster is exact to
# ~1e-8 (mechanisms) and to round-off (rigid bodies, built geometrically).
_NEGLIGIBLE = 1e-6


@dataclass(frozen=True)
class ModalPlant:
    """The physical modal model with the bookkeeping a reader needs."""

    system: ct.StateSpace  #: named inputs (actuators, N m), outputs (sensors; *_angle [rad])
    frequencies_hz: np.ndarray  #: of the retained modes
    damping: np.ndarray
    labels: tuple[str, ...]
    shapes: np.ndarray  #: (n_dof, n_modes) mode shapes behind the states (zero cluster rotated)
    removed_states: tuple[tuple[str, str], ...]  #: (state name, reason)


def _reduce_zero_cluster(zero: np.ndarray, phi: np.ndarray, labels: tuple[str, ...], modal_b: np.ndarray,
                         disp_out: dict[str, np.ndarray], rate_out: dict[str, np.ndarray]):
    """Rotate the zero-frequency modes so that controllable and observable directions come first.

    Returns the rotated (phi, labels, modal_b), the numbers of controllable and of
    displacement-observable directions, and the reasons for what goes; ``disp_out`` and
    ``rate_out`` (output rows over the modes) are rotated in place.
    """
    removed: list[tuple[str, str]] = []
    if not len(zero):
        return phi, labels, modal_b, 0, 0, removed
    u_b, s_b, _ = np.linalg.svd(modal_b[zero], full_matrices=True)
    n_ctrl = int(np.sum(s_b > _NEGLIGIBLE * np.abs(modal_b).max()))
    c_d = np.array([r[zero] for r in disp_out.values()]) @ u_b[:, :n_ctrl]
    _, s_d, vt_d = np.linalg.svd(c_d, full_matrices=True)
    n_obs = int(np.sum(s_d > _NEGLIGIBLE * max(np.abs(np.array(list(disp_out.values()))).max(), 1e-300)))
    rot = np.hstack([u_b[:, :n_ctrl] @ vt_d.T, u_b[:, n_ctrl:]])
    if n_ctrl < len(zero):
        removed.append(("zero-frequency cluster", f"{len(zero) - n_ctrl} directions no actuator moves (internal "
                        "torques conserve the rigid-body momenta): uncontrollable, both states removed"))
    if n_obs < n_ctrl:
        removed.append(("zero-frequency cluster", f"{n_ctrl - n_obs} displacement directions no output reads "
                        "(rate sensing only): unobservable, displacement states removed"))
    phi = phi.copy()
    phi[:, zero] = phi[:, zero] @ rot
    new_labels = list(labels)  # a rotated direction keeps the name of the motion it is mostly made of
    for k, j in enumerate(zero):
        new_labels[j] = labels[zero[int(np.argmax(np.abs(rot[:, k])))]]
    modal_b = modal_b.copy()
    modal_b[zero] = rot.T @ modal_b[zero]
    for table in (disp_out, rate_out):
        for key in table:
            table[key] = table[key].copy()
            table[key][zero] = table[key][zero] @ rot
    return phi, tuple(new_labels), modal_b, n_ctrl, n_obs, removed


def modal_plant(modes: Modes, instruments: Instruments, damping: np.ndarray, *, max_hz: float) -> ModalPlant:
    """Modal state-space of the modes up to ``max_hz`` [Hz] with the instruments' DOFs (no gains)."""
    keep = modes.frequencies_hz <= max_hz
    freq = modes.frequencies_hz[keep]
    zeta = damping[keep]
    labels = tuple(lab for lab, k in zip(modes.labels, keep) if k)
    phi = modes.shapes[:, keep]
    omega = 2.0 * np.pi * np.where(np.abs(freq) < ZERO_HZ, 0.0, freq)

    b = np.array([influence_vector(a.dofs, modes.dofs, modes.cd_frames) for a in instruments.actuators]).T
    modal_b = phi.T @ b  # (n_modes, n_inputs)
    rows = {s.name: influence_vector(s.dofs, modes.dofs, modes.cd_frames) @ phi for s in instruments.sensors}
    rate_names = [s.name for s in instruments.sensors if s.kind == "rate"]
    integrated = [s.name for s in instruments.sensors if s.name in instruments.servos.gimbals.values()]
    disp_out = {s.name: rows[s.name] for s in instruments.sensors if s.kind == "displacement"}
    disp_out.update({f"{n}_angle": rows[n] for n in integrated})
    rate_out = {n: rows[n] for n in rate_names}

    zero = np.flatnonzero(np.abs(freq) < ZERO_HZ)
    phi, labels, modal_b, n_ctrl, n_obs, removed = _reduce_zero_cluster(zero, phi, labels, modal_b, disp_out, rate_out)
    n = len(freq)
    keep_disp = np.ones(n, dtype=bool)
    keep_rate = np.ones(n, dtype=bool)
    keep_rate[zero[n_ctrl:]] = False
    keep_disp[zero[n_obs:]] = False
    d_idx, r_idx = np.flatnonzero(keep_disp), np.flatnonzero(keep_rate)
    nd, nr = len(d_idx), len(r_idx)
    a = np.zeros((nd + nr, nd + nr))
    pos_r = {j: nd + k for k, j in enumerate(r_idx)}
    for k, j in enumerate(d_idx):
        a[k, pos_r[j]] = 1.0
        a[pos_r[j], k] = -omega[j] ** 2
    for j in r_idx:
        a[pos_r[j], pos_r[j]] = -2.0 * zeta[j] * omega[j]
    bm = np.vstack([np.zeros((nd, modal_b.shape[1])), modal_b[r_idx]])
    names_out = list(disp_out) + list(rate_out)
    c = np.zeros((len(names_out), nd + nr))
    for i, name in enumerate(names_out):
        if name in disp_out:
            c[i, :nd] = disp_out[name][d_idx]
        else:
            c[i, nd:] = rate_out[name][r_idx]
    sensor_order = [s.name for s in instruments.sensors] + [f"{n}_angle" for n in integrated]
    order = [names_out.index(name) for name in sensor_order]
    states = [f"mode{j + 1}_disp" for j in d_idx] + [f"mode{j + 1}_vel" for j in r_idx]
    sys = ct.ss(a, bm, c[order], np.zeros((len(order), bm.shape[1])), inputs=[x.name for x in instruments.actuators],
                outputs=sensor_order, states=states, name="structure")
    return ModalPlant(system=sys, frequencies_hz=freq, damping=zeta, labels=labels, shapes=phi,
                      removed_states=tuple(removed))
