"""Modes from measured FRFs (experimental modal analysis): poles by the least-squares complex frequency method,
mode shapes by least-squares frequency-domain residues, both from sdypy-EMA.

Several FRF files (one per driving point, the same accelerometers in each) are fitted together: one common
denominator (LSCF, polynomial orders 2, 4, ... ``max_order``), so each mode has one pole in every file, and the
residues of every output/input pair (LSFD, lower and upper residual terms). The physical poles are chosen from the
stabilisation diagram without a hand in it: a pole is stable when a pole of the next lower order lies within 1 %
in frequency and 5 % in damping (the usual criteria); the poles that stay stable over at least a third of the
orders, clustered within 0.5 % in frequency, are the modes.

Our own code where sdypy-EMA falls short, and why:

- **the pole refinement.** LSCF is a linear least-squares estimator, biased by noise on the FRFs (Verboven 2002;
  Pintelon and Schoukens): with 1 % noise its poles are 1e-4 to 1e-3 off. Each selected pole set is refined by
  nonlinear least squares on the pole-residue model itself (the residues for given poles by sdypy-EMA's LSFD, a
  variable projection), which removes that bias: 1e-5 to 1e-6 on the same data
  (``tests/updating/modal/test_identify.py``).
- **the automatic selection.** sdypy-EMA picks poles near frequencies one gives it or by hand in a window; a
  command line has neither, so the stable clusters choose.
- **several driving points and mass-normalised shapes.** sdypy-EMA scales residues by one driving point; with
  several, the modal constants C_jk = phi_j phi_k of every measured pair are fitted together (least squares over
  the pairs whose input has a driving point among the outputs).

Conventions (sdypy-EMA's): a receptance is sum_r A_r / (i w - lambda_r) + conj(A_r) / (i w - conj(lambda_r)),
a mobility i w times it, an accelerance -w^2 times it; the modal constant is C = 2 i Im(lambda) A, which is
phi_j phi_k for a mass-normalised real mode (phi in 1/sqrt(kg) when the FRFs are in SI units).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.measured import MeasuredFrf

#: output unit -> FRF form, for a response per N or N m (SI); the form fixes how residues are fitted
_FORMS = {"m/s^2": "accelerance", "m/s2": "accelerance", "rad/s^2": "accelerance", "rad/s2": "accelerance",
          "m/s": "mobility", "rad/s": "mobility", "m": "receptance", "rad": "receptance"}
FRF_FORMS = ("accelerance", "mobility", "receptance")
#: stabilisation criteria: relative change of frequency and damping between consecutive orders
STABLE_FREQUENCY, STABLE_DAMPING = 0.01, 0.05
#: poles clustered within this relative frequency are one mode
CLUSTER_FREQUENCY = 0.005
#: a mode is a cluster stable over at least this fraction of the orders
MIN_STABLE_FRACTION = 1.0 / 3.0
#: physical poles: damping ratio in (0, this]
MAX_DAMPING = 0.3


@dataclass(frozen=True)
class IdentifiedMode:
    """One identified mode at the measured DOFs (the FRFs' outputs)."""

    frequency_hz: float  #: undamped natural frequency abs(lambda) / (2 pi) [Hz]
    damping: float  #: damping ratio -Re(lambda) / abs(lambda)
    order: int  #: the model order (number of poles of the LSCF denominator) the pole was taken at
    modal_constants: np.ndarray  #: complex C_jk (output, input) = 2 i Im(lambda) A_jk; NaN where not measured
    shape_complex: np.ndarray  #: complex shape at the outputs, its largest component 1
    shape_real: np.ndarray  #: real-normalised shape: the real mode closest to the complex one, largest component +1
    #: mass-normalised shape [1/sqrt(kg) for SI FRFs] at the outputs; None without a driving point
    shape_mass_normalised: np.ndarray | None
    mpc: float  #: modal phase collinearity of the complex shape (1: a real mode)

    @property
    def pole(self) -> complex:
        """lambda [rad/s], Im > 0."""
        w = 2 * np.pi * self.frequency_hz
        return complex(-self.damping * w, w * np.sqrt(1 - self.damping**2))


@dataclass(frozen=True)
class Stabilisation:
    """The stabilisation diagram's poles: one row per (order, pole) with 0 < damping <= MAX_DAMPING in the band."""

    orders: np.ndarray  #: model order of each pole
    frequencies_hz: np.ndarray  #: [Hz]
    damping: np.ndarray  #: damping ratios
    status: np.ndarray  #: 0 new, 1 stable in frequency, 2 stable in frequency and damping


@dataclass(frozen=True)
class Identification:
    """What :func:`identify_modes` found, and how."""

    modes: tuple[IdentifiedMode, ...]  #: the modes found, by ascending frequency
    outputs: tuple[str, ...]  #: the measured DOFs (the FRFs' outputs), in the shapes' order
    inputs: tuple[str, ...]  #: the driving points' inputs, in the modal constants' column order
    driving_points: Mapping[str, str]  #: input -> the output at its DOF (the scaling of mass-normalised shapes)
    band_hz: tuple[float, float]  #: the band fitted [Hz]
    max_order: int  #: the highest LSCF model order
    frf_form: str  #: "accelerance", "mobility" or "receptance"
    method: str  #: how the poles and residues were found, in words
    files: tuple[str, ...]  #: the FRF files
    units: Mapping[str, str]  #: signal -> unit
    stabilisation: Stabilisation  #: the stabilisation diagram's poles
    frequencies_hz: np.ndarray  #: the lines fitted [Hz]
    measured: np.ndarray  #: H (k, output, input) at those lines
    synthesised: np.ndarray  #: the identified modal model's H there (with its residual terms)
    notes: tuple[str, ...] = field(default_factory=tuple)  #: what the identification could not do, in words

    @property
    def fit_error(self) -> float:
        """norm(H_measured - H_model) / norm(H_measured) over the fitted lines and pairs (unmeasured pairs left out)."""
        ok = np.isfinite(self.measured)
        return float(np.linalg.norm((self.measured - self.synthesised)[ok]) / np.linalg.norm(self.measured[ok]))


def frf_form_of(frd: MeasuredFrf) -> str:
    """The FRF form its units say: m/s^2 per N is an accelerance, m/s per N a mobility, m per N a receptance."""
    forms = {_FORMS.get(frd.unit(o).replace(" ", "")) for o in frd.outputs}
    if len(forms) != 1 or None in forms:
        units = sorted({frd.unit(o) for o in frd.outputs})
        raise MaceError(f"{frd.source}: outputs in {', '.join(units)}: the FRF form (accelerance, mobility or "
                        "receptance) cannot be told from the units; give it (--frf-form)")
    return forms.pop()


@dataclass(frozen=True)
class _Stacked:
    """Every file's FRFs as rows of one matrix: row r is output ``out[r]`` over input ``inp[r]``."""

    frequencies_hz: np.ndarray
    rows: np.ndarray  #: (n_rows, n_lines) complex
    out: np.ndarray  #: output index of each row
    inp: np.ndarray  #: input index of each row
    outputs: tuple[str, ...]
    inputs: tuple[str, ...]
    units: dict


def _stack(frfs: Sequence[MeasuredFrf]) -> _Stacked:
    if not frfs:
        raise MaceError("no FRF files to identify modes from")
    first = frfs[0]
    outputs = first.outputs
    inputs: list[str] = []
    units: dict[str, str] = {}
    rows, out, inp = [], [], []
    for frd in frfs:
        if frd.frequencies_hz.shape != first.frequencies_hz.shape or not np.allclose(
                frd.frequencies_hz, first.frequencies_hz, rtol=max(frd.frequency_precision, 1e-9), atol=0.0):
            raise MaceError(f"{frd.source}: its frequencies differ from {first.source}'s (every file needs the same "
                            "lines)")
        if set(frd.outputs) != set(outputs):
            raise MaceError(f"{frd.source}: outputs {', '.join(frd.outputs)}, {first.source} has "
                            f"{', '.join(outputs)} (the files must measure the same DOFs)")
        for j, name in enumerate(frd.inputs):
            if name in inputs:
                raise MaceError(f"{frd.source}: input {name!r} is also in an earlier file (one file per driving "
                                "point)")
            inputs.append(name)
            for i, o in enumerate(outputs):
                rows.append(frd.response[:, frd.outputs.index(o), j])
                out.append(i)
                inp.append(len(inputs) - 1)
        for name in frd.outputs + frd.inputs:
            if name in units and units[name] != frd.unit(name):
                raise MaceError(f"{frd.source}: {name!r} in {frd.unit(name)}, {first.source} says {units[name]}")
            units[name] = frd.unit(name)
    return _Stacked(first.frequencies_hz, np.array(rows), np.array(out), np.array(inp), tuple(outputs),
                    tuple(inputs), units)


def _band(f: np.ndarray, band_hz: tuple[float, float] | None, source: str) -> tuple[float, float]:
    positive = f[f > 0]
    lo, hi = (float(positive[0]), float(f[-1])) if band_hz is None else (float(band_hz[0]), float(band_hz[1]))
    if not (0 < lo < hi) or hi > f[-1] * (1 + 1e-12) or lo < positive[0] * (1 - 1e-12):
        raise MaceError(f"band {lo:g}-{hi:g} Hz: expected 0 < LOW < HIGH within the data's {positive[0]:g}-"
                        f"{f[-1]:g} Hz ({source})")
    if np.count_nonzero((f >= lo) & (f <= hi)) < 10:
        raise MaceError(f"band {lo:g}-{hi:g} Hz holds fewer than 10 of the data's lines ({source})")
    return lo, hi


def _poles_of(all_poles: list, lo: float, hi: float) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per order: (poles, f [Hz], zeta) of the physical ones (Im > 0, in the band, 0 < zeta <= MAX_DAMPING)."""
    out = []
    for p in all_poles:
        p = np.asarray(p, dtype=complex)
        f = np.abs(p) / (2 * np.pi)
        z = -p.real / np.maximum(np.abs(p), 1e-300)
        keep = (p.imag > 0) & (f >= lo) & (f <= hi) & (z > 0) & (z <= MAX_DAMPING) & np.isfinite(p)
        out.append((p[keep], f[keep], z[keep]))
    return out


def stabilisation(per_order: list, orders: Sequence[int]) -> Stabilisation:
    """Each physical pole compared with the poles of the next lower order (STABLE_FREQUENCY, STABLE_DAMPING)."""
    o, f, z, s = [], [], [], []
    previous = (np.zeros(0), np.zeros(0), np.zeros(0))
    for order, (p, fk, zk) in zip(orders, per_order):
        for fi, zi in zip(fk, zk):
            status = 0
            if previous[1].size:
                j = int(np.argmin(np.abs(previous[1] - fi)))
                if abs(previous[1][j] - fi) <= STABLE_FREQUENCY * fi:
                    status = 2 if abs(previous[2][j] - zi) <= STABLE_DAMPING * zi else 1
            o.append(order), f.append(fi), z.append(zi), s.append(status)
        previous = (p, fk, zk)
    return Stabilisation(np.array(o, dtype=int), np.array(f), np.array(z), np.array(s, dtype=int))


def _select(per_order: list, orders: Sequence[int], stab: Stabilisation,
            near_hz: Sequence[float] | None) -> list[tuple[int, complex]]:
    """(order, pole) of each mode: clusters of fully stable poles over enough orders, the pole of the highest
    order nearest the cluster's median frequency; with ``near_hz``, the cluster nearest each frequency."""
    stable = np.flatnonzero(stab.status == 2)
    order_f = sorted(zip(stab.frequencies_hz[stable], stab.orders[stable]))
    clusters: list[list[tuple[float, int]]] = []
    for fi, oi in order_f:
        if clusters and abs(fi - np.median([c[0] for c in clusters[-1]])) <= CLUSTER_FREQUENCY * fi:
            clusters[-1].append((fi, oi))
        else:
            clusters.append([(fi, oi)])
    need = max(3, int(np.ceil(MIN_STABLE_FRACTION * len(orders))))
    if near_hz is not None:
        chosen = []
        for target in near_hz:
            if not clusters:
                raise MaceError(f"no stable pole near {target:g} Hz (no stable pole at all in the band)")
            best = min(clusters, key=lambda c: abs(np.median([x[0] for x in c]) - target))
            if abs(np.median([x[0] for x in best]) / target - 1) > 0.05:
                raise MaceError(f"no stable pole within 5 % of {target:g} Hz (nearest: "
                                f"{np.median([x[0] for x in best]):.4g} Hz)")
            chosen.append(best)
    else:
        chosen = [c for c in clusters if len({o for _, o in c}) >= need]
    out = []
    for cluster in chosen:
        centre = float(np.median([x[0] for x in cluster]))
        top = max(o for _, o in cluster)
        k = list(orders).index(top)
        p, fk, _ = per_order[k]
        j = int(np.argmin(np.abs(fk - centre)))
        out.append((top, complex(p[j])))
    return out


def _residues(poles: np.ndarray, rows: np.ndarray, f: np.ndarray, lo_i: int, hi_i: int, form: str):
    """sdypy-EMA's LSFD: (A (rows, modes), H synthesised (rows, lines)) for given poles, lower and upper residuals."""
    from sdypy.EMA.EMA import LSFD

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a, h, _, _ = LSFD(poles, rows, f, True, True, lo_i, hi_i, form)
    return a, h


def _refine(poles: np.ndarray, rows: np.ndarray, f: np.ndarray, lo_i: int, hi_i: int, form: str) -> np.ndarray:
    """Poles refined by nonlinear least squares on the pole-residue model (residues by LSFD for each trial)."""
    from scipy.optimize import least_squares

    def residual(x: np.ndarray) -> np.ndarray:
        trial = x[0::2] + 1j * x[1::2]
        _, h = _residues(trial, rows, f, lo_i, hi_i, form)
        e = (rows - h)[:, lo_i:hi_i]
        return np.concatenate([e.real.ravel(), e.imag.ravel()])

    x0 = np.column_stack([poles.real, poles.imag]).ravel()
    sol = least_squares(residual, x0, x_scale=np.abs(x0) + 1e-12, max_nfev=200)
    refined = sol.x[0::2] + 1j * sol.x[1::2]
    # a refinement that left the pole's neighbourhood (a mode the data barely show) is not taken
    moved = np.abs(refined - poles) > 0.02 * np.abs(poles)
    bad = (refined.real >= 0) | moved
    return np.where(bad, poles, refined)


def _mpc(shape: np.ndarray) -> float:
    """Modal phase collinearity (Pappa et al.): 1 for a shape whose components share one phase (a real mode)."""
    x, y = shape.real, shape.imag
    sxx, syy, sxy = x @ x, y @ y, x @ y
    if sxx + syy == 0:
        return float("nan")
    return float(((sxx - syy) ** 2 + 4 * sxy**2) / (sxx + syy) ** 2)


def _real_mode(shape: np.ndarray) -> np.ndarray:
    """sdypy-EMA's complex-to-normal mode (Gladwell and Ahmadian), largest component +1."""
    from sdypy.EMA.normal_modes import complex_to_normal_mode

    real = np.asarray(complex_to_normal_mode(shape.astype(complex)), dtype=float).ravel()
    k = int(np.argmax(np.abs(real)))
    return real / real[k]


def _mass_normalised(constants: np.ndarray, driving: Mapping[int, int], reference: np.ndarray) -> np.ndarray | None:
    """phi minimising sum |Re C_jk - phi_j phi_d(k)|^2 over the inputs k with a driving point d(k); sign as
    ``reference``. None when no input has one or the driving-point constants are not positive."""
    from scipy.optimize import least_squares

    columns = [(k, d) for k, d in driving.items() if np.isfinite(constants[d, k]) and constants[d, k].real > 0]
    if not columns:
        return None
    c = constants.real
    k0, d0 = max(columns, key=lambda kd: c[kd[1], kd[0]])
    start = c[:, k0] / np.sqrt(c[d0, k0])

    def residual(phi: np.ndarray) -> np.ndarray:
        return np.concatenate([c[:, k] - phi * phi[d] for k, d in columns])

    phi = least_squares(residual, start).x
    return phi if phi @ reference >= 0 else -phi


def identify_modes(frfs: Sequence[MeasuredFrf], *, band_hz: tuple[float, float] | None = None,
                   max_order: int = 40, frf_form: str | None = None, driving_points: Mapping[str, str] | None = None,
                   near_hz: Sequence[float] | None = None, refine: bool = True) -> Identification:
    """Identify modes from measured FRFs: LSCF poles, automatic stable-pole selection, refinement, LSFD shapes.

    Parameters
    ----------
    frfs : sequence of MeasuredFrf
        One per file (driving point); every file measures the same outputs, at the same lines.
    band_hz : (float, float), optional
        The band fitted [Hz] (default: all lines above 0 Hz).
    max_order : int
        The highest LSCF model order (the denominator's degree; orders 2, 4, ... up to it are fitted).
    frf_form : {"accelerance", "mobility", "receptance"}, optional
        What the FRFs are (default: from the outputs' units, m/s^2, m/s or m per N).
    driving_points : mapping of str to str, optional
        Input -> the output measured at its DOF, for mass-normalised shapes (default: an output of the input's
        name, e.g. both "101+X").
    near_hz : sequence of float, optional
        Take the stable poles nearest these frequencies [Hz] instead of every stable cluster.
    refine : bool
        Refine the selected poles by nonlinear least squares (default; see the module docstring).

    Returns
    -------
    Identification
        The modes, the stabilisation diagram's poles, the measured and synthesised FRFs.

    Raises
    ------
    MaceError
        Files that do not fit together, a band outside the data, an unknown FRF form, no stable mode.
    """
    from unittest import mock

    from sdypy import EMA
    from sdypy.EMA import stabilization

    if not (isinstance(max_order, int) and 4 <= max_order <= 400 and max_order % 2 == 0):
        raise MaceError(f"model order {max_order!r}: expected an even number from 4 to 400")
    data = _stack(frfs)
    sources = ", ".join(frd.source for frd in frfs)
    form = frf_form or frf_form_of(frfs[0])
    if form not in FRF_FORMS:
        raise MaceError(f"FRF form {form!r}: expected one of {', '.join(FRF_FORMS)}")
    lo, hi = _band(data.frequencies_hz, band_hz, sources)
    f = data.frequencies_hz
    keep = f <= hi * (1 + 1e-12)  # sdypy-EMA cuts at the upper limit itself; below the lower one it pads zeros
    f, rows = f[keep], data.rows[:, keep]
    with warnings.catch_warnings(), mock.patch.object(stabilization, "tqdm", lambda iterable, **_: iterable):
        warnings.simplefilter("ignore")
        model = EMA.Model(frf=rows, freq=f, lower=lo, upper=hi, pol_order_high=max_order // 2, frf_form=form)
        model.get_poles(method="lscf", show_progress=False)
    orders = [2 * (k + 1) for k in range(len(model.all_poles))]
    per_order = _poles_of(model.all_poles, lo, hi)
    stab = stabilisation(per_order, orders)
    chosen = _select(per_order, orders, stab, near_hz)
    if not chosen:
        raise MaceError(f"no mode stable over a third of the orders 2-{max_order} in {lo:g}-{hi:g} Hz ({sources}): "
                        "a higher --order, another --band-hz, or --near-hz")
    chosen.sort(key=lambda op: abs(op[1]))
    poles = np.array([p for _, p in chosen])
    lo_i = int(np.searchsorted(f, lo - 1e-12 * lo))
    hi_i = int(np.searchsorted(f, hi * (1 + 1e-12), side="right"))
    method = f"LSCF poles (sdypy-EMA), orders 2-{max_order}"
    if refine:
        poles = _refine(poles, rows, f, lo_i, hi_i, form)
        method += ", refined by nonlinear least squares on the pole-residue model"
    method += "; LSFD residues with lower and upper residual terms (sdypy-EMA)"
    a, h = _residues(poles, rows, f, lo_i, hi_i, form)
    driving = dict(driving_points or {n: n for n in data.inputs if n in data.outputs})
    unknown = [f"{k} -> {v}" for k, v in driving.items() if k not in data.inputs or v not in data.outputs]
    if unknown:
        raise MaceError(f"driving point(s) {', '.join(unknown)}: not an input and an output of the files")
    driving_index = {data.inputs.index(k): data.outputs.index(v) for k, v in driving.items()}
    modes = []
    for r, (pole, (order, _)) in enumerate(zip(poles, chosen)):
        constants = np.full((len(data.outputs), len(data.inputs)), np.nan + 0j)
        constants[data.out, data.inp] = 2j * pole.imag * a[:, r]
        measured = np.where(np.isfinite(constants), constants, 0.0)
        u, _, _ = np.linalg.svd(measured, full_matrices=False)
        shape = u[:, 0] / u[np.argmax(np.abs(u[:, 0])), 0]
        real = _real_mode(shape)
        scaled = _mass_normalised(constants, driving_index, real)
        w = abs(pole)
        modes.append(IdentifiedMode(frequency_hz=float(w / (2 * np.pi)), damping=float(-pole.real / w), order=int(order),
                                    modal_constants=constants, shape_complex=shape, shape_real=real,
                                    shape_mass_normalised=scaled, mpc=_mpc(shape)))
    band = slice(lo_i, hi_i)
    measured_h = np.full((hi_i - lo_i, len(data.outputs), len(data.inputs)), np.nan + 0j)
    synthesised = measured_h.copy()
    measured_h[:, data.out, data.inp] = rows[:, band].T
    synthesised[:, data.out, data.inp] = h[:, band].T
    notes = []
    if not driving_index:
        notes.append("no driving point among the outputs: shapes are not mass-normalised")
    return Identification(modes=tuple(modes), outputs=data.outputs, inputs=data.inputs, driving_points=driving,
                          band_hz=(lo, hi), max_order=max_order, frf_form=form, method=method,
                          files=tuple(frd.source for frd in frfs), units=data.units, stabilisation=stab,
                          frequencies_hz=f[band], measured=measured_h, synthesised=synthesised, notes=tuple(notes))


def peak_frequencies_hz(frd: MeasuredFrf, *, output: str, input: str, near_hz: Sequence[float],
                        window: float = 0.05) -> np.ndarray:
    """The frequency line of the largest |H| of one pair within ``window`` (relative) of each of ``near_hz`` [Hz]:
    the resonances an analyser's cursor reads, independent of any fit."""
    h = np.abs(frd.response[:, frd.outputs.index(output), frd.inputs.index(input)])
    f = frd.frequencies_hz
    out = []
    for target in near_hz:
        band = np.flatnonzero(np.abs(f / target - 1) <= window)
        out.append(float(f[band[np.argmax(h[band])]]))
    return np.array(out)
