"""The compiled precision kernel (gnc/infocost_kernels.py) against the numpy reference
(gnc/infocost.py) on random poses: equal values, visibility decided alike except within
rounding of a boundary, the same errors on bad input."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

from gnc import infocost, infocost_kernels
from gnc.infocost import Camera
from gnc.poi import sphere_pois

CAM = Camera(math.radians(15.0), 40.0, 2.0)


def _poses(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    p = rng.normal(0.0, 20.0, (n, 3))
    b = -p / np.linalg.norm(p, axis=1, keepdims=True) + rng.normal(0.0, 0.3, (n, 3))
    return p, b


@pytest.mark.parametrize("normals", [True, False])
def test_kernel_equals_the_numpy_reference(normals: bool) -> None:
    s, nrm = sphere_pois(3000, 5.0)
    p, b = _poses(np.random.default_rng(4), 300)
    n = nrm if normals else None
    got = infocost_kernels.precision(p, b, s, n, CAM)
    ref = infocost.precision(p, b, s, n, CAM)
    both = (got > 0) & (ref > 0)
    assert both.sum() > 10_000  # the cases exercise every test
    assert np.allclose(got[both], ref[both], rtol=1e-12, atol=0.0)
    differ = (got > 0) != (ref > 0)
    if differ.any():  # only on a boundary, within rounding
        i, j = np.nonzero(differ)
        bu = b[i] / np.linalg.norm(b[i], axis=1, keepdims=True)
        d = s[j] - p[i]
        d2 = np.einsum("ij,ij->i", d, d)
        proj = np.einsum("ij,ij->i", bu, d)
        cone = np.abs(proj**2 - math.cos(CAM.half_angle_rad) ** 2 * d2) / d2
        near = (cone < 1e-9) | (np.abs(d2 - CAM.max_range_m**2) < 1e-9 * d2)
        assert near.all()
    assert differ.sum() <= 3


def test_kernel_refuses_what_the_reference_refuses() -> None:
    s, nrm = sphere_pois(100, 5.0)
    p, b = _poses(np.random.default_rng(1), 3)
    p[1, 0] = np.nan
    for f in (infocost.precision, infocost_kernels.precision):
        with pytest.raises(ValueError):
            f(p, b, s, nrm, CAM)


def test_pois_validated_once_give_the_same_bits() -> None:
    """``precision_on`` (a ``PoiSet`` made once, as the twin and the sim's cameras hold it)
    is ``precision`` bit for bit; its columns are the POIs' own."""
    s, nrm = sphere_pois(2000, 5.0)
    p, b = _poses(np.random.default_rng(6), 40)
    for n in (nrm, None):
        pois = infocost.PoiSet(s, n)
        assert np.array_equal(infocost_kernels.precision_on(p, b, pois, CAM),
                              infocost_kernels.precision(p, b, s, n, CAM))
    sx, sy, sz, ss, nx, ny, nz, ns = infocost.PoiSet(s, nrm).columns
    assert np.array_equal(np.c_[sx, sy, sz], s) and np.array_equal(np.c_[nx, ny, nz], nrm)
    np.testing.assert_allclose(ss, np.sum(s * s, axis=1), rtol=1e-15)
    np.testing.assert_allclose(ns, np.sum(s * nrm, axis=1), rtol=1e-15)
    with pytest.raises(ValueError, match="zero-length row"):
        infocost.PoiSet(s, np.zeros_like(s))
    with pytest.raises(ValueError, match="poi_normal must have shape"):
        infocost.PoiSet(s, nrm[:1])  # the kernel would read past the normals
    pois = infocost.PoiSet(s, nrm)
    before = pickle.dumps(pois)
    infocost_kernels.precision_on(p, b, pois, CAM)  # its columns made: a cache, not state
    assert pickle.dumps(pois) == before
    assert np.array_equal(pickle.loads(before).columns[0], pois.columns[0])
    s[0] = 99.0  # the set holds its own read-only copy
    assert not np.array_equal(pois.pos[0], s[0]) and not pois.pos.flags.writeable
