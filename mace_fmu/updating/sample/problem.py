"""The automated-updating sample problem of thesis 4.3 (Figure 4.3, Tables 4.2 and 4.3).

The 'actual' two-mass system (k1 = 0.75, k2 = 1.20 N/m, physical dampers) is driven by white
noise on mass 1 and its displacement recorded with additive white measurement noise; the
initial model has k1 = k2 = 1. From those records: an H1 frequency-response estimate
(scipy.signal Welch averages, Hann window) and a measurement model fitted to it (sdypy-EMA, LSCF).
Five cases, as in the thesis: 1 modal cost on the measurement model's frequencies (modal
sensitivities, damping taken from the measurement model); 2a/2b time-domain cost identifying
the damping ratios too (reanalysis / modal sensitivities); 3a/3b log frequency-response cost on
the H1 estimate (reanalysis / modal sensitivities); and 3a/3b again with the stiffnesses and the
damping ratios updated separately (Table 4.3). Our noise is not the thesis's: its conclusions and
tolerances are what we match, not its fourth digit.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.thesis import thesis_data
from mace_fmu.updating.engine.costs import Cost, FrequencyResponseCost, ModalCost, TimeResponseCost
from mace_fmu.updating.engine.linear_model import simulate_discrete, zoh_transition
from mace_fmu.updating.engine.measured import FrequencyResponseData, MeasuredMode, TimeHistory
from mace_fmu.updating.engine.solve import Bounds, Stage, UpdateResult, UpdateSettings, update
from mace_fmu.updating.files import h1_estimate
from mace_fmu.updating.sample.family import MODE_LABELS, TwoMassFamily
from mace_fmu.updating.sample.two_mass import TwoMassSystem
from mace_fmu.util.threads import single_blas_thread

CASES = ("1", "2a", "2b", "3a", "3b")
SEPARATE_CASES = ("3a", "3b")  #: Table 4.3
QUANTITIES = ("k1", "k2", "omega1", "omega2", "zeta1", "zeta2", "omega_z", "zeta_z")
INITIAL = {"k_1": 1.0, "k_2": 1.0}


@dataclass(frozen=True)
class SampleSettings:
    """How the 'experiment' is run (the thesis states none of these numbers)."""

    sample_time_s: float = 0.5  #: 7.5 samples per period of the 0.27 Hz second mode, 22 of the first
    samples: int = 32768  #: 4.6 h of data: ~32 decay times of the 0.0035-damped first mode
    noise_fraction: float = 0.05  #: measurement noise standard deviation / output standard deviation
    segment: int = 2048  #: Welch segment (1024 s, Hann window, half overlap): 31 averages
    band_hz: tuple[float, float] = (0.02, 0.45)  #: frequency lines used by the FRF cost and the fit
    seed: int = 1990


@dataclass(frozen=True)
class MeasurementModel:
    """Modal parameters fitted to the H1 estimate (sdypy-EMA LSCF)."""

    frequencies_hz: np.ndarray
    damping: np.ndarray


@dataclass(frozen=True)
class SampleData:
    """The 'experiment': records, the H1 estimate and its measurement model."""

    actual: TwoMassSystem
    time: TimeHistory
    frf: FrequencyResponseData
    measurement_model: MeasurementModel
    settings: SampleSettings


def generate_data(settings: SampleSettings = SampleSettings(), actual: TwoMassSystem = TwoMassSystem()) -> SampleData:
    """White-noise force on mass 1 (held over each sample), displacement of mass 1 plus white noise."""
    rng = np.random.default_rng(settings.seed)
    dt, n = settings.sample_time_s, settings.samples
    plant = actual.state_space(force_on=1, measured=1)
    u = rng.standard_normal(n)
    phi, gamma = zoh_transition(plant.A, plant.B, dt)
    y = simulate_discrete(phi, gamma, plant.C, plant.D, u[:, None])[:, 0]
    y = y + settings.noise_fraction * np.std(y) * rng.standard_normal(n)
    times = dt * np.arange(n)
    record = TimeHistory(times, {"force_1": u}, {"displacement_1": y}, source="sample problem (simulated)")
    frf = h1_estimate(record, segment_length=settings.segment, band_hz=settings.band_hz)
    approx = actual.modes()[0] / (2 * np.pi)
    return SampleData(actual=actual, time=record, frf=frf, measurement_model=fit_measurement_model(frf, approx),
                      settings=settings)


def fit_measurement_model(frf: FrequencyResponseData, approx_hz: np.ndarray) -> MeasurementModel:
    """Natural frequencies [Hz] and damping ratios from an LSCF fit (sdypy-EMA) near ``approx_hz``.

    The fit runs on a time axis scaled by 1000 (frequencies in mHz): sdypy-EMA's pole search
    windows are in whole frequency units, far wider than this 0.1 Hz problem. Damping ratios do
    not change with the scaling.
    """
    import warnings
    from unittest import mock

    from sdypy import EMA
    from sdypy.EMA import stabilization

    scale = 1000.0
    # select_closest_poles draws a tqdm bar of its own, unconditionally (sdypy-EMA 0.28): the library
    # prints nothing, so the bar is swapped for the bare iterable for the length of the call
    with warnings.catch_warnings(), mock.patch.object(stabilization, "tqdm", lambda iterable, **_: iterable):
        warnings.simplefilter("ignore")
        model = EMA.Model(frf=frf.response[:, 0, 0][None, :], freq=scale * frf.frequencies_hz,
                          lower=scale * frf.frequencies_hz[0], upper=scale * frf.frequencies_hz[-1], pol_order_high=30,
                          frf_form="receptance")
        model.get_poles(show_progress=False)
        model.select_closest_poles(list(scale * np.asarray(approx_hz)), f_window=50)
    return MeasurementModel(frequencies_hz=np.asarray(model.nat_freq) / scale, damping=np.asarray(model.nat_xi))


@dataclass(frozen=True)
class CaseResult:
    """Converged parameters of one case (Table 4.2's column)."""

    case: str
    values: Mapping[str, float]  #: k1, k2 [N/m], omega1, omega2, omega_z [rad/s], zeta1, zeta2, zeta_z
    update: UpdateResult


def _quantities(family: TwoMassFamily, values: Mapping[str, float]) -> dict[str, float]:
    import control as ct

    model = family.full(values)
    poles = model.poles()
    zeros = ct.zeros(ct.ss(model.a, model.b, model.c, model.d))
    z = zeros[np.argmax(zeros.imag)]
    return {"k1": values["k_1"], "k2": values["k_2"], "omega1": abs(poles[0].eigenvalue),
            "omega2": abs(poles[1].eigenvalue), "zeta1": poles[0].damping, "zeta2": poles[1].damping,
            "omega_z": float(abs(z)), "zeta_z": float(-z.real / abs(z))}


def growing_records(record: TimeHistory, *, first: int = 64, factor: int = 4) -> list[TimeResponseCost]:
    """Time-domain costs over ever longer heads of ``record``, ending with all of it.

    Over a long record a frequency error becomes a phase drift of many cycles, and the cost has
    a local minimum at every cycle; over a record shorter than about a quarter of a drift cycle
    it has one. Each cost starts from the answer of the one before (a continuation).
    """
    lengths, n = [], first
    while n < record.times_s.size:
        lengths.append(n)
        n *= factor
    return [TimeResponseCost(record.head(n)) for n in lengths] + [TimeResponseCost(record)]


def _case_setup(case: str, data: SampleData) -> tuple[list[Cost], tuple[str, ...], str]:
    """(costs, in order, updated parameters, inclusion) of a case."""
    mm = data.measurement_model
    if case == "1":
        measured = tuple(MeasuredMode(label=label, pattern=label, frequency_hz=float(f), damping=float(z))
                         for label, f, z in zip(MODE_LABELS, mm.frequencies_hz, mm.damping))
        return [ModalCost(measured=measured, damping_weight=0.0)], ("k_1", "k_2"), "modal-sensitivity"
    stiff_and_damping = ("k_1", "k_2") + tuple(f"damping:{label}" for label in MODE_LABELS)
    inclusion = "reanalysis" if case.endswith("a") else "modal-sensitivity"
    if case.startswith("2"):
        return growing_records(data.time), stiff_and_damping, inclusion
    return [FrequencyResponseCost(data.frf, kind="log")], stiff_and_damping, inclusion


def run_case(case: str, data: SampleData, *, separate: bool = False) -> CaseResult:
    """Update k1, k2 (and the damping ratios, cases 2 and 3) from the initial model; ``separate``:
    stiffnesses and damping ratios in alternating stages (Table 4.3)."""
    if case not in CASES:
        raise MaceError(f"sample problem case must be one of {', '.join(CASES)}, got {case!r}")
    family = TwoMassFamily(masses=data.actual)
    costs, names, inclusion = _case_setup(case, data)
    start = {**INITIAL, **{f"damping:{label}": float(z) for label, z in zip(MODE_LABELS, data.measurement_model.damping)}}
    bounds = {n: Bounds(0.2 * start[n], 5.0 * start[n]) for n in names}
    if separate:
        stages = [Stage("stiffness", ("k_1", "k_2")), Stage("damping", names[2:])]
        rounds = 30
    else:
        stages, rounds = [Stage("all", names)], 1
    # the phase of a noisy H1 near its anti-resonance and at its high end jumps by up to 2 pi: a
    # robust loss keeps those few lines from deciding the fit (a plain one can stop in a wrong basin)
    robust = {"loss": "soft_l1", "loss_scale": 1.0} if isinstance(costs[0], FrequencyResponseCost) else {}
    settings = UpdateSettings(method=inclusion, penalty=False, rounds=rounds, relative_step=1e-3, tolerance=1e-5,
                              max_outer=10, **robust)
    values = dict(start)
    for cost in costs:
        result = update(family, cost, start=values, stages=stages, bounds=bounds, settings=settings)
        values = {**values, **result.values}
    return CaseResult(case=case, values=_quantities(family, values), update=result)


@dataclass(frozen=True)
class SampleProblem:
    """Every case, Tables 4.2 and 4.3 side by side with the thesis."""

    data: SampleData
    actual: Mapping[str, float]
    cases: Mapping[str, CaseResult]
    separate: Mapping[str, CaseResult] = field(default_factory=dict)


@single_blas_thread
def run_sample_problem(settings: SampleSettings = SampleSettings()) -> SampleProblem:
    """Generate the data, run the five cases and the two separate-updating variants.

    Parameters
    ----------
    settings : SampleSettings
        Record length, sample time [s], noise, H1 segment, band [Hz] and seed of the synthetic data.

    Returns
    -------
    SampleProblem
        The data, the five updating cases of Table 4.2 and the two separate-updating variants, each with
        its values and costs.
    """
    data = generate_data(settings)
    actual_values = {"k_1": data.actual.k1, "k_2": data.actual.k2}
    omega, phi = data.actual.modes()
    del phi
    plant = data.actual.state_space()
    import control as ct

    poles = sorted((p for p in ct.poles(plant) if p.imag > 0), key=abs)
    zeros = [z for z in ct.zeros(plant) if z.imag > 0]
    actual = {"k1": actual_values["k_1"], "k2": actual_values["k_2"], "omega1": float(omega[0]),
              "omega2": float(omega[1]), "zeta1": float(-poles[0].real / abs(poles[0])),
              "zeta2": float(-poles[1].real / abs(poles[1])), "omega_z": float(abs(zeros[0])),
              "zeta_z": float(-zeros[0].real / abs(zeros[0]))}
    cases = {c: run_case(c, data) for c in CASES}
    separate = {c: run_case(c, data, separate=True) for c in SEPARATE_CASES}
    return SampleProblem(data=data, actual=actual, cases=cases, separate=separate)


def format_tables(problem: SampleProblem) -> str:
    """Our Tables 4.2 and 4.3 beside the thesis's (thesis value in brackets)."""
    t42, t43 = thesis_data()["table_4_2"], thesis_data()["table_4_3"]
    names = {"k1": "k1 (N/m)", "k2": "k2 (N/m)", "omega1": "w1 (rad/s)", "omega2": "w2 (rad/s)", "zeta1": "zeta1",
             "zeta2": "zeta2", "omega_z": "wz (rad/s)", "zeta_z": "zeta_z"}

    def table(title, columns, thesis):
        head = f"{'':11s} {'actual':>16s}" + "".join(f" {c:>16s}" for c in columns)
        lines = [title, head, "-" * len(head)]
        for k, q in enumerate(QUANTITIES):
            row = f"{names[q]:11s} {problem.actual[q]:7.4f} ({t42['actual'][k]:.4f})"
            row += "".join(f" {columns[c].values[q]:7.4f} ({thesis[c][k]:.4f})" for c in columns)
            lines.append(row)
        return lines

    mm = problem.data.measurement_model
    s = problem.data.settings
    lines = table("Table 4.2: converged parameters, ours (thesis)", problem.cases, t42)
    lines += [""] + table("Table 4.3: cases 3a and 3b, stiffness and damping updated separately, ours (thesis)",
                          problem.separate, t43)
    lines += ["", f"data: {s.samples} samples at {s.sample_time_s} s, white-noise force, {100 * s.noise_fraction:g} % "
                  f"white output noise, seed {s.seed}; H1 with {s.segment}-sample Hann segments, "
                  f"{s.band_hz[0]}-{s.band_hz[1]} Hz",
              "measurement model (sdypy-EMA LSCF on H1): w = "
              + ", ".join(f"{2 * np.pi * f:.4f}" for f in mm.frequencies_hz) + " rad/s, zeta = "
              + ", ".join(f"{z:.4f}" for z in mm.damping)]
    return "\n".join(lines)


def as_json(problem: SampleProblem) -> dict:
    """The tables as data: case -> quantity -> value (and the thesis's)."""
    t42, t43 = thesis_data()["table_4_2"], thesis_data()["table_4_3"]
    out = {"actual": dict(problem.actual), "cases": {}, "separate": {}, "thesis": {"table_4_2": {}, "table_4_3": {}}}
    for c, r in problem.cases.items():
        out["cases"][c] = {q: float(r.values[q]) for q in QUANTITIES}
        out["thesis"]["table_4_2"][c] = dict(zip(QUANTITIES, t42[c]))
    for c, r in problem.separate.items():
        out["separate"][c] = {q: float(r.values[q]) for q in QUANTITIES}
        out["thesis"]["table_4_3"][c] = dict(zip(QUANTITIES, t43[c]))
    out["thesis"]["table_4_2"]["actual"] = dict(zip(QUANTITIES, t42["actual"]))
    return out
