"""Tests of ground.planning.pro_sets on its own: the uplink form of a PRO, the planning weights,
and a set chosen around an untasked observer (its PRO kept, its coverage counted, the others
clear of it)."""

from __future__ import annotations

import math

import numpy as np

from gnc.mission import MissionConstants
from gnc.poi_map import PoiMap
from gnc.pro import Pro, min_distance_between
from ground.planning.pro_sets import ProSetPlanner, elements
from interfaces.contracts.scenario import Scenario

SC = Scenario.model_validate({
    "name": "sets", "duration_s": 5000.0, "target": {"pois": 200},
    "observers": {"count": 3, "start": "pro", "rho_x_m": 30.0, "rho_z_m": 30.0},
    "assignment": {"rho_x_m": [10.0, 20.0], "rho_z_m": [10.0, 25.0], "phases": 4,
                   "samples": 8, "poi_stride": 2}})


def _planner() -> ProSetPlanner:
    return ProSetPlanner(SC, MissionConstants.of(SC))


def test_elements_and_pro_of_are_inverse() -> None:
    pro = Pro(12.0, 0.3, -1.0, 20.0, 1.1)
    assert Pro.of(elements(pro)) == pro


def test_weights_subsample_the_map_and_count_the_untasked() -> None:
    sets, fused = _planner(), PoiMap.uniform(200, 1.0, 3)
    w, phi = sets.weights(100.0, fused, set(), {})
    assert w.shape == (100,) and np.allclose(phi, 2.0 * fused.phi[::2])
    pros = {1: elements(sets.library[0])}
    w1, _ = sets.weights(100.0, fused, {1}, pros)
    assert np.allclose(w1, w + sets.expected(sets.library[0], 100.0))


def test_a_set_around_an_untasked_observer() -> None:
    sets, fused = _planner(), PoiMap.uniform(200, 1.0, 3)
    pros = {i: elements(sets.library[i]) for i in (1, 2, 3)}
    w, phi = sets.weights(700.0, fused, {2}, pros)
    out, per_observer, gain, bound = sets.plan_set(400.0, 700.0, w, phi, {2}, {}, pros)
    assert out[2] == pros[2] and per_observer[1] == -1
    assert 0.0 < gain <= bound
    assert math.isclose(gain, sets.gain(per_observer, 700.0, w, phi), rel_tol=1e-9)
    sep = SC.assignment.min_separation_m
    for i in (1, 3):
        assert min_distance_between(Pro.of(out[i]), Pro.of(pros[2]), sets.n)[0] >= sep
