"""Records of structures the two-mass model cannot reproduce, and the consistency study of their intervals.

When the model lacks something the data hold (a sensor's dynamics, a mode, an element),
do the intervals an update reports still cover what another record of the same structure gives? Each kind of
model-form error below is a continuous-time system driven by a white force on mass 1 and read at mass 1
(zero-order hold, 0.5 s samples as the thesis's two-mass records), with white measurement noise of
``NOISE`` times the noise-free output's RMS. The model fitted to it is always the two-mass family
(:class:`~mace_fmu.updating.sample.family.TwoMassFamily`): k1 and k2 updated, the modal damping ratios held
at those of the actual two-mass system. The size of each error is drawn from the case's seed. The kind
"none" is the model itself, the control; :func:`frf_control` is the control of the frequency path (a
frequency response of the model itself, its lines unweighted).

A case gives two comparisons:

- **split record**: one record of ``samples`` samples, its first half (``record.head(N / 2)``) against its
  second half (the whole record simulated, compared from half-time on: ``TimeResponseCost(record,
  compare_from_s=t_half)``);
- **separate tests**: the whole record against a second record of the same structure, with its own force
  and noise.

Every fit of a case starts from the same point, 1 % off the k1 and k2 whose two-mass model has the
structure's resonances (:func:`matched_start`, what a modal test of the structure gives): a time cost of a
lightly damped structure has a local minimum at every cycle of phase drift, and a fit started in another
cycle ends there, which no interval about the fit's own minimum can cover (the benchmark shows it, starting
from the actual two-mass system's k1 and k2 instead).

Two estimates agree when |a - b| <= 1.96 sqrt(sd_a^2 + sd_b^2) for every parameter, sd each fit's standard
deviation. The intervals compared: the sandwich (``stage_uncertainty(..., residual_blocks=...)``), what the
update reports (the sandwich unless the model explains the data), the noise-based covariance with the stated
noise (``noise_variance`` from the noise floor) and with the residual's own level (j^T j / (m - n)). With
intervals of exactly 95 % for each of two parameters, two estimates agree in both with a probability between
90 % and 95 % (0.95^2 = 90.25 % if the two gaps are independent).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from support.two_mass_records import true_damping

from mace_fmu.updating.engine.convergence import convergence_report, time_noise_floor
from mace_fmu.updating.engine.costs import TimeResponseCost
from mace_fmu.updating.engine.linear_model import simulate_discrete, zoh_transition
from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.engine.solve import Bounds, Stage, UpdateSettings, update
from mace_fmu.updating.engine.uncertainty import Z95, stage_uncertainty
from mace_fmu.updating.sample.family import MODE_LABELS, TwoMassFamily
from mace_fmu.updating.sample.two_mass import TwoMassSystem

STEP_S = 0.5  #: sample time [s] (Nyquist 1 Hz; the two-mass modes are at 0.090 and 0.268 Hz)
NOISE = 0.05  #: noise RMS / noise-free output RMS
NAMES = ("k_1", "k_2")
#: the kinds of model-form error, each a structure (or sensor) the two-mass model lacks something of
KINDS = ("sensor lag", "sensor resonance", "extra mode", "extra element", "none")
ERRORS = KINDS[:-1]
#: the intervals compared: the sandwich always, the noise's (the stated noise; the residual's own level), and
#: what the update reports (the sandwich unless the model explains the data)
METHODS = ("sandwich", "reported", "noise (stated)", "noise (residual level)")
ACTUAL = {"k_1": TwoMassSystem().k1, "k_2": TwoMassSystem().k2}  #: the actual two-mass system's [N/m]


@dataclass(frozen=True)
class Truth:
    """A continuous-time system force_1 [N] -> displacement_1 [m] (as a sensor reads it)."""

    kind: str
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    what: str  #: the model error in words, with its drawn size

    def record(self, *, samples: int, seed: int) -> tuple[TimeHistory, float]:
        """A white force (seeded) and the output with white noise of ``NOISE`` times its noise-free RMS; and the
        noise's standard deviation [m]."""
        rng = np.random.default_rng(seed)
        u = rng.standard_normal(samples)
        phi, gamma = zoh_transition(self.a, self.b, STEP_S)
        y = simulate_discrete(phi, gamma, self.c, np.zeros((1, 1)), u[:, None])[:, 0]
        sd = NOISE * float(np.sqrt(np.mean(y**2)))
        y = y + sd * rng.standard_normal(samples)
        return TimeHistory(STEP_S * np.arange(samples), {"force_1": u}, {"displacement_1": y},
                           source=f"{self.kind}, seed {seed}"), sd


def _chain(k: np.ndarray, m: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, B, C) of masses ``m`` with stiffness ``k`` and damping ``c`` matrices, force on and displacement of
    the first mass."""
    n = len(m)
    m_inv = np.diag(1.0 / m)
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-m_inv @ k, -m_inv @ c]])
    b = np.zeros((2 * n, 1))
    b[n, 0] = 1.0 / m[0]
    cc = np.zeros((1, 2 * n))
    cc[0, 0] = 1.0
    return a, b, cc


def _with_sensor(a: np.ndarray, b: np.ndarray, c: np.ndarray, num: np.ndarray, den: np.ndarray):
    """The structure (A, B, C) read through a sensor of transfer function num / den (unit static gain)."""
    import scipy.signal

    sa, sb, sc, sd = scipy.signal.tf2ss(num, den)
    n, ns = a.shape[0], sa.shape[0]
    big = np.block([[a, np.zeros((n, ns))], [sb @ c, sa]])
    return big, np.vstack([b, np.zeros((ns, 1))]), np.hstack([sd @ c, sc])


def truth(kind: str, seed: int) -> Truth:
    """The structure of one case: the actual two-mass system with the model error of ``kind``, its size
    drawn from ``seed`` ("none": the two-mass model itself, for the control)."""
    rng = np.random.default_rng(10_000 + seed)
    s = TwoMassSystem()
    k, m, c = s.stiffness_matrix, np.array([s.m1, s.m2]), s.damping_matrix
    if kind == "none":  # the model family itself at the actual k1, k2 and damping ratios: no model error at all
        model = TwoMassFamily(masses=s).full({**ACTUAL, **{f"damping:{label}": z
                                                          for label, z in zip(MODE_LABELS, true_damping())}})
        return Truth(kind, model.a, model.b, model.c, what="the two-mass model itself")
    if kind == "sensor lag":  # a first-order sensor the model has not: tau y' + y = x
        tau = rng.uniform(0.2, 0.6)
        return Truth(kind, *_with_sensor(*_chain(k, m, c), np.array([1.0]), np.array([tau, 1.0])),
                     what=f"first-order sensor lag {tau:.3g} s")
    if kind == "sensor resonance":  # a second-order sensor: its resonance above the structure's modes
        f_s, z_s = rng.uniform(0.45, 0.7), rng.uniform(0.1, 0.3)
        w = 2 * math.pi * f_s
        return Truth(kind, *_with_sensor(*_chain(k, m, c), np.array([w**2]), np.array([1.0, 2 * z_s * w, w**2])),
                     what=f"sensor resonance {f_s:.3g} Hz, damping {z_s:.2g}")
    if kind == "extra mode":  # a small mass on a spring hung on mass 1: a third mode the model lacks
        m3, f3 = rng.uniform(0.05, 0.15), rng.uniform(0.35, 0.55)
        k3 = m3 * (2 * math.pi * f3) ** 2
        k3m = np.zeros((3, 3))
        k3m[:2, :2] = k
        k3m += k3 * np.array([[1, 0, -1], [0, 0, 0], [-1, 0, 1]])
        c3 = np.zeros((3, 3))
        c3[:2, :2] = c
        c3 += 0.01 * np.array([[1, 0, -1], [0, 0, 0], [-1, 0, 1]])
        return Truth(kind, *_chain(k3m, np.array([s.m1, s.m2, m3]), c3),
                     what=f"extra mass {m3:.3g} kg on mass 1, alone at {f3:.3g} Hz")
    if kind == "extra element":  # a spring from mass 2 to the wall and a damper between the masses
        kg, cx = rng.uniform(0.05, 0.15), rng.uniform(0.005, 0.02)
        k2 = k + kg * np.array([[0, 0], [0, 1]])
        c2 = c + cx * np.array([[1, -1], [-1, 1]])
        return Truth(kind, *_chain(k2, m, c2),
                     what=f"spring {kg:.3g} N/m from mass 2 to the wall, damper {cx:.3g} N s/m between the masses")
    raise ValueError(f"unknown kind {kind!r}; known: {', '.join(KINDS)}")


def matched_start(system: Truth) -> dict:
    """k1 and k2 whose two-mass model has the structure's two modes nearest the actual system's (the data's
    resonances, as a modal test finds them): where a time fit must start, within a quarter cycle of phase drift
    of its minimum (a lightly damped record has a local minimum at every cycle). For the structures with a
    sensor or an element the model lacks this is not the actual system's k1 and k2 (a spring from mass 2 to
    the wall of 2 % of k2 moves the matched k1 by 5 %)."""
    poles = np.linalg.eigvals(system.a)
    poles = poles[(poles.imag > 0) & (-poles.real / np.abs(poles) < 0.1)]  # the structure's modes, not a sensor's
    nominal = TwoMassSystem().modes()[0]
    w = np.array([np.abs(poles)[np.argmin(np.abs(np.abs(poles) - w0))] for w0 in nominal])
    trace, det = float(np.sum(w**2)), float(np.prod(w**2))  # k1 + 2 k2 and k1 k2 of unit masses
    k1 = 0.5 * (trace - math.sqrt(trace**2 - 8 * det))
    return {"k_1": k1, "k_2": det / k1}


@dataclass(frozen=True)
class Fit:
    """One update's estimates and their standard deviations [SI] by each method."""

    values: dict  #: name -> estimate [N/m]
    sd: dict  #: method -> name -> standard deviation [N/m]
    verdict: str  #: the convergence report's, with the stated noise
    converged: bool
    rms_over_noise: float  #: the residual's RMS over the stated noise's
    method: str = ""  #: the reported covariance's method: "residuals" (the sandwich) or "noise"
    jacobian: np.ndarray = field(default=None, repr=False)  #: the last linearisation's J (per unit relative change)
    residual: np.ndarray = field(default=None, repr=False)  #: the final residual
    blocks: tuple = field(default=(), repr=False)  #: the cost's residual blocks

    def covers(self, method: str, truth: dict) -> bool:
        """The 95 % interval of every parameter holds its value in ``truth``."""
        return all(abs(self.values[n] - truth[n]) <= Z95 * self.sd[method][n] for n in NAMES)


def fit(cost: TimeResponseCost, *, noise_sd: float, start: dict) -> Fit:
    """k1 and k2 of the two-mass family fitted to ``cost`` from ``start`` (cost-sensitivity method,
    reanalysis; no penalty: the uncertainty is the data's), the verdict with the stated noise (``noise_sd``
    [m], given as a fraction of the compared part's RMS: a record's first half, the structure starting from
    rest, is quieter than the whole), and each method's standard deviations. "reported" is what ``mace-fmu
    update`` reports (``_write_fmu_update``): the sandwich when the verdict is not "explained" or the residual
    is not white, else the noise's."""
    values = {**start, **{f"damping:{label}": z for label, z in zip(MODE_LABELS, true_damping())}}
    bounds = {n: Bounds(0.2 * values[n], 5.0 * values[n]) for n in NAMES}
    settings = UpdateSettings(method="cost-sensitivity", perturbation="reanalysis", penalty=False,
                              relative_step=1e-4, max_outer=20)
    result = update(TwoMassFamily(masses=TwoMassSystem()), cost, start=values, stages=[Stage("stiffness", NAMES)],
                    bounds=bounds, settings=settings)
    measured = cost.compared.outputs["displacement_1"]
    fraction = noise_sd / float(np.sqrt(np.mean(measured**2)))
    floor = time_noise_floor(cost, noise_rms_fraction=fraction)
    report = convergence_report(result, noise_floor=floor, cost=cost)
    sigma2 = floor.expected_cost / result.final_residual.size
    stages = {"sandwich": stage_uncertainty(result, noise_variance=sigma2, residual_blocks=cost.residual_blocks())[0],
              "noise (stated)": stage_uncertainty(result, noise_variance=sigma2)[0],
              "noise (residual level)": stage_uncertainty(result)[0]}
    from_residuals = report.verdict != "explained" or (report.residuals is not None and not report.residuals.white)
    stages["reported"] = stages["sandwich" if from_residuals else "noise (stated)"]
    vals = {n: float(result.values[n]) for n in NAMES}
    sd = {method: {n: vals[n] * st.standard_deviation_percent[n] / 100 for n in NAMES}
          for method, st in stages.items()}
    rms = float(np.sqrt(np.mean(result.final_residual**2)))
    jacobian = [it.sensitivities.matrix for it in result.history if it.sensitivities is not None][-1]
    return Fit(values=vals, sd=sd, verdict=report.verdict, converged=result.converged,
               rms_over_noise=rms / math.sqrt(sigma2), method=stages["reported"].method, jacobian=jacobian,
               residual=result.final_residual, blocks=cost.residual_blocks())


def agree(a: Fit, b: Fit, method: str) -> bool:
    """|a - b| <= 1.96 sqrt(sd_a^2 + sd_b^2) for every parameter."""
    return all(gap <= Z95 for gap in normalised_gaps(a, b, method).values())


def normalised_gaps(a: Fit, b: Fit, method: str) -> dict:
    """|a - b| / sqrt(sd_a^2 + sd_b^2) per parameter (at most 1.96: agreement)."""
    return {n: abs(a.values[n] - b.values[n]) / math.hypot(a.sd[method][n], b.sd[method][n]) for n in NAMES}


@dataclass(frozen=True)
class Case:
    """One seeded case: the split-record and separate-test comparisons."""

    kind: str
    seed: int
    what: str  #: the model error and its drawn size
    start: dict  #: where the four fits started
    first: Fit  #: the record's first half
    second: Fit  #: its second half (simulated from the start, compared from half-time)
    whole: Fit  #: the whole record
    other: Fit  #: a second record of the same structure

    def split_agrees(self, method: str) -> bool:
        return agree(self.first, self.second, method)

    def tests_agree(self, method: str) -> bool:
        return agree(self.whole, self.other, method)

    def fits(self) -> tuple[Fit, ...]:
        return (self.first, self.second, self.whole, self.other)


def run_case(kind: str, seed: int, *, samples: int = 4096, start: str = "matched") -> Case:
    """Four fits of one case: the record's halves, the whole record and a second record (another force and
    noise, the same structure). ``start``: "matched", 1 % off the structure's matched k1 and k2
    (:func:`matched_start`, what a modal test gives), or "actual", 2 % off the actual two-mass system's (for a
    structure whose matched values lie further off, a start in another cycle of phase drift)."""
    system = truth(kind, seed)
    if start == "matched":
        matched = matched_start(system)
        begin = {"k_1": 0.99 * matched["k_1"], "k_2": 1.01 * matched["k_2"]}
    else:
        actual = TwoMassSystem()
        begin = {"k_1": 0.98 * actual.k1, "k_2": 1.02 * actual.k2}
    record, sd = system.record(samples=samples, seed=2 * seed + 1)
    second, sd_second = system.record(samples=samples, seed=2 * seed + 2)
    half = samples // 2
    return Case(kind=kind, seed=seed, what=system.what, start=begin,
                first=fit(TimeResponseCost(record.head(half)), noise_sd=sd, start=begin),
                second=fit(TimeResponseCost(record, compare_from_s=float(record.times_s[half])), noise_sd=sd,
                           start=begin),
                whole=fit(TimeResponseCost(record), noise_sd=sd, start=begin),
                other=fit(TimeResponseCost(second), noise_sd=sd_second, start=begin))


#: lines of the frequency-response control [Hz]: two bands, 0.5 mHz apart, about the two-mass resonances
CONTROL_LINES_HZ = np.concatenate([np.arange(0.080, 0.100, 0.0005), np.arange(0.255, 0.281, 0.0005)])
FRF_NOISE = 0.02  #: the control's log-FRF noise: standard deviation of log magnitude and of phase [1, rad]


@dataclass(frozen=True)
class FrfFit:
    """A fit of k1 and k2 to a frequency response of the model itself: estimates [N/m], standard deviations
    [N/m] by the noise (the stated FRF_NOISE), the sandwich as shipped (the width from the lines' scores) and
    the sandwich with the fixed two-line window it had before."""

    values: dict
    sd: dict  #: "noise", "sandwich", "sandwich, two lines" -> name -> sd [N/m]


def frf_control(seed: int) -> FrfFit:
    """The no-model-error control of the frequency path: the two-mass model's response at CONTROL_LINES_HZ
    times exp(complex white noise of FRF_NOISE), fitted on the log-FRF cost (lines unweighted, as a file
    without coherence is)."""
    from mace_fmu.updating.engine.costs import FrequencyResponseCost
    from mace_fmu.updating.engine.measured import FrequencyResponseData
    from mace_fmu.updating.engine.residual_covariance import residual_covariance

    family = TwoMassFamily(masses=TwoMassSystem())
    damping = {f"damping:{label}": z for label, z in zip(MODE_LABELS, true_damping())}
    h = family.full({**ACTUAL, **damping}).frequency_response(CONTROL_LINES_HZ)
    rng = np.random.default_rng(seed)
    noise = FRF_NOISE * (rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape))
    data = FrequencyResponseData(CONTROL_LINES_HZ, ("force_1",), ("displacement_1",), h * np.exp(noise),
                                 source=f"control, seed {seed}")
    cost = FrequencyResponseCost(data)
    start = {"k_1": 0.99 * ACTUAL["k_1"], "k_2": 1.01 * ACTUAL["k_2"], **damping}
    result = update(family, cost, start=start, stages=[Stage("stiffness", NAMES)],
                    bounds={n: Bounds(0.2 * start[n], 5.0 * start[n]) for n in NAMES},
                    settings=UpdateSettings(method="cost-sensitivity", perturbation="reanalysis", penalty=False,
                                            relative_step=1e-4, max_outer=20))
    values = {n: float(result.values[n]) for n in NAMES}
    jac = [it.sensitivities.matrix for it in result.history if it.sensitivities is not None][-1]
    covariances = {"noise": FRF_NOISE**2 * np.linalg.inv(jac.T @ jac),
                   "sandwich": residual_covariance(jac, result.final_residual, cost.residual_blocks(),
                                                   other_variance=0.0),
                   "sandwich, two lines": residual_covariance(jac, result.final_residual, cost.residual_blocks(),
                                                              other_variance=0.0, bins=2)}
    return FrfFit(values=values, sd={k: {n: values[n] * float(np.sqrt(c[i, i])) for i, n in enumerate(NAMES)}
                                     for k, c in covariances.items()})
