"""The formation study flown short (Sec. III.G; deploy/campaigns/formations.toml): 1 and 2
observers on the paper's set-up, a state disturbance on observer 1 and a nominal twin of each,
through the campaign's own run and study code.  The ground FDIR detects, isolates and names the
disturbance; the truth jumps by the disturbance's size at its onset; the twin is the same run
until then; the study writes its report."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from deploy.campaign import execute_run, load_campaign
from harness.archive.reader import load_run
from harness.campaign.formation_study import load_study, twins, write_formation_study
from interfaces.contracts import catalogue as cat
from tests.conftest import REPO

ONSET_S = 100.0
CAMPAIGN = f"""
name = "formations-short"
base = "{REPO / 'deploy' / 'scenarios' / 'nominal.toml'}"
seeds = [1]
duration_s = 220.0
study = "formations"
""" + "".join(f"""
[[groups]]
name = "n{n}-nominal"
nominal = true
overrides = {{ observers = {{ count = {n} }} }}

[[groups]]
name = "n{n}-disturbance"
overrides = {{ observers = {{ count = {n} }} }}
[[groups.faults]]
spacecraft = 1
kind = "state_disturbance"
start_s = {ONSET_S}
magnitude = 4.0
velocity_mps = 0.01
""" for n in (1, 2))


@pytest.fixture(scope="module")
def flown(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[str]]:
    out = tmp_path_factory.mktemp("formations")
    (out / "campaign.toml").write_text(CAMPAIGN)
    _, runs = load_campaign(out / "campaign.toml")
    for spec in runs:
        assert execute_run(spec, str(out))["status"] == "completed", spec.id
    return out, [r.id for r in runs]


def test_the_disturbance_is_detected_isolated_and_named_in_both_formations(
        flown: tuple[Path, list[str]]) -> None:
    out, ids = flown
    studied = load_study(out, ids)
    faulty = [r for r in studied if r.fault is not None]
    assert sorted(r.observers for r in faulty) == [1, 2]
    for run in faulty:
        assert run.score is not None and run.score.isolated, run.id
        assert run.score.latency_s is not None and run.score.latency_s <= 60.0
        assert run.score.identified_class == "actuator"
    assert all(not r.score for r in studied if r.fault is None)


def test_the_truth_jumps_by_the_disturbance_at_its_onset(flown: tuple[Path, list[str]]) -> None:
    out, _ = flown
    archive = load_run(out / "runs" / "n2-disturbance-0000" / "run.mcap")
    truth = {round(m.t_sim, 6): m for m in archive.of(cat.TRUTH, archive.mission())}
    (event,) = [e for e in archive.of(cat.FAULT_EVENTS, archive.mission()) if e.active]
    before, at = truth[round(ONSET_S - 0.1, 6)], truth[ONSET_S]
    dr = np.array(at.r_lvlh_m[0]) - np.array(before.r_lvlh_m[0])
    drift = np.array(before.v_lvlh_mps[0]) * 0.1  # one tick of the free motion, about 1 mm
    assert np.allclose(dr - drift, event.detail["delta_r_lvlh_m"], atol=2e-3)
    assert np.linalg.norm(event.detail["delta_r_lvlh_m"]) == pytest.approx(4.0)
    other = np.array(at.r_lvlh_m[1]) - np.array(before.r_lvlh_m[1])
    assert np.linalg.norm(other) < 0.01  # observer 2 is not moved


def test_the_twin_is_the_same_run_until_the_fault_and_the_study_is_written(
        flown: tuple[Path, list[str]]) -> None:
    out, ids = flown
    pairs = twins(load_study(out, ids))
    assert len(pairs) == 2
    for run, twin in pairs:
        before = run.curves.t_s < ONSET_S
        assert np.array_equal(run.curves.h[before], twin.curves.h[before])
        assert np.array_equal(run.curves.h_i[before], twin.curves.h_i[before])
    report = write_formation_study(out, ids).read_text()
    assert "## The chapter's claims" in report
    assert "### 1 observer(s), state_disturbance" in report
    assert (out / "study" / "n2-state_disturbance.png").stat().st_size > 0
