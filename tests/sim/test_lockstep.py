"""The sim's lockstep bookkeeping on its own: answers of the current tick, lost and rejoining
participants, the waits."""

from __future__ import annotations

import logging
import threading
import time

import pytest

from interfaces.contracts import topics
from interfaces.contracts.messages import TickDone
from sim.lockstep import LinkAwait, Lockstep

M = "sl"


def _lockstep(now: list[float], last_tick: int = 9) -> Lockstep:
    return Lockstep(["sc1", "sc2"], M, last_tick, lambda: now[0], threading.Event(),
                    logging.getLogger("test.lockstep"), realtime=True)


def _done(sender: str, k: int, published: dict[str, int]) -> TickDone:
    return TickDone(sender=sender, t_sim=0.5 * k, k=k, published=published)


def test_answers_of_the_current_tick_are_merged_own_keys_only() -> None:
    ls = _lockstep([0.0])
    own1, own2 = topics.key(M, "sc1", "nav", "estimate"), topics.key(M, "sc2", "nav", "estimate")
    assert ls.open_tick(3) == []
    ls.on_done(_done("sc1", 3, {own1: 4, own2: 99}))
    ls.on_done(_done("sc2", 2, {own2: 7}))  # an old tick's answer: not counted
    assert ls.answers == {"sc1": {own1: 4}}
    ls.on_done(_done("sc2", 3, {own2: 8}))
    assert ls.collect_answers(3, deadline=0.0) == {own1: 4, own2: 8}
    assert ls.missed_answers == 0
    ls.open_tick(4)
    assert ls.collect_answers(4, deadline=0.0) == {} and ls.missed_answers == 1


def test_a_lost_participant_is_not_waited_for_and_is_named_until_it_answers() -> None:
    now = [1.0]
    ls = _lockstep(now)
    for node in ("sc1", "sc2"):
        ls.on_liveness(node, True)
    ls.wait_for_participants(0.0)
    ls.on_liveness("sc2", False)
    ls.open_tick(2)
    ls.on_done(_done("sc1", 2, {}))
    assert ls.collect_answers(2, deadline=float("inf")) == {}  # sc2 lost: not waited for
    now[0] = 4.0
    ls.on_liveness("sc2", True)
    assert ls.open_tick(8) == ["sc2"]
    ls.on_done(_done("sc2", 8, {}))
    assert ls.rejoining == set() and ls.open_tick(9) == []
    assert ls.events_now() == {"sc2": [("lost", 1.0), ("rejoined", 4.0)]}


def test_leaving_after_the_last_tick_is_no_loss() -> None:
    ls = _lockstep([0.0], last_tick=5)
    ls.on_liveness("sc1", True)
    with pytest.raises(TimeoutError, match="sc2"):
        ls.wait_for_participants(0.0)
    ls.open_tick(5)
    ls.on_liveness("sc1", False)
    ls.await_departure(timeout_s=0.0)
    assert ls.events == {}


def test_a_lost_participant_holds_the_tick_until_it_is_back_and_is_sent_it_again() -> None:
    ls = _lockstep([12.0])
    ls.hold_s = 5.0
    for node in ("sc1", "sc2"):
        ls.on_liveness(node, True)
    ls.open_tick(5)
    ls.on_done(_done("sc1", 5, {}))
    ls.on_liveness("sc2", False)  # its process died mid-tick: the launcher restarts it
    sent_again: list[list[str]] = []

    def resend(back: list[str]) -> None:  # the sim sends the tick again; sc2 runs it, answers
        sent_again.append(back)
        threading.Timer(0.05, ls.on_done, (_done("sc2", 5, {}),)).start()

    threading.Timer(0.2, ls.on_liveness, ("sc2", True)).start()
    t0 = time.monotonic()
    ls.collect_answers(5, deadline=time.monotonic() + 0.01, resend=resend,
                       answer_timeout_s=2.0)  # returns on sc2's answer, long before the bound
    assert sent_again == [["sc2"]] and set(ls.answers) == {"sc1", "sc2"}
    assert 0.2 <= ls.held_s <= time.monotonic() - t0 < 4.0 and ls.missed_answers == 0
    assert [w for w, _ in ls.events["sc2"]] == ["lost", "rejoined"]
    ls.hold_s = 0.3
    ls.open_tick(6)
    ls.on_liveness("sc1", False)  # never back: held for the bound, then the sim flies on
    t0 = time.monotonic()
    ls.collect_answers(6, deadline=time.monotonic(), resend=resend)
    assert 0.25 <= time.monotonic() - t0 < 1.0 and ls.late == {"sc2": 1}
    ls.open_tick(7)
    t0 = time.monotonic()
    ls.on_done(_done("sc2", 7, {}))
    ls.collect_answers(7, deadline=time.monotonic() + 5.0)  # past its bound: not held again
    assert time.monotonic() - t0 < 0.2 and ls.held_s == 0.0


def test_an_answer_to_the_open_tick_is_the_rejoin_even_before_the_token() -> None:
    """A restored node runs the open tick as it catches up, before it announces itself: its
    answer ends the hold, and the rejoin is dated at that tick, not at the token's later one."""
    now = [4.0]
    ls = _lockstep(now)
    ls.hold_s = 60.0
    for node in ("sc1", "sc2"):
        ls.on_liveness(node, True)
    ls.open_tick(8)
    ls.on_done(_done("sc1", 8, {}))
    ls.on_liveness("sc2", False)
    threading.Timer(0.1, ls.on_done, (_done("sc2", 8, {}),)).start()
    t0 = time.monotonic()
    ls.collect_answers(8, deadline=time.monotonic())
    assert time.monotonic() - t0 < 30.0 and set(ls.answers) == {"sc1", "sc2"}
    now[0] = 4.5
    assert ls.open_tick(9) == []  # answered: not named rejoining
    ls.on_liveness("sc2", True)  # its token, a tick later: no second event
    assert ls.events_now() == {"sc2": [("lost", 4.0), ("rejoined", 4.0)]}
    ls.on_done(_done("sc1", 9, {}))
    ls.on_done(_done("sc2", 9, {}))
    assert ls.collect_answers(9, deadline=time.monotonic()) == {} and ls.missed_answers == 0

def test_the_clock_holds_while_the_recorder_restarts() -> None:
    ls = _lockstep([3.0])
    assert ls.hold_for_services() == 0.0  # no restarts supervised
    ls.hold_s = 5.0
    ls.on_liveness(topics.RECORDER, True)
    assert ls.hold_for_services() == 0.0 and "recorder" not in ls.events
    ls.on_liveness(topics.RECORDER, False)
    threading.Timer(0.2, ls.on_liveness, (topics.RECORDER, True)).start()
    assert 0.15 <= ls.hold_for_services() < 4.0


def test_a_link_change_holds_the_clock_until_the_nodes_are_gone_or_back() -> None:
    """A rehearsal's cut (docs/hosts.md): the sim holds after the tick at the cut's time until
    the cut host's spacecraft are lost, and after the restore's until they are back."""
    now = [60.0]
    ls = _lockstep(now)
    for node in ("sc1", "sc2"):
        ls.on_liveness(node, True)
    ls.open_tick(1)
    threading.Timer(0.2, ls.on_liveness, ("sc2", False)).start()
    t0 = time.monotonic()
    assert ls.await_liveness(("sc2",), False, timeout_s=10.0) >= 0.15
    assert time.monotonic() - t0 < 5.0
    assert ls.events_now() == {"sc2": [("lost", 60.0)]}
    now[0] = 90.0
    threading.Timer(0.2, ls.on_liveness, ("sc2", True)).start()
    assert ls.await_liveness(("sc2",), True, timeout_s=10.0) >= 0.15
    assert ls.open_tick(2) == ["sc2"]  # named in the next tick's rejoin
    assert ls.events_now() == {"sc2": [("lost", 60.0), ("rejoined", 90.0)]}
    held = ls.await_liveness(("sc1",), False, timeout_s=0.3)  # never lost: flies on
    assert 0.3 <= held < 2.0


def test_link_awaits_are_read_from_the_command_line() -> None:
    cut = LinkAwait.parse("lost:sc1,sc2:600")
    assert cut == LinkAwait(False, ("sc1", "sc2"), 600.0) and str(cut) == "lost:sc1,sc2:600.0"
    assert LinkAwait.parse(str(LinkAwait(True, ("sc1",), 1234567.125))).t_s == 1234567.125
    assert LinkAwait.parse("back:sc3:630.5") == LinkAwait(True, ("sc3",), 630.5)
    for bad in ("cut:sc1:600", "lost::600", "lost:sc1", "lost:sc1:x"):
        with pytest.raises(ValueError):
            LinkAwait.parse(bad)
