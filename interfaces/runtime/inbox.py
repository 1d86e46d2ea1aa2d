"""A node's inbox: the messages its Bus holds for deferred delivery, when each becomes due, and
the barrier that waits for announced messages to arrive.

* **Due.** A message of this node or of the sim is due once its send time is ``<= t_now``; one
  from another flight/ground node once it was sent strictly before ``t_now`` (at ``t_now`` too
  with ``include_now``) and, when it crosses a modelled link (``link_stage.crosses_link``), the
  link's delay has elapsed (times in s, compared within ``TIME_TOL_S``).
* **Order.** The due messages are handed over sorted by (send time, key, sequence), whatever
  the order they arrived in.
* **Barrier.** ``wait`` blocks until every announced key has reached its sequence number.  The
  receivers queue a message and record its number under ``lock`` in one step, and wake the
  barrier (``wake``) only while a thread waits in it.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

from interfaces.contracts import topics
from interfaces.contracts.messages import Message
from interfaces.contracts.timing import TIME_TOL_S
from interfaces.runtime.link_stage import crosses_link
from interfaces.runtime.subscriptions import Sub


class Envelope:
    """A message waiting in a node's inbox for its subscribers ``subs``: received on ``key``
    from node ``src`` (``local``: published by this node); ``order`` is its place in the
    delivery order, (send time, key, sequence)."""

    __slots__ = ("msg", "key", "src", "local", "subs", "order")

    def __init__(self, msg: Message, key: str, src: str | None, local: bool,
                 subs: list[Sub]) -> None:
        self.msg, self.key, self.src, self.local, self.subs = msg, key, src, local, subs
        self.order = (msg.t_sim, key, msg.seq)


def _order(env: Envelope) -> tuple[float, str, int]:
    return env.order


@dataclass(eq=False)
class Inbox:
    """The deferred messages of node ``node``, and its barrier."""

    node: str
    pending: list[Envelope] = field(default_factory=list)
    """Messages not yet due, in arrival order (appended under ``lock``)."""
    lock: threading.Condition = field(default_factory=threading.Condition)
    waiting: int = 0
    """Threads inside ``wait`` (changed and read under ``lock``)."""
    _crosses: dict[str | None, bool] = field(default_factory=dict)
    """Per source node: whether its messages to this node cross a modelled link."""

    def wake(self) -> None:
        """Wake the barrier if a thread waits in it (call under ``lock``, after queueing)."""
        if self.waiting:
            self.lock.notify_all()

    def take_due(self, t_now: float, include_now: bool, delay_s: float) -> list[Envelope]:
        """Remove and return the messages due at ``t_now`` (s) in delivery order (module
        docstring); ``delay_s``: the delay of the links into this node, s."""
        with self.lock:
            if not self.pending:
                return []
            due, keep = [], []
            for env in self.pending:
                (due if self._is_due(env, t_now, include_now, delay_s) else keep).append(env)
            self.pending = keep
        due.sort(key=_order)
        return due

    def _is_due(self, env: Envelope, t_now: float, include_now: bool, delay: float) -> bool:
        t = env.msg.t_sim
        if env.local or env.src == topics.SIM:
            return t <= t_now + TIME_TOL_S
        link_delay = delay if self.crosses_link(env.src) else 0.0
        sent_before = t <= t_now + TIME_TOL_S if include_now else t < t_now - TIME_TOL_S
        return sent_before and t + link_delay <= t_now + TIME_TOL_S

    def crosses_link(self, src: str | None) -> bool:
        """Whether messages from node ``src`` cross a modelled link to this node (cached)."""
        hit = self._crosses.get(src)
        if hit is None:
            hit = self._crosses[src] = crosses_link(src, self.node)
        return hit

    def wait(self, wanted: dict[str, int], seen: dict[str, int], timeout_s: float) -> list[str]:
        """Block until ``seen`` (each key's highest sequence number received, updated under
        ``lock``) reaches every number of ``wanted``, or for ``timeout_s`` (s) at most; return
        the keys still missing."""
        deadline = time.monotonic() + timeout_s
        with self.lock:
            self.waiting += 1  # receivers notify only while someone waits
            try:
                while True:
                    missing = [k for k, s in wanted.items() if seen.get(k, 0) < s]
                    left = deadline - time.monotonic()
                    if not missing or left <= 0:
                        return missing
                    self.lock.wait(left)
            finally:
                self.waiting -= 1
