"""Tests of ground.archive.mcap_file on its own: the layout (a channel per key and type, a
schema per type name, log time from the sim time), the counts, and a flushed chunk read back."""

from __future__ import annotations

from collections import deque
from pathlib import Path

from mcap.reader import make_reader

from ground.archive.mcap_file import LIBRARY, McapFile, Pending

KEY = "insp/mf/sc/1/exec/heartbeat"


def _pending(key: str, type_name: str, t_ns: int | None, is_object: bool = True) -> Pending:
    return (key, type_name, b'{"t_sim": 1.0}', None, is_object, t_ns, 7, 123)


def test_layout_and_counts(tmp_path: Path) -> None:
    path = tmp_path / "f.mcap"
    f = McapFile(path, {"run": {"seed": "1"}}, chunk_size=1024)
    queue = deque([_pending(KEY, "Heartbeat", 2_000_000_000),
                   _pending(KEY, "NoSuchType", None, is_object=False),
                   _pending(KEY, "Heartbeat", 3_000_000_000)])
    f.write_all(queue)
    assert not queue
    assert (f.recorded, f.invalid, f.unknown_type, f.dropped) == (3, 1, 1, 0)
    assert f.counts == {KEY: 3} and f.last_log_ns == 3_000_000_000
    f.add_metadata("result", {"status": "finished"})
    f.finish()
    with path.open("rb") as fh:
        reader = make_reader(fh)
        assert reader.get_header().library == LIBRARY
        summary = reader.get_summary()
        assert summary is not None
        assert sorted(s.name for s in summary.schemas.values()) == ["Heartbeat", "NoSuchType"]
        assert {c.topic for c in summary.channels.values()} == {KEY}
        assert len(summary.channels) == 2  # one per (key, type)
        logs = [(m.log_time, m.sequence) for _, _, m in reader.iter_messages()]
        assert logs == [(2_000_000_000, 7), (2_000_000_000, 7), (3_000_000_000, 7)]
        assert {m.name for m in reader.iter_metadata()} == {"run", "result"}


def test_a_flushed_chunk_is_in_the_file_before_it_is_finished(tmp_path: Path) -> None:
    path = tmp_path / "f.mcap"
    f = McapFile(path, {}, chunk_size=1 << 20)
    f.write_all(deque([_pending(KEY, "Heartbeat", 1)]))
    size = path.stat().st_size
    f.flush()
    assert path.stat().st_size > size
    f.finish()
