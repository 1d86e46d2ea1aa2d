"""A campaign whose disk fills: it stops cleanly with one line (exit 1), keeps every run that
finished, marks the run the disk stopped ``retry`` (not failed) in ``retry.json``, writes its
report over what finished, and the same command, once space is freed, flies exactly the runs
left.  A disk too small for one run is refused before any run (exit 2)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from deploy.campaign import load_campaign
from deploy.disk_space import RESERVE_BYTES, estimate_archive_bytes, free_bytes
from deploy.run_campaign import main as run_campaign
from tests.deploy.test_campaign import _campaign
from tests.mounts import tmpfs


def _fill(folder: Path, leave_bytes: int) -> Path:
    """A filler file leaving about ``leave_bytes`` free on ``folder``'s disk."""
    filler = folder / "filler"
    with open(filler, "wb") as f:
        os.posix_fallocate(f.fileno(), 0, max(free_bytes(folder) - leave_bytes, 1))
    return filler


def test_a_full_disk_stops_the_campaign_cleanly_and_a_resume_flies_the_rest(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _campaign(tmp_path, seeds=3)  # 9 short runs
    _, runs = load_campaign(path)
    one = max(estimate_archive_bytes(r.scenario) for r in runs)
    with tmpfs(tmp_path / "disk", 16.0) as disk:
        out = disk / "out"
        filler = _fill(disk, RESERVE_BYTES + 2 * one)  # room for about three runs
        code = run_campaign(["--campaign", str(path), "--out", str(out), "--workers", "1"])
        err = capsys.readouterr().err
        assert code == 1 and "Traceback" not in err
        stopped = [ln for ln in err.splitlines() if ln.startswith("error: ")]
        assert len(stopped) == 1 and "disk full" in stopped[0] and "campaign stopped" in \
            stopped[0], err
        done = sorted(p.parent.name for p in (out / "runs").glob("*/summary.json"))
        assert 1 <= len(done) < len(runs)
        retry = json.loads((out / "retry.json").read_text())
        assert len(retry) == 1 and all("disk full" in c for c in retry.values())
        assert not set(retry) & set(done)  # a run the disk stopped is not finished
        assert f"{len(done)} of {len(runs)} runs finished (0 failed" in \
            (out / "report.md").read_text()
        before = {d: (out / "runs" / d / "summary.json").stat().st_mtime_ns for d in done}
        filler.unlink()  # space freed: the same command flies the rest
        assert run_campaign(["--campaign", str(path), "--out", str(out), "--workers", "1"]) == 0
        after = {p.parent.name: p.stat().st_mtime_ns for p in (out / "runs").glob("*/summary.json")}
        assert len(after) == len(runs) and all(after[d] == t for d, t in before.items())
        assert not (out / "retry.json").exists()
        _fill(disk, RESERVE_BYTES // 2)
        capsys.readouterr()
        assert run_campaign(["--campaign", str(path), "--out", str(disk / "other"),
                             "--workers", "1"]) == 2
        assert "free; the run needs about" in capsys.readouterr().err
