"""A run's archive in segments (ground/archive/segments.py) read back as one run
(harness.archive.reader.load_run): the segments listed and claimed, their records merged, a
message two segments hold kept once, and the messages lost between counted from the sequence
numbers (harness/archive/sequences.py).

Files are real MCAP files written by the project's McapRecorder; a recorder killed mid-run is
the snapshot of a live recorder's file (its flushed chunks, not the messages after them).  The
recorder process restarted by the launcher: tests/missions/test_constellation.py.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import pytest

from ground.archive.metadata import run_metadata
from ground.archive.recorder import McapRecorder, prepare_raw
from ground.archive.segments import (
    SEGMENT_RECORD,
    claim_segment,
    remove_segments,
    run_archive,
    segment_path,
    segment_paths,
    with_segment,
)
from harness.archive.live import LiveArchive
from harness.archive.reader import ArchiveError, Record, load_run
from harness.archive.run_scenario import archived_scenario
from interfaces.contracts.messages import Heartbeat, StateEstimate
from tests.conftest import small_scenario

M = "seg"
NAV = f"insp/{M}/sc/1/nav/estimate"
BEAT = f"insp/{M}/sc/2/exec/heartbeat"
META = {"run": {"scenario": M, "seed": "7"}}


def _nav(seq: int, t: float | None = None) -> bytes:
    """A nav estimate numbered ``seq`` at sim time ``t`` (default: seq / 10 s)."""
    eye = [[1.0 if i == j else 0.0 for j in range(6)] for i in range(6)]
    msg = StateEstimate(sender="sc1", seq=seq, t_sim=seq / 10 if t is None else t, spacecraft=1,
                        x=[float(seq)] * 6, P=eye)
    return msg.model_dump_json().encode()


def _beat(seq: int, t: float | None = None) -> bytes:
    msg = Heartbeat(sender="sc2", seq=seq, t_sim=seq / 10 if t is None else t, node="sc2",
                    apps=["nav"], k=seq)
    return msg.model_dump_json().encode()


def _write(path: Path, nav: Sequence[int], beat: Sequence[int] = (), index: int = 0) -> Path:
    """A complete segment holding the nav estimates and heartbeats numbered so."""
    with McapRecorder(path, with_segment(META, path, index)) as rec:
        for seq in nav:
            rec.record(NAV, "StateEstimate", _nav(seq))
        for seq in beat:
            rec.record(BEAT, "Heartbeat", _beat(seq))
    return path


def _killed(path: Path, flushed: list[int], in_flight: list[int],
            metadata: dict[str, dict[str, str]] = META) -> Path:
    """``path`` as a recorder killed after flushing ``flushed`` leaves it: ``in_flight``, not
    yet in a complete chunk, is not in the file."""
    live = path.with_name("live.mcap")
    rec = McapRecorder(live, metadata)
    for seq in flushed:
        rec.record(NAV, "StateEstimate", _nav(seq))
    rec.flush()
    for seq in in_flight:
        rec.record(NAV, "StateEstimate", _nav(seq))
    path.write_bytes(live.read_bytes())
    rec.close()
    live.unlink()
    return path


def _seqs(records: list[Record]) -> list[int]:
    return [StateEstimate.model_validate_json(r.payload).seq for r in records]


# --- naming, listing, claiming ----------------------------------------------------------------


def test_segments_are_named_after_the_first(tmp_path: Path) -> None:
    first = run_archive(tmp_path)
    assert first == tmp_path / "run.mcap"
    assert [segment_path(first, i).name for i in range(3)] == ["run.mcap", "run-1.mcap",
                                                               "run-2.mcap"]
    with pytest.raises(ValueError):
        segment_path(first, -1)


def test_listing_follows_the_segments_up_to_the_first_missing(tmp_path: Path) -> None:
    first = tmp_path / "run.mcap"
    assert segment_paths(first) == [first]  # missing: its reader says so
    for name in ("run.mcap", "run-1.mcap", "run-2.mcap", "run-4.mcap", "other-1.mcap"):
        (tmp_path / name).write_bytes(b"")
    assert [p.name for p in segment_paths(first)] == ["run.mcap", "run-1.mcap", "run-2.mcap"]


def test_claiming_takes_the_next_free_segment_and_never_an_existing_one(tmp_path: Path) -> None:
    first = tmp_path / "run.mcap"
    assert claim_segment(first) == (first, 0)
    first.write_bytes(b"the first recorder's")
    assert claim_segment(first) == (tmp_path / "run-1.mcap", 1)
    assert claim_segment(first) == (tmp_path / "run-2.mcap", 2)
    assert first.read_bytes() == b"the first recorder's"
    assert (tmp_path / "run-2.mcap").read_bytes() == b""


def test_removing_a_runs_segments_leaves_other_files(tmp_path: Path) -> None:
    for name in ("run.mcap", "run-1.mcap", "run-12.mcap", "run-x.mcap", "run-01.mcap",
                 "other.mcap", "summary.json"):
        (tmp_path / name).write_bytes(b"")
    removed = remove_segments(tmp_path / "run.mcap")
    assert sorted(p.name for p in removed) == ["run-1.mcap", "run-12.mcap", "run.mcap"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["other.mcap", "run-01.mcap",
                                                         "run-x.mcap", "summary.json"]
    assert remove_segments(tmp_path / "run.mcap") == []


def test_a_later_segment_carries_the_run_metadata_and_its_index(tmp_path: Path) -> None:
    first = tmp_path / "run.mcap"
    assert with_segment(META, first, 0) == META  # one segment: as it always was
    assert with_segment(META, first, 2) == {**META, SEGMENT_RECORD: {"index": "2",
                                                                     "first": "run.mcap"}}


# --- read as one run --------------------------------------------------------------------------


def test_segments_read_as_one_run_with_the_messages_lost_between(tmp_path: Path) -> None:
    """A recorder killed with 3 messages in flight, restarted while 2 more went by: one run,
    in order, its first segment's metadata, 5 messages of the key lost and none of the other."""
    first = _killed(tmp_path / "run.mcap", flushed=list(range(1, 11)), in_flight=[11, 12, 13])
    _write(tmp_path / "run-1.mcap", nav=list(range(16, 21)), index=1)
    _write(tmp_path / "run-2.mcap", nav=[], beat=[1, 2, 3], index=2)
    run = load_run(first)
    assert _seqs(run.records(NAV)) == [*range(1, 11), *range(16, 21)]
    assert run.topics() == {BEAT: ("Heartbeat", 3), NAV: ("StateEstimate", 15)}
    assert [s.path.name for s in run.segments] == ["run.mcap", "run-1.mcap", "run-2.mcap"]
    assert [s.truncated for s in run.segments] == [True, False, False]
    assert run.truncated and run.stop_reason.startswith("run.mcap: ")
    assert run.metadata == META  # the first segment's; a later one's index is its own
    assert run.lost == {NAV: 5} and run.duplicates == 0
    assert run.path == first


def test_a_message_two_segments_hold_is_kept_once(tmp_path: Path) -> None:
    first = _write(tmp_path / "run.mcap", nav=[1, 2, 3, 4])
    _write(tmp_path / "run-1.mcap", nav=[3, 4, 5, 6], index=1)
    run = load_run(first)
    assert _seqs(run.records(NAV)) == [1, 2, 3, 4, 5, 6]
    assert run.duplicates == 2 and run.lost == {}
    streamed: list[Record] = []
    assert len(load_run(first, stream={NAV: streamed.append})) == 6
    assert _seqs(streamed) == [1, 2, 3, 4, 5, 6]  # a sink too gets each message once


def test_a_publisher_restarted_cold_is_a_new_incarnation_not_a_gap(tmp_path: Path) -> None:
    """Its numbers start again at 1, at later sim times: nothing lost, nothing a duplicate;
    a new incarnation first seen at 3 lost its first 2."""
    first = tmp_path / "run.mcap"
    with McapRecorder(first, META) as rec:
        for seq, t in ((1, 0.1), (2, 0.2), (3, 0.3), (1, 5.0), (2, 5.1)):
            rec.record(NAV, "StateEstimate", _nav(seq, t))
    with McapRecorder(tmp_path / "run-1.mcap", with_segment(META, first, 1)) as rec:
        for seq, t in ((3, 5.2), (1, 9.0), (3, 9.2), (4, 9.3)):  # restarted twice more
            rec.record(NAV, "StateEstimate", _nav(seq, t))
    run = load_run(first)
    assert len(run) == 9 and run.duplicates == 0
    assert run.lost == {NAV: 1}  # the last incarnation's 2 (at 9.1 s)


def test_gaps_are_counted_in_one_segment_too(tmp_path: Path) -> None:
    """A key first seen at 3 lost its first 2; a jump of 4 lost 3; no number (0) is not
    counted."""
    first = _write(tmp_path / "run.mcap", nav=[3, 4, 8], beat=[1, 2])
    with McapRecorder(tmp_path / "raw.mcap") as rec:
        rec.record(NAV, "StateEstimate", b'{"t_sim": 1.0}')
    assert load_run(first).lost == {NAV: 5}
    assert load_run(tmp_path / "raw.mcap").lost == {}


def test_a_later_segment_that_is_not_mcap_is_reported_not_raised(tmp_path: Path) -> None:
    """A recorder that died after claiming its segment, before writing its header."""
    first = _write(tmp_path / "run.mcap", nav=[1, 2])
    (tmp_path / "run-1.mcap").write_bytes(b"")
    run = load_run(first)
    assert len(run) == 2 and run.truncated
    assert [s.truncated for s in run.segments] == [False, True]
    assert "run-1.mcap" in run.stop_reason and "not an MCAP file" in run.stop_reason
    first.write_bytes(b"garbage!")
    with pytest.raises(ArchiveError):  # the first segment still must be an archive
        load_run(first)


def test_a_one_process_run_counts_as_its_file_read_back(tmp_path: Path) -> None:
    """LiveArchive (a one-process run's digest) and the file give the same accounting."""
    path = tmp_path / "run.mcap"
    live = LiveArchive(path, META, stream={})
    with McapRecorder(path, META) as rec:
        for i, seq in enumerate((1, 2, 5, 6, 1)):
            pending = prepare_raw(NAV, "StateEstimate", _nav(seq, float(i)))
            rec.take(pending)
            live.take(pending)
    assert live.finish().lost == load_run(path).lost == {NAV: 2}


def test_the_scenario_of_a_killed_first_segment_is_read_from_its_head(tmp_path: Path) -> None:
    """A killed recorder's file has no summary section: its metadata records, written first,
    still give the run's scenario (the campaign replay reads it so)."""
    scenario = small_scenario(M)
    first = _killed(tmp_path / "run.mcap", [1, 2], [3], run_metadata(scenario, "zenoh", ""))
    assert archived_scenario(first) == scenario
    first.write_bytes(first.read_bytes()[:12])
    with pytest.raises(ArchiveError, match="metadata unreadable"):
        archived_scenario(first)
