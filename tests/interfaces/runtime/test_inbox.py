"""The Bus's inbox on its own: when a deferred message is due, the delivery order, the barrier."""

from __future__ import annotations

import threading

from interfaces.contracts import topics
from interfaces.contracts.messages import Heartbeat, Message, stamp
from interfaces.runtime.inbox import Envelope, Inbox

M = "ib"


def _msg(sender: str, t: float, seq: int) -> Message:
    msg = Heartbeat(sender=sender, t_sim=t, node=sender, apps=[], k=0)
    stamp(msg, sender, seq, 0.0)
    return msg


def _env(src: str, t: float, seq: int = 1, local: bool = False) -> Envelope:
    return Envelope(_msg(src, t, seq), topics.key(M, src, "exec", "heartbeat"), src, local, [])


def test_sim_and_own_messages_are_due_at_their_time_others_one_tick_later() -> None:
    inbox = Inbox("sc1")
    inbox.pending += [_env("sim", 2.0), _env("sc1", 2.0, local=True), _env("sc2", 2.0)]
    assert [e.src for e in inbox.take_due(2.0, False, 0.0)] == ["sc1", "sim"]
    assert [e.src for e in inbox.take_due(2.0, True, 0.0)] == ["sc2"]  # sent at t_now
    assert inbox.pending == []


def test_a_link_delay_holds_cross_link_messages_only() -> None:
    inbox = Inbox("sc1")
    inbox.pending += [_env("sc2", 1.0), _env("ground", 1.0), _env("sim", 1.0)]
    assert [e.src for e in inbox.take_due(1.5, False, 1.0)] == ["sim"]
    assert [e.src for e in inbox.take_due(2.0, False, 1.0)] == ["ground", "sc2"]
    assert inbox.crosses_link("sc2") and not inbox.crosses_link("sim")


def test_due_messages_come_in_send_time_key_sequence_order() -> None:
    inbox = Inbox("ground")
    inbox.pending += [_env("sc2", 1.0, 2), _env("sc1", 1.0), _env("sc2", 0.5, 3), _env("sc2", 1.0)]
    due = inbox.take_due(5.0, False, 0.0)
    assert [(e.msg.t_sim, e.src, e.msg.seq) for e in due] == [
        (0.5, "sc2", 3), (1.0, "sc1", 1), (1.0, "sc2", 1), (1.0, "sc2", 2)]


def test_the_barrier_waits_for_announced_numbers_and_times_out() -> None:
    inbox, seen = Inbox("sc1"), {"a": 1}
    assert inbox.wait({"a": 1}, seen, 0.0) == []
    assert inbox.wait({"a": 2, "b": 1}, seen, 0.01) == ["a", "b"]

    def arrive() -> None:
        with inbox.lock:
            seen["a"] = 2
            inbox.wake()

    timer = threading.Timer(0.05, arrive)
    timer.start()
    assert inbox.wait({"a": 2}, seen, 5.0) == []
    timer.join()
    assert inbox.waiting == 0
