"""The archive read in time order, in bounded memory (harness.archive.stream.stream_run),
against the whole-file read it must equal (harness.archive.reader.load_run: its held records,
sorted at the end, are the independent order).

Files are real MCAP files written by the project's McapRecorder, with small chunks so that a run
spans many of them: messages out of time order across chunks, a run in two segments that
repeat messages, files cut at many places.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mcap.records import Chunk
from mcap.records import Message as McapMessage
from mcap.stream_reader import StreamReader, breakup_chunk

from ground.archive.recorder import McapRecorder
from ground.archive.segments import with_segment
from harness.archive.reader import Record, load_run, unit_times
from harness.archive.stream import TimeOrder, stream_run
from interfaces.contracts.messages import Heartbeat, StateEstimate

M = "st"
NAV = f"insp/{M}/sc/{{}}/nav/estimate"
BEAT = f"insp/{M}/sc/{{}}/exec/heartbeat"
META = {"run": {"scenario": M, "seed": "5"}}
EYE = [[1.0 if i == j else 0.0 for j in range(6)] for i in range(6)]


def _nav(sc: int, seq: int, t: float) -> bytes:
    return StateEstimate(sender=f"sc{sc}", seq=seq, t_sim=t, spacecraft=sc, x=[t] * 6,
                         P=EYE).model_dump_json().encode()


def _beat(sc: int, seq: int, t: float) -> bytes:
    return Heartbeat(sender=f"sc{sc}", seq=seq, t_sim=t, node=f"sc{sc}", apps=["nav"],
                     k=seq).model_dump_json().encode()


def _jittered(n: int, rng: np.random.Generator) -> list[tuple[str, str, bytes]]:
    """``n`` messages on six keys as a recorder over a network receives them: in time order
    up to a jitter of up to 2 s between publishers (each publisher's own in order)."""
    out = []
    for sc in (1, 2, 3):
        for seq in range(n // 6):
            t = seq * 0.5
            arrival = t + rng.uniform(0.0, 2.0)
            out.append((arrival, sc, NAV.format(sc), "StateEstimate", _nav(sc, seq, t)))
            out.append((arrival, sc, BEAT.format(sc), "Heartbeat", _beat(sc, seq, t)))
    out.sort(key=lambda m: (m[1], m[0]))  # each publisher's arrivals in order...
    per_sc: dict[int, float] = {}
    for i, (arrival, sc, *_rest) in enumerate(out):  # ...never before its own previous one
        per_sc[sc] = max(per_sc.get(sc, 0.0), arrival)
        out[i] = (per_sc[sc], *out[i][1:])
    out.sort(key=lambda m: m[0])
    return [(key, type_name, payload) for _, _, key, type_name, payload in out]


def _write(path: Path, messages: list[tuple[str, str, bytes]], index: int = 0,
           chunk_size: int = 4096) -> Path:
    with McapRecorder(path, with_segment(META, path, index), chunk_size=chunk_size) as rec:
        for key, type_name, payload in messages:
            rec.record(key, type_name, payload)
    return path


def _same(a: list[Record], b: list[Record]) -> bool:
    return [(r.key, r.type_name, r.log_time_ns, r.payload) for r in a] == \
        [(r.key, r.type_name, r.log_time_ns, r.payload) for r in b]


def _check_equal(path: Path) -> TimeOrder:
    """Streamed in time order, every record equals the whole read's held ones, in order, and
    the archives agree on what they count."""
    whole = load_run(path)
    got: list[Record] = []
    archive, order = stream_run(path, {"**": got.append})
    assert _same(got, whole.held())
    assert archive.held() == [] and len(archive) == len(whole)
    assert archive.topics() == whole.topics()
    assert (archive.lost, archive.duplicates, archive.end_s, archive.truncated) == \
        (whole.lost, whole.duplicates, whole.end_s, whole.truncated)
    assert archive.metadata == whole.metadata
    assert order.late == 0
    return order


def test_out_of_order_messages_over_many_chunks_come_in_time_order(tmp_path: Path) -> None:
    messages = _jittered(3000, np.random.default_rng(3))
    path = _write(tmp_path / "run.mcap", messages)
    assert [m[2] for m in messages] != [r.payload for r in load_run(path).held()]  # jittered
    loader = _check_equal(path)
    # bounded: a few chunks' worth waits at once (a 4 KiB chunk holds about ten messages)
    assert 0 < loader.peak_waiting <= 60


def test_kept_keys_are_held_and_the_rest_streamed_in_order(tmp_path: Path) -> None:
    path = _write(tmp_path / "run.mcap", _jittered(1200, np.random.default_rng(4)))
    whole = load_run(path)
    got: list[Record] = []
    archive, _ = stream_run(path, {f"insp/{M}/sc/*/exec/**": None, "**": got.append})
    beats = whole.records(f"insp/{M}/sc/*/exec/**")
    assert _same(archive.held(), beats) and len(beats) == 600
    assert _same(got, whole.records(f"insp/{M}/sc/*/nav/**"))


def test_a_run_in_two_segments_streams_as_one_with_repeats_once(tmp_path: Path) -> None:
    messages = _jittered(1800, np.random.default_rng(5))
    first, second = messages[:1000], messages[800:]  # 200 messages in both segments
    _write(tmp_path / "run.mcap", first)
    _write(tmp_path / "run-1.mcap", second, index=1)
    whole = load_run(tmp_path / "run.mcap")
    assert whole.duplicates == 200 and len(whole.segments) == 2
    _check_equal(tmp_path / "run.mcap")


@pytest.mark.parametrize("fraction", [0.13, 0.5, 0.77, 0.999])
def test_a_file_cut_anywhere_streams_its_readable_prefix_in_order(tmp_path: Path,
                                                                   fraction: float) -> None:
    full = _write(tmp_path / "full.mcap", _jittered(2400, np.random.default_rng(6)))
    data = full.read_bytes()
    cut = tmp_path / "run.mcap"
    cut.write_bytes(data[:int(len(data) * fraction)])
    assert load_run(cut).truncated
    _check_equal(cut)


def test_a_cut_first_segment_then_a_whole_one(tmp_path: Path) -> None:
    messages = _jittered(1800, np.random.default_rng(7))
    _write(tmp_path / "whole-first.mcap", messages[:1000])
    data = (tmp_path / "whole-first.mcap").read_bytes()
    (tmp_path / "run.mcap").write_bytes(data[:len(data) // 2])  # the recorder was killed
    _write(tmp_path / "run-1.mcap", messages[900:], index=1)
    assert load_run(tmp_path / "run.mcap").truncated
    _check_equal(tmp_path / "run.mcap")


def test_not_an_archive_is_refused_as_the_whole_read_refuses_it(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    path.write_bytes(b"not an archive at all")
    with pytest.raises(Exception) as whole:
        load_run(path)
    with pytest.raises(type(whole.value)):
        stream_run(path, {"**": lambda _r: None})


def _library_units(path: Path) -> list[dict[int, int]]:
    """Each chunk's first log time per channel, split by the mcap library itself."""
    out = []
    with open(path, "rb") as f:
        for rec in StreamReader(f, emit_chunks=True).records:
            if isinstance(rec, Chunk):
                first: dict[int, int] = {}
                for item in breakup_chunk(rec):
                    if isinstance(item, McapMessage):
                        first[item.channel_id] = min(first.get(item.channel_id, item.log_time),
                                                     item.log_time)
                out.append(first)
    return out


def test_each_chunks_first_log_time_per_channel_as_the_mcap_library_splits_it(
        tmp_path: Path) -> None:
    path = _write(tmp_path / "run.mcap", _jittered(1200, np.random.default_rng(8)))
    units = unit_times(path)
    assert [dict(u) for u in units] == _library_units(path) and len(units) > 20
    data = path.read_bytes()
    (tmp_path / "cut.mcap").write_bytes(data[:len(data) // 2])
    cut = unit_times(tmp_path / "cut.mcap")
    assert 0 < len(cut) < len(units) and cut[:-1] == units[:len(cut) - 1]


def test_a_held_key_archived_late_holds_nothing_back(tmp_path: Path) -> None:
    """Judgements archived long after the time they are stamped with (the ground's at a pass)
    wait for nothing when held; streamed, they are still put in order."""
    late_key = f"insp/{M}/ground/fdir/window"
    messages = []
    for i, m in enumerate(_jittered(3000, np.random.default_rng(9))):
        messages.append(m)
        if i % 1000 == 999:  # a pass: the last 40 s judged at once, stamped with their times
            t_now = i / 3000 * 250.0
            messages += [(late_key, "Heartbeat", _beat(9, i + j, t_now - 40.0 + 4 * j))
                         for j in range(10)]
    path = _write(tmp_path / "run.mcap", messages)
    whole = load_run(path)
    got: list[Record] = []
    archive, order = stream_run(path, {late_key: None, "**": got.append})
    assert _same(archive.held(), whole.records(late_key)) and len(archive.held()) == 30
    assert _same(got, [r for r in whole.held() if r.key != late_key])
    assert order.late == 0 and order.peak_waiting <= 60
    streamed_too = _check_equal(path)
    assert streamed_too.peak_waiting > 300  # in order, they hold back what came since
