"""Campaigns (deploy/campaign.py, deploy/run_campaign.py): a campaign file expands into the same
run list every time, bad files are clear errors before anything runs, a run that fails is a
finished, failed run, an attempt that outlives its campaign cannot touch the next, one campaign
per directory, one BLAS thread per worker (campaigns that run: tests/missions/test_campaign_run.py).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from deploy.campaign import CampaignError, load_campaign
from deploy.run_campaign import main as run_campaign

BASE = """name = "cb"
seed = 1
duration_s = 60.0
[target]
pois = 300
[rates]
high_hz = 2.0
fdi_period_s = 20.0
[observers]
count = 2
initial_attitude = "lvlh"
rho_x_m = 20.0
rho_z_m = 25.0
"""

CAMPAIGN = """name = "tc"
base = "base.toml"
seeds = {{ first = 1, count = {seeds} }}
[[groups]]
name = "cam"
[[groups.faults]]
spacecraft = [1, 2]
kind = "camera_degradation"
start_s = {{ min = 0.0, max = 10.0 }}
magnitude = 0.5
[[groups]]
name = "nom"
nominal = true
"""


def _campaign(tmp: Path, seeds: int = 1, text: str | None = None) -> Path:
    (tmp / "base.toml").write_text(BASE)
    path = tmp / "c.toml"
    path.write_text(text if text is not None else CAMPAIGN.format(seeds=seeds))
    return path


def test_expansion_is_deterministic_and_complete(tmp_path: Path) -> None:
    path = _campaign(tmp_path, seeds=3)
    _, runs = load_campaign(path)
    _, again = load_campaign(path)
    assert [r.id for r in runs] == [f"cam-{i:04d}" for i in range(6)] + \
        [f"nom-{i:04d}" for i in range(3)]
    assert [r.scenario for r in runs] == [r.scenario for r in again]
    cams = [r for r in runs if r.group == "cam"]
    assert [(r.seed, r.scenario.faults[0].spacecraft) for r in cams] == \
        [(1, 1), (1, 2), (2, 1), (2, 2), (3, 1), (3, 2)]
    starts = [r.scenario.faults[0].start_s for r in cams]
    assert all(0.0 <= s <= 10.0 for s in starts) and len(set(starts)) == 6
    assert all(r.scenario.faults == [] for r in runs if r.group == "nom")


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace('name = "tc"', 'name = "tc"\ncolour = 1'), "colour"),
    (lambda t: t.replace("max = 10.0", "max = -1.0"), "below min"),
    (lambda t: t.replace('kind = "camera_degradation"', 'kind = "gremlins"'), "kind"),
    (lambda t: t.replace("magnitude = 0.5", "magnitude = 1.5"),
     r"magnitude = 1.5: camera_degradation magnitude must be in \(0, 1\)"),
    (lambda t: t.replace('base = "base.toml"', 'base = "missing.toml"'), "cannot read"),
    (lambda t: t + "[[groups]]\nname = \"nom\"\nnominal = true\n", "unique"),
])
def test_bad_campaigns_are_clear_errors(tmp_path: Path, edit: object, message: str) -> None:
    path = _campaign(tmp_path, text=edit(CAMPAIGN.format(seeds=1)))  # type: ignore[operator]
    with pytest.raises(CampaignError, match=message):
        load_campaign(path)
    assert run_campaign(["--campaign", str(path), "--out", str(tmp_path / "out")]) == 2
    assert not (tmp_path / "out" / "runs").exists()  # nothing ran


def test_a_crashing_run_is_recorded_as_failed(tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    """A run that raises is a finished, failed run with its error (the campaign goes on, the
    report counts it); it is not redone on restart."""
    import deploy.inproc
    from deploy.campaign import execute_run
    from harness.campaign.report import write_campaign_report

    def boom(*_a: object, **_k: object) -> None:
        raise RuntimeError("sim exploded")

    monkeypatch.setattr(deploy.inproc, "run_inproc", boom)
    _, runs = load_campaign(_campaign(tmp_path))
    result = execute_run(runs[0], str(tmp_path / "out"))
    assert result["status"] == "failed" and "sim exploded" in result["error"]
    d = tmp_path / "out" / "runs" / runs[0].id
    summary = json.loads((d / "summary.json").read_text())
    assert summary["status"] == "failed" and "RuntimeError: sim exploded" in summary["error"]
    assert "sim exploded" in (d / "run.log").read_text()
    write_campaign_report(tmp_path / "out", "tc", [r.id for r in runs])
    assert f"1 of 3 runs finished (1 failed: {runs[0].id};" in \
        (tmp_path / "out" / "report.md").read_text()


def test_an_attempt_that_outlives_its_campaign_cannot_touch_the_next(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A Dask task cancelled by an interrupt runs on; the restarted campaign's attempt at the
    same run gets a directory of its own and removes the old one, so the old attempt's later
    writes fail instead of landing in (or renaming) the new attempt's directory."""
    import deploy.inproc
    from deploy.campaign import _attempt_dir, execute_run

    _, runs = load_campaign(_campaign(tmp_path))
    spec, runs_dir = runs[0], tmp_path / "out" / "runs"
    orphan = _attempt_dir(runs_dir, spec.id, "partial")
    (orphan / "run.mcap").write_text("half of an old attempt")
    seen: list[object] = []

    def run_while_the_orphan_writes(*_a: object, **_k: object) -> None:
        try:
            (orphan / "summary.json").write_text("{}")
        except OSError as e:
            seen.append(e)
        raise RuntimeError("stop here")

    monkeypatch.setattr(deploy.inproc, "run_inproc", run_while_the_orphan_writes)
    execute_run(spec, str(tmp_path / "out"))
    assert len(seen) == 1 and isinstance(seen[0], FileNotFoundError)
    assert sorted(p.name for p in runs_dir.iterdir()) == [spec.id]
    final = runs_dir / spec.id
    assert b"old attempt" not in (final / "run.mcap").read_bytes()
    assert json.loads((final / "summary.json").read_text())["status"] == "failed"


def test_one_campaign_per_directory(tmp_path: Path) -> None:
    """A second campaign on a directory in use is refused, not interleaved."""
    import fcntl

    path = _campaign(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    with open(out / ".lock", "w") as held:
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        assert run_campaign(["--campaign", str(path), "--out", str(out)]) == 2
    assert not list((out / "runs").iterdir())


def test_campaign_workers_get_one_blas_thread(monkeypatch: pytest.MonkeyPatch) -> None:
    """The pool's workers inherit one BLAS thread each; a count the user set is kept."""
    from deploy.run_campaign import BLAS_THREADS, one_blas_thread

    for name in BLAS_THREADS:
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("OMP_NUM_THREADS", "3")
    one_blas_thread()
    assert {n: os.environ[n] for n in BLAS_THREADS} == {
        "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "3", "MKL_NUM_THREADS": "1"}


def test_set_changes_every_run_flown_and_a_bad_one_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    paper = Path(__file__).resolve().parents[2] / "deploy" / "campaigns" / "paper.toml"
    out = tmp_path / "c"
    args = ["--campaign", str(paper), "--out", str(out), "--report-only"]
    assert run_campaign([*args, "--set", "onboard_fdir.enabld=true"]) == 2
    assert "--set onboard_fdir.enabld: no such setting" in capsys.readouterr().err
    assert run_campaign([*args, "--set", "onboard_fdir.enabled=true"]) == 0
    index = json.loads((out / "campaign.json").read_text())
    assert index["settings"] == {"onboard_fdir.enabled": "true"} and len(index["runs"]) == 200


def test_every_shipped_campaign_expands() -> None:
    """Each file of deploy/campaigns/ loads and expands into valid runs (counts as their
    headers state)."""
    counts = {"paper": 200, "hard": 58, "beyond": 64, "formations": 48, "identify": 184,
              "passes": 52, "space": 360}
    root = Path(__file__).resolve().parents[2] / "deploy" / "campaigns"
    for path in sorted(root.glob("*.toml")):
        campaign, runs = load_campaign(path)
        assert len(runs) == counts[campaign.name], path.name


def test_variants_fly_every_group_with_the_same_faults(tmp_path: Path) -> None:
    """``[[variants]]``: each group once per variant, named ``group-variant``, with the same
    seeds and the same drawn faults, and the variant's overrides."""
    path = Path(__file__).resolve().parents[2] / "deploy" / "campaigns" / "passes.toml"
    campaign, runs = load_campaign(path)
    by_group: dict[str, list] = {}
    for r in runs:
        by_group.setdefault(r.group, []).append(r.scenario)
    assert sorted(by_group) == sorted(f"{g.name}-{v.name}" for g in campaign.groups
                                      for v in campaign.variants)
    for g in campaign.groups:
        off, on = by_group[f"{g.name}-central"], by_group[f"{g.name}-neighbours"]
        assert [s.faults for s in off] == [s.faults for s in on]
        assert [s.seed for s in off] == [s.seed for s in on]
        assert not any(s.neighbours.enabled for s in off) and all(s.neighbours.enabled for s in on)
    starts = [f.start_s for r in runs for f in r.scenario.faults]
    assert starts and all(500.0 <= t <= 560.0 for t in starts)  # just after the pass (498 s)


def test_a_folder_flown_otherwise_is_refused_naming_the_difference(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Other --set settings, or finished runs of another version of the campaign file, are not
    replaced without --overwrite; the refusal names the difference, in one line, exit 2."""
    from deploy.campaign import record_failure

    path, out = _campaign(tmp_path), tmp_path / "out"
    args = ["--campaign", str(path), "--out", str(out), "--report-only"]
    assert run_campaign([*args, "--set", "fdir.floor=0.04"]) == 0
    capsys.readouterr()
    assert run_campaign(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"error: --out {out} was flown with --set fdir.floor=0.04; this command sets "
                   "no --set: give another --out, or --overwrite to replace its runs"]
    assert json.loads((out / "campaign.json").read_text())["settings"] == \
        {"fdir.floor": "0.04"}  # untouched
    assert run_campaign([*args, "--overwrite"]) == 0
    _, runs = load_campaign(path)
    record_failure(runs[0], str(out), "a run finished before the file was edited")
    path.write_text(CAMPAIGN.format(seeds=1).replace("magnitude = 0.5", "magnitude = 0.6"))
    capsys.readouterr()
    assert run_campaign(args) == 2
    assert (f"holds 1 finished runs flown from another version of the campaign file (first: "
            f"{runs[0].id})") in capsys.readouterr().err


def test_a_read_only_campaign_folder_is_refused_before_any_work(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from tests.mounts import read_only

    path, out = _campaign(tmp_path), tmp_path / "ro" / "out"
    assert run_campaign(["--campaign", str(path), "--out", str(out), "--report-only"]) == 0
    report = (out / "report.md").read_bytes()
    capsys.readouterr()
    with read_only(tmp_path / "ro"):
        for extra in (["--report-only"], ["--replay"], ["--replay", "--set", "fdir.floor=0.05"]):
            assert run_campaign(["--out", str(out), *extra]) == 2, extra
            err = capsys.readouterr().err.strip().splitlines()
            assert len(err) == 1 and "Read-only file system" in err[0], err
            assert "--out" in err[0]
        assert run_campaign(["--campaign", str(path), "--out", str(out)]) == 2
        assert "Read-only file system" in capsys.readouterr().err
    assert (out / "report.md").read_bytes() == report


def test_a_campaign_replay_is_not_replaced_without_overwrite(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path, out = _campaign(tmp_path), tmp_path / "out"
    assert run_campaign(["--campaign", str(path), "--out", str(out), "--report-only"]) == 0
    earlier = out / "replay-fdir.floor=0.05"
    earlier.mkdir()
    (earlier / "report.md").write_text("an earlier replay")
    capsys.readouterr()
    assert run_campaign(["--out", str(out), "--replay", "--set", "fdir.floor=0.05"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"error: {earlier} holds a replay already: give --overwrite to replace it, "
                   "or another --out-report"]
    assert (earlier / "report.md").read_text() == "an earlier replay"


def test_a_run_stopped_by_its_host_is_flown_again_not_failed(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A full disk is the host's fault, not the run's: the attempt is removed and the result
    is ``retry`` with the cause, so the run is not finished and a resume flies it."""
    import errno

    import deploy.inproc
    from deploy.campaign import execute_run, finished

    def disk_full(*_a: object, **_k: object) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(deploy.inproc, "run_inproc", disk_full)
    _, runs = load_campaign(_campaign(tmp_path))
    result = execute_run(runs[0], str(tmp_path / "out"))
    assert result["status"] == "retry" and result["error"].startswith("disk full")
    assert list((tmp_path / "out" / "runs").iterdir()) == []
    assert not finished(runs[0], tmp_path / "out")
