"""Replay (harness/replay.py): the live ground re-run on a recorded run reproduces the live
detections, windows and verdicts exactly -- with lossy, range-limited and cut links and three
faults -- and, under another setting, what the live run with that setting declared, up to the
first uplink the two runs differ in.  An archive that lost its last quarter (cut at three
quarters of its bytes) or holds less than its run says where it ends, and nothing past that is
judged."""

from __future__ import annotations

import json
import logging
import shutil
from pathlib import Path

import pytest

from deploy.campaign_replay import replay_job
from deploy.inproc import run_inproc
from ground.archive.metadata import run_metadata
from ground.archive.recorder import McapRecorder
from harness.archive.reader import ArchiveError, load_run
from harness.archive.run_scenario import archived_scenario
from harness.archive.span import seconds
from harness.replay import GroundOutput, Replay, main, replay_run
from harness.summary import Detection, RunSummary
from harness.summary.build import write_summary
from interfaces.contracts.scenario import Scenario
from tests.harness.test_replay import _scenario


def _record(scenario: Scenario, out: Path) -> RunSummary:
    out.mkdir(parents=True, exist_ok=True)
    with McapRecorder(out / "run.mcap", run_metadata(scenario, "inproc", "# test\n")) as rec:
        run_inproc(scenario, sample_tap=rec.record_sample)
    return write_summary(out, scenario, "inproc", 1.0, "completed")


@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, RunSummary]:
    out = tmp_path_factory.mktemp("replay") / "live"
    return out, _record(_scenario(), out)


@pytest.fixture(scope="module")
def cut(live: tuple[Path, RunSummary], tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The live run's folder with its archive cut at three quarters of its bytes (no summary
    section, no footer, a chunk torn: its data ends after the first declarations, before the
    last), and its summary.json (of the whole run)."""
    out, _ = live
    folder = tmp_path_factory.mktemp("replay") / "cut"
    folder.mkdir()
    data = (out / "run.mcap").read_bytes()
    (folder / "run.mcap").write_bytes(data[:len(data) * 3 // 4])
    shutil.copyfile(out / "summary.json", folder / "summary.json")
    return folder


def _due_before(replay: Replay, end_s: float) -> None:
    """Nothing the replay or the live run is compared on was due at or after ``end_s`` (s)."""
    latency = replay.scenario.fdir.latency_s
    for output in (replay.replayed, replay.live):
        assert all(w.t_end_s + latency < end_s for w in output.windows)
        assert all(v.t_end_s + latency < end_s for v in output.verdicts)
        assert all((r.declared_s or 0.0) < end_s for r in output.reports)
        assert all(a.t_sim < end_s for a in output.assignments)


def _unmarked(detections: list[Detection] | None) -> list[dict[str, object]]:
    """Detections as summary.json holds them, less the replay's ``faithful`` mark."""
    return [d.model_dump(exclude={"faithful"}) for d in detections or []]


def test_replay_reproduces_the_live_ground_exactly(live: tuple[Path, RunSummary]) -> None:
    out, summary = live
    archive = load_run(out / "run.mcap")
    links = [c for c in json.loads((out / "summary.json").read_text())["links"]
             if c["dst"] == "ground"]
    assert sum(c["dropped_loss"] for c in links) > 0, "the links lost messages"
    assert sum(c["dropped_range"] for c in links) > 0, "range cut some"
    assert sum(c["dropped_cut"] for c in links) > 0, "and scheduled cuts others"
    assert len({d.spacecraft for d in summary.detections or []}) >= 2
    replay = replay_run(out / "run.mcap")
    assert replay.matches_live()
    res = replay.results()
    assert res.faithful_until_s == 400.0
    assert _unmarked(res.detections) == _unmarked(summary.detections)
    assert all(d.faithful for d in res.detections)
    assert (res.scores, res.baselines, res.fdir_series, res.fdir_settings) \
        == (summary.scores, summary.baselines, summary.fdir_series, summary.fdir_settings)
    live_out = GroundOutput.of_archive(archive, "replay")
    assert len(live_out.windows) == len(replay.replayed.windows) > 20


def test_another_setting_replays_as_the_live_run_with_it(
        live: tuple[Path, RunSummary], tmp_path: Path) -> None:
    out, summary = live
    replay = replay_run(out / "run.mcap", {"fdir.persistence": "2"})
    other = _record(_scenario(persistence=2), tmp_path / "other")
    horizon = replay.faithful_until_s()
    def first_camera(dets: list[Detection] | None) -> float:
        return min(d.time_s for d in dets or [] if d.fault_class == "camera")

    assert first_camera(other.detections) > first_camera(summary.detections), \
        "the setting declares the camera fault later"
    assert horizon < 400.0, "and its recovery uplink differs from the live run's"
    res = replay.results()
    assert res.scores_faithful.false_alarms <= res.scores.false_alarms
    assert res.scores_faithful.nominal_cycles < res.scores.nominal_cycles
    before = [d for d in res.detections if d.time_s <= horizon]
    assert before and all(d.faithful for d in before)
    assert _unmarked(before) == _unmarked([d for d in other.detections or []
                                           if d.time_s <= horizon])
    other_windows = GroundOutput.of_archive(load_run(tmp_path / "other" / "run.mcap"),
                                            "replay").windows
    mine = [w.model_dump(exclude={"t_wall"}) for w in replay.replayed.windows
            if w.t_sim <= horizon]
    assert mine == [w.model_dump(exclude={"t_wall"}) for w in other_windows
                    if w.t_sim <= horizon]


def test_command_line_writes_the_replay_and_refuses_an_archive_without_scenario(
        live: tuple[Path, RunSummary], tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    out, _ = live
    assert main([str(out), "--out", str(tmp_path)]) == 0
    res = json.loads((tmp_path / "live.replay.json").read_text())
    assert res["matches_live"] is True and "matches the live run" in capsys.readouterr().out
    assert list(res)[:7] == ["scenario", "seed", "replay_wall_s", "archive_end_s",
                             "faithful_until_s", "matches_live", "detections"]
    assert list(res)[-1] == "scores_faithful" and res["archive_end_s"] == 400.0
    bare = tmp_path / "bare.mcap"
    with McapRecorder(bare, {}):
        pass
    assert main([str(bare)]) == 2  # refused before any replay, in one line
    assert capsys.readouterr().err == f"error: {bare}: no scenario in the archive's metadata\n"
    with pytest.raises(ArchiveError, match="no scenario"):
        replay_run(bare)
    with pytest.raises(ArchiveError, match="no scenario"):
        archived_scenario(bare)
    assert archived_scenario(out / "run.mcap") == _scenario()


def test_a_cut_archive_is_judged_up_to_its_end_and_no_further(
        live: tuple[Path, RunSummary], cut: Path, tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    out, _ = live
    archive = load_run(cut / "run.mcap")
    end = archive.end_s
    assert archive.truncated and end is not None and 100.0 < end < 300.0
    replay = replay_run(cut)
    res = replay.results()
    assert res.archive_end_s == end and res.faithful_until_s == end
    assert replay.matches_live() and res.detections
    _due_before(replay, end)
    due = [w.model_dump(exclude={"t_wall"}) for w in replay_run(out).replayed.windows
           if w.t_end_s + replay.scenario.fdir.latency_s < end]
    assert [w.model_dump(exclude={"t_wall"}) for w in replay.replayed.windows] == due, \
        "every window due before the cut judged as the whole archive's replay judges it"
    assert main([str(cut), "--out", str(tmp_path)]) == 0
    said = capsys.readouterr().out
    assert (f"archive ends at {seconds(end)} s (run lasted 400 s): judged nothing past it"
            in said)
    assert f"matches the live run; faithful until {end:.0f} s" in said
    written = json.loads((tmp_path / "cut.replay.json").read_text())
    assert written["archive_end_s"] == end and written["faithful_until_s"] == end


def test_a_whole_archive_of_a_run_that_lasted_longer_is_judged_up_to_its_end(
        live: tuple[Path, RunSummary]) -> None:
    """The run's scenario says 800 s, its archive (closed, with its footer) holds 400 s."""
    out, _ = live
    replay = replay_run(out, scenario=_scenario().with_overrides(duration_s=800.0))
    assert replay.span.short and not replay.span.cut
    assert replay.results().archive_end_s == 400.0 and replay.faithful_until_s() == 400.0
    assert replay.span.note() == ("archive ends at 400 s (run lasted 800 s): judged nothing "
                                  "past it")
    _due_before(replay, 400.0)
    assert replay.replayed.windows


def test_the_summarys_replay_record_carries_the_archive_end(cut: Path, tmp_path: Path) -> None:
    """A campaign replay of the cut run (deploy/campaign_replay.py) writes its summary's
    ``replay`` section with where the archive ends."""
    level = logging.getLogger("insp").level
    try:
        row = replay_job(str(cut), {}, str(tmp_path))
    finally:
        logging.getLogger("insp").setLevel(level)
    end = load_run(cut / "run.mcap").end_s
    summary = RunSummary.read(tmp_path / "runs" / "cut" / "summary.json")
    assert row["matches_live"] is True and summary.replay is not None
    assert summary.replay.archive_end_s == end and summary.replay.faithful_until_s == end


def test_the_summary_of_a_cut_archive_says_where_it_ends(cut: Path, tmp_path: Path) -> None:
    """summary.json written from the cut archive: what it holds, and where it ends."""
    shutil.copyfile(cut / "run.mcap", tmp_path / "run.mcap")
    summary = write_summary(tmp_path, _scenario(), "inproc", 1.0, "completed")
    end = load_run(cut / "run.mcap").end_s
    assert summary.archive is not None and summary.archive_error is None
    assert summary.archive.truncated and summary.archive.end_s == end
    assert summary.archive.cut and "read up to byte" in summary.archive.cut
    final = summary.t_sim_final_s  # sim times are sums of steps: a float's noise apart
    assert final is not None and (final <= (end or 0.0) or final == pytest.approx(end))
    assert all(d.time_s < (end or 0.0) for d in summary.detections or [])
