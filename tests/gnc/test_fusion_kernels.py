"""The compiled fusion of an image's precisions (gnc/fusion_kernels.py) against numpy, the
reference: the same sums to the bit, the same errors, nothing added on an error."""

from __future__ import annotations

import numpy as np
import pytest

from gnc.fusion_kernels import ADDED, BAD_INDEX, NOT_FINITE, add_checked, add_to_rows
from gnc.poi_map import PoiMap

M = 500


def _image(rng: np.random.Generator, size: int, readonly: bool = True
           ) -> tuple[np.ndarray, np.ndarray]:
    """An image's arrays: distinct increasing POIs and their precisions (read-only, as a
    message's)."""
    idx = np.sort(rng.choice(M, size=size, replace=False)).astype(np.int64)
    prec = rng.uniform(0.0, 1e3, size) * rng.uniform(0.0, 1.0, size) ** 3
    for a in (idx, prec):
        a.setflags(write=not readonly)
    return idx, prec


def test_fusing_images_gives_numpys_sums_to_the_bit() -> None:
    rng = np.random.default_rng(11)
    compiled, reference = PoiMap.uniform(M, 4.0, 3), PoiMap.uniform(M, 4.0, 3)
    for n in range(300):
        agent = int(rng.integers(1, 4))
        idx, prec = _image(rng, int(rng.integers(0, 120)), readonly=n % 2 == 0)
        if n % 7 == 0:  # repeated, unsorted indices: they add up, in order (np.add.at)
            idx = rng.integers(0, M, 40).astype(np.int64)
            prec = rng.uniform(0.0, 5.0, 40)
        compiled.add(agent, idx, prec)
        reference.add_numpy(agent, idx, prec)
    assert np.array_equal(compiled.F, reference.F) and compiled.F.any()
    assert compiled.cost() == reference.cost()


@pytest.mark.parametrize(("poi", "precision", "match"), [
    ([3, 5], [1.0, np.nan], "precision contains NaN or infinite"),
    ([3, M], [1.0, 2.0], "out of range"),
    ([-1, 4], [1.0, 2.0], "out of range"),
    ([3, 5], [1.0, -2.0], "negative precision"),
    ([3, 5], [1.0], "precision must have shape"),
])
def test_an_image_refused_raises_numpys_error_and_adds_nothing(
        poi: list[int], precision: list[float], match: str) -> None:
    pmap = PoiMap.uniform(M, 4.0, 2)
    pmap.add(1, np.array([1, 2], dtype=np.int64), np.array([3.0, 4.0]))
    before = pmap.F.copy()
    with pytest.raises(ValueError, match=match):
        pmap.add(2, np.array(poi, dtype=np.int64), np.array(precision, dtype=float))
    with pytest.raises(ValueError, match="outside 1..2"):
        pmap.add(3, np.array([1], dtype=np.int64), np.array([1.0]))
    assert np.array_equal(pmap.F, before)


def test_the_kernel_says_why_it_added_nothing() -> None:
    row = np.zeros(4)
    idx = np.array([0, 3], dtype=np.int64)
    assert add_checked(row, idx, np.array([1.0, np.inf])) == NOT_FINITE
    assert add_checked(row, np.array([0, 4], dtype=np.int64), np.ones(2)) == BAD_INDEX
    assert not row.any()
    assert add_checked(row, idx, np.array([1.0, 2.0])) == ADDED and row.tolist() == [
        1.0, 0.0, 0.0, 2.0]


def test_an_image_joins_the_receivers_views_as_numpys_indexed_add() -> None:
    rng = np.random.default_rng(5)
    table = rng.uniform(0.0, 1.0, (4, 4, M))
    expected = table.copy()
    for _ in range(50):
        idx, prec = _image(rng, int(rng.integers(1, 80)))
        receivers = np.flatnonzero(rng.uniform(size=4) < 0.6)
        source = int(rng.integers(0, 4))
        assert add_to_rows(table, receivers, source, idx, prec)
        expected[receivers[:, None], source, idx[None, :]] += prec
    assert np.array_equal(table, expected)
    before = table.copy()
    rows = np.array([0, 2], dtype=np.int64)
    for idx, prec in ((np.array([5, 5], dtype=np.int64), np.ones(2)),  # repeated: numpy's
                      (np.array([7, 3], dtype=np.int64), np.ones(2)),  # unsorted: numpy's
                      (np.array([3, M], dtype=np.int64), np.ones(2)),  # out of range
                      (np.array([3, 4], dtype=np.int64), np.ones(1))):  # lengths differ
        assert not add_to_rows(table, rows, 1, idx, prec)
    assert np.array_equal(table, before)
