"""Spacecraft that share a process step together (interfaces/runtime/fleet.py): a tick runs
once every member has taken it, and spacecraft whose software differs step apart.  That a
fleet changes no message is flown in tests/missions/test_fleet_run.py."""

from __future__ import annotations

import queue
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, ClassVar

import pytest

from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.messages import SimStatus, Tick, TickDone
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topology import Node, topology
from interfaces.runtime.app import App
from interfaces.runtime.assembly import build_executive
from interfaces.runtime.bus import Bus
from interfaces.runtime.executive import Executive, TickClient, serve_together
from interfaces.runtime.fleet import Fleet, fleets_of
from interfaces.runtime.transport import InprocNetwork
from tests.conftest import small_scenario


class _Count(App):
    NAME = "count"
    RATE = "high"

    def __init__(self, ctx: Any) -> None:
        super().__init__(ctx)
        self.steps: list[float] = []

    def step(self, t: float) -> None:
        self.steps.append(t)


class _Batched(_Count):
    """Steps its members together (``App.step_all``), leaving those whose ``alone`` is set to
    their own step; raises for every member when ``fail`` is set."""

    NAME = "batched"
    calls: ClassVar[list[tuple[float, list[str]]]] = []
    fail: ClassVar[bool] = False

    def __init__(self, ctx: Any) -> None:
        super().__init__(ctx)
        self.alone = False
        self.batched: list[float] = []

    @classmethod
    def step_all(cls, apps: Sequence[_Batched], t: float) -> Sequence[_Batched]:
        cls.calls.append((t, [a.ctx.node for a in apps]))
        if cls.fail:
            raise RuntimeError("the batched kernel failed")
        for a in apps:
            if not a.alone:
                a.batched.append(t)
        return [a for a in apps if a.alone]


def _executive(net: InprocNetwork, node: str, scenario: Scenario,
               app: str = "_Count") -> Executive:
    """An executive of node ``node`` running one ``app`` (a class of this module)."""
    return build_executive(Node(node, (f"{__name__}:{app}",), "", ("t", 0), "", spacecraft=1),
                           Bus(node, "m", net.endpoint()), scenario)


def _tick(k: int, scenario: Scenario) -> Tick:
    dt = scenario.rates.dt_s
    return Tick(sender=topics.SIM, t_sim=k * dt, k=k, dt_s=dt, expect={}, final=False)


def test_a_tick_runs_once_every_member_took_it_and_an_old_one_is_answered_again() -> None:
    scenario = small_scenario("f")
    net = InprocNetwork()
    a, b = (_executive(net, n, scenario) for n in ("sc1", "sc2"))
    fleet = Fleet([a, b])
    fleet.take(a, _tick(0, scenario), barrier=False)
    assert a.apps[0].steps == [] and a.last_done is None  # waits for sc2
    fleet.take(b, _tick(0, scenario), barrier=False)
    assert a.apps[0].steps == b.apps[0].steps == [0.0]
    assert a.last_done is not None and a.last_done.k == b.last_done.k == 0
    fleet.take(a, _tick(0, scenario), barrier=False)  # the open tick sent again: answered
    assert a.apps[0].steps == [0.0] and a.ticks == 1
    fleet.take(a, _tick(1, scenario), barrier=False)  # sc2 refuses tick 1: run at tick 2
    fleet.take(a, _tick(2, scenario), barrier=False)
    assert a.apps[0].steps == [0.0, 0.5] and b.apps[0].steps == [0.0]


def test_spacecraft_whose_software_differs_form_fleets_apart() -> None:
    """An agent-level FDIR aboard one spacecraft only: it steps apart from the others."""
    scenario = small_scenario("f", observers={"count": 3})
    net = InprocNetwork()
    nodes = [n for n in topology(scenario).nodes if n.spacecraft is not None]
    executives = {n.name: _executive(net, n.name, scenario) for n in nodes}
    assert len({id(f) for f in fleets_of(nodes, executives).values()}) == 1
    odd = replace(nodes[2], apps=(*nodes[2].apps, "fsw.apps.fdir:OnboardFdirApp"))
    assert len({id(f) for f in fleets_of([*nodes[:2], odd], executives).values()}) == 2
    with pytest.raises(ValueError, match="same apps"):
        Fleet([executives[nodes[0].name], Executive(Bus("sc9", "m", net.endpoint()),
                                                      scenario, [])])


def test_nodes_of_one_process_served_together_step_as_a_fleet() -> None:
    """Ticks queued by the clients of one process (as over Zenoh) run on the serving thread,
    each once every member has it, until the sim says the run is finished; clients that do
    not share their queue are refused."""
    scenario = small_scenario("f")
    net = InprocNetwork()
    a, b = (_executive(net, n, scenario) for n in ("sc1", "sc2"))
    fleet = Fleet([a, b])
    shared: queue.Queue[Any] = queue.Queue()
    clients = [TickClient(e, tick_queue=shared, fleet=fleet.take) for e in (a, b)]
    sim = Bus(topics.SIM, "m", net.endpoint())
    answers: list[tuple[str, int]] = []
    for node in ("sc1", "sc2"):
        sim.subscribe(cat.TICK_DONE.key("m", node), TickDone,
                      lambda m: answers.append((m.sender, m.k)), immediate=True)
    for k in range(3):
        sim.publish(cat.TICK.key("m"), _tick(k, scenario), announce=False)
    assert a.apps[0].steps == [] and shared.qsize() == 6  # queued, not run
    sim.publish(cat.SIM_STATUS.key("m"), SimStatus(sender=topics.SIM, t_sim=1.0, state="finished",
                                                   k=2))
    serve_together(clients)
    assert a.apps[0].steps == b.apps[0].steps == [0.0, 0.5, 1.0]
    assert answers == [("sc1", 0), ("sc2", 0), ("sc1", 1), ("sc2", 1), ("sc1", 2), ("sc2", 2)]
    with pytest.raises(ValueError, match="share one tick queue"):
        serve_together([clients[0], TickClient(_executive(net, "sc3", scenario))])


def test_an_app_class_that_batches_steps_its_members_together() -> None:
    """``App.step_all`` runs once per slot for every member; a member it leaves steps alone;
    each member's group run is counted; an executive alone is a fleet of one."""
    scenario = small_scenario("f")
    net = InprocNetwork()
    _Batched.calls, _Batched.fail = [], False
    a, b, c = (_executive(net, n, scenario, "_Batched") for n in ("sc1", "sc2", "sc3"))
    fleet = Fleet([a, b])
    b.apps[0].alone = True
    for k in range(2):
        for m in (a, b):
            fleet.take(m, _tick(k, scenario), barrier=False)
    assert _Batched.calls == [(0.0, ["sc1", "sc2"]), (0.5, ["sc1", "sc2"])]
    assert a.apps[0].batched == [0.0, 0.5] and a.apps[0].steps == []
    assert b.apps[0].batched == [] and b.apps[0].steps == [0.0, 0.5]  # left to its own step
    assert a.stats["high"].runs == b.stats["high"].runs == 1  # the first run is start-up
    assert a.last_done is not None and a.last_done.k == 1
    c.run_tick(_tick(0, scenario), barrier=False)
    assert _Batched.calls[-1] == (0.0, ["sc3"]) and c.apps[0].batched == [0.0]


def test_a_failing_shared_step_is_every_members_failure_and_the_fleet_flies_on() -> None:
    scenario = small_scenario("f")
    net = InprocNetwork()
    _Batched.calls, _Batched.fail = [], True
    a, b = (_executive(net, n, scenario, "_Batched") for n in ("sc1", "sc2"))
    fleet = Fleet([a, b])
    try:
        for m in (a, b):
            fleet.take(m, _tick(0, scenario), barrier=False)
    finally:
        _Batched.fail = False
    assert a.app_errors == b.app_errors == 1
    assert a.apps[0].steps == b.apps[0].steps == []  # not stepped twice
    assert a.last_done is not None and b.last_done is not None  # both answered
