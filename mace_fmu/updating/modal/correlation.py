"""Measured modes paired with a model's by MAC at the measured DOFs: the paired table and the unpaired modes."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from mace_fmu.updating.engine.modal_model import ModalModel
from mace_fmu.updating.modal.modes_file import ModesFile

#: a measured mode whose best partner has a MAC below this has none
DEFAULT_MIN_MAC = 0.6
#: the model modes compared: from this fraction of the lowest measured frequency to this multiple of the highest
MODEL_RANGE = (0.5, 1.5)


def mac_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """MAC of every column of ``a`` with every column of ``b`` (real or complex): |a^H b|^2 / (a^H a)(b^H b)."""
    cross = np.abs(np.conj(a).T @ b) ** 2
    norms = np.outer(np.sum(np.abs(a) ** 2, axis=0), np.sum(np.abs(b) ** 2, axis=0))
    return cross / np.maximum(norms, 1e-300)


@dataclass(frozen=True)
class Pair:
    """A measured mode and its model partner."""

    measured: int  #: index into the modes file's modes
    model: int  #: index into the model's modes
    mac: float  #: their MAC at the measured DOFs
    measured_hz: float  #: [Hz]
    model_hz: float  #: [Hz]
    measured_label: str  #: the measured mode's label
    model_label: str  #: the model mode's label (carried through re-solves)

    @property
    def difference_percent(self) -> float:
        """(f_model - f_measured) / f_measured [%]."""
        return 100.0 * (self.model_hz / self.measured_hz - 1.0)


@dataclass(frozen=True)
class Correlation:
    """The MAC matrix of the measured modes against the model modes compared, the pairs, and who has no partner."""

    measured_labels: tuple[str, ...]  #: the measured modes' labels
    measured_hz: np.ndarray  #: their frequencies [Hz]
    model_labels: tuple[str, ...]  #: the model modes compared (the MAC matrix's columns)
    model_hz: np.ndarray  #: the compared model modes' frequencies [Hz]
    model_index: np.ndarray  #: their indices into the model's modes
    mac: np.ndarray  #: (measured, compared model mode)
    pairs: tuple[Pair, ...]  #: measured modes with a partner, in the measured order
    unpaired_measured: tuple[int, ...]  #: measured modes whose best partner has MAC < min_mac
    unpaired_model: tuple[int, ...]  #: model modes (indices into the model) in the measured band with no partner
    min_mac: float  #: the MAC a pair needs
    scaled: np.ndarray | None = None  #: per pair: relative difference of the mass-normalised shapes (None: unscaled)

    def rms_difference_percent(self) -> float:
        """RMS of the paired frequency differences [%]."""
        return float(np.sqrt(np.mean([p.difference_percent ** 2 for p in self.pairs]))) if self.pairs else float("nan")


def correlate(measured: ModesFile, model: ModalModel, *, min_mac: float = DEFAULT_MIN_MAC,
              band_hz: tuple[float, float] | None = None) -> Correlation:
    """Pair measured and model modes by MAC (one-to-one, the largest total MAC) at the measured DOFs.

    Parameters
    ----------
    measured : ModesFile
        The measured modes (their real-normalised shapes are compared).
    model : ModalModel
        The model's modes at the same DOFs (:class:`~mace_fmu.updating.modal.family.StructureFamily`).
    min_mac : float
        A measured mode whose partner's MAC is below this is unpaired.
    band_hz : (float, float), optional
        The measured band: model modes in it without a partner are named (default: the modes file's band, else
        the measured modes' range).

    Returns
    -------
    Correlation
        The MAC matrix, the pairs (frequencies, differences, MAC) and the unpaired modes on either side.
    """
    f_meas = np.array([m.frequency_hz for m in measured.modes])
    lo, hi = MODEL_RANGE[0] * f_meas.min(), MODEL_RANGE[1] * f_meas.max()
    compared = np.flatnonzero((model.frequencies_hz >= lo) & (model.frequencies_hz <= hi))
    u = np.column_stack([m.shape_real for m in measured.modes])
    mac = mac_matrix(u, model.shapes[:, compared]) if compared.size else np.zeros((len(f_meas), 0))
    pairs, unpaired = [], []
    if compared.size:
        # the largest total MAC; between equal MACs (few DOFs see few shapes apart) the nearer frequency
        ratio = np.abs(np.log(model.frequencies_hz[compared][None, :] / f_meas[:, None]))
        rows, cols = linear_sum_assignment(-(mac - 1e-3 * ratio))
        partner = dict(zip(rows, cols))
    else:
        partner = {}
    scaled = []
    for i, m in enumerate(measured.modes):
        j = partner.get(i)
        if j is None or mac[i, j] < min_mac:
            unpaired.append(i)
            continue
        k = int(compared[j])
        pairs.append(Pair(measured=i, model=k, mac=float(mac[i, j]), measured_hz=m.frequency_hz,
                          model_hz=float(model.frequencies_hz[k]), measured_label=m.label,
                          model_label=model.labels[k]))
        if m.shape_mass_normalised is not None:
            v = model.shapes[:, k]
            s = np.sign(m.shape_mass_normalised @ v) or 1.0
            scaled.append(float(np.linalg.norm(m.shape_mass_normalised - s * v)
                                / np.linalg.norm(m.shape_mass_normalised)))
    band = band_hz or tuple(measured.identification.get("band_hz", ())) or (f_meas.min(), f_meas.max())
    taken = {p.model for p in pairs}
    unpaired_model = tuple(int(k) for k in compared if k not in taken and band[0] <= model.frequencies_hz[k] <= band[1])
    return Correlation(measured_labels=tuple(m.label for m in measured.modes), measured_hz=f_meas,
                       model_labels=tuple(model.labels[k] for k in compared),
                       model_hz=model.frequencies_hz[compared], model_index=compared, mac=mac, pairs=tuple(pairs),
                       unpaired_measured=tuple(unpaired), unpaired_model=unpaired_model, min_mac=min_mac,
                       scaled=np.array(scaled) if measured.scaled and len(scaled) == len(pairs) else None)


def format_correlation(c: Correlation, model: ModalModel, *, title: Sequence[str] = ()) -> str:
    """The paired table (frequencies, difference, MAC, the mass-normalised shapes' difference) and the unpaired."""
    lines = list(title)
    scaled = c.scaled is not None
    head = (f"{'measured':10s} {'f meas [Hz]':>11s} | {'model mode':28s} {'f model [Hz]':>12s} {'diff [%]':>8s} "
            f"{'MAC':>6s}" + (f" {'shape diff [%]':>14s}" if scaled else ""))
    lines += [head, "-" * len(head)]
    for k, p in enumerate(c.pairs):
        lines.append(f"{p.measured_label:10s} {p.measured_hz:11.4f} | {p.model_label[:28]:28s} {p.model_hz:12.4f} "
                     f"{p.difference_percent:+8.2f} {p.mac:6.3f}" + (f" {100 * c.scaled[k]:14.1f}" if scaled else ""))
    if c.pairs:
        lines.append(f"RMS frequency difference over {len(c.pairs)} pair(s): {c.rms_difference_percent():.2f} %; "
                     f"MAC {min(p.mac for p in c.pairs):.3f} to {max(p.mac for p in c.pairs):.3f}")
    for i in c.unpaired_measured:
        best = int(np.argmax(c.mac[i])) if c.mac.shape[1] else None
        near = (f" (best: {c.model_labels[best]} at {c.model_hz[best]:.4g} Hz, MAC {c.mac[i, best]:.2f})"
                if best is not None else " (no model mode in range)")
        lines.append(f"unpaired measured mode: {c.measured_labels[i]} at {c.measured_hz[i]:.4f} Hz, no model mode "
                     f"with MAC >= {c.min_mac:g}{near}")
    for k in c.unpaired_model:
        lines.append(f"unpaired model mode in the measured band: {model.labels[k]} at {model.frequencies_hz[k]:.4f} Hz")
    return "\n".join(lines)
