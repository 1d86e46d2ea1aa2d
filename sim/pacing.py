"""The sim's pacing against the wall clock (``--realtime SPEED``; docs/architecture.md,
"Runtime model").

By default SPEED is a ceiling: tick k is sent no earlier than t_k / SPEED of wall time after the
start, and the sim still waits for every participant's answer, as in lockstep.  A host that
cannot hold SPEED runs slower, never differently: no node falls behind the sim, no message
arrives future-dated, no command is stale.  A tick that comes late slips the schedule by its
delay, so the sim never runs above SPEED to catch up.  Running below the ceiling is logged (at
most once every ``BEHIND_LOG_S`` of wall time), and the summary reports the factor achieved.

With hard deadlines (opt-in, for runs that must keep the wall clock, as hardware in the loop
does) the sim waits for answers only until the next tick is due; a node that answers later has
missed the tick, counted as its late tick (``Lockstep.late``), and its last commands hold.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field

BEHIND_LOG_S = 10.0
"""Wall time over which the pace achieved is judged (and at most logged once), s."""


@dataclass
class Pacer:
    """Paces ticks to at most ``speed`` × real time; ``hard``: hard deadlines."""

    speed: float
    hard: bool
    log: logging.Logger
    _wall0: float = field(default=0.0, init=False)
    _mark: tuple[float, float] = field(default=(0.0, 0.0), init=False)
    """(wall time, sim time) at the start of the interval over which the pace is judged"""

    def __post_init__(self) -> None:
        if not (math.isfinite(self.speed) and self.speed > 0.0):
            raise ValueError(f"--realtime needs a positive speed, got {self.speed!r}")

    def start(self) -> None:
        """The run starts now (wall clock)."""
        self._wall0 = time.monotonic()
        self._mark = (self._wall0, 0.0)

    def due(self, t_s: float) -> float:
        """When sim time ``t_s`` is due on the wall clock (``time.monotonic``)."""
        return self._wall0 + t_s / self.speed

    def wait(self, t_s: float) -> None:
        """Hold tick time ``t_s`` until it is due.  A tick already late slips the schedule
        by its delay (as a ceiling: the sim never runs above ``speed`` to catch up; with hard
        deadlines the wall clock stays the master and nothing slips)."""
        now = time.monotonic()
        late = now - self.due(t_s)
        if late < 0.0:
            time.sleep(-late)
        elif not self.hard:
            self._wall0 += late
        self._judge(now, t_s)

    def slip(self, wall_s: float) -> None:
        """Move the schedule ``wall_s`` later: the sim held the clock that long on purpose (a
        participant restarting), in either mode; no tick is late for it."""
        self._wall0 += wall_s

    def _judge(self, now: float, t_s: float) -> None:
        """Every ``BEHIND_LOG_S`` of wall time, log the pace achieved over it when below the
        ceiling."""
        wall, t0 = self._mark
        if now - wall < BEHIND_LOG_S:
            return
        self._mark = (now, t_s)
        achieved = (t_s - t0) / (now - wall)
        if achieved < 0.95 * self.speed:
            self.log.warning("%.1fx real time over the last %.0f s of wall time, below the %gx "
                             "ceiling (t=%.0f s)%s", achieved, now - wall, self.speed, t_s,
                             "" if self.hard else ": the lockstep holds, results do not change")

    def answer_deadline(self, t_s: float, dt_s: float, lockstep_timeout_s: float) -> float:
        """Until when the answers to tick time ``t_s`` are waited for (wall clock): the next
        tick's due time with hard deadlines, else the lockstep's own timeout from now."""
        if self.hard:
            return self.due(t_s + dt_s)
        return time.monotonic() + lockstep_timeout_s
