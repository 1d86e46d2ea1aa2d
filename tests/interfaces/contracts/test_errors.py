"""Validation errors a user reads once (interfaces/contracts/errors.py), as a table: each bad
input, through the loader a command uses, gives exactly one line naming the key and the value
-- at a union, the branch the input was written for; "did you mean" for a misspelt name --
and no input dict, link or colour code."""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

import pytest
from pydantic import BaseModel, ValidationError, field_validator

from deploy.campaign_file import Campaign
from deploy.host_map import HostMapError, parse_host_map, parse_link_event
from harness.replay import with_settings
from interfaces.contracts.errors import describe, lines
from interfaces.contracts.scenario import ScenarioError, parse_scenario
from tests.conftest import small_scenario

SCENARIO = 'name = "x"\nduration_s = 100\n'
FAULT = '[[faults]]\nspacecraft = 1\nkind = "thruster_bias"\nstart_s = 10\nmagnitude = 0.3\n'
CAMPAIGN = {"name": "c", "base": "b.toml", "groups": [{"name": "g", "faults": [
    {"spacecraft": 1, "kind": "thruster_bias", "start_s": 10.0, "magnitude": 0.3}]}]}
HOSTS = {"name": "m", "hosts": [
    {"name": "ground", "address": "10.77.0.1", "nodes": ["ground", "recorder", "sim"]},
    {"name": "sca", "address": "10.77.0.11", "nodes": ["sc1"]}]}


def _scenario(text: str) -> str:
    with pytest.raises(ScenarioError) as e:
        parse_scenario(SCENARIO + text, "s.toml")
    return str(e.value)


def _campaign(fault: dict[str, Any]) -> str:
    data = {**CAMPAIGN, "groups": [{"name": "g", "faults": [
        {**CAMPAIGN["groups"][0]["faults"][0], **fault}]}]}  # type: ignore[index]
    with pytest.raises(ValidationError) as e:
        Campaign.model_validate(data)
    return describe(e.value, "c.toml", Campaign, data)


def _hosts(edit: Callable[[dict[str, Any]], None]) -> str:
    data = copy.deepcopy(HOSTS)
    edit(data)
    with pytest.raises(HostMapError) as e:
        parse_host_map(data, "m.toml")
    return str(e.value)


def _refused(call: Callable[[], object]) -> str:
    with pytest.raises(ValueError) as e:
        call()
    return str(e.value)


CASES: list[tuple[str, Callable[[], str], str]] = [
    ("misspelt fault kind", lambda: _scenario(FAULT.replace("thruster_bias", "thruster_bais")),
     "s.toml: faults[#1].kind = 'thruster_bais': unknown; did you mean 'thruster_bias'?"),
    ("misspelt fault key", lambda: _scenario(FAULT + "magnitud = 0.2\n"),
     "s.toml: faults[#1].magnitud: unknown key; did you mean 'magnitude'?"),
    ("fault without kind", lambda: _scenario(FAULT.replace('kind = "thruster_bias"\n', "")),
     "s.toml: faults[#1].kind: missing (required)"),
    ("NaN magnitude", lambda: _scenario(FAULT.replace("0.3", "nan")),
     "s.toml: faults[#1].magnitude = nan: should be a finite number"),
    ("misspelt top key", lambda: _refused(lambda: parse_scenario('name = "x"\nduraton_s = 100\n',
                                                                 "s.toml")),
     "s.toml: duraton_s: unknown key; did you mean 'duration_s'?"),
    ("misspelt section", lambda: _scenario("[fdri]\nfloor = 0.1\n"),
     "s.toml: fdri: unknown key; did you mean 'fdir'?"),
    ("misspelt detector", lambda: _scenario('[fdir]\ndetector = "windw"\n'),
     "s.toml: fdir.detector = 'windw': unknown; did you mean 'window'?"),
    ("a choice far from any", lambda: _scenario('[fdir]\ndetector = "cusum"\n'),
     "s.toml: fdir.detector = 'cusum': one of window, sequential"),
    ("count as text", lambda: _scenario('[observers]\ncount = "five"\n'),
     "s.toml: observers.count = 'five': should be a valid integer, unable to parse string as "
     "an integer"),
    ("fault on a spacecraft the run has not", lambda: _scenario(FAULT.replace(
        "spacecraft = 1", "spacecraft = 9")),
     "s.toml: fault on spacecraft 9 but observers.count = 5"),
    ("a station named", lambda: _scenario('[[ground.stations]]\nname = "gs"\nlatitude_deg = 95\n'
                                          'longitude_deg = 0\n'),
     "s.toml: ground.stations[gs].latitude_deg = 95: should be less than or equal to 90"),
    ("inverted range: one line of six", lambda: _campaign({"magnitude": {"min": 0.7,
                                                                          "max": 0.1}}),
     "c.toml: groups[g].faults[#1].magnitude: range max 0.1 is below min 0.7"),
    ("range above the kind's limit", lambda: _campaign({"magnitude": {"min": 0.2, "max": 1.5}}),
     "c.toml: groups[g].faults[#1]: magnitude range max = 1.5: thruster_bias magnitude must "
     "be in (0, 1] (a leak, fraction of the maximum thrust), got 1.5"),
    ("misspelt kind in a campaign", lambda: _campaign({"kind": "thruster_bais"}),
     "c.toml: groups[g].faults[#1].kind = 'thruster_bais': unknown; did you mean "
     "'thruster_bias'?"),
    ("misspelt kind in a choice", lambda: _campaign({"kind": {"choose": ["pointng_actuator"]}}),
     "c.toml: groups[g].faults[#1].kind.choose[#1] = 'pointng_actuator': unknown; did you mean "
     "'pointing_actuator'?"),
    ("misspelt key of a range", lambda: _campaign({"magnitude": {"min": 0.1, "mx": 0.5}}),
     "c.toml: groups[g].faults[#1].magnitude.mx: unknown key; did you mean 'max'?"),
    ("NaN bound", lambda: _campaign({"start_s": {"min": float("nan"), "max": 5.0}}),
     "c.toml: groups[g].faults[#1].start_s.min = nan: should be a finite number"),
    ("unknown node", lambda: _hosts(lambda d: d["hosts"][1]["nodes"].append("grund")),
     "m.toml: hosts[sca].nodes: unknown node 'grund'; did you mean 'ground'? (a host runs sim, "
     "ground, recorder or spacecraft sc<N>)"),
    ("misspelt host key", lambda: _hosts(lambda d: d["hosts"][1].update(
        adress=d["hosts"][1].pop("address"))),
     "m.toml: hosts[sca].adress: unknown key; did you mean 'address'?"),
    ("a second host counted from 1", lambda: _hosts(lambda d: d["hosts"].append(
        {"address": "10.77.0.12", "nodes": ["sc2"]})),
     "m.toml: hosts[#3].name: missing (required)"),
    ("link event out of range", lambda: _refused(lambda: parse_link_event("sca:loss=150:10:5")),
     "--link-event 'sca:loss=150:10:5': loss_pct = '150': should be less than or equal to 100"),
    ("--set a word for a number", lambda: _refused(lambda: with_settings(
        small_scenario(), {"fdir.floor": "abc"})),
     "--set: fdir.floor = 'abc': should be a valid number, unable to parse string as a number"),
    ("--set a misspelt choice", lambda: _refused(lambda: with_settings(
        small_scenario(), {"fdir.detector": "windw"})),
     "--set: fdir.detector = 'windw': unknown; did you mean 'window'?"),
    ("--set a misspelt setting", lambda: _refused(lambda: with_settings(
        small_scenario(), {"fdir.flor": "0.1"})),
     "--set fdir.flor: no such setting in [fdir]; did you mean 'floor'?"),
]


@pytest.mark.parametrize("said, line", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_each_bad_input_is_one_line_naming_the_key_and_the_value(said: Callable[[], str],
                                                                   line: str) -> None:
    message = said()
    assert message == line
    assert not any(noise in message for noise in ("\n", "http", "{'", "input_value", "\x1b"))


class _Coloured(BaseModel):
    name: str

    @field_validator("name")
    @classmethod
    def _red(cls, name: str) -> str:
        raise ValueError(f"\x1b[31m{name}\x1b[0m is taken,\n  choose another")


def test_colour_codes_and_line_breaks_never_reach_the_line() -> None:
    with pytest.raises(ValidationError) as e:
        _Coloured.model_validate({"name": "sc1"})
    assert lines(e.value, "x") == ["x: name: sc1 is taken, choose another"]


def test_every_distinct_error_has_its_line_and_the_first_comes_first() -> None:
    text = SCENARIO + "[rates]\nhigh_hz = 0\n[fdir]\nflor = 1\n"
    assert _refused(lambda: parse_scenario(text, "s.toml")).split("\n") == [
        "s.toml: rates.high_hz = 0: should be greater than 0",
        "s.toml: fdir.flor: unknown key; did you mean 'floor'?"]
