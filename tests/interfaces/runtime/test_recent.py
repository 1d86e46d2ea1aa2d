"""What a node keeps of its last ticks for a resend request (``interfaces.runtime.recent``);
the request itself is tested on both transports in test_bus.py."""

from __future__ import annotations

import json
import pickle

import pytest

from interfaces.runtime.recent import RecentSent, depth_for, parse_reply
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
