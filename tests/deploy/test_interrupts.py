"""SIGINT and SIGTERM while a run goes (deploy/interrupts.py): the run's reaction is called
once, with the first signal, whose number gives the exit status, on a thread of its own (never
inside the main thread's locks); the handlers before are back after."""

from __future__ import annotations

import os
import signal
import threading

from deploy.interrupts import Interrupts
from tests.conftest import settle


def test_the_first_signal_is_reacted_to_once_and_the_handlers_restored() -> None:
    before = signal.getsignal(signal.SIGTERM)
    seen: list[int] = []
    with Interrupts(seen.append) as caught:
        os.kill(os.getpid(), signal.SIGTERM)
        os.kill(os.getpid(), signal.SIGINT)
        settle(lambda: bool(seen))
    assert seen == [signal.SIGTERM] and caught.exit_status == 143
    assert signal.getsignal(signal.SIGTERM) is before
    assert Interrupts(seen.append).exit_status == 0


def test_a_signal_while_the_main_thread_holds_the_reactions_lock_does_not_hang() -> None:
    """The launcher's watch waits on the stop event the reaction sets; a signal landing while
    the main thread holds that event's lock (inside ``Event.wait``) once hung the launcher
    for ever.  Here the main thread holds a lock the reaction takes when the signal comes."""
    held = threading.Lock()
    took: list[bool] = []

    def react(_signum: int) -> None:
        took.append(held.acquire(timeout=5.0))  # in the main thread: never (it holds it)

    with Interrupts(react), held:
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(1000):  # bytecodes for the handler to run between, the lock held
            pass
    settle(lambda: bool(took), timeout_s=10.0)
    assert took == [True]
