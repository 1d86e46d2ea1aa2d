"""The sim's truth positions as the channel models of one process read them: the ranges of the
links are judged on them at each message's send time (``links.channel``).  One history per
process, fed by the sim's TruthState through a single subscription however many nodes the
process hosts; positions are made from a truth message only for the times a delivery is
decided."""

from __future__ import annotations

import bisect
import threading
from dataclasses import dataclass, field

import numpy as np

from interfaces.contracts.messages import TruthState
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topics import GROUND


@dataclass(eq=False)
class TruthHistory:
    """The sim's truth positions (LVLH, m) of the last ``horizon_s`` seconds, by sim time, as the
    channel models of one process read them (thread-safe).  The first Bus whose channel reads it
    feeds it (``claim_feed``), with the TruthState messages as they come; a time's positions are
    converted when a delivery first asks for them."""

    horizon_s: float = 60.0
    """History kept behind the newest truth (s): at least the link delay and a margin."""
    _t: list[float] = field(default_factory=list)
    _pos: list[dict[str, np.ndarray] | tuple[list[int], list[list[float]]]] = field(
        default_factory=list)
    _fed: bool = False
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def claim_feed(self) -> bool:
        """True for the first caller only: it subscribes ``observe`` to the sim's truth."""
        with self._lock:
            first, self._fed = not self._fed, True
        return first

    def observe(self, msg: TruthState) -> None:
        """Bus handler of the sim's TruthState."""
        self.record(msg.t_sim, msg.spacecraft, msg.r_lvlh_m)

    def record(self, t_sim: float, spacecraft: list[int], r_lvlh_m: list[list[float]]) -> None:
        """Record the true positions (m) of ``spacecraft`` at ``t_sim`` (s)."""
        with self._lock:
            i = bisect.bisect_right(self._t, t_sim)
            if i > 0 and self._t[i - 1] == t_sim:
                self._pos[i - 1] = (spacecraft, r_lvlh_m)
                return
            self._t.insert(i, t_sim)
            self._pos.insert(i, (spacecraft, r_lvlh_m))
            old = bisect.bisect_left(self._t, self._t[-1] - self.horizon_s)
            if old > 0:
                del self._t[:old]
                del self._pos[:old]

    def checkpoint(self, since_s: float) -> tuple[list[float], list[object]]:
        """The history (times, positions) that ``positions_at`` reads for times from
        ``since_s`` (s) on, for a node's critical-data store."""
        with self._lock:
            i = max(0, bisect.bisect_right(self._t, since_s + 1e-6) - 1)
            return self._t[i:], self._pos[i:]

    def restore(self, saved: tuple[list[float], list[object]]) -> None:
        """Take back a ``checkpoint``."""
        with self._lock:
            self._t, self._pos = list(saved[0]), list(saved[1])  # type: ignore[arg-type]

    def positions_at(self, t: float) -> dict[str, np.ndarray] | None:
        """Positions by node (the ground at the origin) at the latest truth time <= t
        (+1 µs tolerance), or None if there is none."""
        with self._lock:
            i = bisect.bisect_right(self._t, t + 1e-6)
            if i == 0:
                return None
            pos = self._pos[i - 1]
            if isinstance(pos, tuple):
                spacecraft, r_lvlh_m = pos
                pos = {f"sc{sc}": np.asarray(r, dtype=float)
                       for sc, r in zip(spacecraft, r_lvlh_m, strict=True)}
                pos[GROUND] = np.zeros(3)
                self._pos[i - 1] = pos
            return pos



def history_for(scenario: Scenario) -> TruthHistory:
    """A truth history long enough for ``scenario``'s link delay."""
    return TruthHistory(horizon_s=scenario.comms.delay_s + 60.0)
