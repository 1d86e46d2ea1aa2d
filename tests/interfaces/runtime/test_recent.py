"""What a node keeps of its last ticks for a resend request (``interfaces.runtime.recent``);
the request itself is tested on both transports in test_bus.py."""

from __future__ import annotations

import json
import pickle

import pytest

from interfaces.runtime.recent import RecentSent, archived_key, depth_for, parse_reply
from interfaces.runtime.transport import Sample


def test_the_last_ticks_are_kept_oldest_first() -> None:
    recent = RecentSent(depth=2)
    for k in range(4):
        recent.add(Sample(f"k/{k}", "T", payload=f'{{"k": {k}}}'.encode()))
        recent.next_tick()
    recent.add(Sample("k/4", "T", payload=b'{"k": 4}'))  # the current tick
    got = parse_reply(recent.reply())
    assert [s.key for s in got] == ["k/2", "k/3", "k/4"]
    assert json.loads(got[0].payload) == {"k": 2}
    assert depth_for(10) > 10


def test_what_was_kept_comes_back_with_the_node_from_its_store() -> None:
    """Restored from the node's critical-data store, the last ticks are sent again as they
    were kept, and the depth stays the one the node was built with."""
    recent = RecentSent(depth=2)
    for k in range(3):
        recent.add(Sample(f"k/{k}", "T", payload=f'{{"k": {k}}}'.encode()))
        recent.next_tick()
    again = RecentSent(depth=2)
    again.restore(pickle.loads(pickle.dumps(recent.checkpoint())))
    assert again.reply() == recent.reply()
    again.next_tick()
    assert [s.key for s in parse_reply(again.reply())] == ["k/2"]


@pytest.mark.parametrize("reply", [b"{}", b'[["a", "b"]]', b'[[1, "b", "c"]]', b"not json",
                                   b"[" + b" " * (9 << 20) + b"]"])
def test_a_malformed_reply_is_refused(reply: bytes) -> None:
    with pytest.raises(ValueError):
        parse_reply(reply)


def _tick(recent: RecentSent, t_s: float, n: int = 1, size: int = 0) -> None:
    """One tick at sim time ``t_s`` (s) in which ``n`` samples of about ``size`` bytes were
    sent, then ended."""
    for i in range(n):
        pad = "x" * size
        recent.add(Sample(f"k/{t_s}/{i}", "T", payload=f'{{"t_sim": {t_s}, "pad": "{pad}"}}'
                          .encode()))
    recent.next_tick()


def _kept_times(recent: RecentSent) -> list[float]:
    return sorted({json.loads(s.payload)["t_sim"] for s in parse_reply(recent.reply())})


def _told(recent: RecentSent, t_s: float) -> None:
    """The recorder says it archived every tick up to ``t_s`` (s)."""
    recent.archived(archived_key("m", "sc1", round(t_s * 1e9)))


def test_with_a_recorder_what_it_has_not_archived_is_kept_beyond_the_last_ticks() -> None:
    recent = RecentSent(depth=2)
    recent.keep_until_archived()
    for k in range(10):
        _tick(recent, float(k))
    assert _kept_times(recent) == [float(k) for k in range(10)]  # nothing archived: all kept
    _told(recent, 5.0)  # ticks 0..4 archived; a tick goes once the two after it are too
    _tick(recent, 10.0)
    assert _kept_times(recent) == [float(k) for k in range(3, 11)]
    _told(recent, 100.0)  # all archived: the last ``depth`` ticks only, as without a recorder
    _tick(recent, 11.0)
    assert _kept_times(recent) == [10.0, 11.0]
    assert recent.forgotten == 0


def test_without_a_recorder_only_the_last_ticks_are_kept() -> None:
    recent = RecentSent(depth=2)
    for k in range(10):
        _tick(recent, float(k))
    assert _kept_times(recent) == [8.0, 9.0]


def test_what_is_kept_for_the_recorder_is_bounded_and_what_goes_is_counted() -> None:
    """Past ``max_bytes`` the oldest ticks go though not archived, counted, and the reply
    stays within what a recorder takes."""
    recent = RecentSent(depth=2, max_bytes=10_000)
    recent.keep_until_archived()
    for k in range(40):
        _tick(recent, float(k), n=2, size=900)  # about 2 kB a tick
    kept = _kept_times(recent)
    assert kept == [float(k) for k in range(40 - len(kept), 40)] and 2 < len(kept) < 8
    assert recent.forgotten == 2 * (40 - len(kept))
    assert len(recent.reply()) < 2 * 10_000


@pytest.mark.parametrize("last", ["", "x", "-5", "1e9", "9" * 25])
def test_a_malformed_archived_notice_changes_nothing(last: str) -> None:
    recent = RecentSent(depth=1)
    recent.keep_until_archived()
    for k in range(5):
        _tick(recent, float(k))
    recent.archived(f"insp/m/sc/1/bus/archived/{last}")
    _tick(recent, 5.0)
    assert _kept_times(recent) == [float(k) for k in range(6)]


def test_kept_until_archived_across_a_restore() -> None:
    """A node restored from its store keeps what it kept, until the recorder archives it."""
    recent = RecentSent(depth=1)
    recent.keep_until_archived()
    for k in range(6):
        _tick(recent, float(k))
    again = RecentSent(depth=1)
    again.keep_until_archived()
    again.restore(pickle.loads(pickle.dumps(recent.checkpoint())))
    _tick(again, 6.0)
    assert _kept_times(again) == [float(k) for k in range(7)]
    _told(again, 6.0)
    _tick(again, 7.0)
    assert _kept_times(again) == [4.0, 5.0, 6.0, 7.0]


def test_at_depth_zero_nothing_is_kept_unless_for_a_recorder() -> None:
    """One process (``deploy.inproc``): nothing can ask for a resend, so nothing is kept; a
    recorder that has not archived still is (``keep_until_archived``)."""
    recent = RecentSent(depth=0)
    for k in range(3):
        recent.add(Sample(f"k/{k}", "T", payload=b'{"t_sim": 1.0}'))
        recent.next_tick()
    assert recent.last_tick() == [] and json.loads(recent.reply()) == []
    recent.keep_until_archived()
    recent.add(Sample("k/9", "T", payload=b'{"t_sim": 1.0}'))
    recent.next_tick()
    assert [s.key for s in recent.last_tick()] == ["k/9"]
