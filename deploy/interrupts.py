"""SIGINT (Ctrl-C) and SIGTERM (``kill``, a job scheduler) while a run goes (issue 40): the run
ends as a run, never with a traceback.  :class:`Interrupts` installs a handler for both in the
main thread for the span of a ``with`` block, notes which signal came, and calls the run's own
reaction: the run's stop event is set, and the in-process sim stops at the next tick boundary,
the multi-process launcher's watch over its processes at its next look (nothing is raised into
the code that runs: a signal that comes while the run is being written changes nothing).  The
exit status of an interrupted run is 128 + the signal's number (130, 143).  Before this, a
SIGINT to the launcher after its sim had finished raised into its shutdown: a traceback and
no summary.json."""

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
        """Note the signal and react on a thread of its own: a handler runs in the main thread
        between two of its bytecodes, maybe while it holds a lock the reaction needs (the
        stop event's, which the launcher's watch waits on; the logging module's), and a
        reaction taking that lock there would wait for ever."""
        first = self.signum is None
        self.signum = self.signum or signum
        if first:
            threading.Thread(target=self.react, args=(signum,), name="interrupt",
                             daemon=True).start()

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

