"""The χ² quantile without scipy.stats: the same bits as ``scipy.stats.chi2.ppf``."""

from __future__ import annotations

import numpy as np
from scipy.stats import chi2

from gnc.chi2 import chi2_quantile


def test_the_quantile_is_scipy_stats_bit_for_bit() -> None:
    p = np.concatenate([[0.0, 1e-12, 0.025, 0.5, 0.975, 1.0 - 1e-9, 1.0],
                        np.random.default_rng(7).uniform(0.0, 1.0, 200)])
    for dof in (1, 2, 5, 6, 30, 6 * 37, 1200):
        assert np.array_equal(chi2_quantile(p, dof), chi2.ppf(p, dof))
    assert float(chi2_quantile(1.0 - 0.001, 12)) == float(chi2.ppf(1.0 - 0.001, 12))


def test_known_values() -> None:
    """Table values: χ²₁(0.95) = 3.841459, χ²₆(0.975) = 14.449375, the median of χ²₂ = 2 ln 2."""
    assert abs(float(chi2_quantile(0.95, 1)) - 3.841459) < 1e-6
    assert abs(float(chi2_quantile(0.975, 6)) - 14.449375) < 1e-6
    assert abs(float(chi2_quantile(0.5, 2)) - 2.0 * np.log(2.0)) < 1e-12
    assert np.isinf(chi2_quantile(1.0, 4)) and chi2_quantile(0.0, 4) == 0.0
