"""Where a run's processes go (deploy/placement.py) and when a rehearsal's link events act
(deploy/link_events.py)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from deploy.access import write_run_access
from deploy.host_access import write_host_access
from deploy.host_map import LinkSpec, load_host_map, parse_link_event
from deploy.link_events import LinkEvents, check_cuts
from deploy.placement import across_hosts, one_host
from deploy.rehearsal.netns import RehearsalError
from interfaces.contracts.scenario import load_scenario
from interfaces.contracts.topology import topology
from tests.conftest import REPO

LAB = REPO / "deploy" / "hosts" / "lab.toml"


def test_across_hosts_each_hosts_spacecraft_share_a_process_on_it(tmp_path: Path) -> None:
    lab = load_host_map(LAB)
    topo = topology(load_scenario(REPO / "deploy" / "scenarios" / "default.toml"))
    place = across_hosts(write_host_access(tmp_path, "m", 5, lab), lab,
                         {h.name: f"ns-{h.name}" for h in lab.hosts})
    assert [p.name for p in place.processes(topo, "packed", 2)] == [
        "ground", "sc1+sc2", "sc3+sc4+sc5"]
    assert [p.name for p in place.processes(topo, "one-per-process", 2)] == [
        "ground", "sc1", "sc2", "sc3", "sc4", "sc5"]
    assert [r.name for r in place.routers] == [
        "router-ground", "router-sim", "router-sca", "router-scb"]
    assert place.routers[2].netns == "ns-sca" and place.routers[2].endpoint.startswith("tls/")
    assert place.netns("sc4") == "ns-scb" and place.netns("recorder") == "ns-ground"
    assert place.config("sc4") == tmp_path / "scb" / "sc4.json5"
    assert json.loads(place.watch_config.read_text())["connect"]["endpoints"] == [
        "tls/10.77.0.1:7447"]


def test_one_host_is_the_run_as_before(tmp_path: Path) -> None:
    access = write_run_access(tmp_path, "m", 3, "tcp/127.0.0.1:7447")
    topo = topology(load_scenario(REPO / "deploy" / "scenarios" / "default.toml"))
    place = one_host(access)
    assert [r.name for r in place.routers] == ["router"] and place.netns("sc1") is None
    assert place.config("sc2") == access.client_config("sc2")
    assert [p.name for p in place.processes(topo, "packed", 2)] == [
        "sc1+sc2", "sc3+sc4+sc5", "ground"]


class _Links:
    """The rehearsed network's link control, recorded (the unit under test decides when)."""

    def __init__(self) -> None:
        self.calls: list[tuple[str, LinkSpec, bool]] = []

    def set_link(self, host: str, link: LinkSpec, up: bool = True) -> None:
        self.calls.append((host, link, up))


def test_a_cut_acts_when_the_sim_waits_for_it_and_delays_on_the_sim_clock() -> None:
    """A cut is made when the sim says it waits for it (after the tick at its time), and so
    is its end; a delay or loss is applied at the first heartbeat at or after its time."""
    lab = load_host_map(LAB).with_links(5.0, None).with_events([
        parse_link_event("scb:cut:30:30"), parse_link_event("sca:loss=10:40:5")])
    net = _Links()
    with LinkEvents(net, lab) as events:  # type: ignore[arg-type]
        assert events.awaits() == ["lost:sc3,sc4,sc5:30.0", "back:sc3,sc4,sc5:60.0"]
        for t in (0.0, 29.0, 30.0, 31.0):
            events.on_time(t)
        assert net.calls == []  # a cut waits for the sim
        events.on_waiting("link 0: awaiting lost:sc3,sc4,sc5:30.0", 30.0)
        for t in (41.0, 46.0, 59.0, 60.0):
            events.on_time(t)
        events.on_waiting("link 1: awaiting back:sc3,sc4,sc5:60.0", 60.0)
        events.on_waiting("link 7: awaiting back:sc9:99.0", 99.0)  # not one of ours: nothing
        assert net.calls == [
            ("scb", LinkSpec(delay_ms=5.0), False),
            ("sca", LinkSpec(delay_ms=5.0, loss_pct=10.0), True),
            ("sca", LinkSpec(delay_ms=5.0), True),
            ("scb", LinkSpec(delay_ms=5.0), True)]
        report = json.loads(events.report())
    assert [(r["started_t_s"], r["ended_t_s"]) for r in report] == [(30.0, 60.0), (41.0, 46.0)]


def test_an_event_still_on_at_the_end_is_undone() -> None:
    lab = load_host_map(LAB).with_events([parse_link_event("sca:cut:10:1000")])
    net = _Links()
    with LinkEvents(net, lab) as events:  # type: ignore[arg-type]
        events.on_waiting("link 0: awaiting lost:sc1,sc2:10.0", 10.0)
    assert net.calls == [("sca", LinkSpec(), False), ("sca", LinkSpec(), True)]


@pytest.mark.parametrize("host, says", [("ground", "is the hub"), ("sim", "not the sim's")])
def test_a_rehearsal_cuts_only_a_host_of_spacecraft(host: str, says: str) -> None:
    lab = load_host_map(LAB).with_events([parse_link_event(f"{host}:cut:10:5")])
    with pytest.raises(ValueError, match=says):
        check_cuts(lab)
    check_cuts(load_host_map(LAB).with_events([parse_link_event(f"{host}:delay=50:10:5")]))


class _Broken:
    """A network that refuses every change (its switch gone)."""

    def set_link(self, host: str, link: LinkSpec, up: bool = True) -> None:
        raise RehearsalError("no answer from the wire")


def test_a_link_change_the_network_refuses_is_kept_never_raised() -> None:
    lab = load_host_map(LAB).with_events([parse_link_event("sca:cut:10:5")])
    with LinkEvents(_Broken(), lab) as events:  # type: ignore[arg-type]
        events.on_waiting("link 0: awaiting lost:sc1,sc2:10.0", 10.0)
    assert len(events.failures) == 2 and "link of sca not changed at sim t=10.0 s" in (
        events.failures[0])
