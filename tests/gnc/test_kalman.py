"""The Kalman update (gnc/kalman.py) against the information form of the same update."""

from __future__ import annotations

import numpy as np

from gnc import kalman


def test_kalman_update_matches_information_form() -> None:
    rng = np.random.default_rng(0)
    A = rng.standard_normal((6, 6))
    P = A @ A.T + 6 * np.eye(6)
    R = np.diag(rng.uniform(0.1, 1.0, 6))
    x, z = rng.standard_normal(6), rng.standard_normal(6)
    x1, P1, nis = kalman.update(x, P, z, np.eye(6), R)
    P_info = np.linalg.inv(np.linalg.inv(P) + np.linalg.inv(R))
    x_info = P_info @ (np.linalg.solve(P, x) + np.linalg.solve(R, z))
    np.testing.assert_allclose(P1, P_info, rtol=1e-10)
    np.testing.assert_allclose(x1, x_info, rtol=1e-10, atol=1e-12)
    assert np.isclose(nis, (z - x) @ np.linalg.solve(P + R, z - x))
