"""Ground passes flown (issue 29, item 1): the target at 500 km and 51.6° over one mid-latitude
station, a pass from 29 s to 498 s, the next at 5,963 s.

* **A link dead for a whole orbit.**  Observer 1 loses every link from 0 s to 5,900 s (it misses
  the first pass); observer 2's camera degrades just after the first pass ends.  Every message
  each spacecraft sent the ground is accounted for at the end, checked against the archive (what
  was sent, on the topics the ground subscribes to): dumped, lost to overflow, or still aboard.
  The ground declares observer 1 silent in the first pass, and observer 2's camera once its
  dump comes down in the second: judged from the window after the onset, declared a gap later.
  Uplinks wait for a pass.
* **A store too small.**  A 20 kB store fills before the first acquisition: the overflow is
  counted by topic and time, the decisive telemetry (priority 0) is never lost, and the ground
  reads the lost window as a link fault of known cause, never as a fault of an observer.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import pytest

from deploy.campaign import RunSpec, execute_run
from gnc.passes import ContactPlan
from harness.archive.reader import load_run
from harness.summary import RunSummary
from interfaces.contracts import catalogue as cat
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topology import topology
from interfaces.runtime.assembly import app_class
from tests.conftest import small_scenario

ONSET_S = 520.0
CUT_END_S = 5900.0


def _scenario(name: str, duration_s: float, **sections: Any) -> Scenario:
    return small_scenario(
        name, seed=11, duration_s=duration_s,
        orbit={"inclination_deg": 51.6, "raan_deg": 255.0, "arg_latitude_deg": 90.0},
        ground={"contact": "passes",
                "stations": [{"name": "mid", "latitude_deg": 48.08, "longitude_deg": 11.28}],
                **sections.pop("ground", {})},
        target={"radius_m": 5.0, "pois": 200}, camera={"half_angle_deg": 12.0},
        rates={"fdi_period_s": 30.0},
        observers={"count": 2, "start": "pro", "initial_attitude": "lvlh", "rho_x_m": 10.0,
                   "rho_z_m": 15.0},
        **sections)


def _fly(factory: pytest.TempPathFactory, scenario: Scenario) -> Path:
    out = factory.mktemp(scenario.name)
    result = execute_run(RunSpec(scenario.name, scenario.name, scenario), str(out))
    assert result["status"] == "completed", result
    return out / "runs" / scenario.name


@pytest.fixture(scope="module")
def orbit(tmp_path_factory: pytest.TempPathFactory) -> tuple[Scenario, Path]:
    sc = _scenario("orbit", 6400.0, faults=[
        {"spacecraft": 1, "kind": "link_loss", "start_s": 0.0, "end_s": CUT_END_S},
        {"spacecraft": 2, "kind": "camera_degradation", "start_s": ONSET_S, "magnitude": 0.3}])
    return sc, _fly(tmp_path_factory, sc)


@pytest.fixture(scope="module")
def small_store(tmp_path_factory: pytest.TempPathFactory) -> tuple[Scenario, Path]:
    sc = _scenario("overflow", 150.0, ground={"store_bytes": 20_000})
    return sc, _fly(tmp_path_factory, sc)


def _sent_to_ground(scenario: Scenario, run: Path) -> dict[str, int]:
    """Messages each spacecraft node sent on a topic the ground subscribes to (the archive),
    before the ground's last link counters (those of the run's last tick reach no node)."""
    ground = topology(scenario).node("ground")
    topics = {i.topic for a in ground.apps for i in app_class(a).INPUTS if i.every_spacecraft}
    archive, counts = load_run(run / "run.mcap"), Counter[str]()
    m = archive.mission()
    end = max(s.t_sim for s in archive.of(cat.LINK_STATS, m) if s.node == "ground")
    for t in topics:
        for msg in archive.of(t, m):
            counts[msg.sender] += msg.sender.startswith("sc") and msg.t_sim < end
    return {node: n for node, n in counts.items() if n}


def test_every_message_sent_the_ground_is_dumped_lost_or_aboard(orbit: tuple[Scenario, Path]
                                                              ) -> None:
    sc, run = orbit
    g = RunSummary.read(run / "summary.json").ground_contact
    assert g is not None
    sent = _sent_to_ground(sc, run)
    assert sorted(g.stores) == sorted(sent) == ["sc1", "sc2"]
    for node, s in g.stores.items():
        assert s.dumped + s.overflow + s.onboard == sent[node], node
        assert s.overflow == 0 and s.overflow_runs == []
        assert s.stored == sent[node]
    # observer 1 kept a whole orbit aboard and the second pass brought all of it down: what
    # is still aboard at the end was sent after that pass began
    aos2 = g.passes[1].aos_s
    for s in g.stores.values():
        assert s.onboard_since_s is not None and s.onboard_since_s > aos2
    assert g.longest_gap_s == pytest.approx(aos2 - g.passes[0].los_s, abs=1e-3)


def test_the_ground_hears_observer_2_s_fault_a_gap_later(orbit: tuple[Scenario, Path]) -> None:
    sc, run = orbit
    summary = RunSummary.read(run / "summary.json")
    g = summary.ground_contact
    assert g is not None and summary.scores is not None and summary.detections is not None
    los1, aos2 = g.passes[0].los_s, g.passes[1].aos_s
    camera = next(f for f in summary.scores.per_fault if f.kind == "camera_degradation")
    assert camera.detected and camera.isolated and camera.identified_class == "camera"
    assert camera.latency_s is not None and camera.latency_s <= 2 * sc.rates.fdi_period_s
    assert camera.declared_latency_s is not None
    assert aos2 - ONSET_S <= camera.declared_latency_s <= aos2 - ONSET_S + 120.0
    silent = [d for d in summary.detections if d.spacecraft == 1 and d.fault_class == "link"]
    assert silent and silent[0].declared_s is not None and silent[0].declared_s <= los1 + 1.0
    # nothing declared before its window's data could have come down
    plan = ContactPlan.of(sc)
    assert plan is not None
    for d in summary.detections:
        assert d.declared_s is not None and d.declared_s >= plan.next_contact(d.time_s), d


def test_uplinks_wait_for_a_pass(orbit: tuple[Scenario, Path]) -> None:
    sc, run = orbit
    plan = ContactPlan.of(sc)
    assert plan is not None
    archive = load_run(run / "run.mcap")
    m = archive.mission()
    sent: dict[tuple[int, int], float] = {}
    for msg in archive.of(cat.ASSIGNMENTS, m):
        for a in msg.assignments:
            sent.setdefault((a.spacecraft, a.assignment_id), msg.t_sim)
    first_seen: dict[tuple[int, int], float] = {}
    for s in archive.of(cat.GUIDANCE_STATUS, m):
        first_seen.setdefault((s.spacecraft, s.assignment_id), s.t_sim)
    flown = [k for k in sent if k in first_seen]
    assert len(flown) >= 3  # both first plans, and the re-plan after the declaration
    for k in flown:  # what is sent at the start was loaded before the run
        assert first_seen[k] >= plan.uplinked_s(sent[k]), k
    for sc in (1, 2):  # loaded before the run: flown at once, sc1's link cut from 0 s or not
        assert sent[(sc, 1)] == 0.0 and first_seen[(sc, 1)] < plan.windows[0][0]
    held = RunSummary.read(run / "summary.json").ground_contact.uplink_held  # type: ignore[union-attr]
    assert held["sc1"] > 0 and held["sc2"] > 0


def test_an_overflowing_store_is_counted_and_read_as_a_link_fault_of_known_cause(
        small_store: tuple[Scenario, Path]) -> None:
    sc, run = small_store
    summary = RunSummary.read(run / "summary.json")
    g = summary.ground_contact
    assert g is not None and summary.detections is not None and summary.scores is not None
    sent = _sent_to_ground(sc, run)
    aos = g.passes[0].aos_s
    for node, s in g.stores.items():
        assert s.overflow > 0 and s.dumped + s.overflow + s.onboard == sent[node], node
        assert sum(r.count for r in s.overflow_runs) == s.overflow
        assert all(r.first_s <= r.last_s <= aos for r in s.overflow_runs)
        first = {f"{t.app}/{t.name}" for t in cat.DOWNLINK_FIRST}
        assert not first & {r.topic for r in s.overflow_runs}  # priority 0 never lost
    causes = [d for d in summary.detections if d.cause == "store_overflow"]
    assert {d.spacecraft for d in causes} == {1, 2}
    assert all(d.fault_class == "link" for d in causes)
    assert [d for d in summary.detections if d.cause is None] == []
    assert summary.scores.false_alarms == 0
