"""The compiled interpolation of reported series (gnc/interpolate.py) gives numpy.interp's bits
and the same unknown (NaN) values, at the ends, at samples, between, beyond the gap."""

from __future__ import annotations

import numpy as np
import pytest

from gnc.interpolate import columns_at, columns_at_reference


@pytest.mark.parametrize("seed", range(4))
def test_the_kernel_gives_the_references_bits(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for trial in range(300):
        t = np.unique(rng.uniform(0.0, 100.0, rng.integers(1, 50)))
        if trial % 3 == 0:
            t = np.unique(np.round(t))  # whole seconds: times that hit samples exactly
        columns = rng.normal(size=(rng.integers(1, 9), len(t))) * 10.0 ** rng.integers(-6, 6)
        times = rng.uniform(-10.0, 110.0, rng.integers(1, 40))
        times[::3] = t[rng.integers(0, len(t), len(times[::3]))]
        gap = float(rng.choice([0.5, 5.0, 1e9]))
        want = columns_at_reference(times, t, columns, gap)
        got = columns_at(times, t, columns, gap)
        assert np.array_equal(want, got, equal_nan=True), trial


def test_a_slice_of_a_longer_buffer_and_known_values() -> None:
    t = np.array([0.0, 1.0, 2.0, 10.0, 0.0])[:4]  # a series' arrays hold room beyond it
    columns = np.array([[0.0, 2.0, 4.0, 20.0, 9.0], [1.0, 1.0, 1.0, 1.0, 9.0]])[:, :4]
    out = columns_at(np.array([-1.0, 0.5, 2.0, 6.0, 12.0, 20.0]), t, columns, 5.0)
    assert out[:, 1].tolist()[:2] == [1.0, 1.0]
    assert out[:5, 0].tolist() == [0.0, 1.0, 4.0, 12.0, 20.0]  # held at the ends, linear
    assert np.isnan(out[5]).all()  # 10 s beyond the last sample: unknown
