"""The handler that stops a node, the recorder or the router (interfaces/runtime/signals.py):
it sets the stop event even when the signal lands while the main thread holds the event's lock
(inside ``stop.wait``), where setting it in the handler would wait for ever."""

from __future__ import annotations

import os
import signal

from interfaces.runtime.signals import signal_setter
from tests.conftest import settle


def test_a_signal_inside_the_events_own_lock_still_stops() -> None:
    import threading

    stop = threading.Event()
    before = signal.signal(signal.SIGUSR1, signal_setter(stop))
    try:
        with stop._cond:  # as the main thread holds it inside stop.wait
            os.kill(os.getpid(), signal.SIGUSR1)
            for _ in range(1000):  # bytecodes for the handler to run between
                pass
            assert not stop.is_set()  # not yet: the lock is held here
        settle(stop.is_set, timeout_s=5.0)
    finally:
        signal.signal(signal.SIGUSR1, before)
