"""``python -m harness.archive`` (harness/archive/cli.py): nested fields flattened to CSV columns,
a missing file is a clear error, an export of an archive cut short says so (list, summary and
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
