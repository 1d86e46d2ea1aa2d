"""Sequence accounting of a run's archive: which messages were lost, and which a later segment
repeats (docs/campaigns-and-replay.md, "Segments and lost messages").

Every bus message carries its key's sequence number ``seq``: 1 for the first message its
publisher sends on the key, one more for each after (``interfaces/runtime/bus.py``; the
recorder stores it as the MCAP sequence).  Read in archive order over every segment of the run:

* a number one above the key's last is the next message;
* a number further above skips messages: those between were **lost** (sent, never archived:
  in flight when the recorder died, or sent while it was down);
* a number at or below the key's last, at a later sim time, starts a **new incarnation** of
  its publisher (a process restarted cold counts from 1 again): the messages before it in that
  incarnation were lost (none when it is 1);
* a key's first number n says that the n - 1 before it were lost;
* 0 is no number (a payload without a usable ``seq``): not counted;
* a number the Bus itself would refuse (a first one above ``MAX_FIRST_SEQ``, or a jump of more
  than ``MAX_SEQ_JUMP`` past the key's last: ``interfaces/runtime/admission.py``) is not a
  loss but a forged or broken message: archived as evidence, not counted, and the key's last
  number stays.  (So a recorder down for more than ``MAX_SEQ_JUMP`` messages of a key would
  not see that key's loss; the sim holds the clock while it is down.)

A message recorded again (a number not above the key's last and a sim time not after it, or
the same key, number and sim time as one of an earlier segment) is a **duplicate**, kept once.
A number counted lost that comes after all (recorded late, out of order: what a recorder took
from the nodes' last ticks once the network was back) is no longer lost.  To know the repeats
of earlier segments without holding every number, the ledger keeps, per key, the runs of
consecutive numbers each earlier segment held, with their sim times (a few per key: one, plus
one per gap or incarnation).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from interfaces.contracts.catalogue import topic_of
from interfaces.runtime.admission import MAX_FIRST_SEQ, MAX_SEQ_JUMP


@dataclass(slots=True)
class _Run:
    """Consecutive sequence numbers of one key in one segment, and their sim times (ns)."""

    first_seq: int
    last_seq: int
    first_ns: int
    last_ns: int

    def holds(self, seq: int, log_ns: int) -> bool:
        """Whether the message numbered ``seq`` at sim time ``log_ns`` is one of this run."""
        return (self.first_seq <= seq <= self.last_seq
                and self.first_ns <= log_ns <= self.last_ns)


class SequenceLedger:
    """The sequence accounting of one archive read (see the module docstring): fed every
    message in archive order (:meth:`admit`), segment by segment (:meth:`begin_segment`)."""

    def __init__(self) -> None:
        self._last: dict[str, int] = {}
        """Per key, the number of its last message."""
        self._last_ns: dict[str, int] = {}
        """Per key, the sim time (ns) of its last message."""
        self._lost: dict[str, int] = {}
        self._missing: dict[str, set[int]] = {}
        """Per key, the numbers counted lost in its current incarnation."""
        self._earlier: dict[str, list[_Run]] = {}
        self._current: dict[str, list[_Run]] = {}
        self._track = False
        self.duplicates = 0
        """Messages dropped because an earlier segment holds them."""

    def begin_segment(self, more_follow: bool) -> None:
        """Start the next segment; ``more_follow``: another segment comes after it (its runs
        are then kept to find the messages that one repeats)."""
        for key, runs in self._current.items():
            self._earlier.setdefault(key, []).extend(runs)
        self._current = {}
        self._track = more_follow

    def admit(self, key: str, seq: int, log_ns: int) -> bool:
        """Account for the message numbered ``seq`` of ``key`` at sim time ``log_ns`` (ns);
        False if it is a duplicate (to drop)."""
        last = self._last.get(key, 0)
        if seq == last + 1 and not self._earlier and not self._track:  # the common case
            self._last[key], self._last_ns[key] = seq, log_ns
            return True
        if seq <= 0 or seq > (last + MAX_SEQ_JUMP if key in self._last else MAX_FIRST_SEQ):
            return True  # no number, or one the Bus would refuse: not accounted
        if self._late(key, seq):
            return True
        if (seq <= last and log_ns <= self._last_ns[key]) or (
                self._earlier and self._repeats(key, seq, log_ns)):
            self.duplicates += 1
            return False
        if seq != last + 1:
            self._count_lost(key, range(last + 1, seq) if seq > last else range(1, seq),
                             new_incarnation=seq <= last)
        self._last[key], self._last_ns[key] = seq, log_ns
        if self._track:
            self._extend(key, seq, log_ns)
        return True

    def _late(self, key: str, seq: int) -> bool:
        """Whether ``seq`` is one counted lost that came after all (recorded late: what a
        recorder took from the nodes' recent ticks after the network came back)."""
        missing = self._missing.get(key)
        if not missing or seq not in missing:
            return False
        missing.discard(seq)
        self._lost[key] -= 1
        return True

    def _count_lost(self, key: str, numbers: range, new_incarnation: bool) -> None:
        """Count ``numbers`` lost for ``key`` (those of a former incarnation can no longer
        come late)."""
        if new_incarnation:
            self._missing.pop(key, None)
        if numbers:
            self._lost[key] = self._lost.get(key, 0) + len(numbers)
            self._missing.setdefault(key, set()).update(numbers)

    def _repeats(self, key: str, seq: int, log_ns: int) -> bool:
        """Whether an earlier segment holds this message."""
        return any(run.holds(seq, log_ns) for run in self._earlier.get(key, ()))

    def _extend(self, key: str, seq: int, log_ns: int) -> None:
        """Add the message to its key's current run, or start a new run with it."""
        runs = self._current.setdefault(key, [])
        if runs and runs[-1].last_seq + 1 == seq and runs[-1].last_ns <= log_ns:
            runs[-1].last_seq, runs[-1].last_ns = seq, log_ns
        else:
            runs.append(_Run(seq, seq, log_ns, log_ns))

    @property
    def lost(self) -> dict[str, int]:
        """Messages lost per key (keys with none left out), keys sorted."""
        return dict(sorted((k, n) for k, n in self._lost.items() if n))


def topic_name(key: str) -> str:
    """The catalogue topic of ``key`` as ``app/name`` (``nav/estimate``), or the key itself
    when it is outside the catalogue."""
    topic = topic_of(key)
    return key if topic is None else f"{topic.app}/{topic.name}"


def by_topic(per_key: Mapping[str, int]) -> dict[str, int]:
    """Counts per key summed per catalogue topic (:func:`topic_name`), names sorted, zeros
    left out."""
    out: dict[str, int] = {}
    for key, n in per_key.items():
        if n:
            name = topic_name(key)
            out[name] = out.get(name, 0) + n
    return dict(sorted(out.items()))
