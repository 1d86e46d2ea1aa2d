"""Where a replay writes (harness/replay.py, harness/destination.py), as tables: a replay's file
is named after its settings and never replaces another one's; a bad setting, a replay already
written with the same settings and a read-only destination are each refused before any replay,
in one line, with exit status 2, nothing written or changed.  The archive is a short one of
ticks alone (a replay of a flown run: tests/missions/test_replay.py)."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

import harness.replay
from ground.archive.metadata import run_metadata
from ground.archive.recorder import McapRecorder
from harness.replay import main, output_name
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import Tick
from tests.conftest import small_scenario
from tests.mounts import read_only as mounted_read_only


@pytest.fixture
def run(tmp_path: Path) -> Path:
    """A run folder whose archive holds its scenario and a few ticks."""
    folder = tmp_path / "run"
    folder.mkdir()
    scenario = small_scenario("r", duration_s=2.0)
    with McapRecorder(folder / "run.mcap", run_metadata(scenario, "inproc", "# t\n")) as rec:
        for k in range(5):
            tick = Tick(sender="sim", seq=k + 1, t_sim=k * 0.5, k=k, dt_s=0.5)
            rec.record(cat.TICK.key("r"), "Tick", tick.model_dump_json().encode())
    return folder


@pytest.mark.parametrize("values, name", [
    ({}, "replay"),
    ({"fdir.persistence": 3}, "replay-fdir.persistence=3"),
    ({"fdir.persistence": 3, "fdir.floor": 0.07}, "replay-fdir.floor=0.07+fdir.persistence=3"),
    ({"fdir.detector": "sequential"}, "replay-fdir.detector=sequential"),
    ({"fdir.threshold": "a b/c"}, "replay-fdir.threshold=a_b_c"),
])
def test_a_replay_is_named_after_its_settings(values: dict[str, object], name: str) -> None:
    assert output_name(values) == name


def test_a_long_name_is_cut_and_told_apart_by_a_digest() -> None:
    one = output_name({f"fdir.k{i}": i for i in range(30)})
    other = output_name({f"fdir.k{i}": i + 1 for i in range(30)})
    assert len(one) <= 130 and one.startswith("replay-fdir.k0=0+") and one != other


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_replays_under_other_settings_are_kept_side_by_side(
        run: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([str(run)]) == 0
    assert main([str(run), "--set", "fdir.persistence=3"]) == 0
    first = _files(run)
    assert set(first) == {"run.mcap", "replay.json", "replay-fdir.persistence=3.json"}
    # 3.0 is the same setting as 3 (an integer): the same file, refused, nothing changed
    assert main([str(run), "--set", "fdir.persistence=3.0"]) == 2
    err = capsys.readouterr().err
    assert err == (f"error: {run / 'replay-fdir.persistence=3.json'} exists: give --overwrite "
                   "to replace it, or --out DIR\n")
    assert _files(run) == first
    assert main([str(run), "--set", "fdir.persistence=3", "--overwrite"]) == 0


@pytest.mark.parametrize("argv, says", [
    (["--set", "fdir.floor=abc"], "{run}: --set: fdir.floor = 'abc': should be a valid number"),
    (["--set", "fdir.flor=0.1"], "{run}: --set fdir.flor: no such setting in [fdir]; did you "
                                 "mean 'floor'?"),
    (["--set", "fdir.detector=windw"], "--set: fdir.detector = 'windw': unknown; did you mean "
                                       "'window'?"),
    (["--set", "fdri.floor=0.1"], "--set fdri.floor: the scenario has no [fdri]; did you mean "
                                  "'fdir'?"),
    (["--set", "comms.packet_loss=0.5"], "comms.packet_loss changes what was flown"),
    (["--set", "fdir.floor"], "--set 'fdir.floor': expected SECTION.KEY=VALUE"),
    (["--set", "fdir.floor=-1"], "fdir.floor = -1: should be greater than or equal to 0"),
])
def test_a_bad_setting_is_refused_before_any_replay(
        run: Path, argv: list[str], says: str, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    replayed: list[Path] = []
    monkeypatch.setattr(harness.replay, "replay_run", lambda *a, **k: replayed.append(a[0]))
    before = _files(run)
    assert main([str(run), str(run), *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and says.format(run=run) in err
    assert replayed == [] and _files(run) == before


@pytest.fixture
def read_only(tmp_path: Path) -> Iterator[Path]:
    """A folder to be made read-only by :func:`tests.mounts.read_only` (a bind mount remounted
    read-only: permissions do not stop root); skipped where a mount cannot be made."""
    folder = tmp_path / "ro"
    folder.mkdir()
    yield folder


@pytest.mark.parametrize("where", ["beside the archive", "--out"])
def test_a_read_only_destination_is_refused_before_any_replay(
        run: Path, read_only: Path, where: str, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    replayed: list[Path] = []
    monkeypatch.setattr(harness.replay, "replay_run", lambda *a, **k: replayed.append(a[0]))
    if where == "--out":
        argv, folder, option = [str(run), "--out", str(read_only / "x")], read_only / "x", \
            "another --out"
    else:
        shutil.copytree(run, read_only / "run")
        argv, folder, option = [str(read_only / "run")], read_only / "run", "--out DIR"
    with mounted_read_only(read_only):
        assert main(argv) == 2
    assert capsys.readouterr().err == (f"error: cannot write into {folder}: Read-only file "
                                       f"system (give {option})\n")
    assert replayed == []
