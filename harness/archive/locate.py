"""The archive a command-line path names: an MCAP file, or a run folder holding ``run.mcap``.

Every command that reads a run's archive (``python -m harness.archive``, ``python -m
harness.replay``, ``python -m harness.campaign.calibrate``) resolves its paths here, so that
each takes either form and refuses anything else the same way: one line naming the path and
what was expected (:class:`ArchivePathError`), which the command prints before exiting with
status 2.
"""

from __future__ import annotations

from pathlib import Path
from typing import Final

from ground.archive.segments import ARCHIVE_NAME, run_archive
from harness.archive.reader import MCAP_MAGIC, ArchiveError

EXPECTED: Final = f"expected an MCAP archive or a run folder holding {ARCHIVE_NAME}"
"""What a path given for an archive must be, as the errors say it."""


class ArchivePathError(ArchiveError):
    """A path given for an archive names neither an MCAP file nor a run folder with one."""


def archive_file(path: str | Path) -> Path:
    """The archive ``path`` names: ``path`` itself when it is an MCAP file, ``run.mcap`` in it
    when it is a folder (the run's first segment; its later segments are read with it).

    Raises :class:`ArchivePathError` for a path that does not exist, a folder without
    ``run.mcap``, a file that cannot be read or does not start with the MCAP magic.
    """
    path = Path(path)
    if path.is_dir():
        file = run_archive(path)
        if not file.is_file():
            raise ArchivePathError(f"{path}: a folder without {ARCHIVE_NAME} ({EXPECTED})")
        return _checked(file)
    if not path.exists():
        raise ArchivePathError(f"{path}: no such file or folder ({EXPECTED})")
    return _checked(path)


def _checked(file: Path) -> Path:
    """``file`` if it starts with the MCAP magic, else :class:`ArchivePathError`."""
    try:
        with open(file, "rb") as f:
            head = f.read(len(MCAP_MAGIC))
    except OSError as e:
        raise ArchivePathError(f"{file}: cannot be read: {e.strerror or e} ({EXPECTED})") from e
    if head != MCAP_MAGIC:
        what = "an empty file" if not head else "not an MCAP file"
        raise ArchivePathError(f"{file}: {what} ({EXPECTED})")
    return file


__all__ = ["EXPECTED", "ArchivePathError", "archive_file"]
