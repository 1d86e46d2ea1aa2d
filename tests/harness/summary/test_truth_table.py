"""The truth table holds exactly the numbers of the TruthState messages it is built from, finds
them by sim time and observer, and refuses truth whose layout changes mid-run."""

from __future__ import annotations

import numpy as np
import pytest

from harness.archive.reader import ArchiveError
from harness.summary.truth_table import TruthTable
from interfaces.contracts.messages import TruthState


def _truth(t: float, rng: np.random.Generator, ids: list[int], attitude: bool) -> TruthState:
    n = len(ids)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    extra = dict(q_lvlh_body=q.tolist(), w_body_radps=rng.normal(size=(n, 3)).tolist(),
                 dv_mps=rng.uniform(0, 1, n).tolist()) if attitude else {}
    return TruthState(sender="sim", t_sim=t, spacecraft=ids,
                      r_lvlh_m=rng.normal(size=(n, 3)).tolist(),
                      v_lvlh_mps=rng.normal(size=(n, 3)).tolist(), **extra)


@pytest.mark.parametrize("attitude", [True, False])
def test_table_holds_every_number_of_the_messages(attitude: bool) -> None:
    rng = np.random.default_rng(5)
    msgs = [_truth(0.1 * k, rng, [2, 4, 7], attitude) for k in range(40)]
    table = TruthTable.from_messages(msgs)
    assert len(table) == 40 and table.spacecraft == (2, 4, 7)
    assert table.has_attitude is attitude
    for msg in msgs:
        i = table.row(msg.t_sim + 4e-7)  # found to the microsecond
        assert i is not None and table.t_s[i] == msg.t_sim
        for j, sc in enumerate(msg.spacecraft):
            assert table.column(sc) == j
            assert table.r_m[i, j].tolist() == msg.r_lvlh_m[j]
            assert table.v_mps[i, j].tolist() == msg.v_lvlh_mps[j]
            if attitude:
                assert table.q_lvlh_body[i, j].tolist() == msg.q_lvlh_body[j]
                assert table.w_body_radps[i, j].tolist() == msg.w_body_radps[j]
                assert table.dv_mps[i, j] == msg.dv_mps[j]
    assert table.row(0.05) is None and table.column(3) is None
    if not attitude:
        assert table.q_lvlh_body.shape == (40, 0, 4) and table.dv_mps.shape == (40, 0)


def test_empty_truth_is_an_empty_table() -> None:
    table = TruthTable.from_messages([])
    assert len(table) == 0 and table.r_m.shape == (0, 0, 3) and not table.has_attitude


def test_a_change_of_layout_mid_run_is_an_archive_error() -> None:
    rng = np.random.default_rng(1)
    with pytest.raises(ArchiveError, match="spacecraft"):
        TruthTable.from_messages([_truth(0.0, rng, [1, 2], True), _truth(0.1, rng, [1, 3], True)])
    with pytest.raises(ArchiveError, match="without attitude"):
        TruthTable.from_messages([_truth(0.0, rng, [1, 2], True), _truth(0.1, rng, [1, 2], False)])
