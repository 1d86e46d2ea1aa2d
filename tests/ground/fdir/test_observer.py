"""The FDIR's per-observer state and the pure pieces of a window's verdict, called directly:
loss counting by sequence number and its limit, the ground's own H_i with loss compensation,
the twin's pointing and the sampled threshold."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gnc.infocost import Camera
from gnc.poi import sphere_pois
from gnc.poi_map import PoiMap
from gnc.twin import TwinModel, centre_boresights, planned_boresights
from ground.fdir.observer import ObserverState, TimeSeries, loss_limit, loss_tail
from ground.fdir.threshold import sampled_threshold


def test_losses_are_counted_from_sequence_gaps() -> None:
    obs = ObserverState()
    assert obs.count_observations([1, 2, 3]) == 0
    assert obs.count_observations([5, 8]) == 3  # 4, 6 and 7 never arrived
    assert (obs.received, obs.lost, obs.last_seq) == (5, 3, 8)
    assert obs.lost_fraction() == pytest.approx(3 / 8)
    assert obs.count_observations([7]) == 0, "a late one is not a loss"


def test_loss_limit_is_the_nominal_loss_plus_tolerance_and_two_sigma() -> None:
    # Bernoulli (L = 1): p + tol + 2 sqrt(p (1-p) / n)
    assert loss_limit(0.1, 1.0, 0.05, 100) == pytest.approx(0.15 + 2 * math.sqrt(0.09 / 100))
    # bursts of mean length L inflate the variance by 2L - 1
    assert loss_limit(0.1, 5.0, 0.05, 100) == pytest.approx(0.15 + 2 * math.sqrt(0.81 / 100))
    assert loss_limit(0.0, 1.0, 0.05, 0) == pytest.approx(0.05)
    assert loss_limit(0.9, 1.0, 0.5, 1) == 1.0


def test_loss_tail_is_the_binomial_tail_with_bursts_thinning_the_draws() -> None:
    from scipy.stats import binom

    assert loss_tail(5, 15, 0.05, 1.0) == pytest.approx(binom.sf(4, 15, 0.05))
    assert loss_tail(12, 22, 0.05, 1.0) == pytest.approx(binom.sf(11, 22, 0.05))
    # bursts of mean length 3: a fifth of the draws (2L - 1 = 5)
    assert loss_tail(10, 50, 0.1, 3.0) == pytest.approx(binom.sf(1, 10, 0.1))
    assert loss_tail(0, 10, 0.1, 1.0) == 1.0 and loss_tail(1, 10, 0.0, 1.0) == 0.0
    assert loss_tail(10, 10, 0.1, 1.0) == pytest.approx(1e-10)  # all lost: p^n
    # k = 0.4 of n = 4 after thinning: more likely than losing one whole draw of four
    assert 1.0 - 0.9**4 < loss_tail(2, 20, 0.1, 3.0) < 1.0
    assert loss_tail(5, 5, 1.0, 1.0) == 1.0  # a link that loses everything nominally


def test_a_series_is_nan_where_it_is_stale_and_none_where_any_is() -> None:
    series = TimeSeries()
    for t in (0.0, 2.0, 20.0):
        series.add(t, np.array([t, -t]))
    each = series.at_each(np.array([1.0, 10.0, 21.0]))
    assert each is not None
    assert each[0].tolist() == [1.0, -1.0] and each[2].tolist() == [20.0, -20.0]
    assert np.isnan(each[1]).all()  # 8 s from every sample
    assert series.at(np.array([1.0, 10.0])) is None
    assert series.at(np.array([1.0, 21.0])).tolist() == [[1.0, -1.0], [20.0, -20.0]]
    assert TimeSeries().at_each(np.array([1.0])) is None
    series.add(10.0, np.array([10.0, -10.0]))  # read after a change: the new sample counts
    assert series.at(np.array([9.0])).tolist() == [[9.0, -9.0]]
    series.forget_before(15.0)  # and after forgetting: the samples before 10 s are gone
    assert series.t == [10.0, 20.0] and np.isnan(series.at_each(np.array([1.0]))).all()


def test_a_series_read_while_it_grows_reads_as_one_built_at_once() -> None:
    """Samples after the last extend the arrays in place (grown as they fill); one out of
    order, a forgotten start or a sample of another width makes them afresh: every read equals
    a series given the same samples at once, bit for bit."""
    rng = np.random.default_rng(4)
    grown = TimeSeries()
    times = np.cumsum(rng.uniform(0.5, 1.5, 60))
    for k, t in enumerate(times):
        grown.add(float(t), rng.standard_normal(3))
        if k == 30:
            grown.add(float(t) - 0.2, rng.standard_normal(3))  # out of order
        if k == 45:
            grown.forget_before(float(times[20]))
        fresh = TimeSeries()
        for u, v in zip(grown.t, grown.v, strict=True):
            fresh.add(u, v)
        at = np.sort(rng.uniform(grown.t[0] - 1.0, t + 1.0, 5))
        assert np.array_equal(grown.at_each(at), fresh.at_each(at), equal_nan=True)
    grown.add(float(times[-1]) + 1.0, np.ones(2))  # another width: refused by the reader
    with pytest.raises(ValueError):
        grown.at_each(np.array([times[-1]]))


def test_twin_points_at_the_reported_aim_or_the_centre() -> None:
    pos = np.array([[30.0, 0.0, 0.0], [0.0, 40.0, 0.0]])
    assert planned_boresights(None, pos) == pytest.approx(centre_boresights(pos))
    aim = np.zeros((2, 7))
    aim[:, 4:7] = [[30.0, 0.0, 10.0], [0.0, 40.0, -10.0]]
    assert planned_boresights(aim, pos) == pytest.approx(np.array([[0, 0, 1.0], [0, 0, -1.0]]))
    aim[1, 4:7] = pos[1]  # aim point on the spacecraft: no direction, the centre instead
    assert planned_boresights(aim, pos) == pytest.approx(centre_boresights(pos))


def test_sampled_threshold_is_seeded_and_grows_with_the_cone() -> None:
    # a camera narrower than the target: where it points decides what it sees
    twin = TwinModel(*sphere_pois(500, 5.0), Camera(math.radians(3.0), 100.0, 0.01), 5.0)
    m = PoiMap.uniform(500, 4.0, 1)
    psi, phi = m.variance() ** 2, m.phi
    t = np.linspace(0.0, 2 * math.pi, 40, endpoint=False)
    pos = np.stack([20 * np.sin(t), 40 * np.cos(t), 25 * np.sin(t)], axis=1)
    bore = centre_boresights(pos)

    def tau(eps_deg: float, seed: int = 1) -> float | None:
        return sampled_threshold(twin, pos, bore, psi, phi, 0.0, math.radians(eps_deg), 10, 0.0,
                                 np.random.default_rng(seed))

    assert tau(1.0) == tau(1.0) and tau(1.0) != tau(1.0, seed=2)
    assert 0.0 < tau(0.5) < tau(3.0)
    floored = sampled_threshold(twin, pos, bore, psi, phi, 0.0, math.radians(0.5), 10, 0.5,
                                np.random.default_rng(1))
    assert floored == 0.5


def test_plans_evaluated_once_over_a_window_give_each_images_own_bits() -> None:
    """``planned_on``: an image's planned position taken from the plans evaluated once over
    the window's image times is the one evaluated at its time alone, to the bit, on a transfer
    and on the PRO; a time off the grid is evaluated alone; a new plan is taken up."""
    from fsw.lib.scp import plan_transfer
    from gnc.hcw import mean_motion
    from gnc.pro import Pro
    from gnc.twin import FlightPlan, Transfer

    n = mean_motion(500e3)
    old, new = Pro(20.0, 0.0, 0.0, 25.0, 0.0), Pro(12.0, 1.0, 0.0, 15.0, 2.0)
    plan = plan_transfer(n, old.state(n, 30.0), new.state(n, 330.0), 300.0, 30, 1e-3, 8.0)
    obs = ObserverState()
    obs.plans[1] = FlightPlan(0.0, old)
    obs.plans[2] = FlightPlan(30.0, new, Transfer(plan.t_s + 30.0, plan.x, plan.u))
    grid = np.array([k * 0.1 for k in range(0, 4000, 10)])  # the ticks' own times, k dt
    for t in (grid[[5]], grid[[100, 101]], grid[[390]], np.array([12.345])):
        alone, on = obs.planned(n, t), obs.planned_on(n, t, grid)
        assert alone is not None and on is not None
        assert all(np.array_equal(a, b) for a, b in zip(alone, on, strict=True)), t
    obs.plans[2] = FlightPlan(30.0, old)  # replaced: evaluated again
    replaced = obs.planned_on(n, grid[[100]], grid)
    assert replaced is not None
    assert np.array_equal(replaced[0], old.states(n, grid[[100]])[:, :3])
