"""Mode labels from each mode's kinetic- and strain-energy distribution, as in Tables 3.10 and 5.1.

Conventions of the structure data file: the flexible backbone is the component ``bus``;
suspension cables are components named ``cable_<n>``; mechanism names read
``"<stage> <axis>"`` (e.g. ``"primary gimbal X"``).

Rules, in order:
1. |f| below ``zero_hz``: the cluster is rotated into rigid-body motions (those that lie in it)
   and mechanisms (unit relative rotation at one hinge, none at the others).
2. >= 50 % of the kinetic energy in cables: violin mode, order = number of half waves, in- or
   out-of-plane with respect to the plane of the cables.
3. < 50 % of the potential energy as bus strain: gravity-stiffened mode. When the gimbal bars
   store more potential energy than the suspension elements (cables, springs, attachment
   plates), a pendulum of the gimbal stage that rotates most; otherwise a suspension mode named
   after the dominant rigid motion of the test article (all but the cables), e.g. "Z tilt".
4. Otherwise bus bending about Y or Z, or torsion, whichever holds most bus strain energy;
   bending modes are numbered by frequency within their family, torsion modes by the end
   (primary at low x, secondary at high x) holding most of the torsional strain energy.

MACE's rules apply when the structure file asks for them (``[labels] rules = "mace"``, as the
bundled mace_em.toml does). Any other structure gets labels that are true of any structure
instead: rigid-body names for the zero cluster, else the family that holds most of the mode's
strain energy, numbered by frequency: "1st bending about Z", "2nd torsion", "1st axial", "1st
spring mode" (bending assigned to the basic axis each bar's bending axis is closest to).

Every label of a model is unique: a violin mode shared by two cables says whether they swing in
phase or in antiphase, and any label that still repeats is numbered in frequency order, the
first keeping the plain label (Table 5.1's "torsion, primary end", then "2nd torsion, primary end").
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np

from mace_fmu.fe.assembly import FEModel
from mace_fmu.fe.corotational import (BarState, bar_dof_indices, bar_energies, deformation_jacobian,
                                      undeformed_jacobian)
from mace_fmu.fe.modal import Modes
from mace_fmu.structure.file import StructureSpec
from mace_fmu.util.frequency import ZERO_HZ
from mace_fmu.util.threads import usable_cores

_AXES = "XYZ"
_RIGID_NAMES = ("X translation", "Y translation", "Z translation", "X rotation", "Y rotation", "Z rotation")
_SUSPENSION_NAMES = ("X suspension pendulum (X translation)", "bounce (Y translation)",
                     "Z suspension pendulum (Z translation)", "X twist (X rotation)",
                     "Y suspension twist (Y rotation)", "Z tilt (Z rotation)")


def ordinal(n: int) -> str:
    """1 -> '1st', 2 -> '2nd', 11 -> '11th'."""
    suffix = "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"{n}{suffix}"


def rigid_body_vectors(model: FEModel, reference: np.ndarray) -> np.ndarray:
    """(n_dof, 6) unit rigid translations and rotations about ``reference`` [m], basic axes."""
    n_grid = len(model.positions)
    d = np.zeros((n_grid, 6, 6))
    r = model.positions - reference
    d[:, 0:3, 0:3] = np.eye(3)
    d[:, 3:6, 3:6] = np.eye(3)
    # u = theta x r = -skew(r) theta
    d[:, 0, 4], d[:, 0, 5] = r[:, 2], -r[:, 1]
    d[:, 1, 3], d[:, 1, 5] = -r[:, 2], r[:, 0]
    d[:, 2, 3], d[:, 2, 4] = r[:, 1], -r[:, 0]
    return d.reshape(6 * n_grid, 6)


def _grid_mask(model: FEModel, grids: frozenset[int]) -> np.ndarray:
    return np.array([g in grids for g in model.dofs.grid_ids])


#: bars per chunk when the modes' natural deformations are computed
_CHUNK = 4000


#: natural DOFs of a bar by family: 0 stretch, 1/4 torsion, 2/5 rotation about element y, 3/6 about element z
_FAMILIES = ((0,), (1, 4), (2, 5), (3, 6))


def _family_energies(jacobian: np.ndarray, k_natural: np.ndarray, dof_index: np.ndarray, shapes: np.ndarray,
                     bars: np.ndarray) -> np.ndarray:
    """(4, len(bars), n_modes) strain energy of the chosen ``bars`` per mode in each family of natural DOFs
    (stretch, torsion, bending about element y, about element z): 1/2 d_f^T k_ff d_f with d = B phi.

    In chunks of bars: the gathered shapes of 70k bars would be 350 MB. The families' blocks are at most
    2 x 2, so their quadratic forms are written out rather than run through stacked products. The chunks
    share the usable cores: numpy's gathers, stacked products and element-wise arithmetic release Python's
    lock (the wide lattice's 78,304 bars and 50 modes: 0.48-0.54 s on one core, 0.23-0.27 s on two).
    """
    out = np.empty((len(_FAMILIES), len(bars), shapes.shape[1]))

    def chunk(start: int) -> None:
        rows = bars[start:start + _CHUNK]
        d = np.matmul(jacobian[rows], shapes[dof_index[rows]])  # (chunk, 7, n_modes) natural deformations
        k = k_natural[rows]
        for f, family in enumerate(_FAMILIES):
            energy = out[f, start:start + len(rows)]
            energy[:] = 0.0
            for i in family:
                for j in family:
                    energy += k[:, i, j, None] * d[:, i] * d[:, j]
            energy *= 0.5

    starts = range(0, len(bars), _CHUNK)
    if len(starts) < 2:
        for start in starts:
            chunk(start)
        return out
    with ThreadPoolExecutor(max_workers=usable_cores()) as threads:
        list(threads.map(chunk, starts))
    return out


class _Energies:
    """Per-mode energy bookkeeping shared by the rules."""

    def __init__(self, model: FEModel, modes: Modes, spec: StructureSpec, state: BarState | None,
                 bus_bar: np.ndarray | None = None):
        self.model, self.modes, self.spec = model, modes, spec
        phi = modes.shapes
        n_grid = len(model.positions)
        self.ke = (phi * (model.mass @ phi)).reshape(n_grid, 6, -1)  # sums to 1 per mode
        if bus_bar is None:
            bus = spec.components.get("bus", frozenset())
            bus_bar = np.array([model.dofs.grid_ids[a] in bus and model.dofs.grid_ids[b] in bus
                                for a, b in zip(model.bars.node_a, model.bars.node_b)], dtype=bool)
        # None: the undeformed structure, whose jacobian has a closed form
        b = undeformed_jacobian(model.bars) if state is None else deformation_jacobian(model.bars, state)[1]
        stretch, self.bus_torsion, plane_y, plane_z = _family_energies(
            b, model.bars.k_natural, bar_dof_indices(model.bars), phi, np.flatnonzero(bus_bar))
        frames = model.bars.frames0[bus_bar]
        # each plane's energy with the bending axis of that plane: element z for x-y, element y for x-z
        energies = np.concatenate([plane_z, plane_y])  # (2 n_bar, n_modes)
        axes = np.abs(np.concatenate([frames[:, 2], frames[:, 1]]))  # (2 n_bar, 3)
        # Assign each bar's plane energy to the basic axis it bends about (Y or Z: MACE's bus lies along X).
        about_y = (axes[:, 1] >= axes[:, 2]) @ energies
        about_z = (axes[:, 1] < axes[:, 2]) @ energies
        self.bus_bending = {"Y": about_y, "Z": about_z}
        self.bus_stretch = stretch.sum(0)
        self.bus_strain = self.bus_torsion.sum(0) + about_y + about_z + self.bus_stretch
        # the same plane energies by the basic axis each bar's bending axis lies closest to
        closest = np.argmax(axes, axis=1)
        self.bending_about = (closest == np.arange(3)[:, None]) @ energies
        xa = model.positions[model.bars.node_a[bus_bar], 0]
        self.torsion_x = (self.bus_torsion * xa[:, None]).sum(0) / np.maximum(self.bus_torsion.sum(0), 1e-300)

    def component_ke(self, name_filter) -> np.ndarray:
        """Kinetic-energy fraction of all components whose name passes ``name_filter``."""
        grids = frozenset().union(*(g for n, g in self.spec.components.items() if name_filter(n)))
        return self.ke[_grid_mask(self.model, grids)].sum(axis=(0, 1))


def _mechanism_rotations(modes: Modes, spec: StructureSpec) -> np.ndarray:
    """(n_mech, n_modes) relative rotation at each mechanism in its released component."""
    out = []
    for m in spec.mechanisms:
        if m.dependent in modes.dofs.grid_ids and m.independent in modes.dofs.grid_ids:
            out.append(modes.shape(m.dependent, m.component, system="cd")
                       - modes.shape(m.independent, m.component, system="cd"))
        else:
            out.append(np.zeros(len(modes)))
    return np.array(out).reshape(len(spec.mechanisms), len(modes))


def _m_orthonormal(vectors: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """Gram-Schmidt in the mass inner product, in column order (the first columns keep their direction)."""
    gram = vectors.T @ mass @ vectors
    return vectors @ np.linalg.inv(np.linalg.cholesky(gram).T)


def _zero_cluster(model: FEModel, modes: Modes, spec: StructureSpec, zero: np.ndarray, reference: np.ndarray
                  ) -> tuple[np.ndarray, list[str]]:
    """Replace the zero-frequency shapes by exact rigid-body motions and single-mechanism motions.

    Rigid motions are built geometrically rather than projected from the computed shapes, which
    are exact only to ~1e-7: internal torques then give exactly zero modal force on them.
    """
    z = modes.shapes[:, zero]
    mass = model.mass
    rigid = rigid_body_vectors(model, reference)
    rigid[np.all(modes.shapes == 0.0, axis=1)] = 0.0  # constrained DOFs
    names: list[str] = []
    cols = []
    for r in range(6):
        a = z.T @ (mass @ rigid[:, r])
        norm2 = rigid[:, r] @ mass @ rigid[:, r]
        if norm2 > 0 and a @ a >= 0.999 * norm2:
            cols.append(rigid[:, r])
            names.append(f"rigid body: {_RIGID_NAMES[r]}")
    basis = _m_orthonormal(np.array(cols).T, mass) if cols else np.zeros((len(z), 0))
    rest = z - basis @ (basis.T @ mass @ z)  # the mechanism part of the zero space, rank k - n_rigid
    w, v = np.linalg.eigh(rest.T @ mass @ rest)
    rest = rest @ v[:, len(cols):]
    sub = replace(modes, frequencies_hz=np.zeros(rest.shape[1]), shapes=rest)
    jac = _mechanism_rotations(sub, spec)
    largest = np.abs(jac).max() if jac.size else 0.0  # no mechanism part left: nothing moves
    moving = np.linalg.norm(jac, axis=1) > 1e-6 * max(largest, 1e-300)
    mechs = rest @ np.linalg.pinv(jac[moving])
    names += [f"mechanism: {m.name}" for m, mv in zip(spec.mechanisms, moving) if mv]
    if len(names) != z.shape[1]:
        return z, [f"zero-frequency mode {i + 1}" for i in range(z.shape[1])]
    return _m_orthonormal(np.hstack([basis, mechs]), mass), names


def _cable_profile(model: FEModel, modes: Modes, spec: StructureSpec, cable: str, m: int, along: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(fraction of the cable's length, translations (n, 3), unit axis) of cable grids in mode ``m``.

    Grids are ordered along ``along`` (so that parallel cables are walked the same way).
    """
    grids = sorted((g for g in spec.components[cable] if g in model.dofs.grid_ids),
                   key=lambda g: model.positions[model.dofs.grid_index(g)] @ along)
    pts = np.array([model.positions[model.dofs.grid_index(g)] for g in grids])
    chord = pts[-1] - pts[0]
    fraction = (pts - pts[0]) @ chord / (chord @ chord)
    disp = np.array([modes.shapes[model.dofs.indices(g)[:3], m] for g in grids])
    return fraction, disp, chord / np.linalg.norm(chord)


def _cable_label(model: FEModel, modes: Modes, spec: StructureSpec, m: int, ke_cables: dict[str, float]) -> str:
    """'2nd in-plane violin, cable 3'; 'cables 1 and 3' when two share the energy, with
    'in-phase' or 'antiphase' before 'violin' (the two cables' lateral deflections alike or opposite)."""
    cables = sorted(n for n, e in ke_cables.items() if e >= 0.25) or [max(ke_cables, key=lambda n: ke_cables[n])]
    main = max(cables, key=lambda n: ke_cables[n])
    all_cable = np.array([model.positions[model.dofs.grid_index(g)] for n in ke_cables
                          for g in spec.components[n] if g in model.dofs.grid_ids])
    _, _, vt = np.linalg.svd(all_cable - all_cable.mean(axis=0))
    normal = vt[2]
    fraction, disp, axis = _cable_profile(model, modes, spec, main, m, vt[0])
    in_plane = np.cross(normal, axis)
    numbers = " and ".join(n.split("_", 1)[1] for n in cables)
    axial = disp @ axis
    if np.sum(axial**2) > np.sum((disp - np.outer(axial, axis)) ** 2):
        # the carriage bouncing on the cable's axial stiffness, not a string mode
        return f"axial (carriage bounce), {'cables' if len(cables) > 1 else 'cable'} {numbers}"

    def lateral(fraction: np.ndarray, disp: np.ndarray, direction: np.ndarray) -> np.ndarray:
        """Deflection along ``direction`` relative to the moving chord."""
        return (disp - np.outer(1.0 - fraction, disp[0]) - np.outer(fraction, disp[-1])) @ direction

    w_in, w_out = lateral(fraction, disp, in_plane), lateral(fraction, disp, normal)
    plane, w, direction = (("in-plane", w_in, in_plane) if np.sum(w_in**2) >= np.sum(w_out**2)
                           else ("out-of-plane", w_out, normal))
    significant = w[1:-1][np.abs(w[1:-1]) > 0.05 * np.abs(w).max()]
    order = 1 + int(np.sum(np.diff(np.sign(significant)) != 0))
    phase = ""
    if len(cables) == 2:  # the cables are parallel: compare deflections at the same fractions of length
        other = next(n for n in cables if n != main)
        f_other, d_other, _ = _cable_profile(model, modes, spec, other, m, vt[0])
        w_other = np.interp(fraction, f_other, lateral(f_other, d_other, direction))
        phase = "in-phase " if w @ w_other >= 0.0 else "antiphase "
    return f"{ordinal(order)} {plane} {phase}violin, {'cables' if len(cables) > 1 else 'cable'} {numbers}"


def unique_labels(labels: list[str], frequencies_hz: np.ndarray) -> tuple[str, ...]:
    """Labels with every repeat numbered: the lowest-frequency mode keeps the label (Table 5.1's
    'torsion, primary end'), the k-th gets its ordinal in front ('2nd torsion, primary end')."""
    seen: dict[str, int] = {}
    out = list(labels)
    for m in np.argsort(frequencies_hz, kind="stable"):
        seen[labels[m]] = seen.get(labels[m], 0) + 1
        if seen[labels[m]] > 1:
            out[m] = f"{ordinal(seen[labels[m]])} {labels[m]}"
    if len(set(out)) != len(out):  # a numbered label equal to another label: number by index instead
        out = [f"{lab} (mode {m + 1})" if out.count(lab) > 1 else lab for m, lab in enumerate(out)]
    return tuple(out)


def _generic_labels(model: FEModel, modes: Modes, state: BarState | None, zero: np.ndarray,
                    labels: list[str]) -> list[str]:
    """Labels that are true of any structure: the family holding most of a mode's strain energy.

    Families: axial, torsion and bending about the basic X, Y or Z axis (bar strain energy, each
    bar's bending plane assigned to the basic axis its bending axis lies closest to), and spring
    (CELAS energy), numbered by frequency within the family: "1st bending about Z", "2nd torsion".
    Zero-frequency modes keep the names the cluster rotation gave them (rigid bodies).
    """
    out = list(labels)
    if not len(model.bars.ids) and not len(model.spring_ids):
        return [x or f"mode {m + 1}" for m, x in enumerate(out)]
    en = _Energies(model, modes, StructureSpec.empty(), state, bus_bar=np.ones(len(model.bars.ids), dtype=bool))
    springs = (0.5 * model.spring_constants[:, None] * (model.spring_vectors @ modes.shapes) ** 2).sum(0)
    families = {"axial": en.bus_stretch, "torsion": en.bus_torsion.sum(0), "bending about X": en.bending_about[0],
                "bending about Y": en.bending_about[1], "bending about Z": en.bending_about[2], "spring": springs}
    counters = dict.fromkeys(families, 0)
    for m in np.argsort(modes.frequencies_hz, kind="stable"):
        if zero[m]:
            continue
        family = max(families, key=lambda f: families[f][m])
        counters[family] += 1
        out[m] = f"{ordinal(counters[family])} {family}" + (" mode" if family == "spring" else "")
    return out


def label_modes(model: FEModel, modes: Modes, spec: StructureSpec, *, reference: np.ndarray,
                state: BarState | None = None, bar_forces: np.ndarray | None = None,
                zero_hz: float = ZERO_HZ) -> Modes:
    """Modes with labels (zero-frequency cluster rotated into named motions).

    ``reference`` [m] is the point for rigid rotations and the end split of torsion modes (the
    centre node); ``state`` is the configuration the modes are about (preloaded state for the
    large-displacement 1-g model, undeformed when None): bus strain is measured about it.
    ``bar_forces`` are the preload's natural bar forces (none: unstressed).

    Parameters
    ----------
    model : FEModel
        The model the modes belong to.
    modes : Modes
        The modes to label.
    spec : StructureSpec
        Component names (MACE's, or none: generic labels).
    reference : numpy.ndarray
        (3,) point [m] for rigid rotations and the torsion split.
    state : BarState, optional
        The configuration the modes are about (preloaded; None: undeformed).
    bar_forces : numpy.ndarray, optional
        (n_bars, 7) natural bar forces of the preload [N, N m].
    zero_hz : float
        Modes below this [Hz] form the zero-frequency cluster.

    Returns
    -------
    Modes
        The same modes with labels, the zero cluster rotated into named motions.
    """
    zero = np.abs(modes.frequencies_hz) < zero_hz
    shapes = modes.shapes.copy()
    labels = [""] * len(modes)
    if zero.any():
        rotated, names = _zero_cluster(model, modes, spec, zero, reference)
        shapes[:, zero] = rotated
        for i, name in zip(np.flatnonzero(zero), names):
            labels[i] = name
        # Exact flexible modes are mass-orthogonal to rigid and mechanism motions; the computed
        # ones are so only to the accuracy of the zero cluster (~1e-7), so purify them.
        flex = shapes[:, ~zero]
        flex -= rotated @ (rotated.T @ model.mass @ flex)
        shapes[:, ~zero] = flex / np.sqrt(np.einsum("im,im->m", flex, model.mass @ flex))
    modes = replace(modes, shapes=shapes)
    if spec.label_rules != "mace":
        return replace(modes, labels=unique_labels(_generic_labels(model, modes, state, zero, labels),
                                                   modes.frequencies_hz))
    en = _Energies(model, modes, spec, state)
    cable_names = sorted(n for n in spec.components if n.startswith("cable_"))
    ke_cable = {n: en.component_ke(lambda c, n=n: c == n) for n in cable_names}
    forces = bar_forces if bar_forces is not None else np.zeros((len(model.bars.ids), 7))
    pe_bar = bar_energies(model.bars, state, forces, modes.shapes)  # state None: undeformed, unstressed
    pe_spring = 0.5 * model.spring_constants[:, None] * (model.spring_vectors @ modes.shapes) ** 2
    in_suspension = np.array([i in spec.suspension_elements for i in model.bars.ids])
    gimbal_grids = frozenset().union(*(g for n, g in spec.components.items() if "gimbal" in n))
    touches_gimbal = np.array([model.dofs.grid_ids[a] in gimbal_grids or model.dofs.grid_ids[b] in gimbal_grids
                               for a, b in zip(model.bars.node_a, model.bars.node_b)]) & ~in_suspension
    pe_suspension = pe_bar[in_suspension].sum(0) + pe_spring[[i in spec.suspension_elements
                                                               for i in model.spring_ids]].sum(0)
    pe_gimbal = pe_bar[touches_gimbal].sum(0)
    mech = _mechanism_rotations(modes, spec)
    omega2 = (2.0 * np.pi * modes.frequencies_hz) ** 2
    rigid = rigid_body_vectors(model, reference)
    article = ~_grid_mask(model, frozenset().union(*(spec.components[n] for n in cable_names))) \
        if cable_names else np.ones(len(model.positions), dtype=bool)
    rows = np.repeat(article, 6)
    m_art = model.mass[np.ix_(np.flatnonzero(rows), np.flatnonzero(rows))].toarray()
    d_art = rigid[rows]
    m_rigid = d_art.T @ m_art @ d_art
    # lstsq: a line of point masses has no inertia about its own axis
    fit = np.linalg.lstsq(m_rigid, d_art.T @ m_art @ modes.shapes[rows], rcond=1e-12)[0]
    rigid_ke = np.diag(m_rigid)[:, None] * fit**2
    counters = {"Y": 0, "Z": 0}
    for m in np.argsort(modes.frequencies_hz):
        if zero[m]:
            continue
        cable_total = sum(e[m] for e in ke_cable.values())
        if cable_total >= 0.5:
            labels[m] = _cable_label(model, modes, spec, m, {n: e[m] for n, e in ke_cable.items()})
        elif en.bus_strain[m] < 0.25 * omega2[m]:  # less than half of the potential energy w^2/2
            if pe_gimbal[m] > pe_suspension[m]:
                gimbals = [(abs(mech[i, m]), mm) for i, mm in enumerate(spec.mechanisms) if "gimbal" in mm.name]
                best = max(gimbals, key=lambda t: t[0])[1]
                stage, axis = best.name.rsplit(" ", 1)
                labels[m] = f"{axis} gimbal pendulum, {stage.replace(' gimbal', '')}"
            else:
                labels[m] = _SUSPENSION_NAMES[int(np.argmax(rigid_ke[:, m]))]
        else:
            tor = en.bus_torsion[:, m].sum()
            family = max((("Y", en.bus_bending["Y"][m]), ("Z", en.bus_bending["Z"][m]), ("T", tor)),
                         key=lambda t: t[1])[0]
            if family == "T":
                end = "primary" if en.torsion_x[m] < reference[0] else "secondary"
                labels[m] = f"torsion, {end} end"
            else:
                counters[family] += 1
                labels[m] = f"{ordinal(counters[family])} {family} bending"
    return replace(modes, labels=unique_labels(labels, modes.frequencies_hz))
