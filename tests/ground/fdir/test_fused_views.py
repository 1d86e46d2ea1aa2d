"""What each observer fused, as the ground reconstructs it (ground/fdir/fused_views.py): an
image joins the views of the observers within crosslink range of its observer at the image
time, by their nav positions; H_i on an observer's own view is Eq. 8 on that view, and on a
view holding everything it is the ground's."""

from __future__ import annotations

import numpy as np
import pytest

from gnc.infocost import agent_contributions
from gnc.poi_map import PoiMap
from ground.fdir.fused_views import MAX_SHARE, FusedViews
from ground.fdir.observer import MAX_JUDGED_LOSS, ObserverState
from interfaces.contracts.messages import PoiObservations


def _at(*positions: tuple[float, float, float]) -> dict[int, ObserverState]:
    """Observers with a nav report at 10 s at each of ``positions`` (LVLH, m)."""
    out = {}
    for sc, p in enumerate(positions, 1):
        out[sc] = ObserverState()
        out[sc].nav.add(10.0, np.array(p))
    return out


def _image(sc: int, poi: list[int], prec: list[float]) -> PoiObservations:
    return PoiObservations(sender=f"sc{sc}", t_sim=10.0, spacecraft=sc, image_t_s=10.0,
                           poi=poi, precision=prec)


def test_an_image_joins_the_views_of_the_observers_in_range() -> None:
    observers = _at((0.0, 0.0, 0.0), (50.0, 0.0, 0.0), (0.0, 90.0, 0.0))
    views = FusedViews.of(3, 4, range_m=80.0)
    views.add([_image(1, [0, 2], [0.5, 0.25])], observers)
    assert views.by_source.sum(axis=1).tolist() == [[0.5, 0, 0.25, 0], [0.5, 0, 0.25, 0],
                                                    [0, 0, 0, 0]]
    views.add([_image(3, [3], [1.0])], observers)  # 90 m from sc1, 103 m from sc2: alone
    assert views.by_source.sum(axis=1)[:, 3].tolist() == [0.0, 0.0, 1.0]
    del observers[2].nav.t[:], observers[2].nav.v[:]  # sc2's position unknown: not shared
    views.add([_image(1, [1], [2.0])], observers)
    assert views.by_source.sum(axis=1)[:, 1].tolist() == [2.0, 0.0, 0.0]


def test_h_i_on_a_view_of_everything_is_the_grounds_and_less_fused_raises_it() -> None:
    rng = np.random.default_rng(4)
    m = PoiMap.uniform(30, 2.0, 2)
    for agent in (1, 2):
        m.add(agent, np.arange(30), rng.uniform(0.2, 1.0, 30))
    everything = FusedViews(80.0, np.tile(m.F[None], (2, 1, 1)), np.ones((2, 2)))
    ground = agent_contributions(m.phi, m.w_inv, m.F)
    assert everything.contributions(m, np.zeros(2)) == pytest.approx(ground)
    # each fused only its own: ψ larger
    alone = FusedViews(80.0, np.einsum("ij,jm->ijm", np.eye(2), m.F), np.eye(2))
    own = alone.contributions(m, np.zeros(2))
    assert np.all(own > ground)
    expected = [float(np.sum(m.phi * m.F[i] / (m.w_inv + m.F[i]) ** 2)) for i in range(2)]
    assert own == pytest.approx(expected)


def test_a_window_of_images_is_added_as_one_image_at_a_time_would() -> None:
    observers = _at((0.0, 0.0, 0.0), (50.0, 0.0, 0.0), (0.0, 90.0, 0.0))
    images = [_image(1, [0, 2], [0.5, 0.25]), _image(3, [3], [1.0]), _image(2, [1, 2], [0.1, 0.2])]
    together, alone = FusedViews.of(3, 4, 80.0), FusedViews.of(3, 4, 80.0)
    together.add(images, observers)
    for m in images:
        alone.add([m], observers)
    assert together.by_source.sum(axis=1).tolist() == alone.by_source.sum(axis=1).tolist()
    assert together.images.tolist() == alone.images.tolist() == [[1, 1, 0], [1, 1, 0], [0, 0, 1]]
    # sc2's image: sc1 in range
    assert together.by_source.sum(axis=1)[:, 1].tolist() == [0.1, 0.1, 0.0]


def test_what_was_lost_on_the_way_is_scaled_up_on_each_view() -> None:
    """Half of sc1's observations lost on the way to the ground: its precision doubled, in its
    own H_i and in every view; a share above MAX_JUDGED_LOSS is capped."""
    rng = np.random.default_rng(2)
    m = PoiMap.uniform(50, 4.0, 3)
    for agent in range(1, 4):
        m.add(agent, rng.choice(50, 20, replace=False), rng.uniform(0.5, 2.0, 20))
    views = FusedViews(80.0, np.tile(m.F[None], (3, 1, 1)), np.ones((3, 3)))
    assert views.contributions(m, np.zeros(3)) == pytest.approx(
        agent_contributions(m.phi, m.w_inv, m.F))
    for lost, scale in ((0.5, 2.0), (0.99, 1.0 / (1.0 - MAX_JUDGED_LOSS))):
        scaled = m.F.copy()
        scaled[0] *= scale
        assert views.contributions(m, np.array([lost, 0.0, 0.0])) == pytest.approx(
            agent_contributions(m.phi, m.w_inv, scaled))


def test_each_neighbours_part_of_a_view_is_scaled_to_the_images_its_observer_fused() -> None:
    """Three observers, each with 10 images every view holds.  sc1 says it fused 5 of sc2's
    and all 10 of sc3's (a crosslink from sc2 losing half): its H_i is Eq. 8 on its own
    precision, half of sc2's and all of sc3's; sc2 fused everything; sc3 said nothing (no
    scaling).  One who fused more than the ground counts is scaled up, at most MAX_SHARE."""
    rng = np.random.default_rng(5)
    m = PoiMap.uniform(40, 3.0, 3)
    for agent in range(1, 4):
        m.add(agent, rng.choice(40, 15, replace=False), rng.uniform(0.5, 2.0, 15))
    views = FusedViews(80.0, np.tile(m.F[None], (3, 1, 1)), np.full((3, 3), 10.0))
    nan = np.nan
    shared = np.array([[nan, 5.0, 10.0], [10.0, nan, 10.0], [nan, nan, nan]])
    got = views.contributions(m, np.zeros(3), shared)
    full = agent_contributions(m.phi, m.w_inv, m.F)
    view1 = m.F[0] + 0.5 * m.F[1] + m.F[2]
    h1 = float(np.sum(m.phi * m.F[0] / (m.w_inv + view1) ** 2))
    assert got == pytest.approx([h1, full[1], full[2]])
    assert abs(got[0] / full[0] - 1.0) > 0.05  # unscaled, its honest report would be off
    more = np.array([[nan, 100.0, 10.0], [nan, nan, nan], [nan, nan, nan]])
    view1 = m.F[0] + MAX_SHARE * m.F[1] + m.F[2]
    assert views.contributions(m, np.zeros(3), more)[0] == pytest.approx(
        float(np.sum(m.phi * m.F[0] / (m.w_inv + view1) ** 2)))


def test_views_are_kept_by_source() -> None:
    """An image joins the view of each observer in range under its own source: the sum over
    sources is the view."""
    observers = _at((0.0, 0.0, 0.0), (50.0, 0.0, 0.0), (0.0, 90.0, 0.0))
    views = FusedViews.of(3, 4, 80.0)
    views.add([_image(1, [0, 2], [0.5, 0.25]), _image(2, [2], [1.0])], observers)
    assert views.by_source[1, 0].tolist() == [0.5, 0.0, 0.25, 0.0]  # sc1's image in sc2's view
    assert views.by_source[0, 1].tolist() == [0.0, 0.0, 1.0, 0.0]
    assert views.by_source[2].sum() == 0.0  # sc3 out of range of both
    assert views.by_source.sum(axis=1)[0].tolist() == [0.5, 0.0, 1.25, 0.0]
