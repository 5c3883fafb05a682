"""Modal state-space matrices (eq. 3.5-3.6) from modal data, with numpy only.

Used by mace_fmu.iomodel.modal_ss and copied verbatim into FMUs, which rebuild their structure
after a reanalysis at initialisation. Zero-frequency modes (rigid bodies and mechanisms) obey
eta'' = Phi^T b u in any orthonormal basis of their cluster, so the cluster is rotated (mass
normalisation kept) and reduced by rule, with the reason recorded:
- directions no actuator moves are uncontrollable: all inputs are internal torques, so the
  rigid-body momenta are conserved; both states of these directions go;
- of the rest, displacement directions no sensor reads (wheel angles: the tachometers sense
  rate) keep only their rate state, unless a motion output (grid motion for animation) reads
  them. Sensor readings of such directions are below NEGLIGIBLE, rounding noise of the mechanism
  modes, and are set to zero, so that motion outputs never change what the sensors see.
Appendix C (gimcon3) reduces its 0-g cluster by an SVD of the rate outputs in the same spirit.
"""

from __future__ import annotations

import numpy as np

from mace_fmu.util.frequency import ZERO_HZ  # fmu: inlined

# Relative to the largest modal input/output coefficient. The computed zero cluster is exact to
# ~1e-8 (mechanisms) and to round-off (rigid bodies, built geometrically).
NEGLIGIBLE = 1e-6


def signed_omega2(freq_hz: np.ndarray) -> np.ndarray:
    """Eigenvalues omega^2 [rad^2/s^2] of signed frequencies [Hz] (negative: a negative eigenvalue)."""
    freq = np.asarray(freq_hz, dtype=float)
    return np.sign(freq) * (2.0 * np.pi * freq) ** 2


def signed_frequency_hz(omega2: np.ndarray) -> np.ndarray:
    """Signed frequencies [Hz] of eigenvalues omega^2 [rad^2/s^2], the inverse of signed_omega2."""
    return np.sign(omega2) * np.sqrt(np.abs(omega2)) / (2.0 * np.pi)


def _read_directions(rows: dict[str, np.ndarray], zero: np.ndarray, basis: np.ndarray) -> tuple[int, np.ndarray]:
    """How many directions of ``basis`` (columns over the zero modes) the output rows read, and the
    rotation of ``basis`` that puts those first."""
    if not rows or not basis.shape[1]:
        return 0, np.eye(basis.shape[1])
    table = np.array(list(rows.values()))  # the threshold is relative to the largest reading of any mode
    _, s, vt = np.linalg.svd(table[:, zero] @ basis, full_matrices=True)
    return int(np.sum(s > NEGLIGIBLE * max(np.abs(table).max(), 1e-300))), vt.T


def reduce_zero_cluster(zero: np.ndarray, phi: np.ndarray, labels: tuple[str, ...], modal_b: np.ndarray,
                         disp_out: dict[str, np.ndarray], rate_out: dict[str, np.ndarray],
                         motion_out: dict[str, np.ndarray] | None = None,
                         acc_out: dict[str, np.ndarray] | None = None):
    """Rotate the zero-frequency modes so that controllable and observable directions come first.

    Returns the rotated (phi, labels, modal_b), the numbers of controllable directions and of
    directions whose displacement is kept (read by a sensor or a motion output), and the reasons
    for what goes; ``disp_out``, ``rate_out``, ``motion_out`` and ``acc_out`` (rows over the modes)
    are rotated in place. Acceleration rows do not decide what is kept: a zero-frequency direction's
    acceleration is its modal force alone, a feedthrough.
    """
    removed: list[tuple[str, str]] = []
    motion_out = {} if motion_out is None else motion_out
    acc_out = {} if acc_out is None else acc_out
    if not len(zero):
        return phi, labels, modal_b, 0, 0, removed
    u_b, s_b, _ = np.linalg.svd(modal_b[zero], full_matrices=True)
    n_ctrl = int(np.sum(s_b > NEGLIGIBLE * np.abs(modal_b).max()))
    ctrl = u_b[:, :n_ctrl]
    n_obs, turn = _read_directions(disp_out, zero, ctrl)
    ctrl = ctrl @ turn
    n_mot, turn = _read_directions(motion_out, zero, ctrl[:, n_obs:])
    ctrl[:, n_obs:] = ctrl[:, n_obs:] @ turn
    rot = np.hstack([ctrl, u_b[:, n_ctrl:]])
    if n_ctrl < len(zero):
        removed.append(("zero-frequency cluster", f"{len(zero) - n_ctrl} directions no actuator moves (internal "
                        "torques conserve the rigid-body momenta): uncontrollable, both states removed"))
    if n_obs + n_mot < n_ctrl:
        removed.append(("zero-frequency cluster", f"{n_ctrl - n_obs - n_mot} displacement directions no output "
                        "reads (rate sensing only): unobservable, displacement states removed"))
    phi = phi.copy()
    phi[:, zero] = phi[:, zero] @ rot
    new_labels = list(labels)  # a rotated direction keeps the name of the motion it is mostly made of
    for k, j in enumerate(zero):
        new_labels[j] = labels[zero[int(np.argmax(np.abs(rot[:, k])))]]
    modal_b = modal_b.copy()
    modal_b[zero] = rot.T @ modal_b[zero]
    for table in (disp_out, rate_out, motion_out, acc_out):
        for key in table:
            table[key] = table[key].copy()
            table[key][zero] = table[key][zero] @ rot
    for key in disp_out:  # below NEGLIGIBLE: what the sensor-only model drops with the states
        disp_out[key][zero[n_obs:]] = 0.0
    return phi, tuple(new_labels), modal_b, n_ctrl, n_obs + n_mot, removed


def modal_matrices(freq_hz: np.ndarray, zeta: np.ndarray, labels: tuple[str, ...], shapes: np.ndarray,
                   modal_b: np.ndarray, disp_out: dict[str, np.ndarray], rate_out: dict[str, np.ndarray],
                   output_order: list[str], motion_out: dict[str, np.ndarray] | None = None,
                   acc_out: dict[str, np.ndarray] | None = None):
    """(A, B, C, D, state names, rotated labels, rotated shapes, reasons for removed states).

    x = [eta; eta_dot] over the kept states; rows of C and D follow ``output_order`` (names of
    ``disp_out``, ``rate_out``, ``motion_out`` and ``acc_out``, whose rows are over the modes).
    ``motion_out`` are displacement outputs that do not decide the sensors' model (grid motion).
    An acceleration row a reads eta'' = -Omega^2 eta - 2 zeta Omega eta' + Phi^T b u: C gets
    -a Omega^2 and -2 a zeta Omega, D = a Phi^T b over every retained mode (the rigid bodies'
    and mechanisms' acceleration is all feedthrough); D is zero without acceleration outputs.
    """
    disp_out = {k: v.copy() for k, v in disp_out.items()}
    rate_out = {k: v.copy() for k, v in rate_out.items()}
    motion_out = {k: v.copy() for k, v in (motion_out or {}).items()}
    acc_out = {k: v.copy() for k, v in (acc_out or {}).items()}
    # signed: a negative frequency is a negative eigenvalue (an unstable mode, e.g. a softened
    # spring), whose state-space block must diverge, not oscillate
    freq = np.where(np.abs(freq_hz) < ZERO_HZ, 0.0, freq_hz)
    omega2, omega = signed_omega2(freq), 2.0 * np.pi * np.abs(freq)
    zero = np.flatnonzero(np.abs(freq_hz) < ZERO_HZ)
    shapes, labels, modal_b, n_ctrl, n_obs, removed = reduce_zero_cluster(zero, shapes, labels, modal_b, disp_out,
                                                                          rate_out, motion_out, acc_out)
    n = len(freq_hz)
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
        a[pos_r[j], k] = -omega2[j]
    for j in r_idx:
        a[pos_r[j], pos_r[j]] = -2.0 * zeta[j] * omega[j]
    b = np.vstack([np.zeros((nd, modal_b.shape[1])), modal_b[r_idx]])
    c = np.zeros((len(output_order), nd + nr))
    d = np.zeros((len(output_order), modal_b.shape[1]))
    for i, name in enumerate(output_order):
        if name in acc_out:
            row = acc_out[name]
            c[i, :nd] = (-omega2 * row)[d_idx]
            c[i, nd:] = (-2.0 * zeta * omega * row)[r_idx]
            d[i] = row @ modal_b
        elif name in disp_out or name in motion_out:
            c[i, :nd] = (disp_out[name] if name in disp_out else motion_out[name])[d_idx]
        else:
            c[i, nd:] = rate_out[name][r_idx]
    states = [f"mode{j + 1}_disp" for j in d_idx] + [f"mode{j + 1}_vel" for j in r_idx]
    return a, b, c, d, states, labels, shapes, removed
