"""Campaigns that run (deploy/run_campaign.py): a local pool and a real Dask scheduler and worker
(separate processes on loopback) give identical results, a campaign interrupted by SIGTERM and
started again finishes every run exactly once with a complete report, and runs over Zenoh match
runs in-process."""

from __future__ import annotations

import csv
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

from deploy.run_campaign import main as run_campaign
from ground.archive.metadata import software_version
from tests.conftest import REPO, dask_cluster
from tests.deploy.test_campaign import _campaign


def _results(out: Path) -> dict[str, dict[str, object]]:
    """Each run's summary without what may differ between executions (wall time)."""
    res = {}
    for d in sorted((out / "runs").iterdir()):
        s = json.loads((d / "summary.json").read_text())
        for k in ("wall_s", "real_time_factor", "exec"):
            s.pop(k, None)
        res[d.name] = s
    return res


def test_local_pool_and_dask_cluster_agree(tmp_path: Path) -> None:
    path = _campaign(tmp_path)
    assert run_campaign(["--campaign", str(path), "--out", str(tmp_path / "local"),
                         "--workers", "2"]) == 0
    with dask_cluster() as address:
        assert run_campaign(["--campaign", str(path), "--out", str(tmp_path / "dask"),
                             "--cluster", address]) == 0
    local, dask = _results(tmp_path / "local"), _results(tmp_path / "dask")
    assert list(local) == ["cam-0000", "cam-0001", "nom-0000"]
    assert local == dask
    rows = list(csv.DictReader(open(tmp_path / "dask" / "results.csv")))
    assert {r["detector"] for r in rows} == {"main", "chi2_nis", "cusum", "fixed_threshold",
                                             "window"}
    assert len([r for r in rows if r["detector"] == "main"]) == 3


def _finished(out: Path) -> dict[str, int]:
    """The finished runs of a campaign (renamed from ``<id>.partial-*``): their summary's
    modification time (ns) by run id."""
    return {p.parent.name: p.stat().st_mtime_ns for p in (out / "runs").glob("*/summary.json")
            if "." not in p.parent.name}


def test_interrupted_campaign_resumes_each_run_once(tmp_path: Path) -> None:
    path = _campaign(tmp_path, seeds=3)
    out = tmp_path / "out"
    cmd = [sys.executable, str(REPO / "deploy" / "run_campaign.py"), "--campaign", str(path),
           "--out", str(out), "--workers", "1"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and not _finished(out):
        time.sleep(0.2)
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=60) == 128 + signal.SIGTERM
    first = _finished(out)  # a run caught between its summary and its rename is not finished
    assert 1 <= len(first) < 9
    assert run_campaign(["--campaign", str(path), "--out", str(out), "--workers", "2"]) == 0
    after = _finished(out)
    assert len(after) == 9 and not list((out / "runs").glob("*.partial*"))
    assert all(after[k] == v for k, v in first.items())  # finished runs were not redone
    report = (out / "report.md").read_text()
    assert "9 of 9 runs finished (0 failed;" in report
    assert f"Software: {software_version()} (9 runs)." in report
    assert (out / "roc.png").exists() and (out / "confusion.png").exists()


def test_zenoh_runs_match_inproc_runs(tmp_path: Path) -> None:
    """--transport zenoh: each run multi-process on its own port and mission key space, with
    the same results as in-process for the same scenario and seed."""
    path = _campaign(tmp_path)
    for transport in ("inproc", "zenoh"):
        assert run_campaign(["--campaign", str(path), "--out", str(tmp_path / transport),
                             "--transport", transport, "--limit", "1"]) == 0
    a = json.loads((tmp_path / "inproc" / "runs" / "cam-0000" / "summary.json").read_text())
    b = json.loads((tmp_path / "zenoh" / "runs" / "cam-0000" / "summary.json").read_text())
    assert b["transport"] == "zenoh" and b["t_sim_final_s"] == a["t_sim_final_s"] == 60.0
    for k in ("coverage", "detections", "scores", "baselines", "fdir_series", "fault_events"):
        assert a[k] == b[k], k
