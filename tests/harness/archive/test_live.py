"""The archive a one-process run writes as it goes (harness/archive/live.py): what it keeps to the
end of a run holds no more memory than the bytes kept."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

from harness.archive.live import LiveArchive
from interfaces.contracts.messages import StateEstimate
from interfaces.runtime.encoding import encode
from interfaces.runtime.transport import Sample


def test_kept_records_hold_no_more_memory_than_their_bytes(tmp_path: Path) -> None:
    """A record kept to the end of a run holds a copy of its payload's own size: an encoder's
    bytes can sit in a larger block (orjson's in 4 KiB), and a two-orbit run keeps 190,000 of
    them (0.8 GB had grown that way)."""
    eye = [[1.0 if i == j else 0.0 for j in range(6)] for i in range(6)]
    msg = StateEstimate(sender="sc1", t_sim=1.0, spacecraft=1, x=[1.0] * 6, P=eye)
    key = "insp/m/sc/1/nav/estimate"
    live = LiveArchive(tmp_path / "run.mcap", {}, stream={})
    tracemalloc.start()
    try:
        before = tracemalloc.take_snapshot()
        for _ in range(500):
            live.record_sample(Sample(key, "StateEstimate", message=msg))
        grown = sum(d.size_diff for d in tracemalloc.take_snapshot().compare_to(before, "filename"))
    finally:
        tracemalloc.stop()
    size = len(encode(msg))
    assert len(live.finish().held()) == 500
    assert grown / 500 < size + 400  # the bytes, the record and its list slot
