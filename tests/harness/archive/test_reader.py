"""Tests of the MCAP run archive: ground.archive.recorder.McapRecorder and
harness.archive.reader.load_run.

Files are real MCAP files in ``tmp_path``; the file structure is checked with the ``mcap``
library's own reader (independent of harness.archive.reader).  A SIGKILLed writer, a real
process: tests/missions/test_archive_killed_writer.py.
"""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader

from ground.archive.recorder import LIBRARY, McapRecorder
from harness.archive.reader import ArchiveError, load_run
from interfaces.contracts.messages import (
    ExecStats,
    GroupStats,
    Heartbeat,
    Message,
    RelNavMeasurement,
    SimStatus,
    StateEstimate,
    TelemetryStatus,
    Tick,
    json_schema,
    registry,
)

M = "m1"


def _key(*parts: str) -> str:
    return "/".join(("insp", M, *parts))


def _sample_messages() -> list[tuple[str, Message]]:
    """A mix of message types on several keys, deliberately not in t_sim order."""
    eye = [[1.0 if i == j else 0.0 for j in range(6)] for i in range(6)]
    out: list[tuple[str, Message]] = []
    for k in range(5):
        t = 0.5 * k
        tick = Tick(
            sender="sim", seq=k, t_sim=t, t_wall=1.7e9 + k, k=k, dt_s=0.5,
            expect={_key("sc", "1", "nav", "state"): k}, final=k == 4,
        )
        relnav = RelNavMeasurement(
            sender="sim", seq=k, t_sim=t, spacecraft=1, r_m=[100.0 + k, -2.5, 0.125],
            v_mps=[0.01, -0.02, 0.0], sigma_r_m=0.5, sigma_v_mps=0.01,
        )
        estimate = StateEstimate(
            sender="sc1", seq=k, t_sim=t, spacecraft=1, x=[1.0, 2.0, 3.0, 0.1, 0.2, 0.3], P=eye,
            nis=None if k == 0 else 1.5 * k,
        )
        out.append((_key("sim", "clock", "tick"), tick))
        out.append((_key("sim", "sensors", "sc1", "relnav"), relnav))
        out.append((_key("sc", "1", "nav", "state"), estimate))
    stats = ExecStats(
        sender="sc2", t_sim=1.0, node="sc2", app_errors=2,
        groups={"high": GroupStats(runs=10, cycle_slips=1, max_exec_ms=2.5, budget_ms=10.0)},
    )
    tlm = TelemetryStatus(
        sender="ground", t_sim=0.75,
        entries=[
            TelemetryStatus.Entry(spacecraft=1, received=3, seq_gaps=1, last_t_sim=0.5),
            TelemetryStatus.Entry(spacecraft=2),
        ],
    )
    heartbeat = Heartbeat(sender="sc2", seq=3, t_sim=0.25, node="sc2", apps=["nav", "gnc"], k=1)
    status = SimStatus(sender="sim", seq=1, t_sim=2.0, state="finished", k=4)
    out.append((_key("sc", "2", "exec", "stats"), stats))
    out.append((_key("ground", "telemetry", "status"), tlm))
    out.append((_key("sc", "2", "exec", "heartbeat"), heartbeat))
    out.append((_key("sim", "clock", "status"), status))
    return out


def _record_all(rec: McapRecorder, items: list[tuple[str, Message]]) -> None:
    for key, msg in items:
        rec.record(key, type(msg).__name__, msg.model_dump_json().encode())


def _t_ns(msg: Message) -> int:
    return round(msg.t_sim * 1e9)


# --- round trip ----------------------------------------------------------------------------------


def test_round_trip_of_several_types(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    items = _sample_messages()
    t_before = time.time_ns()
    with McapRecorder(path) as rec:
        _record_all(rec, items)
        assert rec.recorded == len(items) and rec.invalid == 0 and rec.unknown_type == 0
    t_after = time.time_ns()

    run = load_run(path)
    assert not run.truncated and run.stop_reason is None
    assert run.library == LIBRARY and run.profile == ""
    assert len(run) == len(items)

    # All messages back, equal to the originals, in (log time, file order).
    expected = [m for _, m in sorted(enumerate(items), key=lambda im: (_t_ns(im[1][1]), im[0]))]
    assert run.messages() == [m for _, m in expected]
    records = run.records()
    assert [r.log_time_ns for r in records] == sorted(_t_ns(m) for _, m in items)
    assert all(t_before <= r.publish_time_ns <= t_after for r in records)
    assert [r.message() for r in records] == run.messages()

    # Per key, per type.
    for key, msg in items:
        assert msg in run.messages(key, type(msg))
    estimates = run.messages(_key("sc", "*", "nav", "state"), StateEstimate)
    assert [e.seq for e in estimates] == [0, 1, 2, 3, 4]
    assert all(isinstance(e, StateEstimate) for e in estimates)
    assert run.messages("**", "Heartbeat") == [items[-2][1]]
    assert len(run.records(_key("sc", "**"))) == 7
    assert len(run.records(_key("sim", "*", "*"))) == 6
    assert run.records("nothing/**") == []

    topics = run.topics()
    assert topics[_key("sim", "clock", "tick")] == ("Tick", 5)
    assert topics[_key("sc", "2", "exec", "stats")] == ("ExecStats", 1)
    assert sum(n for _, n in topics.values()) == len(items)
    assert rec.counts == {k: n for k, (_, n) in topics.items()}


def test_file_structure_with_the_mcap_library(tmp_path: Path) -> None:
    """Schemas are JSON schemas of the models, channels are JSON, one channel per key, and a
    closed file has a summary and footer."""
    path = tmp_path / "run.mcap"
    items = _sample_messages()
    with McapRecorder(path, chunk_size=512) as rec:  # several chunks
        _record_all(rec, items)

    with open(path, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        assert header.profile == "" and header.library == LIBRARY
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_count == len(items)
        assert summary.statistics.chunk_count > 1
        assert all(ci.compression == "zstd" for ci in summary.chunk_indexes)
        types = {type(m).__name__: type(m) for _, m in items}
        assert {s.name for s in summary.schemas.values()} == set(types)
        for schema in summary.schemas.values():
            assert schema.encoding == "jsonschema"
            assert json.loads(schema.data) == json_schema(types[schema.name])
        topics = [c.topic for c in summary.channels.values()]
        assert sorted(topics) == sorted({k for k, _ in items})
        for channel in summary.channels.values():
            assert channel.message_encoding == "json"
        n = 0
        for schema, _channel, message in reader.iter_messages(log_time_order=True):
            assert schema is not None
            registry()[schema.name].model_validate_json(message.data)
            assert message.log_time % 250_000_000 == 0
            n += 1
        assert n == len(items)


def test_metadata_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    toml = '[scenario]\nname = "approach"\nseed = 7  # é ∆\n'
    meta = {
        "run": {"scenario": "approach", "seed": "7", "transport": "local", "version": "0.1"},
        "scenario": {"toml": toml},
    }
    with McapRecorder(path, metadata=meta) as rec:
        _record_all(rec, _sample_messages()[:3])
        rec.add_metadata("result", {"status": "finished", "ticks": "5"})
        with pytest.raises(TypeError):
            rec.add_metadata("bad", {"n": 5})  # type: ignore[dict-item]
    with pytest.raises(RuntimeError):
        rec.add_metadata("late", {"a": "b"})
    run = load_run(path)
    assert run.metadata == {**meta, "result": {"status": "finished", "ticks": "5"}}
    with open(path, "rb") as f:
        names = [m.name for m in make_reader(f).iter_metadata()]
    assert names == ["run", "scenario", "result"]


def test_close_is_idempotent_and_later_records_are_counted(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    rec = McapRecorder(path)
    _record_all(rec, _sample_messages()[:2])
    rec.close()
    size = path.stat().st_size
    rec.close()
    rec.record(_key("sim", "x"), "Tick", b"{}")
    rec.record(_key("sim", "x"), "Tick", b"{}")
    rec.flush()
    assert rec.closed and rec.after_close == 2 and rec.recorded == 2
    assert path.stat().st_size == size
    assert len(load_run(path)) == 2


# --- concurrency ---------------------------------------------------------------------------------


def test_concurrent_record_from_four_threads_loses_nothing(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    n_threads, n_each = 4, 3000
    start = threading.Barrier(n_threads)

    def producer(sc: int, rec: McapRecorder) -> None:
        key = _key("sc", str(sc), "nav", "relnav")
        start.wait()
        for i in range(n_each):
            msg = RelNavMeasurement(
                sender=f"sc{sc}", seq=i, t_sim=i * 0.01, spacecraft=sc, r_m=[float(i), 0.0, 0.0],
                v_mps=[0.0, 0.0, 0.0], sigma_r_m=1.0, sigma_v_mps=1.0,
            )
            rec.record(key, "RelNavMeasurement", msg.model_dump_json().encode())

    with McapRecorder(path, chunk_size=16 * 1024) as rec:
        threads = [
            threading.Thread(target=producer, args=(sc, rec)) for sc in range(1, n_threads + 1)
        ]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert rec.recorded == n_threads * n_each
        assert rec.counts == {_key("sc", str(sc), "nav", "relnav"): n_each for sc in range(1, 5)}

    run = load_run(path)
    assert len(run) == n_threads * n_each
    for sc in range(1, n_threads + 1):
        msgs = run.messages(_key("sc", str(sc), "**"), RelNavMeasurement)
        assert [m.seq for m in msgs] == list(range(n_each))  # all there, in order
        assert all(m.spacecraft == sc for m in msgs)


# --- hostile / odd input -------------------------------------------------------------------------


def test_invalid_payloads_are_stored_and_counted(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    key = _key("sc", "3", "nav", "state")
    good = Heartbeat(sender="sc3", t_sim=4.0, node="sc3", apps=[], k=8)
    with McapRecorder(path) as rec:
        rec.record(key, "Heartbeat", good.model_dump_json().encode())
        rec.record(key, "Heartbeat", b"{not json")
        rec.record(key, "Heartbeat", b'{"sender": "sc3", "t_sim": NaN}')
        rec.record(key, "Heartbeat", b"[1, 2, 3]")
        rec.record(key, "Heartbeat", b'{"sender": "sc3", "t_sim": 9.0, "bogus": 1}')  # bad model
        rec.record(key, "NoSuchType\udcff", b'{"t_sim": 1.0}')
        rec.record(key, "Heartbeat", bytearray(good.model_dump_json().encode()), log_time_ns=123)
        with pytest.raises(ValueError):
            rec.record(key, "Heartbeat", b"{}", log_time_ns=-1)
        assert rec.invalid == 3
        assert rec.unknown_type == 1
        assert rec.recorded == 7

    run = load_run(path)
    records = run.records(key)
    assert len(records) == 7
    by_payload = {r.payload: r for r in records}
    # Non-JSON payloads keep the last sim time seen (4.0 s), stored as received.
    assert by_payload[b"{not json"].log_time_ns == 4_000_000_000
    assert by_payload[b"[1, 2, 3]"].log_time_ns == 4_000_000_000
    assert by_payload[b'{"sender": "sc3", "t_sim": 9.0, "bogus": 1}'].log_time_ns == 9_000_000_000
    with pytest.raises(ArchiveError):
        by_payload[b"{not json"].message()
    with pytest.raises(ArchiveError):
        by_payload[b'{"sender": "sc3", "t_sim": 9.0, "bogus": 1}'].message()
    unknown = [r for r in records if r.type_name.startswith("NoSuchType")]
    assert len(unknown) == 1 and unknown[0].log_time_ns == 1_000_000_000
    with pytest.raises(ArchiveError, match="unknown message type"):
        unknown[0].message()
    assert run.schemas[unknown[0].type_name].encoding == "jsonschema"
    assert min(r.log_time_ns for r in records) == 123  # explicit log time wins
    assert run.topics()[key][0] == "Heartbeat|" + unknown[0].type_name
    assert run.messages(key, Heartbeat, skip_invalid=True) == [good, good]
    with pytest.raises(ArchiveError):
        run.messages(key, Heartbeat)


def test_message_without_t_sim_uses_last_sim_time(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    with McapRecorder(path) as rec:
        rec.record(_key("sim", "a"), "Tick", b'{"sender": "sim"}')  # before any sim time: 0
        rec.record(_key("sim", "a"), "Tick", b'{"t_sim": 2.5}')
        rec.record(_key("sim", "a"), "Tick", b'{"t_sim": -1.0}')
        rec.record(_key("sim", "a"), "Tick", b'{"t_sim": true}')
    times = [r.log_time_ns for r in load_run(path).records()]
    assert times == [0, 2_500_000_000, 2_500_000_000, 2_500_000_000]


def test_not_an_mcap_file_raises_archive_error(tmp_path: Path) -> None:
    garbage = tmp_path / "garbage.mcap"
    garbage.write_bytes(b"this is not an mcap file at all, just some text\n" * 10)
    with pytest.raises(ArchiveError, match="not an MCAP file"):
        load_run(garbage)
    empty = tmp_path / "empty.mcap"
    empty.write_bytes(b"")
    with pytest.raises(ArchiveError):
        load_run(empty)


# --- truncated files (writer killed) -------------------------------------------------------------


def _relnav_payload(i: int) -> bytes:
    msg = RelNavMeasurement(
        sender="sim", seq=i, t_sim=i * 0.1, spacecraft=1, r_m=[float(i), 1.0, 2.0],
        v_mps=[0.0, 0.1, 0.2], sigma_r_m=1.0, sigma_v_mps=0.1,
    )
    return msg.model_dump_json().encode()


def test_unclosed_file_reads_back_complete_chunks(tmp_path: Path) -> None:
    """Snapshot of the file of a live recorder (no close): exactly the flushed chunks."""
    path = tmp_path / "live.mcap"
    key = _key("sim", "sensors", "sc1", "relnav")
    rec = McapRecorder(path, metadata={"run": {"seed": "3"}}, chunk_size=2048)
    for i in range(500):
        rec.record(key, "RelNavMeasurement", _relnav_payload(i))
    rec.flush()  # the first 500 are now in complete chunks
    for i in range(500, 505):  # far less than a chunk: stays in memory
        rec.record(key, "RelNavMeasurement", _relnav_payload(i))
    snapshot = tmp_path / "snapshot.mcap"
    snapshot.write_bytes(path.read_bytes())

    run = load_run(snapshot)
    assert run.truncated and run.stop_reason
    assert run.metadata == {"run": {"seed": "3"}}
    assert [m.seq for m in run.messages(key, RelNavMeasurement)] == list(range(500))
    assert run.topics() == {key: ("RelNavMeasurement", 500)}
    rec.close()
    assert len(load_run(path)) == 505


def test_file_cut_anywhere_reads_back_a_prefix_without_raising(tmp_path: Path) -> None:
    path = tmp_path / "full.mcap"
    key = _key("sim", "sensors", "sc1", "relnav")
    with McapRecorder(path, chunk_size=1024) as rec:
        for i in range(120):
            rec.record(key, "RelNavMeasurement", _relnav_payload(i))
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    previous = 0
    for size in [8, 9, 20, *range(60, len(data) - 1, 97), len(data) - 9, len(data) - 1]:
        cut.write_bytes(data[:size])
        run = load_run(cut)
        assert run.truncated
        seqs = [m.seq for m in run.messages(key, RelNavMeasurement)]
        assert seqs == list(range(len(seqs)))  # a prefix, each message intact
        assert len(seqs) >= previous  # never fewer with more bytes
        previous = len(seqs)
    assert previous == 120  # the data section was complete before the summary was cut


def test_a_cut_file_says_where_it_was_cut_and_where_its_data_ends(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """Cut at half its bytes (no footer, a chunk torn): read up to the last whole record, the
    byte and the sim time of its last message given, and logged."""
    path = tmp_path / "full.mcap"
    key = _key("sim", "sensors", "sc1", "relnav")
    with McapRecorder(path, chunk_size=1024) as rec:
        for i in range(200):
            rec.record(key, "RelNavMeasurement", _relnav_payload(i))
    assert load_run(path).end_s == pytest.approx(19.9)
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[:len(data) // 2])
    with caplog.at_level("WARNING", logger="insp.archive"):
        run = load_run(cut, stream={key: lambda _rec: None})  # streamed records count too
    (segment,) = run.segments
    assert segment.truncated and segment.size_bytes == len(data) // 2
    assert segment.cut_at_byte is not None and 8 < segment.cut_at_byte < len(data) // 2
    kept = load_run(cut).messages(key, RelNavMeasurement)
    assert 0 < len(kept) < 200 and run.end_s == pytest.approx(kept[-1].t_sim)
    assert f"read up to byte {segment.cut_at_byte} of {len(data) // 2}" in caplog.text
    assert f"ends at t = {kept[-1].t_sim:.1f} s" in caplog.text
    assert load_run(path).segments[0].cut_at_byte is None


def test_damaged_chunk_stops_reading_at_the_previous_chunk(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    key = _key("sim", "sensors", "sc1", "relnav")
    with McapRecorder(path, chunk_size=1024) as rec:
        for i in range(100):
            rec.record(key, "RelNavMeasurement", _relnav_payload(i))
    data = bytearray(path.read_bytes())
    chunks = _record_offsets(bytes(data), opcode=0x06)
    start, length = chunks[len(chunks) // 2]
    data[start + length // 2] ^= 0xFF  # a byte inside the middle chunk
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(bytes(data))
    run = load_run(damaged)
    assert run.truncated and "damaged" in (run.stop_reason or "")
    seqs = [m.seq for m in run.messages(key, RelNavMeasurement)]
    assert 0 < len(seqs) < 100 and seqs == list(range(len(seqs)))


def _record_offsets(data: bytes, opcode: int) -> list[tuple[int, int]]:
    """(content offset, content length) of each top-level MCAP record with ``opcode``: after
    the 8-byte magic, records are opcode (1 byte), length (uint64 LE), content."""
    found, offset = [], 8
    while offset + 9 <= len(data):
        op, length = data[offset], int.from_bytes(data[offset + 1:offset + 9], "little")
        if op == opcode:
            found.append((offset + 9, length))
        offset += 9 + length
    return found
