"""Host maps (deploy/host_map.py, docs/hosts.md): the maps shipped load, bad maps are refused at
load naming the key, and a map is checked against the run's spacecraft."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from deploy.host_map import (
    HostMapError,
    LinkEvent,
    LinkSpec,
    load_host_map,
    parse_host_map,
    parse_link_event,
)
from tests.conftest import REPO

FIVE = ["sc1", "sc2", "sc3", "sc4", "sc5", "ground"]


def _map(**changes: Any) -> dict[str, Any]:
    """A valid two-host map, with ``changes`` made to its top level."""
    data: dict[str, Any] = {"name": "t", "hosts": [
        {"name": "ground", "address": "10.77.0.1", "nodes": ["ground", "recorder", "sim"]},
        {"name": "sca", "address": "10.77.0.11", "nodes": ["sc1", "sc2"],
         "link": {"delay_ms": 5.0}}]}
    data.update(changes)
    return data


def _refused(data: dict[str, Any]) -> str:
    with pytest.raises(HostMapError) as e:
        parse_host_map(data, "m.toml")
    return str(e.value)


def test_the_shipped_maps_load_and_place_every_node() -> None:
    lab = load_host_map(REPO / "deploy" / "hosts" / "lab.toml")
    assert [h.name for h in lab.hosts] == ["ground", "sim", "sca", "scb"]
    assert lab.hub.name == "ground" and lab.host_of("sc4").name == "scb"
    lab.check_run(FIVE)
    trio = load_host_map(REPO / "deploy" / "hosts" / "trio.toml")
    trio.check_run(["sc1", "sc2", "ground"])
    assert all(h.link.delay_ms == 2.0 for h in trio.hosts)


@pytest.mark.parametrize(("hosts", "key", "says"), [
    ([{"name": "g", "address": "10.77.0.1", "nodes": ["ground", "recorder", "sim", "camera"]}],
     "hosts[g].nodes", "unknown node 'camera'"),
    ([{"name": "g", "address": "10.77.0.1", "nodes": ["ground", "recorder", "sim", "sc1"]},
      {"name": "a", "address": "10.77.0.2", "nodes": ["sc1"]}],
     "hosts[a].nodes", "sc1 is on two hosts, g and a"),
    ([{"name": "g", "nodes": ["ground", "recorder", "sim"]}], "hosts[g].address",
     "missing (required)"),
    ([{"name": "g", "address": "10.77.0.1", "nodes": ["ground", "recorder", "sim"],
       "link": {"delay_ms": -1.0}}], "hosts[g].link.delay_ms = -1.0",
     "should be greater than or equal to 0"),
    ([{"name": "g", "address": "10.77.0.1", "nodes": ["ground", "recorder", "sim"],
       "link": {"loss_pct": 120}}], "hosts[g].link.loss_pct = 120",
     "should be less than or equal to 100"),
    ([{"name": "g", "address": "10.9.0.1", "nodes": ["ground", "recorder", "sim"]}],
     "hosts[g].address", "not a host address of network 10.77.0.0/24"),
    ([{"name": "g", "address": "10.77.0.1", "nodes": ["ground", "sim"]}],
     "hosts", "no host runs recorder"),
    ([{"name": "g", "address": "10.77.0.1", "nodes": ["ground", "recorder", "sim"]},
      {"name": "g", "address": "10.77.0.2", "nodes": ["sc1"]}], "hosts", "names must differ"),
    ([{"name": "Ground!", "address": "10.77.0.1", "nodes": ["ground", "recorder", "sim"]}],
     "hosts[Ground!].name = 'Ground!'", "should match pattern"),
    ([{"name": "g", "address": "10.77.0.1", "nodes": ["ground", "recorder", "sim"],
       "cores": 4}], "hosts[g].cores", "unknown key (known: name, address, nodes, link)"),
])
def test_a_bad_map_is_refused_at_load_naming_the_key(hosts: list[dict[str, Any]], key: str,
                                                       says: str) -> None:
    message = _refused(_map(hosts=hosts))
    assert message.startswith(f"m.toml: {key}: ") and says in message, message
    assert "\n" not in message and "http" not in message


def test_events_name_a_host_of_the_map_and_do_something() -> None:
    assert _refused(_map(events=[{"host": "scaa", "at_s": 10, "duration_s": 30, "cut": True}])
                    ) == "m.toml: events[#1].host: no host 'scaa' in this map; did you mean " \
                         "'sca'? (hosts: ground, sca)"
    assert "no host 'xyz' in this map (hosts: ground, sca)" in _refused(_map(events=[
        {"host": "xyz", "at_s": 10, "duration_s": 30, "cut": True}]))
    assert "cuts the link" in _refused(_map(events=[
        {"host": "sca", "at_s": 10, "duration_s": 30}]))
    assert "events[#1].duration_s = 0" in _refused(_map(events=[
        {"host": "sca", "at_s": 10, "duration_s": 0, "cut": True}]))
    assert "events[#2]: overlaps events[#1] on host sca" in _refused(_map(events=[
        {"host": "sca", "at_s": 10, "duration_s": 30, "cut": True},
        {"host": "sca", "at_s": 39, "duration_s": 5, "delay_ms": 50}]))
    parse_host_map(_map(events=[{"host": "sca", "at_s": 10, "duration_s": 30, "cut": True},
                                {"host": "sca", "at_s": 40, "duration_s": 5, "loss_pct": 5},
                                {"host": "ground", "at_s": 20, "duration_s": 5,
                                 "loss_pct": 5}]), "m.toml")


def test_a_file_that_is_not_toml_or_not_there(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("name = [", encoding="utf-8")
    with pytest.raises(HostMapError, match="not valid TOML"):
        load_host_map(bad)
    with pytest.raises(HostMapError, match="cannot read host map"):
        load_host_map(tmp_path / "none.toml")


def test_the_map_must_hold_exactly_the_runs_spacecraft() -> None:
    two = parse_host_map(_map(), "m.toml")
    two.check_run(["sc1", "sc2", "ground"])
    with pytest.raises(HostMapError, match="sc2 not in this run"):
        two.check_run(["sc1", "ground"])
    with pytest.raises(HostMapError, match="no host runs sc3"):
        two.check_run(["sc1", "sc2", "sc3", "ground"])


def test_an_event_at_or_after_the_runs_end_is_refused_naming_it() -> None:
    events = [{"host": "sca", "at_s": 10, "duration_s": 30, "cut": True},
              {"host": "sca", "at_s": 100, "duration_s": 5, "loss_pct": 5}]
    two = parse_host_map(_map(events=events), "m.toml")
    two.check_run(["sc1", "sc2", "ground"], duration_s=100.5)
    two.check_run(["sc1", "sc2", "ground"])  # the run's length not given: not checked
    for duration_s in (100.0, 50.0):
        with pytest.raises(HostMapError) as e:
            two.check_run(["sc1", "sc2", "ground"], duration_s=duration_s)
        assert str(e.value) == (f"host map t: events[#2] (host sca) at_s = 100: not before the "
                                f"end of the run (duration_s = {duration_s:g})")


def test_link_options_set_every_host_and_keep_the_rest() -> None:
    two = parse_host_map(_map(), "m.toml").with_links(20.0, None)
    assert [h.link for h in two.hosts] == [LinkSpec(delay_ms=20.0)] * 2
    lossy = two.with_links(None, 2.0)
    assert all(h.link.delay_ms == 20.0 and h.link.loss_pct == 2.0 for h in lossy.hosts)
    with pytest.raises(ValueError, match="greater than or equal to 0"):
        two.with_links(-5.0, None)


def test_link_events_from_the_command_line() -> None:
    cut = parse_link_event("sca:cut:600:30")
    assert cut == LinkEvent(host="sca", at_s=600.0, duration_s=30.0, cut=True)
    slow = parse_link_event("sca:delay=50:10:5")
    assert slow.during(LinkSpec(delay_ms=5.0, loss_pct=1.0)) == LinkSpec(delay_ms=50.0,
                                                                          loss_pct=1.0)
    assert parse_link_event("scb:loss=10:0:1").loss_pct == 10.0
    for bad in ("sca:cut:600", "sca:cut=1:600:30", "sca:slow=5:1:1", "sca:delay=-1:1:1",
                "sca:cut:x:30"):
        with pytest.raises(ValueError, match="--link-event"):
            parse_link_event(bad)
    added = parse_host_map(_map(), "m.toml").with_events([cut])
    assert added.events == [cut]
    with pytest.raises(HostMapError) as e:
        added.with_events([parse_link_event("scaa:cut:1:1")])
    assert str(e.value) == ("--link-event (host map t): events[#2].host: no host 'scaa' in this "
                            "map; did you mean 'sca'? (hosts: ground, sca)")
