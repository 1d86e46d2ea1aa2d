"""A run's archive in segments: ``run.mcap``, then ``run-1.mcap``, ``run-2.mcap``, ... when the
recorder was restarted during the run (docs/campaigns-and-replay.md, "Segments").

The one place that names a run's segments.  Every reader of a run lists them here
(:func:`segment_paths`, through :func:`harness.archive.reader.load_run`: the digest, summary and
report, the replay, the archive command line and the topic frames); the recorder process
(``ground/archive/record.py``) claims the next free one (:func:`claim_segment`), so a restarted
recorder never overwrites what its predecessor wrote; the launcher clears a run's segments
before a new run goes into the same directory (:func:`remove_segments`).

A run of one segment is what it always was: ``run.mcap``, with no segment record in its
metadata.  Segment n >= 1 adds the metadata record ``segment`` (:func:`with_segment`).
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Final

ARCHIVE_NAME: Final = "run.mcap"
"""The first segment of a run's archive, in the run's directory."""

SEGMENT_RECORD: Final = "segment"
"""The metadata record of a segment after the first: its ``index`` and its run's ``first``
segment (file name)."""


def run_archive(run_dir: str | Path) -> Path:
    """The first segment of the archive of the run written into ``run_dir``."""
    return Path(run_dir) / ARCHIVE_NAME


def segment_path(first: str | Path, index: int) -> Path:
    """Segment ``index`` of the run whose first segment is ``first``: ``first`` itself for 0,
    ``<stem>-<index><suffix>`` beside it after (``run.mcap`` -> ``run-2.mcap``)."""
    if index < 0:
        raise ValueError(f"a segment index is >= 0, not {index}")
    first = Path(first)
    return first if index == 0 else first.with_name(f"{first.stem}-{index}{first.suffix}")


def segment_paths(first: str | Path) -> list[Path]:
    """The segments of the run whose first segment is ``first``, in order: ``first``, then each
    ``<stem>-<n><suffix>`` that exists for n = 1, 2, ... up to the first missing.  ``[first]``
    alone when it has no successor, or does not exist (its reader then says so)."""
    out = [Path(first)]
    while (path := segment_path(first, len(out))).is_file():
        out.append(path)
    return out


def claim_segment(first: str | Path) -> tuple[Path, int]:
    """Create, empty, the first segment of ``first``'s run that does not exist yet (``first``
    itself if it does not), and return it with its index.  Created exclusively
    (``O_EXCL``): a file that exists, even one made meanwhile by another, is never taken."""
    index = 0
    while True:
        path = segment_path(first, index)
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666)
        except FileExistsError:
            index += 1
            continue
        os.close(fd)
        return path, index


def remove_segments(first: str | Path) -> list[Path]:
    """Delete every segment of ``first``'s run (a new run going into the same directory must
    not be read as the continuation of the old one); the files removed."""
    first = Path(first)
    pattern = re.compile(rf"{re.escape(first.stem)}-[1-9][0-9]*{re.escape(first.suffix)}")
    later = [p for p in first.parent.glob(f"{first.stem}-*{first.suffix}")
             if pattern.fullmatch(p.name)]
    removed = []
    for path in [first, *later]:
        try:
            path.unlink()
        except FileNotFoundError:
            continue
        removed.append(path)
    return removed


def with_segment(metadata: dict[str, dict[str, str]], first: str | Path,
                 index: int) -> dict[str, dict[str, str]]:
    """``metadata`` of segment ``index`` of ``first``'s run: as given for the first segment,
    with the ``segment`` record added for a later one."""
    if index == 0:
        return metadata
    return {**metadata, SEGMENT_RECORD: {"index": str(index), "first": Path(first).name}}
