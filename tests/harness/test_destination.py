"""Where a tool writes, checked before any work (harness/destination.py): a folder is made if
missing, a file already there is not replaced without --overwrite, a folder given as a file is
refused; each refusal one line naming the option to change.  (A read-only mount:
tests/harness/test_replay_output.py and tests/missions/test_environment_failures.py.)"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from harness.destination import DestinationError, check_file, check_folder


def test_a_missing_folder_is_made_and_left_empty(tmp_path: Path) -> None:
    folder = tmp_path / "a" / "b"
    check_folder(folder, "--out")
    assert folder.is_dir() and list(folder.iterdir()) == []


@pytest.mark.parametrize("make, overwrite, message", [
    (lambda p: p.write_text("kept"), False, "exists: give --overwrite to replace it, or --out"),
    (lambda p: p.mkdir(), True, "is a folder, not a file (give --out)"),
])
def test_a_file_is_not_replaced_unless_asked(tmp_path: Path, make: object, overwrite: bool,
                                             message: str) -> None:
    target = tmp_path / "replay.json"
    make(target)  # type: ignore[operator]
    with pytest.raises(DestinationError, match=re.escape(message)) as refused:
        check_file(target, overwrite, "--out")
    assert "\n" not in str(refused.value)
    if target.is_file():
        assert target.read_text() == "kept"
        check_file(target, True, "--out")  # --overwrite: accepted


def test_a_file_is_written_whole_or_not_at_all(tmp_path: Path) -> None:
    """A disk that fills while a file is rewritten leaves the old file, whole, and no part
    of the new one."""
    import errno

    from harness.destination import write_whole
    from tests.mounts import tmpfs

    with tmpfs(tmp_path / "disk", 1.0) as disk:
        target = disk / "summary.json"
        write_whole(target, "old\n")
        with open(disk / "filler", "wb", buffering=0) as f, pytest.raises(OSError):
            while True:  # as much as there is
                f.write(bytes(65536))
        with pytest.raises(OSError) as full:
            write_whole(target, "x" * 100_000)
        assert full.value.errno == errno.ENOSPC
        assert target.read_text() == "old\n"
        assert sorted(p.name for p in disk.iterdir()) == ["filler", "summary.json"]
