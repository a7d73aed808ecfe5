"""Chi-square bands for consistency tests (NEES, NIS) and the number of
independent samples a time series of pose errors holds."""
import math

import numpy as np


def normal_quantile(p):
    """The standard normal quantile, by bisection on erf."""
    lo, hi = -10.0, 10.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if 0.5 * (1.0 + math.erf(mid / math.sqrt(2.0))) < p:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def chi2_quantile(p, dof):
    """Wilson-Hilferty approximation of the chi-square quantile (good to
    ~1 % for dof >= 3, plenty for a band)."""
    z = normal_quantile(p)
    k = float(dof)
    return k * (1.0 - 2.0 / (9.0 * k) + z * math.sqrt(2.0 / (9.0 * k))) ** 3


def whitened(error, covariance):
    """L^-1 e for the Cholesky factor L of the covariance: a consistent
    filter's errors whitened this way are independent standard normal
    components, whose squares sum to the NEES."""
    return np.linalg.solve(np.linalg.cholesky(np.asarray(covariance, dtype=float)),
                           np.asarray(error, dtype=float))


def nees_effective_samples(whitened_errors):
    """The number of independent chi-square(dof) samples the average NEES of
    a time series of whitened errors (rows of `whitened`, one per pose) is
    worth, for its band.

    A pose's error is correlated with its neighbours' over a long stretch:
    within one loop much of it is the map's own error against the start,
    which lasts the whole run. Per component the autocorrelation rho is
    taken about zero, the mean a consistent filter's errors have: about
    the run's own mean, an error that lasts the run would vanish from it
    and the run would seem to hold many more samples than it does. Each
    component's square then has the autocorrelation rho^2 (Gaussian
    errors), which sets its integrated correlation time tau = 1 + 2 sum
    rho^2 (lags up to the first rho <= 0, at most half the series); the
    average NEES has the variance sum_i 2 tau_i / n, that of the average of
    dof * n / sum_i tau_i independent chi-square(dof) values."""
    w = np.asarray(whitened_errors, dtype=float)
    if w.ndim != 2 or len(w) == 0:
        return 0.0
    n, dof = w.shape
    if n < 4:
        return float(n)
    taus = []
    for x in w.T:
        power = float(np.dot(x, x))
        tau = 1.0
        if power > 0.0:
            for lag in range(1, n // 2):
                rho = float(np.dot(x[:-lag], x[lag:])) / power
                if rho <= 0.0:
                    break
                tau += 2.0 * rho * rho
        taus.append(tau)
    return max(1.0, dof * n / sum(taus))


def nees_band(dof, samples, confidence=0.95):
    """Two-sided band of the average of `samples` independent chi-square(dof)
    values."""
    total = dof * samples
    alpha = 1.0 - confidence
    return (chi2_quantile(alpha / 2.0, total) / samples,
            chi2_quantile(1.0 - alpha / 2.0, total) / samples)


def student_t_quantile(p, dof):
    """Cornish-Fisher approximation of Student's t quantile (at the 97.5 %
    point within 0.2 % of the tables for dof >= 5, 3 % low at 2)."""
    z = normal_quantile(p)
    v = float(dof)
    return (z + (z ** 3 + z) / (4.0 * v) + (5.0 * z ** 5 + 16.0 * z ** 3 + 3.0 * z) / (96.0 * v * v)
            + (3.0 * z ** 7 + 19.0 * z ** 5 + 17.0 * z ** 3 - 15.0 * z) / (384.0 * v ** 3))


def runs_band(expected, averages, confidence=0.95):
    """Two-sided band for the mean of independent runs' averages under the
    hypothesis that each has the mean `expected`: expected +- t * s / sqrt(R)
    with s the runs' own spread. It needs no count of independent samples
    within a run, which a single run cannot give when part of its error
    lasts the whole run."""
    x = np.asarray(averages, dtype=float)
    if len(x) < 2:
        return (float("nan"), float("nan"))
    half = student_t_quantile(1.0 - (1.0 - confidence) / 2.0, len(x) - 1) * \
        float(np.std(x, ddof=1)) / math.sqrt(len(x))
    return (expected - half, expected + half)
