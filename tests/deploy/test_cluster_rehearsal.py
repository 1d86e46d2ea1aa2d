"""The rehearsed campaign cluster's layout (deploy/rehearsal/cluster.py); flown, with a worker's
host torn down mid-campaign, in tests/missions/test_cluster_rehearsal.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from deploy.host_map import LinkSpec
from deploy.rehearsal.cluster import (
    NETWORK,
    _out_of,
    cluster_hosts,
    finished_runs,
    scheduler_address,
)


def test_a_scheduler_host_and_a_host_per_worker_on_the_clusters_network() -> None:
    hosts = cluster_hosts(3, LinkSpec(delay_ms=2.0))
    assert [h.name for h in hosts] == ["sched", "w1", "w2", "w3"]
    assert all(h.address in NETWORK and h.link.delay_ms == 2.0 for h in hosts)
    assert len({h.address for h in hosts}) == 4
    assert scheduler_address(hosts) == "tcp://10.79.0.1:8786"


def test_finished_runs_are_the_summaries_out_of_partial_folders(tmp_path: Path) -> None:
    for name in ("a-0000", "a-0001", "a-0002.partial-123"):
        (tmp_path / "runs" / name).mkdir(parents=True)
        (tmp_path / "runs" / name / "summary.json").write_text("{}")
    (tmp_path / "runs" / "a-0003").mkdir()
    assert finished_runs(tmp_path) == 2


def test_the_campaigns_out_folder_is_required() -> None:
    assert _out_of(["--campaign", "c.toml", "--out", "runs/c"]) == Path("runs/c")
    with pytest.raises(SystemExit, match="--out"):
        _out_of(["--campaign", "c.toml"])
