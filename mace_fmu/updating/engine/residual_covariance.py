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
  ``bins`` neighbouring bins for the leakage of lightly damped resonances (Newey and West 1987, there over
  lags in time: here the residual's correlation time is the resonances' decay, seconds long, and the
  frequency domain needs no lag that long). For a white residual of variance sigma^2 the expectation is
  sigma^2 J^T J, today's formula.
- **frequency channels** of one file: the score s_l = sum_pairs (J_re,l e_re,l + J_im,l e_im,l) at each
  line, and M = sum_l s_l s_l^T with the same Bartlett window over neighbouring lines (a Welch estimate's
  lines share their window's leakage; a model error is smooth across them).
- rows in no channel (priors): their own variance, sigma^2 J^T J of those rows.

Tests and files are independent of each other: their M add. M is scaled by m / (m - n) for the n fitted
parameters (the residual is smaller than the error by that much).
"""

from __future__ import annotations

import numpy as np

from mace_fmu.updating.engine.residual_blocks import ResidualBlock

#: the Bartlett window's half-width over neighbouring DFT bins or frequency lines
BINS = 2


def residual_covariance(jacobian: np.ndarray, residual: np.ndarray, blocks: tuple[ResidualBlock, ...], *,
                        other_variance: float, bins: int = BINS) -> np.ndarray:
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
    bins : int
        Half-width of the Bartlett window over bins or lines.

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
        meat += _bartlett(scores, bins)
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


def _bartlett(scores: np.ndarray, bins: int) -> np.ndarray:
    """sum_k w_k sum_l Re(s_l s_(l+k)^H) over |k| <= bins, w_k = 1 - |k| / (bins + 1)."""
    meat = np.real(scores.T @ np.conj(scores))
    for k in range(1, bins + 1):
        w = 1.0 - k / (bins + 1)
        cross = np.real(scores[k:].T @ np.conj(scores[:-k]))
        meat += w * (cross + cross.T)
    return meat
