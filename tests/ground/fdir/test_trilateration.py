"""The trilateration's normal equations (ground/fdir/trilateration.py): the compiled pass
against numpy's, and the least squares against numpy's SVD solution and exact data."""

from __future__ import annotations

import numpy as np

from gnc.poi import sphere_pois
from ground.fdir.trilateration import (
    least_squares,
    normal_equations,
    normal_equations_reference,
)

POS, _ = sphere_pois(3000, 5.0)


def _rows(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    seen = np.sort(rng.choice(len(POS), n, replace=False)).astype(np.int64)
    kp = rng.uniform(1e-3, 1e-2, n)
    kp[::7] = 0.0  # POIs whose noise drew their precision to 0: not rows
    return seen, kp


def test_the_compiled_pass_is_numpys_normal_equations() -> None:
    rng = np.random.default_rng(3)
    for n in (12, 500, 2500):
        seen, kp = _rows(rng, n)
        ata, atb, rows = normal_equations(POS, seen, kp)
        ref_ata, ref_atb, ref_rows = normal_equations_reference(POS, seen, kp)
        assert rows == ref_rows == int((kp > 0).sum())
        np.testing.assert_allclose(ata, ref_ata, rtol=1e-12)
        np.testing.assert_allclose(atb, ref_atb, rtol=1e-12)
        assert np.array_equal(ata, ata.T)


def test_the_solution_is_the_svd_least_squares_one() -> None:
    rng = np.random.default_rng(4)
    seen, kp = _rows(rng, 1500)
    theta = least_squares(POS, seen, kp, 12)
    good = kp > 0
    a = kp[good, None] * np.c_[np.ones(int(good.sum())), POS[seen[good]]]
    svd = np.linalg.lstsq(a, np.ones(len(a)), rcond=None)[0]
    assert theta is not None
    np.testing.assert_allclose(theta, svd, rtol=1e-9)


def test_exact_rows_are_solved_exactly() -> None:
    """Rows built from a known θ (kp_j = 1 / ([1, s_j]·θ)) give θ back."""
    theta = np.array([40.0, -2.0, 3.5, 1.0])
    seen = np.arange(0, 3000, 3, dtype=np.int64)
    kp = 1.0 / (np.c_[np.ones(len(seen)), POS[seen]] @ theta)
    got = least_squares(POS, seen, kp, 12)
    assert got is not None
    np.testing.assert_allclose(got, theta, rtol=1e-10)


def test_too_few_rows_or_pois_near_a_plane_give_no_solution() -> None:
    rng = np.random.default_rng(5)
    seen, kp = _rows(rng, 13)
    assert least_squares(POS, seen, kp, 13) is None  # two of the 13 have no precision
    assert least_squares(POS, seen, kp, 11) is not None
    flat = POS.copy()
    flat[:, 2] = 1.0 + 1e-9 * rng.standard_normal(len(flat))  # κ(A) far above the limit
    seen, kp = _rows(rng, 400)
    assert least_squares(flat, seen, kp, 12) is None
    flat[:, 2] = 1.0 + 0.5 * rng.standard_normal(len(flat))
    assert least_squares(flat, seen, kp, 12) is not None
