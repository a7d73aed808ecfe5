"""Chi-square bands for consistency tests (NEES, NIS) and the number of
independent samples a time-correlated series holds."""
import math

import numpy as np


def chi2_quantile(p, dof):
    """Wilson-Hilferty approximation of the chi-square quantile (good to
    ~1 % for dof >= 3, plenty for a band)."""
    # Standard normal quantile by bisection on erf.
    lo, hi = -10.0, 10.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if 0.5 * (1.0 + math.erf(mid / math.sqrt(2.0))) < p:
            lo = mid
        else:
            hi = mid
    z = 0.5 * (lo + hi)
    k = float(dof)
    return k * (1.0 - 2.0 / (9.0 * k) + z * math.sqrt(2.0 / (9.0 * k))) ** 3


def effective_samples(values):
    """N / (1 + 2 sum of autocorrelations up to the first negative one): the
    number of independent samples a time-correlated series is worth."""
    x = np.asarray(values, dtype=float)
    n = len(x)
    if n < 4:
        return float(n)
    x = x - x.mean()
    var = float(np.dot(x, x)) / n
    if var <= 0.0:
        return float(n)
    tau = 1.0
    for lag in range(1, n // 2):
        rho = float(np.dot(x[:-lag], x[lag:])) / (n * var)
        if rho <= 0.0:
            break
        tau += 2.0 * rho
    return max(1.0, n / tau)


def nees_band(dof, samples, confidence=0.95):
    """Two-sided band of the average of `samples` independent chi-square(dof)
    values."""
    total = dof * samples
    alpha = 1.0 - confidence
    return (chi2_quantile(alpha / 2.0, total) / samples,
            chi2_quantile(1.0 - alpha / 2.0, total) / samples)
