"""Fleet-owned arrays (interfaces/runtime/rows.py): an attribute held in a row reads and writes
as a plain attribute would, and joining rows into one block keeps every value."""

from __future__ import annotations

import numpy as np
import pytest

from interfaces.runtime.rows import Field, Row, Rows, joined

SPEC = {"x": Field((3,)), "t": Field(optional=True), "k": Field(dtype=np.int64),
        "nodes": Field((2, 4))}


class _Owner:
    x, t, k, nodes = Row("x"), Row("t"), Row("k"), Row("nodes")

    def __init__(self) -> None:
        self.rows, self.row = Rows(SPEC, 1), 0


def test_a_row_attribute_reads_and_writes_like_a_plain_one() -> None:
    o = _Owner()
    assert o.t is None and o.k == 0 and isinstance(o.k, int)
    o.x = [1.0, 2.0, 3.0]
    o.x += np.ones(3)  # in place, then written back onto itself
    o.t = 4.5
    assert o.x.tolist() == [2.0, 3.0, 4.0] and o.t == 4.5 and isinstance(o.t, float)
    o.t = None
    assert o.t is None


def test_joined_rows_keep_every_value_pad_what_differs_and_leave_the_owners_in_one_block() -> None:
    owners = [_Owner() for _ in range(3)]
    for i, o in enumerate(owners):
        o.x = [i, i, i]
        o.t = None if i == 1 else float(i)
    owners[2].rows.fit("nodes", (5, 4))  # a longer plan on one of them
    owners[2].rows.data["nodes"][0, 4] = 7.0
    block = joined(owners)
    assert all(o.rows is block for o in owners) and [o.row for o in owners] == [0, 1, 2]
    assert block.data["nodes"].shape == (3, 5, 4) and block.data["nodes"][2, 4, 0] == 7.0
    assert [o.x[0] for o in owners] == [0.0, 1.0, 2.0]
    assert [o.t for o in owners] == [0.0, None, 2.0]
    assert joined(owners) is block  # joined once
    owners[1].x = [9.0, 9.0, 9.0]
    assert block.data["x"][1].tolist() == [9.0, 9.0, 9.0]


def test_a_row_too_short_for_its_value_is_an_error_not_a_truncation() -> None:
    o = _Owner()
    with pytest.raises(ValueError):
        o.x = [1.0, 2.0]
