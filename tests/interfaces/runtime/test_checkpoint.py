"""A node's state taken whole and put back (``interfaces.runtime.checkpoint``), on a node run
on bare ticks (after a real run: tests/missions/test_restore.py)."""

from __future__ import annotations

import pickle

import pytest

from interfaces.contracts.messages import Tick
from interfaces.contracts.topology import topology
from interfaces.runtime.assembly import executive_of
from interfaces.runtime.bus import Bus
from interfaces.runtime.checkpoint import capture, restore
from interfaces.runtime.executive import TickClient
from interfaces.runtime.transport import InprocNetwork
from links.channel import ChannelModel
from tests.conftest import canonical, small_scenario

SC = small_scenario("ck", duration_s=30.0)


def _node(name: str, ticks: int = 0) -> TickClient:
    bus = Bus(name, SC.name, InprocNetwork().endpoint(), channel=ChannelModel.of(name, SC))
    client = TickClient(executive_of(topology(SC).node(name), bus, SC), synchronous=True)
    for k in range(ticks):
        client.catch_up(Tick(sender="sim", t_sim=k * SC.rates.dt_s, k=k, dt_s=SC.rates.dt_s))
    return client


@pytest.mark.parametrize("name", ["sc1", "ground"])
def test_a_state_put_back_is_the_state_taken(name: str) -> None:
    ran = _node(name, ticks=7)
    state = pickle.loads(pickle.dumps(capture(ran.executive)))
    assert state["tick"] == 6 and set(state["apps"]) == {a.NAME for a in ran.executive.apps}
    fresh = _node(name)
    restore(fresh, state)
    assert fresh.last_k == 6 and fresh.executive.ticks == 7
    assert canonical(capture(fresh.executive)) == canonical(capture(ran.executive))


def test_a_state_of_another_make_is_refused_before_anything_changes() -> None:
    state = capture(_node("sc1", ticks=3).executive)
    client = _node("sc1")
    before = canonical(capture(client.executive))
    for broken in ({**state, "apps": {k: v for k, v in state["apps"].items() if k != "nav"}},
                   {**state, "apps": {**state["apps"], "nav": {"rng": None, "state": {}}}},
                   {"tick": 3}, capture(_node("ground").executive)):
        with pytest.raises(ValueError):
            restore(client, broken)
    assert canonical(capture(client.executive)) == before
