"""A node's state taken whole and put back (``interfaces.runtime.checkpoint``), after a real
run (with the onboard FDIR and the neighbours' FDIR on, so that their apps are checked too, and
ground passes, so that what waits in the onboard stores is): every app declares what changes
while it runs, and a fresh node given a running node's state is the same node: the same state,
and the same messages on the next ticks."""

from __future__ import annotations

import pickle
from functools import cache

import pytest

from deploy.inproc import run_inproc
from interfaces.contracts.messages import Tick
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topology import topology
from interfaces.runtime.app import App
from interfaces.runtime.assembly import executive_of
from interfaces.runtime.bus import Bus
from interfaces.runtime.checkpoint import capture, restore
from interfaces.runtime.executive import Executive, TickClient
from interfaces.runtime.transport import InprocNetwork
from links.channel import ChannelModel
from tests.conftest import canonical, small_scenario

SC = small_scenario(
    "ckpt", duration_s=150.0, onboard_fdir={"enabled": True}, neighbours={"enabled": True},
    orbit={"inclination_deg": 51.6, "raan_deg": 255.0, "arg_latitude_deg": 90.0},
    ground={"contact": "passes",  # a pass from 29 s: the stores wait, then dump
            "stations": [{"name": "mid", "latitude_deg": 48.08, "longitude_deg": 11.28}]})


@cache
def _ran() -> dict[str, Executive]:
    """The nodes after a run of 150 s (a transfer, images, FDIR windows)."""
    return run_inproc(SC)[1]


def _fresh(node: str, scenario: Scenario = SC) -> tuple[TickClient, list[tuple[str, bytes]]]:
    """A freshly built node on a network of its own, and what it publishes."""
    net = InprocNetwork()
    sent: list[tuple[str, bytes]] = []
    net.endpoint().subscribe("insp/**", lambda k, _t, p: sent.append((k, p)))
    bus = Bus(node, scenario.name, net.endpoint(), channel=ChannelModel.of(node, scenario))
    return TickClient(executive_of(topology(scenario).node(node), bus, scenario),
                      synchronous=True), sent


def _changed(ran: App, fresh: App) -> set[str]:
    out = set()
    for name, value in vars(ran).items():
        if name in ("ctx", "log", "_outputs"):
            continue
        try:
            same = pickle.dumps(value) == pickle.dumps(vars(fresh)[name])
        except (TypeError, AttributeError, pickle.PicklingError):
            same = False
        if not same:
            out.add(name)
    return out


@pytest.mark.parametrize("node", ["sc2", "ground"])
def test_every_attribute_an_app_changes_is_declared(node: str) -> None:
    fresh, _ = _fresh(node)
    for ran, new in zip(_ran()[node].apps, fresh.executive.apps, strict=True):
        declared = {c.split(".")[0] for c in ran.CRITICAL} | set(ran.REBUILT)
        assert _changed(ran, new) <= declared, f"{ran.NAME}: undeclared state"
    assert _changed(_ran()[node].apps[0], fresh.executive.apps[0])  # it ran: something changed


def _ticks(ex: Executive, after: Tick, n: int) -> None:
    for k in range(after.k + 1, after.k + 1 + n):
        ex.run_tick(Tick(sender="sim", t_sim=k * after.dt_s, k=k, dt_s=after.dt_s),
                    barrier=False)


@pytest.mark.parametrize("node", ["sc2", "ground"])
def test_a_fresh_node_given_the_state_is_the_same_node(node: str) -> None:
    ran = _ran()[node]
    state = pickle.loads(pickle.dumps(capture(ran)))
    client, sent = _fresh(node)
    restore(client, state)
    assert client.last_k == ran.last_done.k  # type: ignore[union-attr]
    assert canonical(capture(client.executive)) == canonical(capture(ran))
    twin, twin_sent = _fresh(node)  # the running node's messages, on a network of its own
    ran.bus.transport = twin.executive.bus.transport
    ran.bus.bundle = None  # each message alone, as the fresh node's (no process around it)
    last = Tick(sender="sim", t_sim=ran.last_done.t_sim, k=ran.last_done.k,  # type: ignore[union-attr]
                dt_s=SC.rates.dt_s)
    _ticks(ran, last, 25)
    _ticks(client.executive, last, 25)
    strip = [(k, _without_wall_time(p)) for k, p in sent]
    assert len(strip) > 25 and strip == [(k, _without_wall_time(p)) for k, p in twin_sent]


def _without_wall_time(payload: bytes) -> bytes:
    import json

    d = json.loads(payload)
    for volatile in ("t_wall", "solve_ms", "mpc_ms", "max_exec_ms", "groups"):
        d.pop(volatile, None)
    return json.dumps(d, sort_keys=True).encode()
