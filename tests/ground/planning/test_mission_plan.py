"""Tests of ground.planning.mission_plan: scenario phases issued as given, information phases
chosen by the greedy of ground.planning.orbit_assignment (checked against an independent call
and brute-force matching), and reassignment when the measured gain saturates, closed on a fused
map fed with what the issued orbits see."""

from __future__ import annotations

import itertools
import math
from itertools import pairwise

import numpy as np
import pytest

from gnc.mission import MissionConstants
from gnc.poi import sphere_pois
from gnc.poi_map import PoiMap
from gnc.pro import Pro, min_distance_between, min_distance_to_origin
from ground.planning.mission_plan import UPLINK_LEAD_S, MissionPlan
from ground.planning.orbit_assignment import expected_precision, greedy_assignment
from interfaces.contracts.scenario import Scenario

POS, NOR = sphere_pois(400, 5.0)


def _scenario(phases: list[dict], **assignment: object) -> Scenario:
    return Scenario.model_validate({
        "name": "plan", "duration_s": 20000.0, "target": {"pois": 400},
        "observers": {"count": 3, "start": "pro", "rho_x_m": 30.0, "rho_z_m": 30.0},
        "assignment": {"rho_x_m": [10.0, 20.0], "rho_z_m": [10.0, 25.0], "phases": 4,
                       "samples": 8, "poi_stride": 1, **assignment},
        "phases": phases})


def _pro(e: object) -> Pro:
    return Pro(e.rho_x_m, e.alpha_x_rad, e.rho_y_m, e.rho_z_m, e.alpha_z_rad)  # type: ignore[attr-defined]


def _fly(plan: MissionPlan, fused: PoiMap, t0: float, t1: float, dt: float = 20.0) -> None:
    """Advance the plan from t0 to t1 (s), feeding the map what the issued PROs see (after
    arrival; one image per second, camera on the target centre)."""
    t = t0
    while t <= t1 + 1e-9:
        plan.update(t, fused)
        cur = plan.current
        if cur is not None and t >= cur.t_arrive_s:
            for i, e in cur.pros.items():
                fused.add(i, np.arange(POS.shape[0]),
                          expected_precision(_pro(e), plan.n, t, dt, int(dt), POS, NOR,
                                             plan.camera))
        t += dt


def test_scenario_phases_are_issued_at_their_uplink_time() -> None:
    sc = _scenario([{"name": "a", "start_s": 500.0, "transfer_s": 300.0, "rho_x_m": 12.0},
                    {"name": "b", "start_s": 1500.0, "transfer_s": 400.0, "phase0_deg": 40.0}])
    plan = MissionPlan(sc, MissionConstants.of(sc))
    fused = PoiMap.uniform(400, 1.0, 3)
    assert plan.current is not None and plan.current.phase == "initial"
    plan.update(500.0 - UPLINK_LEAD_S - 10.0, fused)
    assert plan.current.phase == "initial"
    plan.update(500.0 - UPLINK_LEAD_S, fused)
    a = plan.current
    assert (a.id, a.phase, a.t_depart_s, a.t_arrive_s) == (2, "a", 500.0, 800.0)
    plan.update(2000.0, fused)
    b = plan.current
    assert (b.id, b.phase, b.t_depart_s, b.t_arrive_s) == (3, "b", 1500.0, 1900.0)
    for i in (1, 2, 3):
        assert np.allclose([b.pros[i].rho_x_m, b.pros[i].alpha_x_rad, b.pros[i].rho_z_m],
                           [sc.phases[1].rho_x_m, math.radians(40.0 + 120.0 * (i - 1)),
                            sc.phases[1].rho_z_m])
    assert plan.decisions == []


@pytest.mark.parametrize("contact", ["continuous", "passes"])
def test_with_passes_the_first_phase_is_loaded_before_the_run(contact: str) -> None:
    """Observers released from the target (no initial assignment), the first phase at 500 s:
    under passes.toml's station, whose passes come at 29-498 s and 5,963-6,367 s, its uplink
    time (440 s) is in contact and it waits for it; under a station whose first pass comes
    later, it is issued at t = 0, to be aboard before the run; with continuous contact, at its
    uplink time."""
    base = _scenario([{"name": "a", "start_s": 500.0, "transfer_s": 300.0, "rho_x_m": 12.0}])
    station = {"name": "mid", "latitude_deg": 48.08, "longitude_deg": 11.28}
    data = base.model_dump()
    data["observers"]["start"] = "deploy"
    sc = Scenario.model_validate({**data, "orbit": {"raan_deg": 255.0,
                                                               "arg_latitude_deg": 90.0},
                                  "ground": {"contact": contact, "stations": [station]}})
    late = Scenario.model_validate({**sc.model_dump(), "phases": [
        {"name": "a", "start_s": 1500.0, "transfer_s": 300.0, "rho_x_m": 12.0}]})
    fused = PoiMap.uniform(400, 1.0, 3)
    for scenario, preloaded in ((sc, False), (late, contact == "passes")):
        plan = MissionPlan(scenario, MissionConstants.of(scenario))
        assert plan.current is None
        plan.update(0.0, fused)
        assert (plan.current is not None) is preloaded
        start = scenario.phases[0].start_s
        plan.update(start - UPLINK_LEAD_S, fused)
        assert plan.current is not None and plan.current.t_depart_s == start
        assert len(plan.issued) == 1


def test_with_passes_a_phase_held_for_a_pass_departs_after_it() -> None:
    """Under passes.toml's station (passes 29-498 s, then 5,963-6,367 s): phase a's uplink
    (440 s) is in contact and keeps its time; phase b's (1,440 s) waits for the pass at
    5,963 s and departs UPLINK_LEAD_S after it, with its whole transfer time; continuous
    contact keeps both times."""
    phases = [{"name": "a", "start_s": 500.0, "transfer_s": 300.0, "rho_x_m": 12.0},
              {"name": "b", "start_s": 1500.0, "transfer_s": 400.0, "rho_x_m": 14.0}]
    station = {"name": "mid", "latitude_deg": 48.08, "longitude_deg": 11.28}
    data = _scenario(phases).model_dump()
    fused = PoiMap.uniform(400, 1.0, 3)
    for contact in ("continuous", "passes"):
        sc = Scenario.model_validate({**data, "orbit": {"raan_deg": 255.0,
                                                         "arg_latitude_deg": 90.0},
                                      "ground": {"contact": contact, "stations": [station]}})
        plan = MissionPlan(sc, MissionConstants.of(sc))
        plan.update(440.0, fused)
        plan.update(1440.0, fused)
        a, b = plan.issued[1:]
        assert (a.t_depart_s, a.t_arrive_s) == (500.0, 800.0)
        if contact == "continuous":
            assert (b.t_depart_s, b.t_arrive_s) == (1500.0, 1900.0)
        else:
            assert b.t_depart_s == pytest.approx(5963.0 + UPLINK_LEAD_S, abs=1.0)
            assert b.t_arrive_s == pytest.approx(b.t_depart_s + 400.0)


def test_information_phase_takes_the_greedy_set_matched_to_the_observers() -> None:
    sc = _scenario([{"name": "insp", "start_s": 600.0, "transfer_s": 500.0,
                     "assign": "information"}])
    plan = MissionPlan(sc, MissionConstants.of(sc))
    fused = PoiMap.uniform(400, 1.0, 3)
    rng = np.random.default_rng(3)
    fused.add(1, np.arange(400), rng.uniform(0.0, 2.0, 400))  # an uneven fused view
    plan.update(600.0 - UPLINK_LEAD_S, fused)
    (d,) = plan.decisions
    a = sc.assignment
    ref = greedy_assignment(plan.library, 3, plan.n, 1100.0, a.window_s, a.samples, POS, NOR,
                            fused.phi, fused.w_inv + fused.F.sum(axis=0), plan.camera,
                            a.min_separation_m, sc.guidance.keep_out_m + a.keep_out_margin_m)
    assert sorted(d.library_indices) == sorted(ref.indices)
    assert math.isclose(d.expected_gain, ref.gain, rel_tol=1e-12)
    assert d.reason == "phase" and d.switched and d.current_gain is None
    issued = plan.current
    assert (issued.phase, issued.t_depart_s, issued.t_arrive_s) == ("insp", 600.0, 1100.0)
    # matching: no permutation brings the observers (on their initial PROs at departure)
    # closer in total to their new slots
    start = np.array([Pro(*sc.observers.pro(i)).state(plan.n, 600.0)[:3] for i in (1, 2, 3)])
    slots = [plan.library[k].state(plan.n, 600.0)[:3] for k in d.library_indices]

    def total(perm: tuple[int, ...]) -> float:
        return sum(float(np.linalg.norm(start[i] - slots[j])) for i, j in enumerate(perm))

    assert total((0, 1, 2)) <= min(total(p) for p in itertools.permutations(range(3))) + 1e-9
    for i, k in enumerate(d.library_indices):
        assert _pro(issued.pros[i + 1]) == plan.library[k]


def test_reassigns_when_the_measured_gain_saturates() -> None:
    sc = _scenario([{"name": "insp", "start_s": 300.0, "transfer_s": 300.0,
                     "assign": "information"}], check_period_s=300.0, saturation_fraction=0.5)
    plan = MissionPlan(sc, MissionConstants.of(sc))
    fused = PoiMap.uniform(400, 1.0, 3)
    _fly(plan, fused, 0.0, 6000.0)
    saturated = [d for d in plan.decisions if d.reason == "saturated"]
    assert saturated, "the gain of a fixed set diminishes: a reassignment must be considered"
    f = sc.assignment.saturation_fraction
    for d in saturated:
        g = d.measured_gains
        assert len(g) >= 2 and g[-1] < f * g[0]
        assert all(x >= 0.0 for x in g)  # H never increases
        assert d.current_gain is not None
        assert d.switched == (d.expected_gain > (1.0 + sc.assignment.min_improvement)
                              * d.current_gain)
        assert d.expected_gain <= d.upper_bound + 1e-15
    switched = [d for d in saturated if d.switched]
    assert switched
    ids = [a.id for a in plan.issued]
    assert ids == list(range(1, len(ids) + 1))
    for d in switched:  # issued one uplink lead after the decision, named after the phase
        a = next(x for x in plan.issued if x.phase == d.phase)
        assert a.t_depart_s == d.t_s + UPLINK_LEAD_S
        assert a.t_arrive_s == a.t_depart_s + sc.assignment.transfer_s
        assert a.phase.startswith("insp-r")
    # no check before arrival: the first window starts once the set is flown
    first = next(a for a in plan.issued if a.phase == "insp")
    assert all(d.t_s >= first.t_arrive_s + 2 * sc.assignment.check_period_s - 1e-9
               for d in saturated)


def test_keeps_the_current_set_unless_the_new_one_is_better_by_the_margin() -> None:
    sc = _scenario([{"name": "insp", "start_s": 300.0, "transfer_s": 300.0,
                     "assign": "information"}], min_improvement=1e6)
    plan = MissionPlan(sc, MissionConstants.of(sc))
    fused = PoiMap.uniform(400, 1.0, 3)
    _fly(plan, fused, 0.0, 4000.0)
    saturated = [d for d in plan.decisions if d.reason == "saturated"]
    assert saturated and not any(d.switched for d in saturated)
    assert [a.phase for a in plan.issued] == ["initial", "insp"]
    # each kept decision restarts the measurement: a later decision needs two new windows
    assert len(saturated) >= 2
    for prev, d in pairwise(saturated):
        assert len(d.measured_gains) >= 2
        assert d.t_s - prev.t_s >= len(d.measured_gains) * sc.assignment.check_period_s - 1e-9


def test_a_coming_phase_preempts_reassignment() -> None:
    sc = _scenario([{"name": "insp", "start_s": 300.0, "transfer_s": 300.0,
                     "assign": "information"},
                    {"name": "end", "start_s": 2400.0, "transfer_s": 300.0}],
                   check_period_s=200.0, saturation_fraction=0.9, transfer_s=2000.0)
    plan = MissionPlan(sc, MissionConstants.of(sc))
    fused = PoiMap.uniform(400, 1.0, 3)
    _fly(plan, fused, 0.0, 2300.0)
    # any reassignment would arrive after "end" starts, so none is decided
    assert [d.reason for d in plan.decisions] == ["phase"]
    assert plan.current.phase == "insp"


def test_poi_subsample_evaluates_every_kth_poi_with_scaled_importance() -> None:
    sc = _scenario([{"name": "insp", "start_s": 600.0, "transfer_s": 500.0,
                     "assign": "information"}], poi_stride=4)
    plan = MissionPlan(sc, MissionConstants.of(sc))
    fused = PoiMap.uniform(400, 1.0, 3)
    fused.add(2, np.arange(400), np.random.default_rng(4).uniform(0.0, 1.0, 400))
    plan.update(600.0 - UPLINK_LEAD_S, fused)
    (d,) = plan.decisions
    a = sc.assignment
    ref = greedy_assignment(plan.library, 3, plan.n, 1100.0, a.window_s, a.samples, POS[::4],
                            NOR[::4], 4.0 * fused.phi[::4],
                            (fused.w_inv + fused.F.sum(axis=0))[::4],
                            plan.camera, a.min_separation_m,
                            sc.guidance.keep_out_m + a.keep_out_margin_m)
    assert sorted(d.library_indices) == sorted(ref.indices)
    assert math.isclose(d.expected_gain, ref.gain, rel_tol=1e-12)
    whole = _scenario(sc.model_dump()["phases"], poi_stride=1)
    full = MissionPlan(whole, MissionConstants.of(whole))
    full.update(600.0 - UPLINK_LEAD_S, fused)
    # the subsample estimates the full expected gain (uniform Fibonacci subsample)
    assert math.isclose(d.expected_gain, full.decisions[0].expected_gain, rel_tol=0.1)


def test_recovery_drops_a_failed_camera_and_reassigns_around_it() -> None:
    sc = _scenario([])
    plan = MissionPlan(sc, MissionConstants.of(sc))
    fused = PoiMap.uniform(400, 1.0, 3)
    _fly(plan, fused, 0.0, 400.0)
    before = plan.current
    assert before is not None
    assert plan.recover(400.0, [(2, "camera", {"beta_hat": 0.5})], fused)
    after = plan.current
    assert after is not None and after.id == before.id + 1
    assert after.t_depart_s == 400.0 + UPLINK_LEAD_S
    assert after.pros[2] == before.pros[2]  # untasked, stays on its PRO
    sep = sc.assignment.min_separation_m
    for i in (1, 3):
        p = _pro(after.pros[i])
        assert p in plan.library
        assert min_distance_between(p, _pro(after.pros[2]), plan.n)[0] >= sep
    assert min_distance_between(_pro(after.pros[1]), _pro(after.pros[3]), plan.n)[0] >= sep
    d = plan.decisions[-1]
    assert d.reason == "recovery" and d.library_indices[1] == -1 and d.switched
    assert not plan.recover(500.0, [(2, "camera", {})], fused)  # once per observer and class
    assert not plan.recover(500.0, [(1, "state_sensor", {}), (1, "link", {}), (3, None, {})],
                            fused)  # not replanned


def test_recovery_gives_an_actuator_fault_a_pro_it_can_hold() -> None:
    """A 5° pointing fault with a 20° camera: the whole 5 m target stays in view from
    R / sin(15°) = 19.3 m; a thruster leak that pushed the observer 3 m off needs the keep-out
    plus twice that.  Faults of one FDIR cycle make one assignment; the others keep the
    nominal keep-out."""
    sc = _scenario([])
    plan = MissionPlan(sc, MissionConstants.of(sc))
    fused = PoiMap.uniform(400, 1.0, 3)
    issued = len(plan.issued)
    assert plan.recover(100.0, [(1, "actuator", {"pointing_error_deg": 5.0}),
                                (3, "actuator", {"nav_vs_plan_m": 3.0})], fused)
    assert len(plan.issued) == issued + 1
    need = 5.0 / math.sin(math.radians(15.0))
    keep = sc.guidance.keep_out_m + sc.assignment.keep_out_margin_m
    assert plan.impaired == {1: pytest.approx(need), 3: pytest.approx(keep + 6.0)}
    cur = plan.current
    assert cur is not None
    assert min_distance_to_origin(_pro(cur.pros[1]), plan.n)[0] >= need
    assert min_distance_to_origin(_pro(cur.pros[3]), plan.n)[0] >= keep + 6.0
    assert min_distance_to_origin(_pro(cur.pros[2]), plan.n)[0] >= keep


def test_later_information_phases_keep_the_recovery() -> None:
    """After a recovery, an information phase and its saturation reassignments still leave
    the failed camera's observer untasked and give the impaired one a PRO it can hold."""
    sc = _scenario([{"name": "insp", "start_s": 1000.0, "transfer_s": 300.0,
                     "assign": "information"}], check_period_s=200.0)
    plan = MissionPlan(sc, MissionConstants.of(sc))
    fused = PoiMap.uniform(400, 1.0, 3)
    _fly(plan, fused, 0.0, 300.0)
    assert plan.recover(300.0, [(2, "camera", {}), (3, "actuator", {"nav_vs_plan_m": 3.0})],
                        fused)
    dropped_pro = plan.current.pros[2]  # type: ignore[union-attr]
    _fly(plan, fused, 320.0, 8000.0)
    later = [a for a in plan.issued if a.t_depart_s >= 1000.0]
    assert len(later) >= 2  # the phase and at least one saturation reassignment
    need = plan.impaired[3]
    for a in later:
        assert a.pros[2] == dropped_pro
        assert min_distance_to_origin(_pro(a.pros[3]), plan.n)[0] >= need - 1e-9
    assert all(d.library_indices[1] == -1 for d in plan.decisions if d.t_s >= 300.0)


def test_an_impossible_keep_out_falls_back_and_an_impossible_set_changes_nothing() -> None:
    sc = _scenario([])
    plan = MissionPlan(sc, MissionConstants.of(sc))
    fused = PoiMap.uniform(400, 1.0, 3)
    # no library PRO keeps 1 km: the impaired one falls back to the nominal keep-out
    plan._holdable_keep_out = lambda ev: 1000.0  # type: ignore[method-assign]
    assert plan.recover(100.0, [(1, "actuator", {})], fused)
    # three observers, every one dropped: nothing left to task, the plan stays
    issued = len(plan.issued)
    assert not plan.recover(200.0, [(1, "camera", {}), (2, "camera", {}), (3, "camera", {})],
                            fused)
    assert len(plan.issued) == issued and plan.dropped == set()


def test_a_reissue_is_the_current_plan_under_a_new_id() -> None:
    sc = _scenario([])
    plan = MissionPlan(sc, MissionConstants.of(sc))
    before = plan.current
    assert before is not None
    assert plan.reissue(300.0)
    after = plan.current
    assert after is not None and after.id == before.id + 1 and after.pros == before.pros
    assert after.t_depart_s == 300.0 + UPLINK_LEAD_S
    assert after.t_arrive_s == after.t_depart_s + sc.assignment.transfer_s
