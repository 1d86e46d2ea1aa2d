"""Spacecraft that share a process step together (issue 42; docs/architecture.md, "Fleet
step"): the executives of the spacecraft one process hosts run each tick as one.

Each spacecraft keeps its own executive: its bus, messages, state, rate groups, counters and
answer (TickDone).  The fleet only orders their work.  For each rate group due at the tick,
every member's bus first delivers its due messages; then each app slot (the same app class in
the same place on every member) runs for all members: in one call where the app's class
batches over spacecraft (``App.step_all``, over arrays), else one after the other.  Finally
every member publishes its housekeeping and answers.  The rate-group loop is the executive's
own (``interfaces.runtime.executive.step_together``): an executive alone is a fleet of one.

What an app sees and publishes does not depend on who shares its process: a message another
node published during a tick is delivered at a later tick (``Inbox``: sent strictly before
the tick), so the order in which the members run within a tick changes no message any of them
receives.  Each member's own ``TickClient`` still judges every tick (plausibility, rejoining,
answering a tick again); the fleet runs a tick once every member has taken it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from interfaces.contracts.messages import Tick
from interfaces.contracts.topology import Node
from interfaces.runtime.executive import Executive, step_together


@dataclass(eq=False)
class Fleet:
    """The executives ``members`` of the spacecraft one process hosts, stepped together."""

    members: list[Executive]
    _taken: dict[int, tuple[Tick, list[Executive]]] = field(default_factory=dict)
    """By tick number, the tick and the members that have taken it and wait for the others."""

    def __post_init__(self) -> None:
        if not self.members:
            raise ValueError("a fleet needs at least one member")
        layouts = {tuple(type(a) for a in m.apps) for m in self.members}
        if len(layouts) != 1:
            raise ValueError("the spacecraft of a fleet must run the same apps in the same "
                             f"order; got {[[a.NAME for a in m.apps] for m in self.members]}")

    def take(self, member: Executive, tick: Tick, barrier: bool) -> None:
        """``member`` took ``tick``: the tick runs for every member once all have taken it.
        A tick the member ran already is answered again at once (``Executive.begin_tick``);
        members still waiting on an earlier tick, which a member refused, run it first."""
        if member.last_done is not None and member.last_done.k == tick.k:
            member.run_tick(tick, barrier)
            return
        for k in sorted(k for k in self._taken if k < tick.k):
            self._run(*self._taken.pop(k), barrier)
        waiting = self._taken.setdefault(tick.k, (tick, []))[1]
        if member not in waiting:
            waiting.append(member)
        if len(waiting) == len(self.members):
            del self._taken[tick.k]
            self._run(tick, [m for m in self.members if m in waiting], barrier)

    def _run(self, tick: Tick, members: list[Executive], barrier: bool) -> None:
        """Run ``tick`` for ``members`` (module docstring)."""
        started = [m for m in members if m.begin_tick(tick, barrier)]
        if not started:
            return
        step_together(started, tick)
        for m in started:
            m.end_tick(tick)
        for m in started:  # the process's bundle, once every member answered
            m.bus.flush_bundle()
        for m in started:
            m.tick_ended()


def fleets_of(nodes: list[Node], executives: dict[str, Executive]) -> dict[str, Fleet]:
    """The fleets of ``nodes`` hosted in one process, by node name: the nodes that run the
    same apps in the same order step together (spacecraft whose onboard software differs, an
    agent-level FDIR aboard some only, form fleets apart)."""
    by_layout: dict[tuple[str, ...], list[Executive]] = {}
    for node in nodes:
        by_layout.setdefault(tuple(node.apps), []).append(executives[node.name])
    out: dict[str, Fleet] = {}
    for members in by_layout.values():
        fleet = Fleet(members)
        out |= {m.bus.node: fleet for m in members}
    return out
