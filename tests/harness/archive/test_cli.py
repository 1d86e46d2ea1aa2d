"""``python -m harness.archive`` (harness/archive/cli.py): nested fields flattened to CSV columns,
a missing file is a clear error, an export of an archive cut short says so, an export refused
in one line before writing anything (list, summary and
export of a real run archive: tests/missions/test_archive_cli_run.py)."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from ground.archive.recorder import McapRecorder
from harness.archive.cli import flatten, main
from tests.harness.archive.test_reader import _key, _relnav_payload


def test_flatten() -> None:
    assert list(flatten({"a": 1, "b": [2, {"c": 3}], "d": [[4, 5]]})) == \
        [("a", 1), ("b.0", 2), ("b.1.c", 3), ("d.0.0", 4), ("d.0.1", 5)]


def test_missing_archive_is_an_error(tmp_path: Path) -> None:
    assert main(["summary", str(tmp_path / "none.mcap")]) == 2


def test_an_export_of_a_cut_archive_warns_where_it_ends(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Half the bytes of a 200-message archive: the rows it holds are exported, and a warning
    names the cut."""
    path = tmp_path / "full.mcap"
    key = _key("sim", "sensors", "sc1", "relnav")
    with McapRecorder(path, chunk_size=1024) as rec:
        for i in range(200):
            rec.record(key, "RelNavMeasurement", _relnav_payload(i))
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[:path.stat().st_size // 2])
    out = tmp_path / "x.csv"
    assert main(["export", str(cut), "--topic", key, "--out", str(out)]) == 0
    err = capsys.readouterr().err
    rows = list(csv.DictReader(open(out)))
    assert 0 < len(rows) < 200 and f"{len(rows)} messages exported" in err
    assert "warning: the archive is truncated (cut.mcap read up to byte" in err
    assert main(["export", str(path), "--topic", key, "--out", str(out), "--overwrite"]) == 0
    assert "truncated" not in capsys.readouterr().err


@pytest.fixture
def archive(tmp_path: Path) -> Path:
    """An archive of ten relative-navigation messages."""
    path = tmp_path / "a.mcap"
    with McapRecorder(path) as rec:
        for i in range(10):
            rec.record(_key("sim", "sensors", "sc1", "relnav"), "RelNavMeasurement",
                       _relnav_payload(i))
    return path


# (id, the --out file (None: stdout) and whether it exists first, other options, the line)
EXPORT_REFUSALS = [
    ("nothing matched, CSV", ("x.csv", False), ["--topic", "insp/nothing/**"],
     "error: {archive}: no key matches 'insp/nothing/**' (1 keys; `python -m harness.archive "
     "list {archive}` shows them)"),
    ("nothing matched, Parquet", ("x.parquet", False), ["--topic", "insp/nothing/**"],
     "error: {archive}: no key matches 'insp/nothing/**' (1 keys; `python -m harness.archive "
     "list {archive}` shows them)"),
    ("nothing matched, stdout", (None, False), ["--topic", "insp/nothing/**"],
     "error: {archive}: no key matches 'insp/nothing/**'"),
    ("unknown suffix", ("x.txt", False), [],
     "error: --out {out}: the suffix chooses the format: one of .csv, .parquet, .pq"),
    ("no suffix", ("x", False), [],
     "error: --out {out}: the suffix chooses the format: one of .csv, .parquet, .pq"),
    ("an existing file", ("x.csv", True), [],
     "error: {out} exists: give --overwrite to replace it, or another --out"),
    ("an existing Parquet file", ("x.PQ", True), [],
     "error: {out} exists: give --overwrite to replace it, or another --out"),
]


@pytest.mark.parametrize("out, options, line", [c[1:] for c in EXPORT_REFUSALS],
                         ids=[c[0] for c in EXPORT_REFUSALS])
def test_an_export_is_refused_in_one_line_writing_nothing(
        archive: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        out: tuple[str | None, bool], options: list[str], line: str) -> None:
    name, exists = out
    target = None if name is None else tmp_path / name
    if target is not None and exists:
        target.write_text("kept\n")
    argv = ["export", str(archive), *(options or ["--topic", "**"])]
    assert main(argv + (["--out", str(target)] if target is not None else [])) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith(line.format(archive=archive, out=target))
    assert captured.err.count("\n") == 1 and captured.out == ""
    if target is not None:
        assert (target.read_text() == "kept\n") if exists else not target.exists()


def test_an_existing_file_is_replaced_only_with_overwrite(archive: Path, tmp_path: Path) -> None:
    out = tmp_path / "x.csv"
    out.write_text("kept\n")
    assert main(["export", str(archive), "--topic", "**", "--out", str(out), "--overwrite"]) == 0
    assert len(list(csv.DictReader(open(out)))) == 10
