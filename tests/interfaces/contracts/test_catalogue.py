"""The topic catalogue: keys round-trip, the bus holds each key to its type, and the wiring of
the whole constellation (every input has exactly one producer of its type; what a run publishes:
tests/missions/test_catalogue_run.py)."""

from __future__ import annotations

import pytest

from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.apps import (
    GROUND_APPS,
    NEIGHBOUR_APPS,
    ONBOARD_FDIR_APPS,
    SPACECRAFT_APPS,
)
from interfaces.contracts.catalogue import Space, Topic
from interfaces.contracts.messages import Heartbeat, Message, StateEstimate
from interfaces.runtime.app import App
from interfaces.runtime.assembly import app_class
from interfaces.runtime.bus import Bus
from interfaces.runtime.executive import Executive, TickClient
from interfaces.runtime.transport import InprocNetwork
from sim.node import SimNode

M = "cat"
Producers = dict[Topic[Message], list[str]]


def _owner_node(topic: Topic[Message]) -> str:
    return {Space.SIM: "sim", Space.GROUND: "ground"}.get(topic.space, "sc2")


@pytest.mark.parametrize("topic", cat.ALL, ids=str)
def test_every_topic_round_trips_through_its_keys(topic: Topic[Message]) -> None:
    key = topic.key(M, _owner_node(topic))
    assert cat.topic_of(key) is topic
    assert cat.topic_of(topic.every(M)) is topic
    assert topics.matches(topic.every(M), key)
    assert topics.matches(topic.any_mission(), key)
    assert not topics.matches(topic.any_mission(), key.replace(topic.name, "other"))
    if topic.space in (Space.SPACECRAFT, Space.SIM_HARDWARE):
        assert topics.matches(topic.every_spacecraft(M), key)
        assert topics.node_of_key(key) == ("sc2" if topic.space is Space.SPACECRAFT else "sim")
        assert cat.topic_of(topic.every_spacecraft(M)) is topic
    elif topic.space is not Space.EVERY_NODE:
        assert topics.node_of_key(key) == topic.space.value


def test_catalogue_names_each_key_once() -> None:
    keys = [t.key(M, _owner_node(t)) for t in cat.ALL]
    assert len(set(keys)) == len(keys)
    assert cat.topic_of(f"insp/{M}/sc/1/nav/nope") is None
    assert cat.topic_of("elsewhere/x/y/z/w") is None


def test_topic_keys_refuse_a_wrong_node() -> None:
    with pytest.raises(ValueError, match="spacecraft node"):
        cat.NAV_ESTIMATE.key(M, "ground")
    with pytest.raises(ValueError, match="spacecraft node"):
        cat.RELNAV.key(M, "sim")
    with pytest.raises(ValueError, match="needs a node"):
        cat.TICK_DONE.key(M)
    assert cat.TICK.key(M, "sc1") == cat.TICK.key(M) == f"insp/{M}/sim/clock/tick"


def test_the_bus_holds_a_catalogued_key_to_its_type() -> None:
    bus = Bus("sc1", M, InprocNetwork().endpoint())
    est_key = cat.NAV_ESTIMATE.key(M, "sc1")
    with pytest.raises(TypeError, match="StateEstimate, not Heartbeat"):
        bus.publish(est_key, Heartbeat(sender="sc1", t_sim=0.0, node="sc1", apps=[], k=0))
    with pytest.raises(TypeError, match="StateEstimate, not Heartbeat"):
        bus.subscribe(cat.NAV_ESTIMATE.every_spacecraft(M), Heartbeat, lambda _m: None)
    bus.subscribe(cat.NAV_ESTIMATE.every_spacecraft(M), StateEstimate, lambda _m: None)
    # keys outside the catalogue stay free (tools, tests)
    bus.publish(topics.key(M, "sc1", "tool", "hb"),
                Heartbeat(sender="sc1", t_sim=0.0, node="sc1", apps=[], k=0))


# --- wiring ------------------------------------------------------------------------------------


def declared_wiring() -> tuple[Producers, Producers]:
    """(producers, consumers): each topic with the declarations that publish / subscribe it."""
    producers: Producers = {}
    consumers: Producers = {}
    apps: list[type[App]] = [app_class(a) for a in (*SPACECRAFT_APPS, *ONBOARD_FDIR_APPS,
                                                    *NEIGHBOUR_APPS, *GROUND_APPS)]
    for app in apps:
        for o in app.OUTPUTS:
            producers.setdefault(o.topic, []).append(f"{app.NAME}.{o.name}")
        for i in app.INPUTS:
            consumers.setdefault(i.topic, []).append(f"{app.NAME}.{i.handler}")
    for t in SimNode.PUBLISHES:
        producers.setdefault(t, []).append("sim")
    for t in Executive.PUBLISHES:
        producers.setdefault(t, []).append("executive")
    for t in (*SimNode.SUBSCRIBES, *TickClient.SUBSCRIBES):
        consumers.setdefault(t, []).append("lockstep")
    consumers.setdefault(cat.TRUTH, []).append("channel model")
    return producers, consumers


def wiring_problems(producers: Producers, consumers: Producers) -> list[str]:
    """What is wrong with a wiring: an input with no producer or with several, a producer of
    an uncatalogued topic."""
    out = [f"{t} read by {', '.join(c)} has {len(producers.get(t, []))} producers "
           f"{producers.get(t, [])}" for t, c in consumers.items()
           if len(producers.get(t, [])) != 1]
    out += [f"{t} produced by {p} is not in the catalogue" for t, p in producers.items()
            if t not in cat.ALL]
    return out


def test_every_input_has_exactly_one_producer_of_its_type() -> None:
    producers, consumers = declared_wiring()
    assert wiring_problems(producers, consumers) == []
    assert set(producers) == set(cat.ALL), "every catalogued topic is produced"


def test_the_wiring_check_finds_a_missing_and_a_doubled_producer() -> None:
    producers, consumers = declared_wiring()
    producers[cat.POINTING] = []
    producers[cat.ASSIGNMENTS] = [*producers[cat.ASSIGNMENTS], "rogue.assignments"]
    rogue = Topic(Space.GROUND, "rogue", "x", StateEstimate)
    producers[rogue] = ["rogue.x"]
    problems = wiring_problems(producers, consumers)
    assert len(problems) == 3
    assert any("camera/pointing" in p and "0 producers" in p for p in problems)
    assert any("planner/assignments" in p and "2 producers" in p for p in problems)
