"""gnc.quat against scipy's Rotation (the reference implementation of the same conventions).

Random rotations plus the hard cases: angles near 0 (around the Exp series threshold, down to
1e-15 rad and exactly 0), near and at π, and both signs of every quaternion.  Each function is
checked for one quaternion (the float fast path) and for batches (numpy path), to 1e-12.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gnc import quat

TOL = 1e-12


def _rotvecs(rng: np.random.Generator) -> np.ndarray:
    """Rotation vectors (M, 3), rad: random, tiny, around 1e-3, near/at π, beyond π, zero."""
    axes = rng.standard_normal((12, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = [0.0, 1e-15, 1e-9, 1e-6, 1e-3 * (1 - 1e-12), 1e-3, 1e-3 * (1 + 1e-12), 0.5,
              math.pi - 1e-9, math.pi - 1e-15, math.pi, math.pi + 1e-7]
    special = axes * np.array(angles)[:, None]
    random = rng.standard_normal((40, 3)) * rng.uniform(0.0, 1.5, (40, 1))
    return np.concatenate([special, random, np.zeros((1, 3))])


def _quats(rng: np.random.Generator) -> np.ndarray:
    """Unit quaternions (M, 4) of the rotation vectors above and random ones, both signs."""
    q = np.concatenate([Rotation.from_rotvec(_rotvecs(rng)).as_quat(),
                        Rotation.random(40, random_state=rng).as_quat()])
    q[::2] *= -1.0
    return q


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20240611)


def test_mul_is_scipy_composition(rng: np.random.Generator) -> None:
    p, q = _quats(rng), _quats(rng)[::-1]
    expected = (Rotation.from_quat(p) * Rotation.from_quat(q)).as_quat()  # sign kept
    np.testing.assert_allclose(quat.mul(p, q), expected, rtol=0, atol=TOL)
    for k in range(0, len(p), 7):
        np.testing.assert_allclose(quat.mul(p[k], q[k]), expected[k], rtol=0, atol=TOL)
        assert quat.mul(p[k], q[k]).shape == (4,)
    # broadcasting one against many, lists accepted
    np.testing.assert_allclose(quat.mul(list(p[3]), q), quat.mul(np.tile(p[3], (len(q), 1)), q),
                               rtol=0, atol=0)


def test_conj_is_inverse(rng: np.random.Generator) -> None:
    q = _quats(rng)
    np.testing.assert_allclose(quat.conj(q), Rotation.from_quat(q).inv().as_quat(), rtol=0,
                               atol=TOL)
    np.testing.assert_allclose(quat.conj(q[5]), Rotation.from_quat(q[5]).inv().as_quat(),
                               rtol=0, atol=TOL)
    ident = quat.mul(q, quat.conj(q))
    np.testing.assert_allclose(quat.canonical(ident), np.tile([0, 0, 0, 1.0], (len(q), 1)),
                               rtol=0, atol=TOL)


def test_rotate_and_inverse_are_scipy_apply(rng: np.random.Generator) -> None:
    q = _quats(rng)
    v = rng.standard_normal((len(q), 3)) * 7.0
    r = Rotation.from_quat(q)
    np.testing.assert_allclose(quat.rotate(q, v), r.apply(v), rtol=0, atol=TOL)
    np.testing.assert_allclose(quat.rotate_inv(q, v), r.apply(v, inverse=True), rtol=0, atol=TOL)
    for k in range(0, len(q), 5):
        np.testing.assert_allclose(quat.rotate(q[k], v[k]), r[k].apply(v[k]), rtol=0, atol=TOL)
        np.testing.assert_allclose(quat.rotate_inv(q[k], v[k]), r[k].apply(v[k], inverse=True),
                                   rtol=0, atol=TOL)
    # one quaternion, many vectors
    np.testing.assert_allclose(quat.rotate(q[1], v), r[1].apply(v), rtol=0, atol=TOL)


def test_cross_is_numpy_cross(rng: np.random.Generator) -> None:
    a, b = rng.standard_normal((2, 20, 3))
    np.testing.assert_allclose(quat.cross(a, b), np.cross(a, b), rtol=0, atol=TOL)
    np.testing.assert_allclose(quat.cross(a[0], b[0]), np.cross(a[0], b[0]), rtol=0, atol=TOL)
    np.testing.assert_allclose(quat.cross(a[0], b), np.cross(a[0], b), rtol=0, atol=TOL)


def test_exp_is_scipy_from_rotvec(rng: np.random.Generator) -> None:
    phi = _rotvecs(rng)
    expected = Rotation.from_rotvec(phi).as_quat()
    np.testing.assert_allclose(quat.exp(phi), expected, rtol=0, atol=TOL)
    for k in range(len(phi)):
        got = quat.exp(phi[k])
        np.testing.assert_allclose(got, expected[k], rtol=0, atol=TOL)
        assert abs(np.linalg.norm(got) - 1.0) < TOL
    # tiny angles: the vector part keeps full relative precision (φ/2)
    tiny = np.array([3e-17, -1e-16, 2e-16])
    np.testing.assert_allclose(quat.exp(tiny)[:3], tiny / 2.0, rtol=1e-15, atol=0)
    np.testing.assert_allclose(quat.exp(tiny[None, :])[0, :3], tiny / 2.0, rtol=1e-15, atol=0)


def test_log_is_scipy_as_rotvec_short_way(rng: np.random.Generator) -> None:
    q = _quats(rng)  # both signs: Log takes the short way
    expected = Rotation.from_quat(q).as_rotvec()
    np.testing.assert_allclose(quat.log(q), expected, rtol=0, atol=TOL)
    for k in range(len(q)):
        np.testing.assert_allclose(quat.log(q[k]), expected[k], rtol=0, atol=TOL)
        np.testing.assert_allclose(quat.log(-q[k]), quat.log(q[k]), rtol=0, atol=TOL)
    assert np.max(np.linalg.norm(quat.log(q), axis=1)) <= math.pi + 1e-15
    # Log inverts Exp on |φ| < π; a non-unit quaternion gives the same rotation vector
    phi = _rotvecs(rng)
    inside = np.linalg.norm(phi, axis=1) < math.pi - 1e-9
    np.testing.assert_allclose(quat.log(quat.exp(phi[inside])), phi[inside], rtol=0, atol=TOL)
    np.testing.assert_allclose(quat.log(3.0 * q), expected, rtol=0, atol=TOL)
    np.testing.assert_allclose(quat.log(3.0 * q[4]), expected[4], rtol=0, atol=TOL)
    # tiny angles keep full relative precision; exact identity gives exactly zero
    tiny = np.array([1e-17, -4e-17, 2e-17, 1.0])
    np.testing.assert_allclose(quat.log(tiny), 2.0 * tiny[:3], rtol=1e-15, atol=0)
    np.testing.assert_array_equal(quat.log([0.0, 0.0, 0.0, -1.0]), np.zeros(3))
    np.testing.assert_array_equal(quat.log(np.array([[0.0, 0.0, 0.0, 1.0]])), np.zeros((1, 3)))


def test_log_at_half_turn() -> None:
    """At π exactly (w = ±0) ±φ are the same rotation; as scipy, the first non-zero of x, y, z
    of the result is positive, whatever the sign of q."""
    axes = np.array([[2.0, -1.0, 2.0], [-2.0, 1.0, 2.0], [0.0, -3.0, 0.0], [0.0, 0.0, -3.0]]) / 3.0
    for axis in axes:
        for w in (0.0, -0.0):
            for sign in (1.0, -1.0):
                q = sign * np.concatenate([axis, [w]])
                expected = Rotation.from_quat(q).as_rotvec()
                lead = expected[np.flatnonzero(expected)[0]]
                assert lead > 0.0
                np.testing.assert_allclose(np.abs(expected), math.pi * np.abs(axis), atol=TOL)
                np.testing.assert_allclose(quat.log(q), expected, rtol=0, atol=TOL)
                np.testing.assert_allclose(quat.log(q[None, :])[0], expected, rtol=0, atol=TOL)


def test_normalize_and_canonical(rng: np.random.Generator) -> None:
    q = _quats(rng) * rng.uniform(0.1, 10.0, (1, 1))
    unit = quat.normalize(q)
    np.testing.assert_allclose(unit, Rotation.from_quat(q).as_quat(), rtol=0, atol=TOL)
    np.testing.assert_allclose(quat.normalize(q[3]), unit[3], rtol=0, atol=TOL)
    canon = quat.canonical(unit)
    np.testing.assert_allclose(canon, Rotation.from_quat(unit).as_quat(canonical=True), rtol=0,
                               atol=TOL)  # no w = 0 exactly among these
    assert np.all(canon[:, 3] >= 0.0)
    np.testing.assert_allclose(canon, unit * np.sign(unit[:, 3:]), rtol=0, atol=0)
    half_turn = np.array([[0.0, -1.0, 0.0, 0.0]])  # w = 0: left as it is
    np.testing.assert_array_equal(quat.canonical(half_turn), half_turn)
    np.testing.assert_array_equal(quat.canonical(half_turn[0]), half_turn[0])
    for k in range(len(q)):
        np.testing.assert_array_equal(quat.canonical(unit[k]), canon[k])
    src = unit[0].copy()
    assert quat.canonical(src) is not src  # always a new array
    with pytest.raises(ValueError):
        quat.normalize(np.zeros(4))
    with pytest.raises(ValueError):
        quat.normalize(np.array([[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]]))


def test_matrix_round_trip_is_scipy(rng: np.random.Generator) -> None:
    q = _quats(rng)
    r = Rotation.from_quat(q)
    m = quat.to_matrix(q)
    np.testing.assert_allclose(m, r.as_matrix(), rtol=0, atol=TOL)
    np.testing.assert_allclose(quat.to_matrix(q[2]), r[2].as_matrix(), rtol=0, atol=TOL)
    # from_matrix: scipy's Shepperd choice, hence its sign (largest component positive)
    expected = Rotation.from_matrix(m).as_quat()
    np.testing.assert_allclose(quat.from_matrix(m), expected, rtol=0, atol=TOL)
    np.testing.assert_allclose(quat.from_matrix(m[7]), expected[7], rtol=0, atol=TOL)
    # one matrix is done on floats: the stack's choice of candidate, normalised by math.hypot
    # (within an ulp of the stack's numpy normalisation)
    single = np.array([quat.from_matrix(x) for x in m])
    np.testing.assert_allclose(single, quat.from_matrix(m), rtol=0, atol=3e-16)
    for special in (np.eye(3), np.diag([1.0, -1.0, -1.0]), np.diag([-1.0, 1.0, -1.0]),
                    np.diag([-1.0, -1.0, 1.0])):
        np.testing.assert_allclose(quat.from_matrix(special),
                                   Rotation.from_matrix(special).as_quat(), rtol=0, atol=TOL)


def test_algebra_identities(rng: np.random.Generator) -> None:
    """R(p ⊗ q) = R(p) R(q) and Exp(φ) rotates about φ: consistency among the functions."""
    p, q = _quats(rng), _quats(rng)[::-1]
    v = rng.standard_normal((len(p), 3))
    np.testing.assert_allclose(quat.rotate(quat.mul(p, q), v),
                               quat.rotate(p, quat.rotate(q, v)), rtol=0, atol=TOL)
    np.testing.assert_allclose(quat.rotate_inv(p, quat.rotate(p, v)), v, rtol=0, atol=TOL)
    phi = _rotvecs(rng)
    np.testing.assert_allclose(quat.rotate(quat.exp(phi), phi), phi, rtol=0, atol=TOL)


# ---------------------------------------------------------------------------
# a hot path that uses gnc.quat, against the scipy computation it replaced (the flight
# library's: tests/fsw/lib/test_quat_hot_paths.py)


def test_lvlh_quaternion_is_the_matrix_construction(rng: np.random.Generator) -> None:
    """lvlh_to_eci_quat equals scipy's from_matrix of the LVLH basis (sign included)."""
    from gnc.frames import lvlh_to_eci_quat

    for _ in range(50):
        t, n = rng.uniform(0.0, 1e5), rng.uniform(0.0, 1.2e-3)
        inc, raan, u0 = rng.uniform(0.0, math.pi), rng.uniform(-7.0, 7.0), rng.uniform(-7.0, 7.0)
        u = u0 + n * t
        p = np.array([math.cos(raan), math.sin(raan), 0.0])
        q = np.array([-math.sin(raan) * math.cos(inc), math.cos(raan) * math.cos(inc),
                      math.sin(inc)])
        basis = np.column_stack([math.cos(u) * p + math.sin(u) * q,
                                 -math.sin(u) * p + math.cos(u) * q, np.cross(p, q)])
        expected = Rotation.from_matrix(basis).as_quat()
        np.testing.assert_allclose(lvlh_to_eci_quat(t, n, inc, raan, u0), expected, rtol=0,
                                   atol=1e-11)  # |u| up to ~130 rad: trig arguments lose ~1e-14
