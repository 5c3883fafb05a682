"""Plain data records for the NASTRAN bulk-data cards mace-fmu understands.

No numerics live here: every record is a frozen dataclass that keeps the values as the deck
states them (SI units for the MACE deck, but the reader does not convert anything) and the
source line it came from, so that every later error can point back to ``file:line``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

# still importable from here, where it used to be defined (it is derived from the one card-to-table map now)
from mace_fmu.deck.card_tables import ELEMENT_TABLES as ELEMENT_TABLES

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Source:
    """Where a card starts in a deck file."""

    file: str  #: path of the deck file as given to the reader
    line: int  #: 1-based line number of the card's first line

    def __str__(self) -> str:
        return f"{self.file}:{self.line}"


@dataclass(frozen=True)
class Grid:
    """GRID: a node with position in coordinate system ``cp`` and displacement system ``cd``."""

    id: int  #: grid ID (> 0)
    cp: int  #: coordinate system of ``xyz`` (0 = basic)
    xyz: Vec3  #: position [m] in system ``cp``
    cd: int  #: coordinate system in which the 6 displacement components are measured
    ps: str  #: permanent single-point constraints, digits 1-6, "" for none
    source: Source  #: where the card is


@dataclass(frozen=True)
class Cord2R:
    """CORD2R: rectangular system from origin A, point B on the z-axis, point C in the x-z plane."""

    id: int  #: coordinate system ID
    rid: int  #: system in which A, B, C are given (0 = basic)
    a: Vec3  #: origin [m], in system RID
    b: Vec3  #: a point on the z axis [m], in system RID
    c: Vec3  #: a point in the x-z plane [m], in system RID
    source: Source  #: where the card is


@dataclass(frozen=True)
class Cord1R:
    """CORD1R: rectangular system with origin at grid ``g1``, z-axis towards ``g2`` and ``g3`` in the x-z plane."""

    id: int
    g1: int
    g2: int
    g3: int
    source: Source
    field: int = 2  #: NASTRAN field number of CID on the card (2, or 6 for the second system of a card)


@dataclass(frozen=True)
class CBar:
    """CBAR: two-node beam; orientation by vector ``v`` (in GA's CD system) or by grid ``g0``."""

    id: int  #: element ID
    pid: int  #: PBAR property ID
    ga: int  #: grid of end A
    gb: int  #: grid of end B
    v: Vec3 | None  #: orientation vector, None when ``g0`` is used
    g0: int | None  #: orientation grid, None when ``v`` is used
    source: Source  #: where the card is
    orientation_basic: bool = False  #: OFFT B..: ``v`` is in the basic system, not in GA's CD system


@dataclass(frozen=True)
class PBar:
    """PBAR: bar section; ``k1``/``k2`` are shear area factors (None = rigid in shear)."""

    id: int  #: property ID
    mid: int  #: MAT1 ID
    area: float  #: A [m^2]
    i1: float  #: I1, bending in plane 1 (element x-y plane) [m^4]
    i2: float  #: I2, bending in plane 2 (element x-z plane) [m^4]
    j: float  #: torsion constant [m^4]
    nsm: float  #: non-structural mass per length [kg/m]
    stress_points: tuple[float | None, ...]  #: C1 C2 D1 D2 E1 E2 F1 F2 (stress recovery only)
    k1: float | None  #: shear area factor, plane 1; None = blank = no shear flexibility
    k2: float | None  #: shear area factor, plane 2
    i12: float  #: product of inertia [m^4]
    source: Source  #: where the card is
    #: PBARL section type (e.g. "ROD") when the card was a PBARL, which NASTRAN replaces by this PBAR
    section: str | None = None


@dataclass(frozen=True)
class CBeam:
    """CBEAM: two-node beam of constant section, oriented like CBAR (vector ``v`` or grid ``g0``)."""

    id: int
    pid: int  #: PBEAM or PBEAML property ID
    ga: int
    gb: int
    v: Vec3 | None
    g0: int | None
    source: Source
    orientation_basic: bool = False  #: OFFT B..: ``v`` is in the basic system, not in GA's CD system


@dataclass(frozen=True)
class PBeam:
    """PBEAM of constant section (or a PBEAML, which NASTRAN replaces by one): the end-A values.

    Unlike PBAR, NASTRAN's PBEAM shear factors default to 1.0; 0.0 means rigid in shear.
    """

    id: int
    mid: int
    area: float  #: A [m^2]
    i1: float  #: bending inertia in plane 1 (element x-y plane) [m^4]
    i2: float  #: bending inertia in plane 2 (element x-z plane) [m^4]
    i12: float  #: product of inertia [m^4]
    j: float  #: torsion constant [m^4]
    nsm: float  #: non-structural mass per length [kg/m]
    k1: float  #: shear stiffness factor, plane 1 (0.0: rigid in shear)
    k2: float  #: shear stiffness factor, plane 2
    source: Source
    section: str | None = None  #: PBEAML section type (e.g. "ROD") when the card was a PBEAML


@dataclass(frozen=True)
class Rod:
    """CROD (properties on PROD ``pid``) or CONROD (properties on the card: ``pid`` is None)."""

    id: int
    ga: int
    gb: int
    pid: int | None  #: PROD ID, None for a CONROD
    mid: int | None  #: CONROD's MAT1 ID (None for a CROD)
    area: float  #: CONROD's A [m^2] (0.0 for a CROD)
    j: float  #: CONROD's torsion constant [m^4]
    nsm: float  #: CONROD's non-structural mass [kg/m]
    source: Source
    card: str = "CROD"  #: "CROD" or "CONROD"


@dataclass(frozen=True)
class PRod:
    """PROD: rod section."""

    id: int
    mid: int
    area: float  #: A [m^2]
    j: float  #: torsion constant [m^4]
    nsm: float  #: non-structural mass per length [kg/m]
    source: Source


@dataclass(frozen=True)
class ScalarMass:
    """CMASS1 (mass on PMASS ``pid``) or CMASS2 (mass on the card): a scalar mass between two DOFs
    (or to ground when ``g2`` is None), in each grid's displacement system."""

    id: int
    mass: float | None  #: [kg], None for a CMASS1 (see ``pid``)
    pid: int | None  #: PMASS ID of a CMASS1
    g1: int
    c1: int
    g2: int | None
    c2: int | None
    source: Source
    card: str = "CMASS2"


@dataclass(frozen=True)
class PMass:
    """PMASS: the value of a scalar mass (CMASS1)."""

    id: int
    mass: float  #: [kg]
    source: Source


@dataclass(frozen=True)
class Conm1:
    """CONM1: a symmetric 6x6 mass matrix at grid ``grid``, in system ``cid``."""

    id: int
    grid: int
    cid: int
    matrix: tuple[float, ...]  #: M11 M21 M22 M31 ... M66, the lower triangle row by row [kg, kg m, kg m^2]
    source: Source


@dataclass(frozen=True)
class SetUnion:
    """SPCADD or MPCADD: set ``sid`` is the union of ``sets`` (expanded by the reader)."""

    sid: int
    card: str
    sets: tuple[int, ...]
    source: Source


@dataclass(frozen=True)
class Rigid:
    """RBAR or RBE2 as NASTRAN reads it: components ``components`` of each dependent grid follow the
    rigid-body motion of independent grid ``independent`` (all six of its DOFs)."""

    id: int
    card: str  #: "RBAR" or "RBE2"
    independent: int
    dependent: tuple[tuple[int, str], ...]  #: (grid, components "1".."123456")
    source: Source


@dataclass(frozen=True)
class Interpolation:
    """RBE3 as NASTRAN reads it: components ``reference_components`` of grid ``reference`` follow the
    weighted least-squares rigid motion of the independent grids' listed translations."""

    id: int  #: element ID
    reference: int  #: REFGRID: the grid whose DOFs become dependent
    reference_components: str  #: REFC, "1".."123456" in the reference grid's CD system
    #: (weight, components "1".."123" in each grid's CD system, grids) per WTi/Ci/Gi,j group
    groups: tuple[tuple[float, str, tuple[int, ...]], ...]
    source: Source  #: where the card is


@dataclass(frozen=True)
class Mat1:
    """MAT1: isotropic material exactly as written (blank G or NU stays None)."""

    id: int  #: material ID
    e: float | None  #: Young's modulus [Pa]
    g: float | None  #: shear modulus [Pa]
    nu: float | None  #: Poisson's ratio
    rho: float  #: density [kg/m^3]
    source: Source  #: where the card is

    @property
    def shear_modulus(self) -> float:
        """G [Pa] by NASTRAN's MAT1 rules (G = E / (2 (1 + nu)) when G is blank)."""
        if self.g is not None:
            return self.g
        if self.e is not None and self.nu is not None:
            return self.e / (2.0 * (1.0 + self.nu))
        return 0.0

    @property
    def youngs_modulus(self) -> float:
        """E [Pa] by NASTRAN's MAT1 rules (E = 2 (1 + nu) G when E is blank)."""
        if self.e is not None:
            return self.e
        if self.g is not None and self.nu is not None:
            return 2.0 * (1.0 + self.nu) * self.g
        return 0.0


@dataclass(frozen=True)
class Conm2:
    """CONM2: lumped mass with offset and inertia about its centre of gravity.

    NASTRAN's sign convention: the inertia matrix is
    [[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]].
    """

    id: int  #: element ID
    grid: int  #: grid the mass sits on
    cid: int  #: system of offset and inertia (-1 = offset is the absolute c.g. position)
    mass: float  #: [kg]
    offset: Vec3  #: [m]
    inertia: tuple[float, float, float, float, float, float]  #: I11 I21 I22 I31 I32 I33 [kg m^2]
    source: Source  #: where the card is


@dataclass(frozen=True)
class Celas2:
    """CELAS2: scalar spring between two DOFs, or to ground when ``g2`` is None."""

    id: int  #: element ID
    k: float  #: stiffness [N/m] or [N m/rad]
    g1: int  #: first grid
    c1: int  #: component 1-6 (0 for a scalar point)
    g2: int | None  #: second grid (None: to ground)
    c2: int | None  #: component 1-6 at the second grid (None: to ground)
    source: Source  #: where the card is


@dataclass(frozen=True)
class MpcTerm:
    grid: int  #: grid ID
    component: int  #: 1-6 in the grid's CD system
    coefficient: float  #: coefficient of the term in sum(a_i u_i) = 0


@dataclass(frozen=True)
class Mpc:
    """MPC: sum(coefficient * u) = 0; the first term is the dependent DOF."""

    sid: int  #: set ID
    terms: tuple[MpcTerm, ...]  #: the equation's terms, the dependent one first
    source: Source  #: where the card is


@dataclass(frozen=True)
class Spc1:
    """SPC1: the listed components are fixed at every listed grid."""

    sid: int  #: set ID
    components: str  #: digits 1-6, sorted, no repeats
    grids: tuple[int, ...]  #: constrained grids
    source: Source  #: where the card is


@dataclass(frozen=True)
class Grav:
    """GRAV: acceleration vector scale * n in system ``cid`` [m/s^2]."""

    sid: int  #: set ID
    cid: int  #: coordinate system of the direction (0: basic)
    scale: float  #: acceleration scale [m/s^2]
    direction: Vec3  #: direction vector, in system CID
    source: Source  #: where the card is


@dataclass(frozen=True)
class Load:
    """LOAD: combination scale * sum(s_i * L_i)."""

    sid: int  #: set ID
    scale: float  #: overall scale factor S
    terms: tuple[tuple[float, int], ...]  #: (s_i, load set ID)
    source: Source  #: where the card is


@dataclass(frozen=True)
class Eigrl:
    """EIGRL: Lanczos request for modes with frequencies in [v1, v2] Hz, at most ``nd`` of them."""

    sid: int  #: set ID (the case control's METHOD)
    v1: float | None  #: [Hz]
    v2: float | None  #: [Hz]
    nd: int | None  #: number of modes wanted (None: all in the range)
    msglvl: int  #: NASTRAN's diagnostic level (read, not used)
    source: Source  #: where the card is


@dataclass(frozen=True)
class Eigr:
    """EIGR: real eigenvalue request by a method other than Lanczos (GIV, MGIV, HOU, MHOU, AHOU, INV, SINV,
    LAN); frequencies in [f1, f2] Hz, at most ``nd`` of them."""

    sid: int
    method: str
    f1: float | None  #: [Hz]
    f2: float | None  #: [Hz]
    ne: int | None  #: estimate of the number of roots in the range (INV/SINV only)
    nd: int | None  #: number of roots wanted
    norm: str  #: eigenvector normalisation: MASS, MAX or POINT
    source: Source


@dataclass(frozen=True)
class Nlparm:
    """NLPARM: nonlinear static controls (only the fields mace-fmu uses are typed)."""

    id: int  #: NLPARM ID (the case control's NLPARM)
    ninc: int  #: number of load increments (default 10)
    kmethod: str  #: AUTO, SEMI or ITER
    kstep: int | None  #: iterations between stiffness updates (None: NASTRAN's default)
    max_iter: int  #: default 25
    conv: str  #: convergence flags, e.g. "PW", "UPW", "W"
    eps_u: float  #: default 0.01
    eps_p: float  #: default 0.01
    eps_w: float  #: default 0.01
    source: Source  #: where the card is


@dataclass(frozen=True)
class Param:
    """PARAM: a named parameter with its raw values (int, float or str)."""

    name: str  #: upper case
    values: tuple[int | float | str, ...]  #: the fields after the name, as read (integers, reals or text)
    source: Source  #: where the card is


@dataclass(frozen=True)
class Subcase:
    """One SUBCASE of the case control, with the set selections mace-fmu uses."""

    id: int  #: subcase number (0: the selections above the first SUBCASE)
    spc: int | None  #: SPC set (None: none)
    mpc: int | None  #: MPC set (None: none)
    load: int | None  #: LOAD (or GRAV) set (None: none)
    nlparm: int | None  #: NLPARM ID (None: none)
    method: int | None  #: EIGRL/EIGR set (None: none)
    label: str  #: the subcase's LABEL text (empty when none)
    source: Source  #: where the SUBCASE line is


@dataclass(frozen=True)
class Deck:
    """A whole deck: bulk data keyed by ID, plus the case-control subcases."""

    path: str  #: the deck's file (or a name for a deck read from text)
    grids: Mapping[int, Grid]  #: GRID by ID
    coords: Mapping[int, Cord2R | Cord1R]  #: CORD2R and CORD1R (one ID namespace)
    bars: Mapping[int, CBar]  #: CBAR by element ID
    pbars: Mapping[int, PBar]  #: PBAR (and the PBAR a PBARL stands for) by property ID
    mat1s: Mapping[int, Mat1]  #: MAT1 by material ID
    conm2s: Mapping[int, Conm2]  #: CONM2 by element ID
    celas2s: Mapping[int, Celas2]  #: CELAS2 and CELAS1 (as the CELAS2 it amounts to) by element ID
    mpcs: Mapping[int, tuple[Mpc, ...]]  #: set ID -> equations, in deck order
    spc1s: Mapping[int, tuple[Spc1, ...]]  #: set ID -> cards, in deck order
    gravs: Mapping[int, Grav]  #: GRAV by set ID
    loads: Mapping[int, Load]  #: LOAD combinations by set ID
    eigrls: Mapping[int, Eigrl]  #: EIGRL by set ID
    nlparms: Mapping[int, Nlparm]  #: NLPARM by ID
    params: Mapping[str, Param]  #: PARAM by name
    subcases: Mapping[int, Subcase]  #: empty when the file has no case control
    global_case: Subcase | None = field(default=None)  #: selections above the first SUBCASE
    #: cards read but not modelled because they change neither mass nor stiffness: (name, count, ``file:line`` of
    #: the first)
    skipped: tuple[tuple[str, int, str], ...] = field(default=())
    beams: Mapping[int, CBeam] = field(default_factory=dict)  #: CBEAM
    pbeams: Mapping[int, PBeam] = field(default_factory=dict)  #: PBEAM and PBEAML (as the PBEAM NASTRAN makes)
    rods: Mapping[int, Rod] = field(default_factory=dict)  #: CROD and CONROD
    prods: Mapping[int, PRod] = field(default_factory=dict)  #: PROD by property ID
    scalar_masses: Mapping[int, ScalarMass] = field(default_factory=dict)  #: CMASS1 and CMASS2
    pmasses: Mapping[int, PMass] = field(default_factory=dict)  #: PMASS by property ID
    rigids: Mapping[int, Rigid] = field(default_factory=dict)  #: RBAR and RBE2 (always in force, like NASTRAN's)
    interpolations: Mapping[int, Interpolation] = field(default_factory=dict)  #: RBE3 (always in force)
    eigrs: Mapping[int, Eigr] = field(default_factory=dict)  #: EIGR by set ID
    conm1s: Mapping[int, Conm1] = field(default_factory=dict)  #: CONM1 by element ID
    #: the set IDs of the static loads the deck defines (FORCE, MOMENT, PLOAD...; read past, as they change neither
    #: mass nor stiffness) -> their card names: a LOAD selection may name one, and a 1-g preload refuses it
    static_loads: Mapping[int, tuple[str, ...]] = field(default_factory=dict)
