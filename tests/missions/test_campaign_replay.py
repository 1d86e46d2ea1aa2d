"""A finished campaign re-judged by replay (deploy/campaign_replay.py): with the runs' own
settings every run's FDIR fields come back as the live ones, with another setting the full
report is rewritten, and a sweep writes one table whose row for the live setting has the live
campaign's figures."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from deploy.run_campaign import main as run_campaign
from harness.campaign.rescore import detector_figures
from harness.summary import FdirResults
from tests.conftest import dask_cluster
from tests.deploy.test_campaign import BASE, CAMPAIGN

FDIR_FIELDS = tuple(FdirResults.model_fields)
"""The fields of a run's summary.json that a replay rewrites."""


def _campaign(tmp: Path) -> Path:
    """test_campaign's campaign, long enough (150 s) for the camera faults to be declared,
    judged by the window test (whose persistence the sweep varies)."""
    (tmp / "base.toml").write_text(BASE.replace("duration_s = 60.0", "duration_s = 150.0")
                                   + '[fdir]\ndetector = "window"\n')
    path = tmp / "c.toml"
    path.write_text(CAMPAIGN.format(seeds=2))
    return path


@pytest.fixture(scope="module")
def campaign(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[str]]:
    tmp = tmp_path_factory.mktemp("creplay")
    out = tmp / "out"
    assert run_campaign(["--campaign", str(_campaign(tmp)), "--out", str(out),
                         "--workers", "2"]) == 0
    return out, json.loads((out / "campaign.json").read_text())["runs"]


def _summary(root: Path, rid: str) -> dict:
    return json.loads((root / "runs" / rid / "summary.json").read_text())


def test_own_settings_give_back_the_live_fields(campaign: tuple[Path, list[str]]) -> None:
    out, ids = campaign
    assert run_campaign(["--out", str(out), "--replay", "--workers", "2"]) == 0
    dest = out / "replay-own-settings"
    assert (dest / "report.md").exists() and (dest / "results.csv").exists()
    for rid in ids:
        live, again = _summary(out, rid), _summary(dest, rid)
        assert again["replay"]["matches_live"] is True, rid
        for d in again["detections"]:
            assert d.pop("faithful") is True  # the replay marks them; the live run does not
        for k in FDIR_FIELDS:
            assert again[k] == live[k], (rid, k)
    assert detector_figures(dest, ids) == detector_figures(out, ids)


def test_a_dask_cluster_replays_as_the_local_pool(campaign: tuple[Path, list[str]]) -> None:
    out, ids = campaign
    with dask_cluster() as address:
        assert run_campaign(["--out", str(out), "--replay", "--set", "fdir.persistence=1",
                             "--cluster", address, "--out-report", str(out / "on-dask")]) == 0
    assert run_campaign(["--out", str(out), "--replay", "--set", "fdir.persistence=1",
                         "--workers", "2", "--out-report", str(out / "local")]) == 0
    for rid in ids:
        a, b = _summary(out / "on-dask", rid), _summary(out / "local", rid)
        a["replay"].pop("wall_s"), b["replay"].pop("wall_s")
        assert a["replay"] == b["replay"] and all(a[k] == b[k] for k in FDIR_FIELDS), rid


def test_a_sweep_writes_one_table(campaign: tuple[Path, list[str]]) -> None:
    out, ids = campaign
    assert run_campaign(["--out", str(out), "--sweep", "fdir.persistence=1,2",
                         "--set", "fdir.floor=0.002", "--workers", "2"]) == 0
    dest = out / "sweep-fdir.persistence"
    with open(dest / "sweep.csv") as f:
        rows = {r["fdir.persistence"]: r for r in csv.DictReader(f)}
    live = detector_figures(out, ids)  # the runs flew the defaults: persistence 1
    for k in ("faults", "detected", "isolated", "identified", "false_alarms", "nominal_cycles"):
        assert int(rows["1"][k]) == live[k], k
    assert int(rows["1"]["detected"]) > int(rows["2"]["detected"]), \
        "declaring on the first failed window detects within the runs' 150 s"
    for r in rows.values():
        assert int(r["false_alarms_faithful"]) <= int(r["false_alarms"])
        assert int(r["nominal_cycles_faithful"]) <= int(r["nominal_cycles"])
    assert rows["1"]["nominal_cycles_faithful"] == rows["1"]["nominal_cycles"], \
        "the live setting's replays are faithful to the end"
    assert "| 2 |" in (dest / "sweep.md").read_text()
    assert (dest / "fdir.persistence=2" / "report.md").exists()


def test_settings_that_change_the_flight_are_refused(campaign: tuple[Path, list[str]],
                                                     tmp_path: Path) -> None:
    out, _ = campaign
    assert run_campaign(["--out", str(out), "--replay", "--set", "comms.packet_loss=0.5"]) == 2
    assert run_campaign(["--out", str(out), "--sweep", "fdir.persistence"]) == 2
    assert run_campaign(["--out", str(tmp_path), "--replay"]) == 2
