"""Signals that stop a process: the handler that sets its stop event.

A Python signal handler runs in the main thread between two of its bytecodes, maybe while
that thread is inside ``stop.wait`` with the event's lock held; setting the event there would
wait for ever (a node, the recorder or the router hanging on Ctrl-C or SIGTERM until killed,
its files left unclosed).  The handler therefore sets it from a thread of its own.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from types import FrameType


def signal_setter(stop: threading.Event) -> Callable[[int, FrameType | None], None]:
    """A signal handler that sets ``stop`` (see the module docstring)."""
    def handler(_signum: int, _frame: FrameType | None) -> None:
        threading.Thread(target=stop.set, name="signal", daemon=True).start()

    return handler
