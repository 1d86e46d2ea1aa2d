"""The archive a command-line path names (harness/archive/locate.py): an MCAP file or a run
folder holding run.mcap, and one clear line for anything else; every command that reads an
archive takes both forms and refuses the rest with exit status 2."""

from __future__ import annotations

from pathlib import Path

import pytest

from ground.archive.recorder import McapRecorder
from harness.archive.cli import main as archive_main
from harness.archive.locate import EXPECTED, ArchivePathError, archive_file
from harness.campaign.calibrate import main as calibrate_main
from harness.replay import main as replay_main
from interfaces.contracts.messages import Tick


@pytest.fixture
def run_dir(tmp_path: Path) -> Path:
    """A run folder whose run.mcap holds a few ticks."""
    run = tmp_path / "run"
    run.mkdir()
    with McapRecorder(run / "run.mcap", {"run": {"seed": "1"}}) as rec:
        for k in range(3):
            tick = Tick(sender="sim", seq=k + 1, t_sim=k * 0.5, k=k, dt_s=0.5)
            rec.record("insp/m/sim/lockstep/tick", "Tick", tick.model_dump_json().encode())
    return run


def _not_mcap(tmp_path: Path) -> Path:
    path = tmp_path / "notes.mcap"
    path.write_text("not an archive\n")
    return path


def test_a_file_or_a_run_folder_names_the_archive(run_dir: Path) -> None:
    assert archive_file(run_dir) == run_dir / "run.mcap"
    assert archive_file(run_dir / "run.mcap") == run_dir / "run.mcap"
    assert archive_file(str(run_dir)) == run_dir / "run.mcap"


def test_anything_else_is_refused_in_one_line(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    (tmp_path / "zero.mcap").write_bytes(b"")
    cases = {tmp_path / "none": "no such file or folder",
             tmp_path / "empty": "a folder without run.mcap",
             _not_mcap(tmp_path): "not an MCAP file",
             tmp_path / "zero.mcap": "an empty file"}
    for path, what in cases.items():
        with pytest.raises(ArchivePathError) as err:
            archive_file(path)
        assert str(err.value) == f"{path}: {what} ({EXPECTED})"


@pytest.mark.parametrize("command", ["list", "summary", "export"])
def test_every_archive_subcommand_takes_a_run_folder(
        command: str, run_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    extra = ["--topic", "insp/m/**"] if command == "export" else []
    assert archive_main([command, str(run_dir), *extra]) == 0
    out = capsys.readouterr().out
    assert ("tick" in out) if command == "export" else (f"{run_dir / 'run.mcap'}: 3 messages"
                                                        in out)


@pytest.mark.parametrize("command", ["list", "summary", "export"])
def test_every_archive_subcommand_refuses_a_bad_path_in_one_line(
        command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    extra = ["--topic", "insp/m/**"] if command == "export" else []
    for path, what in ((tmp_path / "none", "no such file or folder"),
                       (tmp_path, "a folder without run.mcap"),
                       (_not_mcap(tmp_path), "not an MCAP file")):
        assert archive_main([command, str(path), *extra]) == 2
        err = capsys.readouterr().err
        assert err == f"error: {path}: {what} ({EXPECTED})\n"


def test_list_refuses_before_listing_any(run_dir: Path, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    assert archive_main(["list", str(run_dir), str(tmp_path / "none")]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "none: no such file or folder" in err


def test_the_replay_and_the_calibration_refuse_a_bad_path_alike(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = _not_mcap(tmp_path)
    for main in (replay_main, calibrate_main):
        for path, what in ((tmp_path / "none", "no such file or folder"),
                           (tmp_path, "a folder without run.mcap"), (bad, "not an MCAP file")):
            assert main([str(path)]) == 2
            assert capsys.readouterr().err == f"error: {path}: {what} ({EXPECTED})\n"
