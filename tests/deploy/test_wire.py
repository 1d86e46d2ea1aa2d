"""The rehearsal's switch (deploy/rehearsal/wire.py): what a host's link does to the frames the
host sends -- delayed in order, lost at the declared rate, nothing through a cut -- and MAC
learning.  The switch's logic is driven here with frames and times; its TAP links, in real
namespaces, in tests/missions/test_hosts_rehearsal.py."""

from __future__ import annotations

import json

import numpy as np
import pytest

from deploy.rehearsal.wire import BROADCAST, Link, Port, Switch, _change

MAC = {name: bytes([0x02, 0, 0, 0, 0, i]) for i, name in enumerate(("a", "b", "c"), 1)}
EVERYONE = b"\xff" * 6


def _frame(src: str, dst: bytes, body: bytes = b"x") -> bytes:
    return dst + MAC[src] + b"\x08\x00" + body


def _switch(links: dict[str, Link], seed: int = 1) -> Switch:
    sw = Switch(np.random.default_rng(seed))
    for i, (name, link) in enumerate(links.items()):
        sw.ports[name] = Port(name, fd=100 + i, link=link)
    return sw


def test_a_frame_leaves_after_its_senders_delay_and_floods_until_learned() -> None:
    sw = _switch({"a": Link(delay_s=0.005), "b": Link(delay_s=0.020), "c": Link()})
    sw.receive("a", _frame("a", EVERYONE), now=1.0)  # ARP-like: to everyone
    assert sw.next_due() == pytest.approx(1.005)
    assert sw.deliver(1.004) == []
    assert sorted(n for n, _ in sw.deliver(1.005)) == ["b", "c"]
    sw.receive("b", _frame("b", MAC["a"], b"reply"), now=1.010)  # a is known: to a only
    assert sw.deliver(1.029) == []
    assert sw.deliver(1.030) == [("a", _frame("b", MAC["a"], b"reply"))]
    assert EVERYONE[0] & BROADCAST


def test_jitter_never_reorders_a_links_frames() -> None:
    sw = _switch({"a": Link(delay_s=0.010, jitter_s=0.008), "b": Link()})
    sw.receive("b", _frame("b", EVERYONE), now=0.0)
    sw.deliver(1.0)
    sent = [_frame("a", MAC["b"], bytes([i])) for i in range(200)]
    for i, f in enumerate(sent):
        sw.receive("a", f, now=i * 1e-4)
    out = sw.deliver(10.0)
    assert [f for _, f in out] == sent
    # the delays drawn spread over the jitter's range (not all the nominal 10 ms)
    assert sw.ports["a"].last_out > 199e-4 + 0.002


def test_loss_drops_the_declared_fraction() -> None:
    sw = _switch({"a": Link(loss=0.02), "b": Link()})
    for i in range(20_000):
        sw.receive("a", _frame("a", EVERYONE), now=float(i))
    lost = sw.ports["a"].counts["lost"]
    assert 0.017 < lost / 20_000 < 0.023  # 2 %: about 7 sigma apart
    assert len(sw.deliver(1e9)) == 20_000 - lost


def test_a_cut_link_passes_nothing_either_way() -> None:
    sw = _switch({"a": Link(), "b": Link()})
    sw.receive("a", _frame("a", EVERYONE), now=0.0)
    sw.receive("b", _frame("b", EVERYONE), now=0.0)
    assert len(sw.deliver(0.0)) == 2
    sw.ports["b"].link = sw.ports["b"].link.changed({"up": False})
    sw.receive("b", _frame("b", MAC["a"]), now=1.0)
    sw.receive("a", _frame("a", MAC["b"]), now=1.0)
    assert sw.deliver(2.0) == []
    assert sw.ports["b"].counts["cut"] == 1 and sw.ports["a"].counts["cut"] == 1
    sw.ports["b"].link = sw.ports["b"].link.changed({"up": True})
    sw.receive("a", _frame("a", MAC["b"]), now=3.0)
    assert [n for n, _ in sw.deliver(3.0)] == ["b"]


def test_link_changes_come_as_lines_and_bad_ones_are_answered() -> None:
    sw = _switch({"a": Link.from_spec({"delay_ms": 5.0, "loss_pct": 1.0}), "b": Link()})
    assert sw.ports["a"].link == Link(0.005, 0.0, 0.01, True)
    line = json.dumps({"port": "a", "delay_ms": 20.0, "up": False}).encode()
    assert _change(sw, line) == "ok"
    assert sw.ports["a"].link == Link(0.020, 0.0, 0.01, False)
    assert _change(sw, b'{"port": "z"}').startswith("error: KeyError")
    assert _change(sw, b"not json").startswith("error:")
    assert sw.ports["a"].link == Link(0.020, 0.0, 0.01, False)
