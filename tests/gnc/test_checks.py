"""The input check the pure algorithms share (gnc/checks.py): a float array of the stated shape
with only finite entries, or a ValueError that names the input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gnc.checks import finite_array


def test_a_finite_value_of_the_shape_comes_back_as_floats() -> None:
    a = finite_array("r", [1, 2, 3], (3,))
    assert a.dtype == np.float64 and a.tolist() == [1.0, 2.0, 3.0]
    m = finite_array("P", np.eye(2, dtype=np.int32), (2, 2))
    assert m.dtype == np.float64 and (m == np.eye(2)).all()
    assert finite_array("t", 4, ()).shape == ()


@pytest.mark.parametrize("value, shape, needle", [
    ([1.0, 2.0], (3,), "r must have shape (3,), got (2,)"),
    ([[1.0, 2.0, 3.0]], (3,), "got (1, 3)"),
    ([1.0, math.nan, 3.0], (3,), "r contains NaN or infinite values"),
    ([1.0, -math.inf, 3.0], (3,), "NaN or infinite"),
    (["a", "b", "c"], (3,), "r must be numeric with shape (3,)"),
    ([1.0, None, 3.0], (3,), "NaN or infinite"),  # None becomes NaN: refused all the same
    ({"x": 1.0}, (3,), "r must"),
])
def test_bad_input_is_a_value_error_naming_it(value: object, shape: tuple[int, ...],
                                             needle: str) -> None:
    with pytest.raises(ValueError) as e:
        finite_array("r", value, shape)  # type: ignore[arg-type]
    assert needle in str(e.value)
