"""SIGINT (Ctrl-C) and SIGTERM (``kill``, a job scheduler) while a run goes (issue 40): the run
ends as a run, never with a traceback.  :class:`Interrupts` installs a handler for both in the
main thread for the span of a ``with`` block, notes which signal came, and calls the run's own
reaction: the in-process run sets its sim's stop event (it stops at the next tick boundary),
the multi-process launcher raises ``KeyboardInterrupt`` into its supervision loop.  The exit
status of an interrupted run is 128 + the signal's number (130, 143)."""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from types import FrameType
from typing import Any

SIGNALS = (signal.SIGINT, signal.SIGTERM)


@dataclass
class Interrupts:
    """The handlers while in the ``with`` block (none outside the main thread, where Python
    cannot install them); ``signum`` is the first signal that came (None: none)."""

    react: Callable[[int], None]
    signum: int | None = None
    _previous: dict[int, Any] = field(default_factory=dict)

    def _handle(self, signum: int, _frame: FrameType | None) -> None:
        first = self.signum is None
        self.signum = self.signum or signum
        if first:
            self.react(signum)

    def __enter__(self) -> Interrupts:
        if threading.current_thread() is threading.main_thread():
            self._previous = {s: signal.signal(s, self._handle) for s in SIGNALS}
        return self

    def __exit__(self, *exc: object) -> None:
        for s, previous in self._previous.items():
            signal.signal(s, previous)

    @property
    def exit_status(self) -> int:
        """128 + the signal's number (0 when none came)."""
        return 128 + self.signum if self.signum is not None else 0


def raise_keyboard_interrupt(signum: int) -> None:
    """The launcher's reaction: its supervision loop stops the children and writes the run."""
    raise KeyboardInterrupt(f"signal {signum}")
