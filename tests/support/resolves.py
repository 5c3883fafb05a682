"""Full re-solves as the independent reference of the FMUs' parameter route.

A re-solve (the deck with the parameter built in, the FE model, preload and modes solved again) knows
nothing of the reanalysis it checks. It continues the nominal modes (``compute_modes``'s default for a
parameter set: mode k is the physical mode the nominal mode k became, with its label and damping ratio),
as ``export --parameters`` does, so the comparison is the one a user makes.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.linalg import expm
from scipy.signal import butter, lfilter
from support.lifted import lifted_response

from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.parametric import ParametricSystem
from mace_fmu.iomodel.parametric_data import parametric_arrays
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.parameters.sets import ParameterSet

STEP_S = 2e-3  #: the checked record: 10 s at 2 ms
SAMPLES = 5000


def band_limited_inputs(names: list[str], driven: tuple[str, ...], *, seed: int = 1) -> np.ndarray:
    """(SAMPLES, n_inputs) inputs [V]: independent noise below 20 Hz on the inputs whose names start with one
    of ``driven``, zero elsewhere."""
    rng = np.random.default_rng(seed)
    b, a = butter(4, 20.0 * 2 * STEP_S)
    u = np.zeros((SAMPLES, len(names)))
    for k, name in enumerate(names):
        if name.startswith(driven):
            u[:, k] = lfilter(b, a, rng.standard_normal(SAMPLES))
    return u


def zoh_response(system: tuple[np.ndarray, ...], u: np.ndarray, step_s: float = STEP_S) -> np.ndarray:
    """(len(u), n_outputs) exact zero-order-hold response of (A, B, C, D) from rest, inputs u[k] held for step_s."""
    a, b, c, d = system
    ad, bd = _discretised(a.tobytes(), b.tobytes(), b.shape, step_s)
    return lifted_response(ad, bd, c, d, u)


@functools.lru_cache(maxsize=8)
def _discretised(a: bytes, b: bytes, shape: tuple[int, int], step_s: float) -> tuple[np.ndarray, np.ndarray]:
    """(Ad, Bd) of the exact zero-order hold (one matrix exponential per system: a point's inputs one at a time
    reuse it)."""
    n, m = shape
    block = expm(np.block([[np.frombuffer(a).reshape(n, n), np.frombuffer(b).reshape(n, m)],
                           [np.zeros((m, n + m))]]) * step_s)
    return block[:n, :n], block[:n, n:]


def resolved_system(configuration: str, values: dict[str, float], nominal) -> tuple[np.ndarray, ...]:
    """(A, B, C, D) of a full re-solve with moduli and springs ``values`` [Pa, N/m], continuing the modes of
    ``nominal`` (its VoltsModel)."""
    model = volts_model(compute_modes(configuration=configuration, parameters=ParameterSet(values),
                                      continue_from=nominal.structure_modes))
    system = ParametricSystem(parametric_arrays(model, physical=False))
    return system.build(system.nominal)


@functools.lru_cache(maxsize=4)
def _nominal(configuration: str):
    model = volts_model(compute_modes(configuration=configuration))
    return model, ParametricSystem(parametric_arrays(model, physical=False))


@functools.lru_cache(maxsize=64)
def _resolved(configuration: str, name: str, factor: float,
              about: tuple[tuple[str, float], ...] = ()) -> tuple[np.ndarray, ...]:
    """The re-solve with ``name`` times ``factor``, the others at ``about`` (name, value) or the deck's (cached:
    several plans share their re-solves)."""
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.parameters.sets import deck_values
    from mace_fmu.structure.file import bundled_deck_path

    values = {**deck_values(read_deck(bundled_deck_path())), **dict(about)}
    return resolved_system(configuration, {**values, name: values[name] * factor}, _nominal(configuration)[0])


def fisher_standard_deviations(configuration: str, names: list[str], tests, *, relative_step: float = 0.01,
                               seed: int = 0, about: dict[str, float] | None = None) -> dict[str, float]:
    """The standard deviations [%] of ``names`` (and of the recorded outputs' gains a test knows only to a
    percentage, as ``gain:<output>``) that an update on ``tests`` (planning.TestDesign) would report, from the
    Fisher information of full re-solves: d y / d ln p by central differences of re-solved models, each
    output in units of its noise (``noise_rms_percent`` of its RMS), the tests' excitations as plan-test
    draws them (``seed + 1000 k + j``), a gain's prior as one more row, about the deck's values or the point
    ``about`` (name -> value, the others the deck's). Nothing of the reanalysis enters."""
    from mace_fmu.updating.fmu.truth import band_limited_noise

    _, base = _nominal(configuration)
    point = tuple(sorted((about or {}).items()))
    systems = {(name, sign): _resolved(configuration, name, 1 + sign * relative_step, point)
               for name in names for sign in (1, -1)}
    gains = [(k, o) for k, t in enumerate(tests) for o in t.gain_uncertainty_percent]
    rows, priors = [], []
    for k, test in enumerate(tests):
        n = int(round(test.seconds / test.sample_time_s)) + 1
        u = np.zeros((n, len(base.inputs)))
        for j, name in enumerate(test.inputs):
            u[:, base.inputs.index(name)] = band_limited_noise(samples=n, step_s=test.sample_time_s,
                                                               band_hz=test.band_hz, seed=seed + 1000 * k + j)
        picked = [base.outputs.index(o) for o in test.outputs]

        def response(built, u=u, picked=picked, step=test.sample_time_s):
            return zoh_response(built, u, step)[:, picked]

        y0 = response(base.build(base.nominal)) if not point else \
            0.5 * (response(systems[names[0], 1]) + response(systems[names[0], -1]))  # the response at the point
        noise = test.noise_rms_percent / 100 * np.sqrt(np.mean(y0**2, axis=0))
        columns = [((response(systems[nm, 1]) - response(systems[nm, -1])) / (2 * relative_step) / noise).T.ravel()
                   for nm in names]
        for kk, o in gains:  # d y / d ln g = y for the gain of output o, zero elsewhere
            column = np.zeros_like(y0)
            if kk == k:
                column[:, test.outputs.index(o)] = y0[:, test.outputs.index(o)]
            columns.append((column / noise).T.ravel())
        rows.append(np.column_stack(columns))
    for g, (k, o) in enumerate(gains):
        prior = np.zeros(len(names) + len(gains))
        prior[len(names) + g] = 1.0 / (tests[k].gain_uncertainty_percent[o] / 100)
        priors.append(prior)
    jacobian = np.vstack(rows + ([np.array(priors)] if priors else []))
    sd = 100 * np.sqrt(np.diag(np.linalg.inv(jacobian.T @ jacobian)))
    return dict(zip(list(names) + [f"gain:{o}" for _, o in gains], sd))

