"""Admission of received messages: the Bus's plausibility rules, applied after schema validation
and before a message is queued, waited for or delivered.

A message that passed its schema can still be hostile or broken in ways only the bus can see:

* **Sender.** Who sent a message follows from the key space it came on (only that node may
  publish there: ``topics.node_of_key``, enforced by access control on a secured network); a
  body whose ``sender`` names another node is refused.
* **Sequence.** A key's sequence count grows by one per message.  A first message numbered above
  ``MAX_FIRST_SEQ`` or a jump of more than ``MAX_SEQ_JUMP`` past the highest seen is refused: it
  would make the barrier believe that messages arrived which never will.  A number already seen
  is a duplicate (a message sent again: a publisher restored from its critical-data store
  running its interrupted tick again, or an answer to a resend request that this node did not
  need), dropped and counted apart (``Admission.duplicates``), not refused; a 1 as the first
  message after its publisher's liveliness came back (``Admission.restarted``) is the key's
  publisher started afresh (it numbers from 1 again), and starts the count anew.
* **Time.** Once the bus has a clock (the lockstep's tick time, ``Admission.advance``), a message
  dated more than ``MAX_AHEAD_S`` after it is refused instead of queued for a future that may
  never come.
* **Queue.** At most ``MAX_PENDING`` messages wait for delivery; beyond that new ones are refused.

The lockstep's tick is exempt from the sequence and time rules (``Admission.judged_by_subscriber``):
it defines the clock the time rule reads, and its subscriber judges it by rules of its own
(``interfaces.runtime.executive.TickClient``), which let a node cut off from the sim follow it
again.

A refusal is counted by kind (``Admission.refused``) and logged (rate-limited) by the Bus;
nothing else happens.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from interfaces.contracts import topics
from interfaces.contracts.messages import Message

MAX_FIRST_SEQ = 10**9
"""Highest sequence number a key's first message may carry (10 Hz for three years)."""
MAX_SEQ_JUMP = 10_000
"""Largest step of a key's sequence count past the highest seen (a late subscriber, a burst)."""
MAX_AHEAD_S = 10.0
"""How far past the bus's clock a message may be dated, s (a tick is 0.1 s)."""
MAX_PENDING = 100_000
"""Messages that may wait for delivery at once (a node receives a few hundred per tick)."""


Refusal = tuple[str, str]
"""(kind, detail): kind is one of "sender", "sequence", "time", "queue" (and "tick", from the
lockstep client)."""


@dataclass
class Admission:
    """The admission state of one Bus: its clock and each key's highest sequence number."""

    clock_s: float | None = None
    """Latest lockstep time seen (s); None until the node's first tick (no time rule before)."""
    highest_seq: dict[str, int] = field(default_factory=dict)
    refused: Counter[str] = field(default_factory=Counter)
    """Refusals so far, by kind (counted by ``Bus.refuse``)."""
    duplicates: int = 0
    """Messages dropped as already seen (their key's number not above the highest)."""
    judged_by_subscriber: set[str] = field(default_factory=set)
    """Keys exempt from the sequence and time rules: their subscriber judges them (the tick)."""
    _owner: dict[str, str | None] = field(default_factory=dict)
    _may_restart: set[str] = field(default_factory=set)
    """Keys whose publisher came back, until their next message: a 1 starts the count anew."""

    def advance(self, t_s: float) -> None:
        """The lockstep has reached ``t_s`` (a tick arrived or was dispatched)."""
        if self.clock_s is None or t_s > self.clock_s:
            self.clock_s = t_s

    def check(self, key: str, msg: Message, pending: int) -> Refusal | None:
        """Why ``msg`` received on ``key`` must be refused, or None to admit it (the Bus counts
        a refusal; an admitted message is recorded by ``admit`` once it is queued)."""
        return self._why(key, msg, pending)

    def duplicate(self, key: str, msg: Message) -> bool:
        """Whether ``msg`` was seen already (its number not above the key's highest, and not
        the 1 of a publisher that came back); counted.  The lockstep's tick is judged by its
        subscriber.  Call under the inbox's lock, with ``admit``."""
        last = self.highest_seq.get(key)
        came_back = key in self._may_restart
        if came_back:
            self._may_restart.discard(key)
        if last is None or msg.seq > last or key in self.judged_by_subscriber:
            return False
        if msg.seq == 1 and came_back:
            self.highest_seq.pop(key, None)  # its publisher started afresh: count from 1 again
            return False
        self.duplicates += 1
        return True

    def owner(self, key: str) -> str | None:
        """The node whose key space ``key`` is in (``topics.node_of_key``, cached per key)."""
        owner = self._owner.get(key, "")
        if owner == "":
            owner = self._owner[key] = topics.node_of_key(key)
        return owner

    def _why(self, key: str, msg: Message, pending: int) -> Refusal | None:
        owner = self.owner(key)
        if msg.sender != owner:
            return "sender", f"sender {msg.sender!r} does not own the key (owner {owner!r})"
        why = None if key in self.judged_by_subscriber else self._out_of_order(key, msg)
        if why is not None:
            return why
        if pending >= MAX_PENDING:
            return "queue", f"{pending} messages already waiting for delivery"
        return None

    def _out_of_order(self, key: str, msg: Message) -> Refusal | None:
        """The sequence and time rules."""
        last = self.highest_seq.get(key)
        if last is None and msg.seq > MAX_FIRST_SEQ:
            return "sequence", f"first sequence number {msg.seq} exceeds {MAX_FIRST_SEQ}"
        if last is not None and msg.seq > last + MAX_SEQ_JUMP:
            return "sequence", f"sequence number jumps from {last} to {msg.seq}"
        if self.clock_s is not None and msg.t_sim > self.clock_s + MAX_AHEAD_S:
            return "time", (f"dated t={msg.t_sim:.6g} s, more than {MAX_AHEAD_S:g} s after "
                            f"the clock's t={self.clock_s:g} s")
        return None

    def forget(self, prefix: str = "") -> None:
        """Forget the sequence numbers of the keys under ``prefix`` (all, by default) and, for
        all, the clock: their publisher restarted, or this node rejoins the lockstep."""
        self.highest_seq = {k: s for k, s in self.highest_seq.items()
                            if prefix and not k.startswith(prefix)}
        if not prefix:
            self.clock_s = None

    def restarted(self, prefix: str) -> None:
        """The publisher of the keys under ``prefix`` came back (its liveliness token): from
        a process started afresh, its keys count from 1 again; restored from its critical-data
        store, they go on, and what it sends again is a duplicate."""
        self._may_restart.update(k for k in list(self.highest_seq) if k.startswith(prefix))

    def checkpoint(self) -> dict[str, object]:
        """The clock, the highest numbers seen and the counts (for a node's store)."""
        return {"clock_s": self.clock_s, "highest_seq": dict(self.highest_seq),
                "refused": Counter(self.refused), "duplicates": self.duplicates,
                "may_restart": set(self._may_restart)}

    def restore(self, saved: dict[str, Any]) -> None:
        """Take back a ``checkpoint``."""
        self.clock_s, self.highest_seq = saved["clock_s"], saved["highest_seq"]
        self.refused, self.duplicates = saved["refused"], saved["duplicates"]
        self._may_restart = saved["may_restart"]

    def admit(self, key: str, msg: Message) -> None:
        """Record an admitted message's sequence number (the barrier waits on it)."""
        if msg.seq > self.highest_seq.get(key, 0):
            self.highest_seq[key] = msg.seq
