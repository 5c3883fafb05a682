"""The parameters' covariance from the residuals themselves, for fits whose residual is not white noise.

A least-squares estimate's covariance sigma^2 (J^T J)^-1 holds when the residual is white noise of
variance sigma^2. When the model cannot reproduce the data, the residual is the misfit: correlated in
time (it rings at the structure's resonances) and from one channel to another, and its size is not the
noise's. The estimate is then still the minimiser of j^T j, and its spread over repeated tests is the
sandwich (Huber 1967; White 1982; in the frequency domain Brillinger, Time Series, 1981, sec. 6.2)

    Cov = (J^T J)^-1  M  (J^T J)^-1,   M = Var(J^T e),

with M estimated from the residual e itself, its correlations included:

- **time channels** of one test (one record): J^T e = (1/N) sum_f sum_c conj(J_c(f)) E_c(f) over the DFT
  bins f of every channel c. The bins of a stationary residual are nearly uncorrelated, so M is the sum
  over bins of s(f) s(f)^H, s(f) = sum_c conj(J_c(f)) E_c(f) / N, with a Bartlett window over
  :data:`BINS` neighbouring bins for the leakage of lightly damped resonances (Newey and West 1987, there over
  lags in time: here the residual's correlation time is the resonances' decay, seconds long, and the
  frequency domain needs no lag that long). For a white residual of variance sigma^2 the expectation is
  sigma^2 J^T J, today's formula.
- **frequency channels** of one file: the score s_l = sum_pairs (J_re,l e_re,l + J_im,l e_im,l) at each
  line, and M = sum_l s_l s_l^T with a Bartlett window over neighbouring lines, within each band of
  contiguous lines (lines either side of a gap between bands are not neighbours), its width from the scores
  themselves: Andrews's AR(1) plug-in rule (Econometrica 59, 1991, 817-858, sec. 6; :func:`bandwidth`). A
  file's lines are averages: a model error does not fluctuate from line to line as a random input's misfit
  does, it is a smooth shape over each resonance, and the width must span its correlation.
- rows in no channel (priors): their own variance, sigma^2 J^T J of those rows.

Tests and files are independent of each other: their M add. M is scaled by m / (m - n) for the n fitted
parameters (the residual is smaller than the error by that much).

How well it does, measured (``benchmarks/bench_model_error_intervals.py``, benchmarks/RESULTS.md):

- time records of structures the two-mass model lacks something of (a sensor lag or resonance, a third mode,
  an element), 40 seeded cases: the halves of a record agree within these intervals in 39 of 40 cases and
  separate records in 40 of 40 (within the noise's intervals 0 and 4 of 40). They are conservative: over 40
  records of one structure of each kind the estimates scatter by 0.30-0.42 of the mean standard deviation
  reported. The cause is the misfit's share of each bin's score: with a random input, E(f) = D(f) U(f) + noise,
  the score of a bin fluctuates only through |U(f)|^2, in the phase of conj(J(f)) D(f) and about a mean that is
  not zero bin by bin (only the sum is), while |s(f)|^2 counts the quadrature part and the mean as well. The
  real parts alone, what the time score sums, would give 0.55-1.15 (too narrow for some kinds, and 1.46-1.51
  without a model error); a wider window (5 bins: 0.24-0.38; Andrews's rule, as for lines: 0.24-0.39, and
  1.22-1.29 without a model error against 1.29-1.32) or none (0.41-0.58) changes little. The two-bin window
  is kept.
- without a model error the update reports the noise's intervals (the verdict is "explained"); the sandwich
  would be 0.87-0.89 of their width in the median, with a spread of 0.45-1.60 from fit to fit (the score's
  variance rests on the few bins about the resonances), and hold the truth less often (63-64 of 80 fits
  against 71-73 of 80).
- the three-storey frame's three measured FRF files, one update of nine parameters each: with a fixed window
  of two lines the three estimates of each parameter agree pairwise in 17 of 27 pairs (within the noise's
  intervals 15); with the width from the scores (8-17 lines of 39 per band) in 25 of 27, the other two at
  2.02 and 1.98 combined standard deviations.
- a frequency response of the model itself with 2 % log noise, its lines unweighted (40 fits of the two-mass
  model): the width from the scores gives 1.04-1.07 of the two-line window's intervals in the median and
  holds the truth as often or more (31 and 38 of 40 against 29 and 38; the noise's 38 and 38). Both are
  narrow for the parameter whose information sits in two or three lines (k1, 0.72 of the noise's width): a
  variance from so few lines scatters, and no small-sample correction is made for it.
"""

from __future__ import annotations

import numpy as np

from mace_fmu.updating.engine.residual_blocks import ResidualBlock

#: the Bartlett window's half-width over neighbouring DFT bins of a time record (a frequency response's lines
#: have theirs from their scores, :func:`bandwidth`)
BINS = 2
#: the AR(1) coefficient of Andrews's rule is held within [0, this]: below this, so that a near-unit root does not
#: give an unbounded width (the width is also at most the longest band's lines); above 0, because a negative
#: lag-one correlation of the scores is the fit's own (their sum is zero at the minimum, and a white residual
#: has nothing else), and a window over it only subtracts
RHO_LIMIT = 0.97


def residual_covariance(jacobian: np.ndarray, residual: np.ndarray, blocks: tuple[ResidualBlock, ...], *,
                        other_variance: float, bins: int | None = None) -> np.ndarray:
    """Cov of the parameters (per unit relative change) from the residual: the sandwich of the module docstring.

    Parameters
    ----------
    jacobian : ndarray
        J = d j / d delta (m, n), rows as the residual's.
    residual : ndarray
        The final residual j (m).
    blocks : tuple of ResidualBlock
        The residual's measured channels (grouped into tests by ``group``).
    other_variance : float
        sigma^2 of the rows in no channel (priors).
    bins : int, optional
        Half-width of the Bartlett window over bins or lines (weights 1 - k / (bins + 1) for lags k <= bins);
        default: :data:`BINS` over a time record's bins, and over a frequency response's lines a width from
        their scores (:func:`bandwidth`).

    Returns
    -------
    ndarray
        (n, n) covariance.
    """
    jac = np.asarray(jacobian, dtype=float)
    e = np.asarray(residual, dtype=float)
    m, n = jac.shape
    covered = np.zeros(m, dtype=bool)
    meat = np.zeros((n, n))
    for group in _groups(blocks):
        scores = _time_scores(group, jac, e) if group[0].domain == "time" else _line_scores(group, jac, e)
        runs = _runs(group[0])
        if bins is not None:
            width = bins + 1.0
        elif group[0].domain == "time":
            width = BINS + 1.0  # a stationary residual's bins: nearly independent, leakage over the resonance
        else:
            width = bandwidth(scores, runs)  # a file's lines: the model error is smooth over the resonance
        meat += _bartlett(scores, width, runs)
        for b in group:
            covered[b.rows] = True
            if b.imaginary_rows is not None:
                covered[b.imaginary_rows] = True
    rest = jac[~covered]
    meat += other_variance * rest.T @ rest
    meat *= m / max(m - n, 1)
    bread = np.linalg.pinv(jac.T @ jac)
    cov = bread @ meat @ bread
    return 0.5 * (cov + cov.T)


def _groups(blocks: tuple[ResidualBlock, ...]) -> list[list[ResidualBlock]]:
    """The blocks of one test (same group and domain, same axis) together."""
    out: dict[tuple, list[ResidualBlock]] = {}
    for b in blocks:
        out.setdefault((b.group, b.domain, b.axis.size), []).append(b)
    return list(out.values())


def _runs(block: ResidualBlock) -> list[slice]:
    """The stretches of neighbouring scores: a time block's DFT bins are one; a frequency block's lines break
    where a band ends (a step over 1.5 times the smallest), and lines of different bands are not neighbours."""
    if block.domain == "time":
        return [slice(0, block.rows.size // 2 + 1)]
    f = np.asarray(block.axis, dtype=float)
    if f.size < 2:
        return [slice(0, f.size)]
    step = np.diff(f)
    positive = step[step > 0]
    breaks = np.flatnonzero(step > 1.5 * positive.min()) + 1 if positive.size else np.zeros(0, dtype=int)
    edges = [0, *breaks.tolist(), f.size]
    return [slice(a, b) for a, b in zip(edges[:-1], edges[1:])]


def _time_scores(group: list[ResidualBlock], jac: np.ndarray, e: np.ndarray) -> np.ndarray:
    """s(f) (bins, n), complex: sum over the channels of conj(J_c(f)) E_c(f) / N, one-sided bins weighted so
    that sum_f s s^H over them is the two-sided sum."""
    n_samples = group[0].rows.size
    total = None
    for b in group:
        jf = np.fft.rfft(jac[b.rows], axis=0)
        ef = np.fft.rfft(e[b.rows])
        s = np.conj(jf) * ef[:, None] / n_samples
        total = s if total is None else total + s
    weight = np.full(total.shape[0], np.sqrt(2.0))
    weight[0] = 1.0
    if n_samples % 2 == 0:
        weight[-1] = 1.0
    return total * weight[:, None]


def _line_scores(group: list[ResidualBlock], jac: np.ndarray, e: np.ndarray) -> np.ndarray:
    """s_l (lines, n): the score of every line, summed over the pairs of one file."""
    total = None
    for b in group:
        s = jac[b.rows] * e[b.rows][:, None]
        if b.imaginary_rows is not None:
            s = s + jac[b.imaginary_rows] * e[b.imaginary_rows][:, None]
        total = s if total is None else total + s
    return total


def bandwidth(scores: np.ndarray, runs: list[slice] | None = None) -> float:
    """The Bartlett window's width for ``scores`` (lines or bins, n), real or complex: Andrews's AR(1) plug-in
    (Andrews, Econometrica 59, 1991, sec. 6), S = 1.1447 (alpha T)^(1/3),

        alpha = sum_a 4 rho_a^2 sigma_a^4 / ((1 - rho_a)^6 (1 + rho_a)^2) / sum_a sigma_a^4 / (1 - rho_a)^4,

    rho_a and sigma_a^2 the lag-one coefficient (within [0, :data:`RHO_LIMIT`]) and innovation variance of
    parameter a's scores (within each run of neighbours, ``runs``; default one), T their number; at least 1 (the
    lines alone), at most the longest run."""
    s = np.asarray(scores)
    runs = runs or [slice(0, s.shape[0])]
    num = np.zeros(s.shape[1])
    den = np.zeros(s.shape[1])
    for r in runs:
        x = s[r]
        num += np.real(np.sum(x[1:] * np.conj(x[:-1]), axis=0))
        den += np.real(np.sum(x[:-1] * np.conj(x[:-1]), axis=0))
    ok = den > 0
    if not ok.any():
        return 1.0
    rho = np.clip(num[ok] / den[ok], 0.0, RHO_LIMIT)
    innovations = np.zeros(ok.sum())
    count = 0
    for r in runs:
        x = s[r][:, ok]
        innovations += np.sum(np.abs(x[1:] - rho * x[:-1]) ** 2, axis=0)
        count += max(x.shape[0] - 1, 0)
    sigma4 = (innovations / max(count, 1)) ** 2
    scale = np.sum(sigma4 / (1 - rho) ** 4)
    if not scale > 0:
        return 1.0
    alpha = np.sum(4 * rho**2 * sigma4 / ((1 - rho) ** 6 * (1 + rho) ** 2)) / scale
    longest = max(r.stop - r.start for r in runs)
    return float(min(max(1.1447 * (alpha * s.shape[0]) ** (1 / 3), 1.0), longest))


def _bartlett(scores: np.ndarray, width: float, runs: list[slice] | None = None) -> np.ndarray:
    """sum_k w_k sum_l Re(s_l s_(l+k)^H) over lags |k| < width within each run of neighbours, w_k = 1 - |k| /
    width (width <= 1: the lines alone)."""
    runs = runs or [slice(0, scores.shape[0])]
    meat = np.zeros((scores.shape[1], scores.shape[1]))
    for r in runs:
        x = scores[r]
        meat += np.real(x.T @ np.conj(x))
        for k in range(1, min(int(np.ceil(width)), x.shape[0])):
            w = 1.0 - k / width
            if w <= 0:
                break
            cross = np.real(x[k:].T @ np.conj(x[:-k]))
            meat += w * (cross + cross.T)
    return meat
