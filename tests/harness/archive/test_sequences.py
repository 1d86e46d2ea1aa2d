"""The sequence accounting of a run's archive (harness/archive/sequences.py), message by message;
on real archives in segments: tests/ground/archive/test_segments.py."""

from __future__ import annotations

from harness.archive.sequences import SequenceLedger, by_topic, topic_name
from interfaces.runtime.admission import MAX_FIRST_SEQ, MAX_SEQ_JUMP

K, L = "insp/m/sc/1/nav/estimate", "insp/m/sim/clock/tick"
S = 1_000_000_000  # ns per s


def _admit(ledger: SequenceLedger, key: str, seqs: list[int], t0_s: float = 0.0) -> list[bool]:
    """Admit ``seqs`` of ``key`` at 1 s apart from ``t0_s``."""
    return [ledger.admit(key, seq, round((t0_s + i) * S)) for i, seq in enumerate(seqs)]


def test_consecutive_numbers_lose_nothing() -> None:
    ledger = SequenceLedger()
    ledger.begin_segment(more_follow=False)
    assert all(_admit(ledger, K, [1, 2, 3]) + _admit(ledger, L, [1, 2]))
    assert ledger.lost == {} and ledger.duplicates == 0


def test_a_jump_loses_the_numbers_between_and_a_late_first_number_those_before() -> None:
    ledger = SequenceLedger()
    ledger.begin_segment(more_follow=False)
    _admit(ledger, K, [1, 2, 6, 7])
    _admit(ledger, L, [4, 5])
    assert ledger.lost == {K: 3, L: 3}


def test_a_number_back_to_one_is_a_new_incarnation_and_back_above_one_lost_its_start() -> None:
    ledger = SequenceLedger()
    ledger.begin_segment(more_follow=False)
    _admit(ledger, K, [1, 2, 3, 1, 2, 4, 2])
    assert ledger.lost == {K: 2}  # 3 of the second incarnation, 1 of the third


def test_no_number_and_numbers_the_bus_would_refuse_are_not_counted() -> None:
    """A forger with a node's credentials jumping its key's count (the Bus refuses the jump,
    the recorder keeps it as evidence) makes no loss, and the key's count goes on."""
    ledger = SequenceLedger()
    ledger.begin_segment(more_follow=False)
    assert all(_admit(ledger, K, [0, 0, 1, 0, 2, 2 + MAX_SEQ_JUMP + 1, 10**6, 3, 4]))
    assert all(_admit(ledger, L, [MAX_FIRST_SEQ + 1, 1, 1 + MAX_SEQ_JUMP]))
    assert ledger.lost == {L: MAX_SEQ_JUMP - 1}  # a jump the Bus admits is a loss


def test_a_later_segment_repeating_a_message_has_it_dropped_once() -> None:
    """Same key, number and sim time as a message of an earlier segment: a duplicate; the same
    number at another time (a new incarnation) or of another key is not."""
    ledger = SequenceLedger()
    ledger.begin_segment(more_follow=True)
    _admit(ledger, K, [1, 2, 3, 4])  # at 0..3 s
    _admit(ledger, L, [1])
    ledger.begin_segment(more_follow=False)
    assert _admit(ledger, K, [3, 4, 5], t0_s=2.0) == [False, False, True]
    assert _admit(ledger, K, [1], t0_s=10.0) == [True]  # restarted cold, later
    assert _admit(ledger, L, [2]) == [True]
    assert ledger.duplicates == 2 and ledger.lost == {}


def test_one_segment_repeats_nothing() -> None:
    """Within a segment a number at or below the last is a new incarnation, never a
    duplicate (the recorder archives each message it receives once)."""
    ledger = SequenceLedger()
    ledger.begin_segment(more_follow=False)
    assert all(_admit(ledger, K, [1, 2, 2]))
    assert ledger.duplicates == 0 and ledger.lost == {K: 1}


def test_lost_messages_add_up_by_catalogue_topic() -> None:
    lost = {K: 2, "insp/m/sc/2/nav/estimate": 3, L: 1, "insp/m/sc/1/exec/heartbeat": 0,
            "insp/m/sc/1/nope/thing": 4}
    assert topic_name("insp/m/sim/sensors/sc3/camera") == "sensors/camera"
    assert by_topic(lost) == {"clock/tick": 1, "insp/m/sc/1/nope/thing": 4, "nav/estimate": 5}


def test_a_message_recorded_twice_is_kept_once_and_one_recorded_late_is_not_lost() -> None:
    """After the network came back the recorder records live messages, then what the nodes
    kept of their last ticks: some it had (duplicates), some it missed (late, not lost)."""
    ledger = SequenceLedger()
    ledger.begin_segment(more_follow=False)
    times = {n: round(n * 0.1 * S) for n in range(1, 20)}
    live = [ledger.admit(K, n, times[n]) for n in (1, 2, 3, 4, 8, 9)]  # 5-7 sent while down
    assert all(live) and ledger.lost == {K: 3}
    kept = [ledger.admit(K, n, times[n]) for n in (3, 4, 5, 6, 7)]  # the nodes' last ticks
    assert kept == [False, False, True, True, True]
    assert ledger.lost == {} and ledger.duplicates == 2
    assert ledger.admit(K, 10, times[10]) and ledger.lost == {}
