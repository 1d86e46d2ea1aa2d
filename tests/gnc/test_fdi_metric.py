"""The FDIR metric (Eq. 9), direction (Table 3), global check (Eq. 6), adaptive threshold
(Eq. 11-12) with its floor and persistence, on constructed cases and the paper's Sec. III.F
numbers computed through gnc.infocost."""

from __future__ import annotations

import numpy as np
import pytest

from gnc import infocost as ic
from gnc.fdi_metric import direction, global_check, metric, ratio
from ground.fdir.threshold import Persistence, adaptive_threshold, calibrate_floor
from interfaces.contracts.scenario import FdirSettings

S_1DOF = np.array([[1.0, 1.0, 0.0], [-1.0, -1.0, 0.0]])  # Eq. 13, a = 1
PHI, W_INV, CAM = 0.5, 0.0, ic.Camera(k=1.0)               # Eq. 22
VIS = np.ones((2, 2), dtype=bool)
LOOK = np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])


def _obs(x: np.ndarray) -> np.ndarray:
    return ic.precision(np.column_stack((x, np.zeros(2), np.zeros(2))), LOOK, S_1DOF, None, CAM,
                        visible=VIS)


def test_paper_sensor_fault_numbers_through_the_metric() -> None:
    """Eq. 26-27: β = 0.7 on agent 2; ΔH_i from the library with ψ held at t − Δt."""
    x = np.array([-1.5, 1.5])
    f0, step = _obs(x), _obs(x + np.array([0.1, -0.1]))
    psi = ic.h_poi(W_INV, f0) ** 2
    h_prev = ic.agent_contributions(PHI, W_INV, f0, psi=psi)
    pred = ic.agent_contributions(PHI, W_INV, f0 + step, psi=psi) - h_prev
    real = ic.agent_contributions(PHI, W_INV, f0 + step * np.array([[1.0], [0.7]]),
                                  psi=psi) - h_prev
    hm = [metric(real[i], pred[i], h_prev[i]) for i in range(2)]
    assert hm[0] == pytest.approx(0.0, abs=1e-12) and hm[1] == pytest.approx(0.3, abs=1e-12)
    assert direction(real[1], pred[1], h_prev[1]) == "degraded"
    assert direction(real[0], pred[0], h_prev[0]) is None  # exactly nominal


def test_paper_actuator_fault_numbers_through_the_metric() -> None:
    """Eq. 23-25: the gradient (Eq. 17) times the realised and commanded steps."""
    x = np.array([-1.5, 1.5])
    p = np.column_stack((x, np.zeros(2), np.zeros(2)))
    g = ic.cost_gradient(p, LOOK, S_1DOF, None, CAM, PHI, W_INV, np.zeros((2, 2)),
                         visible=VIS)[:, 0]
    dx_cmd, dx_real = np.array([0.1, -0.1]), np.array([0.15, -0.1])
    assert metric(g[0] * dx_real[0], g[0] * dx_cmd[0]) == pytest.approx(0.5, abs=1e-12)
    assert metric(g[1] * dx_real[1], g[1] * dx_cmd[1]) == pytest.approx(0.0, abs=1e-12)
    assert direction(g[0] * dx_real[0], g[0] * dx_cmd[0]) == "improved"  # r = 1.5 > 1


def test_table3_directions_and_degenerate_predictions() -> None:
    assert direction(-2.0, -1.0) == "improved"     # same sign, x = 2
    assert direction(-0.5, -1.0) == "degraded"     # same sign, x = 0.5
    assert direction(+0.5, -1.0) == "degraded"     # opposite signs
    assert ratio(1.0, 0.0) is None and metric(1.0, 0.0) is None  # Theorem 1, assumption 1
    assert metric(1.0, 1e-20, h_prev=1.0) is None                # relatively degenerate
    assert metric(float("nan"), 1.0) is None and metric(1.0, float("inf")) is None
    assert metric(0.0, -1.0) == 1.0  # nothing gained when something was expected


def test_global_check_eq6() -> None:
    t = np.linspace(0.0, 100.0, 11)
    h_nom = 1.0 - 0.005 * t
    assert not global_check(t, h_nom, h_nom, 1e-6)
    assert global_check(t, h_nom + 0.01, h_nom, 0.009)      # mean shortfall 0.01 ≥ 0.009
    assert not global_check(t, h_nom + 0.01, h_nom, 0.011)
    assert not global_check(t, h_nom + np.nan, h_nom, 0.0)


def test_adaptive_threshold_is_the_closest_nonzero_sample_with_a_floor() -> None:
    pred = -0.01
    samples = [-0.01, -0.009, -0.0125, -0.002]  # one exactly nominal (excluded by Eq. 11)
    assert adaptive_threshold(samples, pred) == pytest.approx(0.1)
    assert adaptive_threshold(samples, pred, floor=0.2) == 0.2
    assert adaptive_threshold([pred, pred], pred, floor=0.05) == 0.05
    assert adaptive_threshold(samples, 0.0) is None


def test_floor_calibration_hits_the_target_rate_on_iid_samples() -> None:
    rng = np.random.default_rng(1)
    nominal = np.abs(rng.normal(0.0, 0.1, 200_000))
    floor = calibrate_floor(nominal, false_alarm_rate=1e-3, persistence=1)
    assert np.mean(nominal > floor) == pytest.approx(1e-3, rel=0.1)
    floor3 = calibrate_floor(nominal, false_alarm_rate=1e-3, persistence=3)
    assert np.mean(nominal > floor3) == pytest.approx(0.1, rel=0.05)  # (1e-3)^(1/3)
    with pytest.raises(ValueError):
        calibrate_floor([], 0.01, 1)
    with pytest.raises(ValueError):
        calibrate_floor([0.1], 1.5, 1)


def test_persistence_declares_once_per_episode_and_ignores_missing_windows() -> None:
    p = Persistence(count=3)
    seq = [True, None, True, True, True, False, True, True, True]
    got = [p.update(2, e) for e in seq]
    assert got == [False, False, False, True, False, False, False, False, True]
    assert p.update(1, True) is False  # per spacecraft


def test_m_of_n_persistence_against_its_definition() -> None:
    """Persistence(m, n) declares on a window that exceeds and brings the exceedances among the
    last n to m, unless the previous window already did (one declaration per episode): checked
    on a hand sequence and against that definition written out on random sequences; m of m is
    m in a row."""
    p = Persistence(count=2, window=3)
    seq = [True, False, True, True, True, False, False, False, True, False, True]
    assert [i for i, e in enumerate(seq) if p.update(1, e)] == [2, 10]
    rng = np.random.default_rng(4)
    for m, n in [(1, 1), (2, 2), (2, 3), (3, 3), (2, 4)]:
        for _ in range(20):
            hits = list(rng.random(30) < 0.4)
            holds = [bool(h) and sum(hits[max(0, i - n + 1):i + 1]) >= m
                     for i, h in enumerate(hits)]
            expected = [i for i, h in enumerate(holds) if h and not (i > 0 and holds[i - 1])]
            p = Persistence(count=m, window=n)
            assert [i for i, h in enumerate(hits) if p.update(1, bool(h))] == expected, (m, n)
    with pytest.raises(ValueError, match="persistence_window"):
        FdirSettings(persistence=3, persistence_window=2)


def test_a_window_begun_before_the_crossing_that_declared_does_not_end_its_episode() -> None:
    """Declared by a scan at 45 s: the window [30, 60) passing on the whole counts as no
    decision (the change began late in it); one that exceeds counts; the window [60, 90)
    passing ends the episode."""
    p = Persistence(count=1)
    p.declare(2, at_s=45.0)
    assert p.counted(2, False, 30.0) is None and p.counted(2, None, 30.0) is None
    assert p.counted(2, True, 30.0) is True
    assert p.update(2, p.counted(2, False, 30.0)) is False and p.declared(2)
    assert p.counted(2, False, 60.0) is False  # after the crossing: its verdict
    p.update(2, False)
    assert not p.declared(2)
    assert p.counted(2, False, 30.0) is False  # the crossing is spent
