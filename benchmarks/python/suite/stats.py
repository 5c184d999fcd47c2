"""Small statistics helpers for the benchmark suite (numpy only: Debian has no extra deps here)."""
import math

import numpy as np


def fitted_order(step_sizes, errors):
    """Slope of log(error) against log(step size): the observed order of the error."""
    return float(np.polyfit(np.log(np.asarray(step_sizes, float)), np.log(np.asarray(errors, float)), 1)[0])


def drift_with_error(times_ps, energies):
    """Drift (kJ/mol/ns) and its standard error: the least-squares slope's error, inflated by the
    residuals' statistical inefficiency (energies sampled along a trajectory are correlated)."""
    t, e = np.asarray(times_ps, float), np.asarray(energies, float)
    slope, intercept = np.polyfit(t, e, 1)
    residuals = e - (slope * t + intercept)
    if t.size < 4:
        return float(slope) * 1000.0, float("nan")
    naive = math.sqrt(np.dot(residuals, residuals) / (t.size - 2) / np.sum((t - t.mean()) ** 2))
    return float(slope) * 1000.0, naive * math.sqrt(statistical_inefficiency(residuals)) * 1000.0


def ks_two_sample(a, b):
    """Two-sample Kolmogorov-Smirnov statistic and asymptotic p-value (of decorrelated series: the p-value is only
    as honest as that subsampling)."""
    a, b = np.sort(np.asarray(a, float)), np.sort(np.asarray(b, float))
    values = np.concatenate([a, b])
    cdf_a = np.searchsorted(a, values, side="right") / a.size
    cdf_b = np.searchsorted(b, values, side="right") / b.size
    d = float(np.max(np.abs(cdf_a - cdf_b)))
    n = a.size * b.size / (a.size + b.size)
    return d, kolmogorov_survival((math.sqrt(n) + 0.12 + 0.11 / math.sqrt(n)) * d)


def kolmogorov_survival(x):
    """P(K > x) for the Kolmogorov distribution."""
    if x < 1e-3:
        return 1.0
    total = 0.0
    for k in range(1, 101):
        term = 2.0 * (-1) ** (k - 1) * math.exp(-2.0 * k * k * x * x)
        total += term
        if abs(term) < 1e-12:
            break
    return min(max(total, 0.0), 1.0)


def statistical_inefficiency(series):
    """Integrated autocorrelation time (in samples) by summing the autocorrelation to its first zero."""
    x = np.asarray(series, float) - np.mean(series)
    n = x.size
    var = np.dot(x, x) / n
    if var == 0:
        return 1.0
    g = 1.0
    for lag in range(1, n // 2):
        c = np.dot(x[:-lag], x[lag:]) / ((n - lag) * var)
        if c <= 0:
            break
        g += 2.0 * c * (1.0 - lag / n)
    return max(g, 1.0)


def decorrelate(series):
    """Every g-th sample, g the statistical inefficiency: roughly independent samples."""
    g = int(math.ceil(statistical_inefficiency(series)))
    return np.asarray(series)[::g]
