"""Tests of ground.planning.orbit_assignment against independent truth: exhaustive search with the
information cost of gnc.infocost, a hand-written visibility model, dense sampling of PRO
distances, brute-force permutations."""

from __future__ import annotations

import itertools
import math
from itertools import pairwise

import numpy as np
import pytest

from gnc.hcw import mean_motion
from gnc.infocost import Camera, information_cost
from gnc.poi import sphere_pois
from gnc.pro import Pro
from ground.planning.orbit_assignment import (
    expected_precision,
    gain_saturated,
    greedy_assignment,
    match_to_observers,
    online_upper_bound,
    pro_library,
    set_gain,
)

N_MEAN = mean_motion(500e3)  # 1.10678e-3 rad/s
PERIOD = 2.0 * math.pi / N_MEAN
CAM = Camera()  # 20 deg half angle, 200 m range, k = 1
POS, NOR = sphere_pois(500, 5.0)
SAMPLES = 20


def _library() -> list[Pro]:
    return pro_library([10.0, 25.0, 40.0], [12.0, 35.0],
                       np.linspace(0.0, 2 * np.pi, 4, endpoint=False),
                       cross_phase_offsets_rad=(0.0, np.pi / 2))


LIB = _library()
PREC = np.array([expected_precision(p, N_MEAN, 0.0, PERIOD, SAMPLES, POS, NOR, CAM) for p in LIB])


def _truth_gain(rows: np.ndarray, phi: np.ndarray, w_inv: np.ndarray) -> float:
    """H(now) - H(after) from gnc.infocost.information_cost (independent of set_gain)."""
    m = w_inv.size
    before = information_cost(phi, w_inv, np.zeros((1, m)))
    after = information_cost(phi, w_inv, rows if rows.size else np.zeros((1, m)))
    return before - after


def _dense_positions(pro: Pro, count: int = 20000) -> np.ndarray:
    return pro.positions_at_phase(np.linspace(0.0, 2 * np.pi, count, endpoint=False))


# ----------------------------------------------------------------------------- precision model


def test_library_parameterisation() -> None:
    lib = pro_library([10.0, 20.0], [30.0], [0.0, 3.0], rho_y_m=2.0,
                      cross_phase_offsets_rad=(0.0, 1.0))
    assert len(lib) == 8
    for p in lib:
        off = (p.alpha_z_rad - p.alpha_x_rad) % (2 * np.pi)
        assert min(abs(off), abs(off - 1.0), abs(off - 2 * np.pi)) < 1e-12
        assert p.rho_y_m == 2.0 and p.rho_z_m == 30.0
    with pytest.raises(ValueError):
        pro_library([np.nan], [1.0], [0.0])
    with pytest.raises(ValueError):
        pro_library([-1.0], [1.0], [0.0])


def test_expected_precision_matches_hand_written_camera_model() -> None:
    pro = LIB[5]
    t0, window, samples = 123.0, 0.6 * PERIOD, 7
    got = expected_precision(pro, N_MEAN, t0, window, samples, POS, NOR, CAM)
    truth = np.zeros(POS.shape[0])
    for j in range(samples):
        p = pro.states(N_MEAN, t0 + (j + 0.5) * window / samples)[0, :3]
        los = POS - p
        d = np.linalg.norm(los, axis=1)
        cos_off = (los @ (-p / np.linalg.norm(p))) / d
        vis = (cos_off >= math.cos(CAM.half_angle_rad)) & (d <= CAM.max_range_m) \
            & (np.einsum("ij,ij->i", NOR, p - POS) > 0.0)
        truth[vis] += 1.0 / (CAM.k * d[vis] ** 2)
    assert np.count_nonzero(truth) > 50
    np.testing.assert_allclose(got, truth, rtol=1e-12, atol=0.0)


def test_nothing_visible_gives_zero_gain() -> None:
    far = Pro(10.0, 0.3, 600.0, 10.0, 1.0)  # always ~600 m away, beyond the 200 m range
    p_far = expected_precision(far, N_MEAN, 0.0, PERIOD, 30, POS, NOR, CAM)
    assert np.all(p_far == 0.0)
    assert set_gain(p_far[None, :], 1.0, 0.02) == 0.0
    p_empty = expected_precision(LIB[0], N_MEAN, 0.0, 0.0, 30, POS, NOR, CAM)
    assert np.all(p_empty == 0.0)
    assert set_gain(p_empty[None, :], 1.0, 0.02) == 0.0
    assert set_gain(np.zeros((0, POS.shape[0])), 1.0, 0.02) == 0.0


# ----------------------------------------------------------------------------- gain properties


def test_set_gain_matches_information_cost() -> None:
    rng = np.random.default_rng(1)
    phi = rng.uniform(0.5, 2.0, POS.shape[0])
    w = rng.uniform(0.005, 0.05, POS.shape[0])
    rows = PREC[[0, 7, 20]]
    assert set_gain(rows, phi, w) == pytest.approx(_truth_gain(rows, phi, w), rel=1e-10)


def test_monotone_and_diminishing_returns_on_random_sets() -> None:
    rng = np.random.default_rng(2)
    m = POS.shape[0]
    for trial in range(40):
        phi = rng.uniform(0.0, 2.0, m)
        w = rng.uniform(0.002, 0.1, m)
        # realistic candidate precisions, or random sparse ones
        pool = PREC if trial % 2 else rng.exponential(0.05, (12, m)) * (rng.random((12, m)) < 0.3)
        perm = rng.permutation(pool.shape[0])
        t_size = int(rng.integers(1, 6))
        s_size = int(rng.integers(0, t_size + 1))
        big, small, e = perm[:t_size], perm[:s_size], perm[t_size]
        f = lambda idx, pool=pool, phi=phi, w=w: set_gain(pool[list(idx)], phi, w)  # noqa: E731
        f_s, f_t = f(small), f(big)
        f_se, f_te = f([*small, e]), f([*big, e])
        tol = 1e-9 * max(1.0, f_te)
        assert f_t >= f_s - tol and f_se >= f_s - tol and f_te >= f_t - tol
        assert f_se - f_s >= f_te - f_t - tol


def test_second_identical_pro_gains_less_than_the_first() -> None:
    w = 0.02
    first = set_gain(PREC[3][None, :], 1.0, w)
    both = set_gain(np.vstack([PREC[3], PREC[3]]), 1.0, w)
    assert first > 0.0
    assert 0.0 < both - first < first
    # closed form per POI: f1 - (f2 - f1) = 2 phi a^2 / (w (w + a) (w + 2a)) (phi = 1)
    a = PREC[3]
    loss = np.sum(2 * a * a / (w * (w + a) * (w + 2 * a)))
    assert first - (both - first) == pytest.approx(loss, rel=1e-9)


# ----------------------------------------------------------------------------- greedy vs optimum


def test_greedy_against_exhaustive_search() -> None:
    rng = np.random.default_rng(3)
    m = POS.shape[0]
    equal = total = 0
    worst_ratio = 1.0
    worst_certified = 1.0
    for _ in range(8):
        subset = np.sort(rng.choice(len(LIB), size=10, replace=False))
        lib = [LIB[i] for i in subset]
        phi = rng.uniform(0.5, 2.0, m)
        w = rng.uniform(0.005, 0.05, m)
        for n_obs in (2, 3):
            res = greedy_assignment(lib, n_obs, N_MEAN, 0.0, PERIOD, SAMPLES, POS, NOR, phi, w,
                                    CAM, min_separation_m=0.0, keep_out_m=0.0)
            rows = PREC[subset]
            opt = max(_truth_gain(rows[list(c)], phi, w)
                      for c in itertools.combinations(range(10), n_obs))
            assert len(set(res.indices)) == n_obs
            truth = _truth_gain(rows[list(res.indices)], phi, w)
            assert res.gain == pytest.approx(truth, rel=1e-10)
            assert sum(res.marginal_gains) == pytest.approx(res.gain, rel=1e-10)
            assert res.gain >= (1.0 - 1.0 / math.e) * opt
            assert res.gain <= opt * (1 + 1e-12)
            assert res.upper_bound >= opt * (1 - 1e-12)
            assert res.ratio_bound <= res.gain / opt + 1e-12
            assert not res.separation_active
            assert online_upper_bound(rows, [], n_obs, phi, w) >= res.upper_bound * (1 - 1e-12)
            equal += res.gain >= opt * (1 - 1e-12)
            total += 1
            worst_ratio = min(worst_ratio, res.gain / opt)
            worst_certified = min(worst_certified, res.ratio_bound)
    print(f"greedy = OPT in {equal}/{total}; worst gain/OPT {worst_ratio:.6f}; "
          f"worst certified ratio_bound {worst_certified:.4f}")
    assert worst_certified > 1.0 - 1.0 / math.e  # the online bound beats the a-priori one here


# ----------------------------------------------------------------------------- safety


def test_separation_and_keep_out_respected() -> None:
    # closely spaced phases: neighbours are a few metres apart; two close orbits (6.5 m from the
    # centre, 1.5 m from the surface) are very informative but violate the keep-out
    lib = pro_library([12.0, 20.0], [15.0], np.linspace(0.0, 1.0, 6),
                      cross_phase_offsets_rad=(np.pi / 2,))
    lib += [Pro(6.5, 0.0, 0.0, 6.5, np.pi / 2), Pro(6.5, 2.0, 0.0, 7.0, 2.0 + np.pi / 2)]
    args = (N_MEAN, 0.0, PERIOD, SAMPLES, POS, NOR, 1.0, 0.5, CAM)
    free = greedy_assignment(lib, 4, *args, min_separation_m=0.0, keep_out_m=0.0)
    sep, keep = 8.0, 8.0
    safe = greedy_assignment(lib, 4, *args, min_separation_m=sep, keep_out_m=keep)

    def dense_min(a: Pro, b: Pro | None) -> float:
        pa = _dense_positions(a)
        pb = 0.0 if b is None else _dense_positions(b)
        return float(np.min(np.linalg.norm(pa - pb, axis=1)))

    # the constraints bind: the unconstrained choice violates both
    assert min(dense_min(p, None) for p in free.pros) < keep
    assert min(dense_min(a, b) for a, b in itertools.combinations(free.pros, 2)) < sep
    assert safe.separation_active
    assert all(dense_min(p, None) >= keep for p in safe.pros)
    assert all(dense_min(a, b) >= sep for a, b in itertools.combinations(safe.pros, 2))
    assert safe.upper_bound >= safe.gain > 0.0
    with pytest.raises(ValueError, match="separation"):
        greedy_assignment(lib, 6, *args, min_separation_m=30.0, keep_out_m=keep)
    with pytest.raises(ValueError, match="keep-out"):
        greedy_assignment(lib, 4, *args, keep_out_m=100.0)


# ----------------------------------------------------------------------------- matching, trigger


def test_match_to_observers_equals_brute_force() -> None:
    rng = np.random.default_rng(4)
    for _ in range(10):
        idx = rng.choice(len(LIB), size=4, replace=False)
        pros = [LIB[i] for i in idx]
        t = float(rng.uniform(0.0, PERIOD))
        states = np.hstack([rng.uniform(-50.0, 50.0, (4, 3)), rng.normal(0.0, 0.02, (4, 3))])
        got = match_to_observers(states, pros, N_MEAN, t)
        assert sorted(got) == [0, 1, 2, 3]
        slots = [p.state(N_MEAN, t)[:3] for p in pros]

        def cost(perm: tuple[int, ...] | list[int], states: np.ndarray = states,
                 slots: list[np.ndarray] = slots) -> float:
            return sum(float(np.linalg.norm(states[i, :3] - slots[j])) for i, j in enumerate(perm))

        best = min(cost(perm) for perm in itertools.permutations(range(4)))
        assert cost(got) == pytest.approx(best, rel=1e-12)
    with pytest.raises(ValueError):
        match_to_observers(np.zeros((5, 6)), pros, N_MEAN, 0.0)
    with pytest.raises(ValueError):
        match_to_observers(np.full((4, 6), np.nan), pros, N_MEAN, 0.0)


def test_gain_saturated_rule() -> None:
    assert not gain_saturated([], 0.2)
    assert not gain_saturated([100.0], 0.2)
    assert not gain_saturated([100.0, 60.0, 30.0, 20.0], 0.2)  # exactly at the threshold
    assert gain_saturated([100.0, 60.0, 30.0, 19.9], 0.2)
    assert not gain_saturated([100.0, 10.0, 50.0], 0.2)  # only the latest window counts
    assert gain_saturated([0.0, 0.0], 0.2)  # the set never gained anything
    # a fixed set on its real precision: per-orbit gains decay as the POIs fill in
    w, gains = 0.02 + 0 * PREC[0], []
    for _ in range(6):
        gains.append(set_gain(PREC[[0, 9]], 1.0, w))
        w = w + PREC[0] + PREC[9]
    assert all(b < a for a, b in pairwise(gains))
    first_below = next(i for i, g in enumerate(gains) if g < 0.2 * gains[0])
    flags = [gain_saturated(gains[: k + 1], 0.2) for k in range(6)]
    assert flags == [k >= first_below for k in range(6)]
    for bad in (0.0, 1.0, math.nan):
        with pytest.raises(ValueError):
            gain_saturated([1.0, 0.5], bad)
    with pytest.raises(ValueError):
        gain_saturated([1.0, math.inf], 0.5)


# ----------------------------------------------------------------------------- bad input


def test_bad_inputs_raise() -> None:
    m = POS.shape[0]
    with pytest.raises(ValueError):
        set_gain(PREC[:2], 1.0, 0.0)  # zero fused precision: infinite variance
    with pytest.raises(ValueError):
        set_gain(PREC[:2], 1.0, np.full(m, np.nan))
    with pytest.raises(ValueError):
        set_gain(PREC[:2, :10], 1.0, np.full(m, 0.02))
    with pytest.raises(ValueError):
        set_gain(-PREC[:2], 1.0, 0.02)
    with pytest.raises(ValueError):
        expected_precision(LIB[0], N_MEAN, 0.0, -1.0, 10, POS, NOR, CAM)
    with pytest.raises(ValueError):
        expected_precision(LIB[0], N_MEAN, 0.0, PERIOD, 0, POS, NOR, CAM)
    with pytest.raises(ValueError):
        greedy_assignment(LIB[:3], 4, N_MEAN, 0.0, PERIOD, SAMPLES, POS, NOR, 1.0, 0.02, CAM)
    with pytest.raises(ValueError):
        online_upper_bound(PREC, [0, 0], 2, 1.0, 0.02)
