"""A volts-volts model as data whose parameters can change: blocks, wiring and modal data, numpy only.

The arrays (see :func:`mace_fmu.iomodel.parametric_data.parametric_arrays`) hold every block of
the diagram, the 0/1 wiring matrices, the retained modes projected on the instruments and the
projected stiffness sensitivities of the physical parameters. ``build`` turns a parameter vector
into (A, B, C, D):
- physical parameters (Young's moduli, spring stiffnesses, concentrated masses): with ``resolve_*`` arrays (what
  every FMU carries where its structure allows) by solving the structure again (mace_fmu.iomodel.resolve: the 1-g
  preload's equilibrium, the modes, the instruments' influence rows times the new shapes); without them by Ritz
  reanalysis on the retained modes and static-correction vectors (mace_fmu.iomodel.reanalysis), the sensor rows
  and modal inputs carried by the same coefficients, plus each parameter's first-order change of the mode
  shapes through the 1-g preload (mace_fmu.iomodel.stiffness_route);
- modal frequency scales: each mode's frequency after the reanalysis times its scale;
- modal damping ratios, time delays (Pade), servo gains: the blocks they belong to.

Used by the updating engine and copied verbatim into FMUs (with modal_core, reanalysis and
modelica_like.algebra before it), so it imports nothing beyond numpy and scipy.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from mace_fmu.iomodel.modal_core import modal_matrices, signed_frequency_hz, signed_omega2  # fmu: inlined
from mace_fmu.iomodel.reanalysis import ritz_reanalysis  # fmu: inlined
from mace_fmu.iomodel.resolve import ExactModes  # fmu: inlined
from modelica_like.algebra import interconnect, pade  # fmu: inlined


class ParametricSystem:
    """(A, B, C, D) of a volts-volts model for any values of its named parameters."""

    def __init__(self, data: Mapping[str, np.ndarray]):
        self.data = data
        self.parameter_names = [str(n) for n in data["param_names"]]
        self.nominal = np.asarray(data["param_values"], dtype=np.float64)
        self.minimum = np.asarray(data["param_min"], dtype=np.float64)  #: declared ranges (inf: none)
        self.maximum = np.asarray(data["param_max"], dtype=np.float64)
        self.inputs = [str(n) for n in data["inputs"]]
        self.outputs = [str(n) for n in data["outputs"]]
        self.mode_labels = tuple(str(x) for x in data["mode_labels"])
        self._index = {name: k for k, name in enumerate(self.parameter_names)}
        physical = {str(x) for x in data["physical_names"]}
        self._physical = np.array([k for k, n in enumerate(self.parameter_names) if n in physical], dtype=int)
        self._damping = np.array([self._index[f"damping_mode_{k + 1}"] for k in range(len(self.mode_labels))],
                                 dtype=int)
        # arrays written before the frequency scales existed have none: those modes keep their frequencies
        self._scaled = np.array([k for k in range(len(self.mode_labels))
                                 if f"frequency_scale_mode_{k + 1}" in self._index], dtype=int)
        self._scale = np.array([self._index[f"frequency_scale_mode_{k + 1}"] for k in self._scaled], dtype=int)
        self.frequencies_hz = np.asarray(data["frequencies_hz"], dtype=np.float64)  #: after the last build
        self.state_names: list[str] = []  #: "block.state" of the last build
        #: labels of the modes behind the structure's states in the last build (zero cluster rotated)
        self.state_mode_labels: tuple[str, ...] = self.mode_labels
        #: the physical parameters by a full re-solve (arrays with ``resolve_*``), else by reanalysis
        self.exact = ExactModes(data) if "resolve_kind" in data else None

    def parameter_problems(self, params: np.ndarray) -> list[str]:
        """Why parameter values cannot be used, one sentence each (empty when all can): not finite, or
        outside the declared [min, max] (the ranges carry every limit: mace_fmu.parameters.kinds)."""
        values = np.asarray(params, dtype=np.float64)
        return [problem for k in range(len(self.parameter_names))
                if (problem := self.parameter_problem(k, float(values[k]))) is not None]

    def parameter_problem(self, k: int, value: float) -> str | None:
        """Why ``value`` cannot be parameter ``k`` (its position in the parameter vector), or None if it can."""
        name, low, high = self.parameter_names[k], self.minimum[k], self.maximum[k]
        if not np.isfinite(value):
            return f"{name} = {value} is not a finite number"
        if value < low or value > high:
            return f"{name} = {value:.17g} is outside its declared range [{low:.15g}, {high:.15g}]"
        return None

    def index(self, name: str) -> int:
        """Position of parameter ``name`` in the parameter vector."""
        return self._index[name]

    def relative_changes(self, params: np.ndarray) -> np.ndarray:
        """p_i / p_i0 - 1 of the physical parameters, in the order of ``physical_dk``."""
        return params[self._physical] / self.nominal[self._physical] - 1.0

    def modes(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(frequencies [Hz], coefficients) of the retained modes after *reanalysis* of the physical
        parameters: new mode k is Phi0 c[:n, k] + W c[n:, k], W the static-correction vectors (none in
        arrays written before they existed: c is then n x n, Phi_R of eq. 4.9)."""
        d = self.data
        correction = {}
        if "correction_stiffness" in d:
            correction = dict(correction_stiffness=d["correction_stiffness"], correction_dk=d["correction_dk"],
                              correction_coupling=d["correction_coupling"],
                              correction_massive=int(d["correction_massive"]))
        if "physical_dm" in d:  # a mass parameter: the mass changes too
            correction["projected_dm"] = d["physical_dm"]
            if "correction_dm" in d:
                correction.update(correction_dm=d["correction_dm"],
                                  correction_mass_coupling=d["correction_mass_coupling"])
        w2, coefficients = ritz_reanalysis(signed_omega2(d["frequencies_hz"]), d["physical_dk"],
                                           self.relative_changes(params), **correction)
        return signed_frequency_hz(w2), coefficients

    def _rows(self, kind: str, coefficients: np.ndarray, rel: np.ndarray) -> dict[str, np.ndarray]:
        """Output rows of one kind (``disp``, ``rate``, ``motion``, ``acc``) over the new modes: the nominal
        rows with each parameter's preload shape change, and the static corrections' rows."""
        d = self.data
        if f"{kind}_names" not in d:
            return {}
        names, rows = [str(x) for x in d[f"{kind}_names"]], np.asarray(d[f"{kind}_rows"], dtype=np.float64)
        rows = rows.reshape(len(names), len(self.mode_labels))
        if f"{kind}_preload" in d and rel is not None:
            rows = rows + np.tensordot(rel, d[f"{kind}_preload"], axes=1)
        if f"{kind}_correction" in d:
            n_w = np.shape(d["correction_stiffness"])[0]
            rows = np.hstack([rows, np.asarray(d[f"{kind}_correction"]).reshape(len(names), n_w)])
        rows = rows[:, :coefficients.shape[0]]  # modes given from outside: no correction vectors
        return {name: row @ coefficients for name, row in zip(names, rows)}

    def _exact_rows(self, kind: str, shapes: np.ndarray) -> dict[str, np.ndarray]:
        """Output rows of one kind over re-solved mode ``shapes`` (n_dof, n_modes): the influence rows times them."""
        d = self.data
        if f"{kind}_names" not in d:
            return {}
        rows = np.asarray(d[f"resolve_{kind}_rows"], dtype=np.float64) @ shapes
        return {str(name): row for name, row in zip(d[f"{kind}_names"], rows)}

    def _modal_b(self, coefficients: np.ndarray, rel: np.ndarray | None) -> np.ndarray:
        """Modal inputs of the new modes (n_modes x n_inputs), as :meth:`_rows` for the outputs."""
        d = self.data
        b = np.asarray(d["modal_b"], dtype=np.float64)
        if "preload_b" in d and rel is not None:
            b = b + np.tensordot(rel, d["preload_b"], axes=1)
        if "correction_b" in d:
            b = np.vstack([b, d["correction_b"]])
        return coefficients.T @ b[:coefficients.shape[0]]

    def structure(self, params: np.ndarray, *, frequencies_hz: np.ndarray | None = None,
                  phi_r: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, list[str]]:
        """(A, B, C, D, state names) of the modal structure block; modes by reanalysis unless given
        (``phi_r``: new modes over the nominal ones, n x n), then scaled by the frequency scales."""
        d = self.data
        # the structure solved again, off nominal: at the nominal values the exported modes are the solution (a
        # second eigen-solution's round-off, 1e-6 of the pendulum frequencies, would part the nominal FMU from them)
        if frequencies_hz is None and self.exact is not None and np.any(self.relative_changes(params) != 0.0):
            frequencies_hz, shapes = self.exact.modes(self.relative_changes(params))
            disp, rate, motion, acc = (self._exact_rows(kind, shapes) for kind in ("disp", "rate", "motion", "acc"))
            modal_b = shapes.T @ np.asarray(d["resolve_inputs"], dtype=np.float64)
        else:
            rel = None
            if frequencies_hz is None:
                frequencies_hz, phi_r = self.modes(params)
                rel = self.relative_changes(params)
            disp, rate, motion, acc = (self._rows(kind, phi_r, rel) for kind in ("disp", "rate", "motion", "acc"))
            modal_b = self._modal_b(phi_r, rel)
        frequencies_hz = np.array(frequencies_hz, dtype=np.float64)
        frequencies_hz[self._scaled] *= params[self._scale]
        self.frequencies_hz = frequencies_hz
        zeta = params[self._damping]
        a, b, c, dd, states, labels, *_ = modal_matrices(frequencies_hz, zeta, self.mode_labels,
                                                         np.zeros((0, len(zeta))), modal_b, disp,
                                                         rate, [str(x) for x in d["structure_outputs"]], motion, acc)
        self.state_mode_labels = labels
        return a, b, c, dd, states

    def _block(self, i: int, params: np.ndarray, structure) -> tuple[np.ndarray, ...]:
        """(A, B, C, D) of block i for the parameter vector ``params``."""
        d = self.data
        kind, param = str(d["block_kinds"][i]), str(d["block_params"][i])
        if kind == "structure":
            return structure[:4]
        if kind == "delay":
            return pade(float(params[self._index[param]]), int(d["pade_order"]))
        if kind == "gain":
            return np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.array([[params[self._index[param]]]])
        if kind == "pd":
            kp, kd = (float(params[self._index[p]]) for p in param.split(","))
            return np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), np.array([[kp, kd]])
        return tuple(d[f"block{i}_{m}"] for m in "ABCD")

    def build(self, params: np.ndarray, *, frequencies_hz: np.ndarray | None = None,
              phi_r: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, C, D) for the parameter vector ``params``; ``frequencies_hz`` and ``phi_r`` [Hz, -]
        replace the reanalysis (the modal-sensitivity route of the updating engine)."""
        params = np.asarray(params, dtype=np.float64)
        structure = self.structure(params, frequencies_hz=frequencies_hz, phi_r=phi_r)
        kinds = [str(k) for k in self.data["block_kinds"]]
        blocks = [self._block(i, params, structure) for i in range(len(kinds))]
        names = [str(n) for n in self.data["block_names"]]
        self.state_names = [f"{names[i]}.{s}" for i, kind in enumerate(kinds) for s in
                            (structure[4] if kind == "structure" else [f"x{k}" for k in range(blocks[i][0].shape[0])])]
        return interconnect(blocks, self.data["wiring"], self.data["entry"], self.data["exit"])
