"""A campaign flown on a Dask cluster rehearsed across network namespaces (docs/hosts.md,
"Campaigns across hosts"): a scheduler in one, a worker in each of two others, the client in
this one.  One worker's host is torn down (link cut, worker killed, namespace removed) after
the first run has finished; the campaign finishes on the other, with the results of a local
pool, and nothing is left behind.  Skipped, with the reason, where namespaces cannot be made."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from deploy.rehearsal.cluster import NETWORK
from deploy.rehearsal.netns import addresses_in, unavailable
from deploy.run_campaign import main as run_campaign
from tests.conftest import REPO
from tests.deploy.test_campaign import _campaign
from tests.missions.test_campaign_run import _results


@pytest.mark.skipif(unavailable() is not None, reason=str(unavailable()))
def test_a_campaign_across_namespaces_survives_a_lost_worker_host(tmp_path: Path) -> None:
    path = _campaign(tmp_path)
    assert run_campaign(["--campaign", str(path), "--out", str(tmp_path / "local"),
                         "--workers", "2"]) == 0
    done = subprocess.run([sys.executable, "-m", "deploy.rehearsal.cluster",
                           "--tear-down-after", "1", "--", "--campaign", str(path), "--out",
                           str(tmp_path / "cluster")],
                          cwd=REPO, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "host w1 torn down" in done.stderr
    assert _results(tmp_path / "local") == _results(tmp_path / "cluster")
    assert addresses_in(NETWORK) == []  # the launcher's port went with the switch
    left = subprocess.run(["ip", "netns"], capture_output=True, text=True).stdout
    assert "-sched" not in left and "-w2" not in left
