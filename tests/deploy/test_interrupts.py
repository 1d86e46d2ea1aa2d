"""SIGINT and SIGTERM while a run goes (deploy/interrupts.py): the run's reaction is called
once, with the first signal, whose number gives the exit status; the handlers before are back
after."""

from __future__ import annotations

import os
import signal

from deploy.interrupts import Interrupts


def test_the_first_signal_is_reacted_to_once_and_the_handlers_restored() -> None:
    before = signal.getsignal(signal.SIGTERM)
    seen: list[int] = []
    with Interrupts(seen.append) as caught:
        os.kill(os.getpid(), signal.SIGTERM)
        os.kill(os.getpid(), signal.SIGINT)
    assert seen == [signal.SIGTERM] and caught.exit_status == 143
    assert signal.getsignal(signal.SIGTERM) is before
    assert Interrupts(seen.append).exit_status == 0
