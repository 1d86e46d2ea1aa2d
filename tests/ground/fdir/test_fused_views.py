"""What each observer fused, as the ground reconstructs it (ground/fdir/fused_views.py): an
image joins the views of the observers within crosslink range of its observer at the image
time, by their nav positions; H_i on an observer's own view is Eq. 8 on that view, and on a
view holding everything it is the ground's."""

from __future__ import annotations

import numpy as np
import pytest

from gnc.infocost import agent_contributions
from gnc.poi_map import PoiMap
from ground.fdir.fused_views import FusedViews
from ground.fdir.observer import ObserverState
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
    views.add(_image(1, [0, 2], [0.5, 0.25]), observers)
    assert views.fused.tolist() == [[0.5, 0, 0.25, 0], [0.5, 0, 0.25, 0], [0, 0, 0, 0]]
    views.add(_image(3, [3], [1.0]), observers)  # 90 m from sc1, 103 m from sc2: alone
    assert views.fused[:, 3].tolist() == [0.0, 0.0, 1.0]
    del observers[2].nav.t[:], observers[2].nav.v[:]  # sc2's position unknown: not shared
    views.add(_image(1, [1], [2.0]), observers)
    assert views.fused[:, 1].tolist() == [2.0, 0.0, 0.0]


def test_h_i_on_a_view_of_everything_is_the_grounds_and_less_fused_raises_it() -> None:
    rng = np.random.default_rng(4)
    m = PoiMap.uniform(30, 2.0, 2)
    for agent in (1, 2):
        m.add(agent, np.arange(30), rng.uniform(0.2, 1.0, 30))
    everything = FusedViews(80.0, np.tile(m.F.sum(axis=0), (2, 1)))
    ground = agent_contributions(m.phi, m.w_inv, m.F)
    assert everything.contributions(m, np.zeros(2)) == pytest.approx(ground)
    alone = FusedViews(80.0, m.F.copy())  # each fused only its own: ψ larger
    own = alone.contributions(m, np.zeros(2))
    assert np.all(own > ground)
    expected = [float(np.sum(m.phi * m.F[i] / (m.w_inv + m.F[i]) ** 2)) for i in range(2)]
    assert own == pytest.approx(expected)
