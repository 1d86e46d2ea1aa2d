"""Lost data is not corrupt data, and neighbours judge the plan a neighbour flies (issue 39),
flown: the case a new user found, shortened.  Three observers under two stations' passes
(107-537 s and 3,163-3,624 s: a 2,626 s gap), the neighbours' FDIR on, a store too small for
the gap, and an inspection phase uplinked at 1,000 s, out of contact: it waits for the pass
at 3,163 s, and the observers start their transfers a minute after it (the planner departs a
held uplink UPLINK_LEAD_S after its pass's acquisition), not at 1,000 s.  Observer 2's camera
degrades at 3,700 s, after the second pass.

Before (main 24321f4, the same set-up at full size): the ground declared data integrity on
every observer once their dumps came down (the images lost to overflow read as corrupt data),
the neighbours declared every observer after the re-plan (judged against the uplink's plan),
and the real fault was missed.  Now:

* the only ground declarations are the stores' overflow, of known cause; the windows and
  reports the ground could not judge say why (store_overflow, aboard, lost);
* the neighbours judge no window of a transfer and declare nobody before the onset;
* observer 2 is declared by its neighbours after the onset;
* the load warned that the store cannot hold the gap, and it overflowed.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from deploy.campaign import RunSpec, execute_run
from harness.archive.reader import load_run
from harness.summary import RunSummary
from interfaces.contracts import catalogue as cat
from interfaces.contracts.scenario import Scenario
from tests.conftest import small_scenario

ONSET_S = 3700.0
AOS_S = 3163.0

pytestmark = pytest.mark.mission


def _scenario() -> Scenario:
    return small_scenario(
        "lost", seed=5, duration_s=4000.0,
        orbit={"inclination_deg": 51.6, "raan_deg": 195.0},
        ground={"contact": "passes", "store_bytes": 3_000_000, "stations": [
            {"name": "hawaii", "latitude_deg": 19.0, "longitude_deg": -155.7},
            {"name": "hartrao", "latitude_deg": -25.9, "longitude_deg": 27.7}]},
        neighbours={"enabled": True},
        target={"radius_m": 5.0, "pois": 300}, camera={"half_angle_deg": 20.0},
        rates={"fdi_period_s": 30.0},
        observers={"count": 3, "start": "pro", "initial_attitude": "lvlh", "rho_x_m": 20.0,
                   "rho_z_m": 25.0},
        phases=[{"name": "inspection", "start_s": 1000.0, "transfer_s": 300.0,
                 "rho_x_m": 15.0, "rho_z_m": 20.0}],
        faults=[{"spacecraft": 2, "kind": "camera_degradation", "start_s": ONSET_S,
                 "magnitude": 0.3}])


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> tuple[RunSummary, Path]:
    sc = _scenario()
    out = tmp_path_factory.mktemp("lost")
    result = execute_run(RunSpec(sc.name, sc.name, sc), str(out))
    assert result["status"] == "completed", result
    path = out / "runs" / sc.name
    return RunSummary.read(path / "summary.json"), path


def test_the_store_overflowed_as_its_budget_said(run: tuple[RunSummary, Path]) -> None:
    summary, _ = run
    gc = summary.ground_contact
    assert gc is not None and gc.data_budget is not None
    assert not gc.data_budget.holds  # warned at load
    assert all(s.overflow > 0 for s in gc.stores.values())
    assert any(r.topic == "camera/observations" for s in gc.stores.values()
               for r in s.overflow_runs)
    assert max(gc.data_budget.measured_peak_bytes.values()) <= gc.store_bytes


def test_no_ground_declaration_rests_on_lost_data(run: tuple[RunSummary, Path]) -> None:
    summary, _ = run
    assert summary.detections is not None and summary.fdir_thresholds is not None
    ground = [d for d in summary.detections if d.declared_by == "ground"]
    assert ground and all(d.cause == "store_overflow" for d in ground
                          if d.time_s < ONSET_S)
    assert not [d for d in ground if d.fault_class == "data_integrity"]
    assert summary.fdir_thresholds.unjudged.store_overflow > 0
    reports = summary.fdir_thresholds.integrity_unjudged
    assert reports.lost + reports.aboard > 0


def test_the_neighbours_judge_no_transfer_and_find_the_fault(
        run: tuple[RunSummary, Path]) -> None:
    summary, path = run
    archive = load_run(path / "run.mcap")
    verdicts = [(j.t_start_s, v) for j in archive.of(cat.NEIGHBOUR_JUDGEMENT, archive.mission())
                for v in j.verdicts]
    assert any(v.unjudged == "transfer" for t, v in verdicts if t >= AOS_S)
    neighbours = [d for d in summary.detections or [] if d.declared_by == "neighbours"]
    assert not [d for d in neighbours if d.time_s < ONSET_S]
    assert [d.spacecraft for d in neighbours] == [2]
