"""How far a run's archive reaches: where its data ends against the run's end.

An archive can hold less than its run: a file cut short (no footer; read up to the cut,
``harness/archive/reader.py``), or a whole file of a run that stopped early.  Its end is the sim
time of its last message (``RunArchive.end_s``); when that is before the run's last tick, or a
file of it was cut, the archive is *short*, and its last instant may itself be torn (part of its
messages in the bytes lost).  The replay (``harness/replay.py``) judges and compares nothing due
at or after a short archive's end; ``summary.json``'s ``archive.end_s`` and the run report say
where it ends.
"""

from __future__ import annotations

from dataclasses import dataclass

from harness.archive.reader import RunArchive
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.timing import TIME_TOL_S


def seconds(t_s: float) -> str:
    """A sim time (s) as text: to 0.1 s, without a trailing ``.0``."""
    return f"{t_s:.1f}".removesuffix(".0")


def cut_of(archive: RunArchive) -> str | None:
    """The first file of ``archive`` cut short: its name, the byte it was read up to (of its
    size) and why reading stopped there; None when none is."""
    seg = next((s for s in archive.segments if s.truncated), None)
    if seg is None:
        return None
    where = (f" read up to byte {seg.cut_at_byte} of {seg.size_bytes}"
             if seg.cut_at_byte is not None else "")
    return f"{seg.path.name}{where}: {seg.stop_reason}"


@dataclass(frozen=True)
class ArchiveSpan:
    """The sim time of the archive's last message (``end_s``) and of the run's last tick
    (``run_s``), s, and whether a file of the archive was cut short (``cut``)."""

    end_s: float
    run_s: float
    cut: bool = False

    @classmethod
    def of(cls, archive: RunArchive, scenario: Scenario) -> ArchiveSpan:
        """The span of ``archive``, a run of ``scenario`` (its last tick: the last multiple of
        the high-rate period within ``duration_s``)."""
        last_tick_s = (scenario.n_ticks - 1) * scenario.rates.dt_s
        return cls(archive.end_s or 0.0, last_tick_s, archive.truncated)

    @property
    def short(self) -> bool:
        """The archive ends before the run did, or a file of it was cut short."""
        return self.cut or self.end_s < self.run_s - TIME_TOL_S

    def holds(self, t_s: float) -> bool:
        """Whether what happened at sim time ``t_s`` (s) is wholly archived: up to the end of a
        whole archive; before the last instant of a short one (that instant may be torn)."""
        if self.short:
            return t_s < self.end_s - TIME_TOL_S
        return t_s <= self.end_s + TIME_TOL_S

    def note(self) -> str:
        """Where a short archive ends, as a replay says it; empty for a whole archive."""
        if not self.short:
            return ""
        return (f"archive ends at {seconds(self.end_s)} s (run lasted {seconds(self.run_s)} s)"
                ": judged nothing past it")


__all__ = ["ArchiveSpan", "cut_of", "seconds"]
