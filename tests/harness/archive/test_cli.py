"""``python -m harness.archive`` (harness/archive/cli.py): nested fields flattened to CSV columns,
a missing file is a clear error (list, summary and export of a real run archive:
tests/missions/test_archive_cli_run.py)."""

from __future__ import annotations

from pathlib import Path

from harness.archive.cli import flatten, main


def test_flatten() -> None:
    assert list(flatten({"a": 1, "b": [2, {"c": 3}], "d": [[4, 5]]})) == \
        [("a", 1), ("b.0", 2), ("b.1.c", 3), ("d.0.0", 4), ("d.0.1", 5)]


def test_missing_archive_is_an_error(tmp_path: Path) -> None:
    assert main(["summary", str(tmp_path / "none.mcap")]) == 2
