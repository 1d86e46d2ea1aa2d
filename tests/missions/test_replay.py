"""Replay (harness/replay.py): the live ground re-run on a recorded run reproduces the live
detections, windows and verdicts exactly -- with lossy, range-limited and cut links and three
faults -- and, under another setting, what the live run with that setting declared, up to the
first uplink the two runs differ in."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from deploy.inproc import run_inproc
from ground.archive.metadata import run_metadata
from ground.archive.recorder import McapRecorder
from harness.archive.reader import ArchiveError, load_run
from harness.archive.run_scenario import archived_scenario
from harness.replay import GroundOutput, main, replay_run
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
    assert list(res)[:6] == ["scenario", "seed", "replay_wall_s", "faithful_until_s",
                             "matches_live", "detections"] and list(res)[-1] == "scores_faithful"
    bare = tmp_path / "bare.mcap"
    with McapRecorder(bare, {}):
        pass
    assert main([str(bare)]) == 1
    assert "no scenario" in capsys.readouterr().err
    with pytest.raises(ArchiveError, match="no scenario"):
        replay_run(bare)
    with pytest.raises(ArchiveError, match="no scenario"):
        archived_scenario(bare)
    assert archived_scenario(out / "run.mcap") == _scenario()
