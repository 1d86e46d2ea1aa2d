"""The Bus's subscription table on its own: typed topics, routes, awaited keys, their caches."""

from __future__ import annotations

import contextlib

import pytest

from interfaces.contracts import catalogue, topics
from interfaces.contracts.messages import Heartbeat, StateEstimate
from interfaces.runtime.subscriptions import Group, Sub, SubscriptionTable

M = "st"
HB_1 = catalogue.HEARTBEAT.key(M, "sc1")
HB_2 = catalogue.HEARTBEAT.key(M, "sc2")


def _table() -> SubscriptionTable:
    return SubscriptionTable(topics.node_prefix(M, "sc1"))


def test_a_catalogued_key_takes_its_type_only() -> None:
    table = _table()
    table.check_type(HB_2, Heartbeat)
    with pytest.raises(TypeError, match="carries Heartbeat"):
        table.check_type(HB_2, StateEstimate)
    assert table.catalogue_type(f"{topics.node_prefix(M, 'sc1')}/free/x") is None


def test_routes_and_awaited_keys_follow_the_subscriptions() -> None:
    table = _table()
    assert table.route(HB_1) == (Heartbeat, [], False) and HB_1 in table.routes
    assert not table.awaits(HB_2)
    everyone = f"{topics.ROOT}/{M}/**/exec/heartbeat"
    own, other = Sub(everyone, Heartbeat, print, False), Sub(everyone, Heartbeat, print, True)
    table.add(own)
    assert table.routes == {}  # resolved again after a subscription
    assert table.route(HB_1) == (Heartbeat, [own], False)
    assert table.awaits(HB_2) and not table.awaits(HB_1)  # its own keys are never awaited
    table.add(other)
    assert table.types() == {everyone: [Heartbeat, Heartbeat]}
    assert table.split[everyone] == Group(Heartbeat, [other], [own])


def test_bundled_topics_are_routed_to_the_bundle_and_matching_is_cached() -> None:
    table = _table()
    done = catalogue.TICK_DONE.key(M, "sc1")
    assert table.route(done)[2] and not table.route(HB_1)[2]  # the catalogue decides
    everyone = f"{topics.ROOT}/{M}/**/exec/heartbeat"
    table.add(Sub(everyone, Heartbeat, print, False))
    assert table.matching(HB_2) == (everyone,) and table.matching(done) == ()
    table.add(Sub(HB_2, Heartbeat, print, False))
    assert table.matching(HB_2) == (everyone, HB_2)  # forgotten when a subscription came


def test_a_group_of_mixed_types_has_no_kind() -> None:
    subs = [Sub("a/**", Heartbeat, print, False), Sub("a/**", StateEstimate, print, False)]
    assert Group.of(subs).kind is None


@pytest.mark.parametrize("scenario", ["default.toml", "paper_fig23.toml"])
def test_no_node_subscribes_one_key_twice(scenario: str) -> None:
    """Admission drops a key's number seen before as a duplicate, and the network delivers a
    sample once per matching subscription: two key expressions of one node matching the same
    key would lose the second delivery.  No node of the declared topology has such a pair."""
    from interfaces.contracts.scenario import load_scenario
    from interfaces.contracts.topology import topology
    from interfaces.runtime.assembly import executive_of
    from interfaces.runtime.bus import Bus
    from interfaces.runtime.executive import TickClient
    from interfaces.runtime.transport import InprocNetwork
    from links.channel import ChannelModel
    from tests.conftest import REPO

    sc = load_scenario(REPO / "deploy" / "scenarios" / scenario)
    nodes = [topics.SIM, topics.GROUND,
             *(topics.sc_node(i) for i in range(1, sc.observers.count + 1))]
    keys = set()
    for t in (t for t in vars(catalogue).values() if isinstance(t, catalogue.Topic)):
        for n in nodes:
            with contextlib.suppress(ValueError):  # a spacecraft topic of the sim, ...
                keys.add(t.key(sc.name, n))
    assert len(keys) > 50
    for node in topology(sc).nodes:
        bus = Bus(node.name, sc.name, InprocNetwork().endpoint(),
                  channel=ChannelModel.of(node.name, sc))
        TickClient(executive_of(node, bus, sc))
        for key in keys:
            matching = [e for e in bus.table.groups if topics.matches(e, key)]
            assert len(matching) <= 1, f"{node.name} subscribes {key} as {matching}"
