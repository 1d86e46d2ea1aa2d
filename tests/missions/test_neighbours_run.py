"""The neighbours' FDIR flown (issue 29, item 2): three observers with ground passes (the target at
500 km and 51.6°, one mid-latitude station, a pass from 29 s to 498 s), observer 2's camera
degraded to β = 0.3 at 300 s, ``[neighbours]`` on.

* Observers 1 and 3 judge every window of each other and of observer 2 (Eq. 9 on their own
  fused maps); both find observer 2's first window after the onset failed and declare it
  within 60 s of the onset; nothing is declared on 1 or 3 (their windows pass).
* From the declaration on, 1 and 3 leave observer 2's observations out of their fusion.
* The ground, in contact, rules on the declaration from its own judgement: upheld.
* summary.json says who declared what, and scores the neighbours as a detector of their own.
"""

from __future__ import annotations

import pytest

from deploy.campaign import RunSpec, execute_run
from harness.archive.reader import RunArchive, load_run
from harness.summary import RunSummary
from interfaces.contracts import catalogue as cat
from tests.conftest import small_scenario

ONSET_S = 300.0


@pytest.fixture(scope="module")
def flown(tmp_path_factory: pytest.TempPathFactory) -> RunArchive:
    sc = small_scenario(
        "neighbours", seed=11, duration_s=480.0,
        orbit={"inclination_deg": 51.6, "raan_deg": 255.0, "arg_latitude_deg": 90.0},
        ground={"contact": "passes",
                "stations": [{"name": "mid", "latitude_deg": 48.08, "longitude_deg": 11.28}]},
        target={"radius_m": 5.0, "pois": 500}, camera={"half_angle_deg": 12.0},
        rates={"high_hz": 2.0, "fdi_period_s": 30.0},
        observers={"count": 3, "start": "pro", "initial_attitude": "lvlh", "rho_x_m": 10.0,
                   "rho_z_m": 15.0},
        neighbours={"enabled": True},
        faults=[{"spacecraft": 2, "kind": "camera_degradation", "start_s": ONSET_S,
                 "magnitude": 0.3}])
    out = tmp_path_factory.mktemp("neighbours")
    assert execute_run(RunSpec(sc.name, sc.name, sc), str(out))["status"] == "completed"
    return load_run(out / "runs" / sc.name / "run.mcap")


def test_the_neighbours_declare_the_faulty_camera_within_60_s(flown: RunArchive) -> None:
    m = flown.mission()
    declarations = flown.of(cat.NEIGHBOUR_DECLARATION, m)
    assert {d.subject for d in declarations} == {2}
    assert {d.spacecraft for d in declarations} == {1, 2, 3}  # 2 is told too
    first = min(declarations, key=lambda d: d.t_sim)
    assert first.judges == [1, 3] and first.decided == [1, 3]
    assert first.t_start_s <= ONSET_S + 30.0 and first.t_sim - ONSET_S <= 60.0


def test_every_window_of_every_neighbour_is_judged_and_the_healthy_pass(flown: RunArchive
                                                                        ) -> None:
    judgements = flown.of(cat.NEIGHBOUR_JUDGEMENT, flown.mission())
    for judge in (1, 2, 3):
        mine = [j for j in judgements if j.spacecraft == judge]
        assert len(mine) >= 12  # the 16 windows less the first, before the attitude settles
        for j in mine:
            assert judge not in {v.subject for v in j.verdicts}
    healthy = [v for j in judgements for v in j.verdicts if v.subject != 2]
    decided = [v for v in healthy if v.exceeded is not None]
    assert len(decided) >= 30 and not any(v.exceeded for v in decided)
    after = [v for j in judgements for v in j.verdicts
             if v.subject == 2 and j.t_start_s >= ONSET_S]
    assert after and all(v.exceeded for v in after if v.exceeded is not None)


def test_the_declared_observer_is_left_out_and_the_ground_upholds(flown: RunArchive) -> None:
    m = flown.mission()
    first = min(flown.of(cat.NEIGHBOUR_DECLARATION, m), key=lambda d: d.t_sim)
    for judge in (1, 3):
        tlm = [x for x in flown.of(cat.INFO_COST, m) if x.spacecraft == judge]
        before = [x for x in tlm if x.t_sim <= first.t_sim]
        after = [x for x in tlm if x.t_sim > first.t_sim + 30.0]
        # past the declaration, one neighbour's images a second are fused, not two
        rate = ((after[-1].shared_received - before[-1].shared_received)
                / (after[-1].t_sim - before[-1].t_sim))
        assert 0.5 < rate < 1.2, (judge, rate)
    rulings = flown.of(cat.NEIGHBOUR_RULING, m)
    assert [(r.subject, r.window_end_s, r.verdict) for r in rulings] == [
        (2, first.t_end_s, "upheld")]


def test_the_summary_says_who_declared(flown: RunArchive) -> None:
    summary = RunSummary.read(flown.path.parent / "summary.json")
    nb = summary.neighbours
    assert nb is not None and summary.detections is not None
    (mine,) = [d for d in summary.detections if d.declared_by == "neighbours"]
    assert (mine.spacecraft, mine.judges) == (2, [1, 3])
    assert all(d.declared_by == "ground" for d in summary.detections if d is not mine)
    (fault,) = nb.scores.per_fault
    assert fault.isolated and fault.declared_latency_s is not None
    assert fault.declared_latency_s <= 60.0
    assert nb.scores.false_alarms == 0 and nb.scores.nominal_cycles >= 20
    assert nb.rulings == {f"2@{mine.time_s:g}": "upheld"}
    assert (nb.disagreements.upheld, nb.disagreements.overruled) == (1, 0)
