"""The declared topology (interfaces/contracts/topology.py) and the executives assembled from it
(interfaces/runtime/assembly.py): the nodes a run holds, every declared app and builder
resolving, each node's executive running exactly its declared apps with its own context, the
software fault hook on a spacecraft, each node's process command, and clear errors for a node
or a name that is not there."""

from __future__ import annotations

import importlib.util

import pytest

from fsw.apps.infocost import InfoCostApp
from interfaces.contracts import topics
from interfaces.contracts.apps import GROUND_APPS, ONBOARD_FDIR_APPS, SPACECRAFT_APPS
from interfaces.contracts.topology import (
    Node,
    NodeProcess,
    describe,
    hosting,
    topology,
)
from interfaces.runtime.app import App
from interfaces.runtime.assembly import app_class, executive_of, resolve
from interfaces.runtime.bus import Bus
from interfaces.runtime.transport import InprocNetwork
from tests.conftest import small_scenario


def test_a_run_holds_one_node_per_observer_then_the_ground() -> None:
    sc = small_scenario(observers={"count": 4})
    assert topology(sc).participants == ["sc1", "sc2", "sc3", "sc4", topics.GROUND]
    assert topology(sc, ground=False).participants == ["sc1", "sc2", "sc3", "sc4"]
    assert [n.spacecraft for n in topology(sc).nodes] == [1, 2, 3, 4, None]


def test_every_declared_name_resolves() -> None:
    for name in (*SPACECRAFT_APPS, *ONBOARD_FDIR_APPS, *GROUND_APPS):
        assert issubclass(app_class(name), App)
    for node in topology(small_scenario()).nodes:
        assert callable(resolve(node.executive))
        assert importlib.util.find_spec(node.module) is not None  # python -m MODULE exists
    for service in topology(small_scenario()).services:
        assert importlib.util.find_spec(service.module) is not None


@pytest.mark.parametrize("node_name", ["sc2", topics.GROUND])
def test_each_nodes_executive_runs_its_declared_apps(node_name: str) -> None:
    sc = small_scenario(observers={"count": 2})
    node = topology(sc).node(node_name)
    bus = Bus(node.name, "topo", InprocNetwork().endpoint())
    executive = executive_of(node, bus, sc)
    assert [type(a) for a in executive.apps] == [app_class(a) for a in node.apps]
    assert all(a.ctx.node == node_name and a.ctx.spacecraft == node.spacecraft
               for a in executive.apps)
    assert executive.log.name == f"insp.{node_name}"


def test_a_spacecraft_reports_its_faulty_data_factor_and_the_others_do_not() -> None:
    sc = small_scenario(observers={"count": 2}, faults=[
        {"spacecraft": 2, "kind": "faulty_data", "start_s": 10.0, "end_s": 20.0,
         "magnitude": 3.0}])

    def factor(name: str, t: float) -> float:
        node = topology(sc).node(name)
        apps = executive_of(node, Bus(name, "topo", InprocNetwork().endpoint()), sc).apps
        return next(a for a in apps if isinstance(a, InfoCostApp)).report_factor(t)

    assert [factor("sc2", t) for t in (5.0, 10.0, 19.0, 20.0)] == [1.0, 3.0, 3.0, 1.0]
    assert factor("sc1", 15.0) == 1.0


def test_each_node_starts_with_its_own_command() -> None:
    topo = topology(small_scenario(observers={"count": 2}))
    assert topo.node("sc2").command == ["-m", "fsw", "--spacecraft", "2"]
    assert topo.node(topics.GROUND).command == ["-m", "ground"]
    table = describe(topo)
    assert all(n in table for n in ("router", "recorder", "sim", "sc1", "sc2", "FdirApp"))


def test_a_missing_node_or_name_is_a_clear_error() -> None:
    with pytest.raises(ValueError, match="no node 'sc3'.*sc1, sc2, ground"):
        topology(small_scenario(observers={"count": 2})).node("sc3")
    with pytest.raises(ValueError, match="does not resolve"):
        app_class("fsw.apps.nav:NoSuchApp")
    with pytest.raises(ValueError, match="not an App subclass"):
        app_class("interfaces.contracts.topology:topology")
    bad = Node("sc1", ("fsw.apps.nowhere:App",), "interfaces.runtime.assembly:build_executive",
               ("fsw", 1), "fsw")
    with pytest.raises(ValueError, match="fsw.apps.nowhere"):
        executive_of(bad, Bus("sc1", "topo", InprocNetwork().endpoint()), small_scenario())


@pytest.mark.parametrize(("observers", "processes", "expected"), [
    (5, 2, ["sc1+sc2", "sc3+sc4+sc5", "ground"]),
    (5, 1, ["sc1+sc2+sc3+sc4+sc5", "ground"]),
    (3, 8, ["sc1", "sc2", "sc3", "ground"]),
    (20, 3, ["+".join(f"sc{i}" for i in range(a, b)) for a, b in ((1, 8), (8, 14), (14, 21))]
     + ["ground"]),
])
def test_packed_hosting_shares_the_spacecraft_among_the_cores(
        observers: int, processes: int, expected: list[str]) -> None:
    """Consecutive spacecraft, as many processes as cores (sizes within one), every node
    hosted once, the ground alone."""
    topo = topology(small_scenario(observers={"count": observers}))
    hosts = hosting(topo, "packed", processes)
    assert [h.name for h in hosts] == expected
    assert sorted(n.name for h in hosts for n in h.nodes) == sorted(topo.participants)


def test_a_packed_host_starts_its_spacecraft_together_and_one_alone_as_before() -> None:
    topo = topology(small_scenario(observers={"count": 4}))
    packed = hosting(topo, "packed", 2)
    assert packed[0].command == ["-m", "fsw", "--spacecraft", "1", "2"]
    assert hosting(topo, "one-per-process", 2)[1].command == topo.node("sc2").command
    assert [h.name for h in hosting(topo, "packed", 2, alone={"sc2"})] == [
        "sc1+sc3", "sc4", "sc2", "ground"]
    with pytest.raises(ValueError, match="at least 1"):
        hosting(topo, "packed", 0)
    with pytest.raises(ValueError, match="start the same way"):
        NodeProcess((topo.node("sc1"), topo.node(topics.GROUND)))
