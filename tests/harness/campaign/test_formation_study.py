"""The formation study's measures (harness/campaign/formation_study.py) on curves whose answer is
known: a twin is the same run until the onset, a move is the mean absolute difference after
it over the twin's mean level, and the claims' verdicts follow the figures."""

from __future__ import annotations

import numpy as np
import pytest

from harness.campaign.formation_study import (
    Curves,
    Moves,
    StudyRun,
    claims,
    moves,
    relative_move,
    twins,
)
from interfaces.contracts.scenario import Fault

T = np.arange(0.0, 101.0, 10.0)


def _run(rid: str, observers: int, seed: int, fault: Fault | None, h: np.ndarray,
         h_i: np.ndarray) -> StudyRun:
    return StudyRun(rid, observers, seed, fault, None, Curves(T, h, h_i))


def test_a_move_is_the_mean_difference_after_the_onset_over_the_twins_level() -> None:
    twin = np.full(T.size, 2.0)
    x = twin.copy()
    x[T >= 50.0] = [2.5, 1.5, 2.0, 3.0, 2.0, 2.0]  # |diff| 0.5, 0.5, 0, 1, 0, 0: mean 1/3
    move, before = relative_move(T, x, T, twin, 50.0)
    assert move == pytest.approx((2.0 / 6.0) / 2.0)
    assert before == 0.0
    x[1] = 2.2  # a difference before the onset is reported apart, not in the move
    assert relative_move(T, x, T, twin, 50.0) == (pytest.approx(1.0 / 6.0), pytest.approx(0.2))


def test_the_twin_is_interpolated_to_the_runs_samples() -> None:
    twin_t = np.array([0.0, 100.0])
    move, _ = relative_move(T, 1.0 + T / 100.0, twin_t, np.array([1.0, 2.0]), 0.0)
    assert move == pytest.approx(0.0, abs=1e-15)
    with pytest.raises(ValueError, match="no sample"):
        relative_move(T, T, T, T, 500.0)


def test_the_faulty_agents_curve_and_the_global_one_are_compared_with_the_twins() -> None:
    fault = Fault(spacecraft=2, kind="camera_misalignment", start_s=50.0, magnitude=8.0)
    h_i = np.ones((T.size, 2))
    faulty_i = h_i.copy()
    faulty_i[T >= 50.0, 1] = 0.5  # agent 2 loses half its contribution
    h = np.full(T.size, 10.0)
    faulty_h = h.copy()
    faulty_h[T >= 50.0] = 10.5
    run = _run("f", 2, 3, fault, faulty_h, faulty_i)
    twin = _run("n", 2, 3, None, h, h_i)
    m = moves(run, twin)
    assert (m.h_i, m.h, m.before_onset) == (pytest.approx(0.5), pytest.approx(0.05), 0.0)


def test_twins_pair_by_formation_and_seed() -> None:
    fault = Fault(spacecraft=1, kind="state_disturbance", start_s=50.0, magnitude=3.0)
    flat = np.ones(T.size)
    runs = [_run("n2s1", 2, 1, None, flat, np.ones((T.size, 2))),
            _run("n4s1", 4, 1, None, flat, np.ones((T.size, 4))),
            _run("f4s1", 4, 1, fault, flat, np.ones((T.size, 4))),
            _run("f4s2", 4, 2, fault, flat, np.ones((T.size, 4)))]  # no twin: left out
    assert [(r.id, w.id) for r, w in twins(runs)] == [("f4s1", "n4s1")]


def test_the_claims_verdicts_follow_the_measured_moves() -> None:
    fault = Fault(spacecraft=1, kind="camera_misalignment", start_s=50.0, magnitude=8.0)
    flat = np.ones(T.size)

    def pair(n: int, hi: float, h: float) -> tuple[StudyRun, Moves]:
        return _run(f"n{n}", n, 1, fault, flat, np.ones((T.size, n))), Moves(hi, h, 0.0)

    growing = "\n".join(claims([pair(1, 0.1, 0.1), pair(2, 0.2, 0.05), pair(4, 0.4, 0.02)]))
    assert "moved less than the faulty agent's H_i in 2 of 3" in growing
    assert "(1: 1.0, 2: 4.0, 4: 20.0): the claim holds" in growing
    flat_ratio = "\n".join(claims([pair(1, 0.3, 0.1), pair(2, 0.3, 0.1), pair(4, 0.3, 0.1)]))
    assert "the claim does not hold here" in flat_ratio
