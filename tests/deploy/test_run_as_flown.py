"""One check, on the run as it will fly, as tables: the command line's seed and duration applied
before the scenario is checked (interfaces/contracts/scenario/model.py); a campaign's drawn
ranges checked as written, both bounds against the setting's own limits, at load
(deploy/draws.py, deploy/campaign_file.py); link events checked against the run's duration
(deploy/host_map.py).  Each refusal is one line naming the key and the value."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from pydantic import ValidationError

from deploy.campaign_file import Campaign, FaultSpec
from deploy.draws import DrawError, check_settings, parse_tree
from deploy.host_map import HostMapError, parse_host_map
from interfaces.contracts.errors import describe
from interfaces.contracts.scenario import ScenarioError, load_scenario

NOMINAL = Path(__file__).resolve().parents[2] / "deploy" / "scenarios" / "nominal.toml"
LATE = '\n[[faults]]\nspacecraft = 1\nkind = "camera_degradation"\nstart_s = 1300\n' \
       'magnitude = 0.5\n'
"""A fault after the end of the paper's 1,200 s scenario."""


@pytest.mark.parametrize("seed, duration_s, says", [
    (None, 1400.0, None),
    (5, 1300.5, None),
    (None, None, "not before the end of the run (duration_s = 1200)"),
    (None, 1300.0, "with duration_s = 1300: a camera_degradation fault starts at 1300 s, not "
                   "before the end of the run (duration_s = 1300)"),
    (None, -5.0, "with duration_s = -5: duration_s = -5.0: should be greater than 0"),
    (None, float("nan"), "with duration_s = nan: duration_s = nan: should be a finite number"),
    (-1, 1400.0, "with seed = -1, duration_s = 1400: seed = -1: should be greater than or "
                 "equal to 0"),
])
def test_the_command_line_is_applied_before_the_scenario_is_checked(
        tmp_path: Path, seed: int | None, duration_s: float | None, says: str | None) -> None:
    path = tmp_path / "late.toml"
    path.write_text(NOMINAL.read_text() + LATE)
    if says is None:
        scenario = load_scenario(path, seed=seed, duration_s=duration_s)
        assert scenario.duration_s == duration_s and scenario.faults[0].start_s == 1300.0
        assert scenario.seed == (7 if seed is None else seed)  # nominal.toml's own seed: 7
        return
    with pytest.raises(ScenarioError) as e:
        load_scenario(path, seed=seed, duration_s=duration_s)
    assert str(e.value).startswith(str(path)) and str(e.value).endswith(says)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("overrides, says", [
    ({"comms": {"packet_loss": {"min": 0.2, "max": 0.9}}}, None),
    ({"orbit": {"raan_deg": {"min": 0.0, "max": 360.0}}}, None),  # draws stay below 360
    ({"observers": {"count": {"min": 2, "max": 6}}}, None),
    ({"comms": {"packet_loss": {"min": 0.2, "max": 1.5}}},
     "overrides.comms.packet_loss: range max = 1.5: should be less than 1"),
    ({"comms": {"packet_loss": {"min": -0.1, "max": 0.5}}},
     "overrides.comms.packet_loss: range min = -0.1: should be greater than or equal to 0"),
    ({"orbit": {"raan_deg": {"min": 0.0, "max": 361.0}}},
     "overrides.orbit.raan_deg: range max = 361.0: should be less than 360"),
    ({"observers": {"count": {"min": 0, "max": 3}}},
     "overrides.observers.count: range min = 0: should be greater than or equal to 1"),
    ({"duration_s": {"min": -10.0, "max": 100.0}},
     "overrides.duration_s: range min = -10.0: should be greater than 0"),
    ({"fdir": {"detector": {"choose": ["window", "windw"]}}},
     "overrides.fdir.detector.choose[#2] = 'windw': unknown; did you mean 'window'?"),
    ({"fdir": {"floor": -1.0}}, "overrides.fdir.floor = -1.0: should be greater than or "
                                "equal to 0"),
    ({"fdir": {"floor": {"min": float("nan"), "max": 1.0}}},
     "overrides.fdir.floor: range bounds must be finite numbers, got nan and 1.0"),
])
def test_drawn_settings_are_checked_as_written(overrides: dict[str, Any],
                                               says: str | None) -> None:
    def check() -> None:
        check_settings(parse_tree(overrides, "overrides"), "overrides")
    if says is None:
        check()
        return
    with pytest.raises(DrawError) as e:
        check()
    assert str(e.value) == says


FAULT = {"spacecraft": 1, "kind": "thruster_bias", "start_s": 10.0, "magnitude": 0.3}


@pytest.mark.parametrize("fault, says", [
    ({"magnitude": {"min": 0.2, "max": 0.9}}, None),
    ({"kind": "camera_degradation", "magnitude": {"min": 0.2, "max": 1.0}}, None),  # < 1 drawn
    ({"magnitude": {"min": 0.2, "max": 1.5}},
     "magnitude range max = 1.5: thruster_bias magnitude must be in (0, 1]"),
    ({"magnitude": {"min": 0.0, "max": 0.5}},
     "magnitude range min = 0: thruster_bias magnitude must be in (0, 1]"),
    ({"magnitude": [0.2, 1.2]}, "magnitude[#2] = 1.2: thruster_bias magnitude must be in (0, 1]"),
    ({"kind": ["thruster_bias", "pointing_actuator"], "magnitude": 5.0},
     "magnitude = 5 (kind thruster_bias): thruster_bias magnitude must be in (0, 1]"),
    ({"kind": "camera_degradation", "magnitude": {"per_kind": {"camera_degradation": {
        "min": 0.5, "max": 1.2}}}}, "magnitude range max = 1.2: camera_degradation magnitude "
                                    "must be in (0, 1)"),
    ({"kind": "state_disturbance", "magnitude": {"min": 1.0, "max": 5.0},
      "velocity_mps": {"min": 0.0, "max": 20.0}},
     "velocity_mps range max = 20: state_disturbance magnitude (m) and velocity_mps (m/s) must "
     "be in [0, 1000] and [0, 10]"),
    ({"start_s": {"min": -5.0, "max": 100.0}},
     "start_s range min = -5: should be greater than or equal to 0"),
    ({"start_s": {"min": 100.0, "max": 300.0}, "end_s": {"min": 200.0, "max": 400.0}},
     "end_s range min = 200: fault end_s must be after start_s"),
])
def test_a_faults_ranges_are_checked_as_written(fault: dict[str, Any], says: str | None) -> None:
    spec = {**FAULT, **fault}
    data = {"name": "c", "base": "b.toml", "groups": [{"name": "g", "faults": [spec]}]}
    if says is None:
        Campaign.model_validate(data)
        return
    with pytest.raises(ValidationError) as e:
        Campaign.model_validate(data)
    message = describe(e.value, "c.toml", Campaign, data)
    assert message.startswith(f"c.toml: groups[g].faults[#1]: {says}"), message
    assert "\n" not in message


@pytest.mark.parametrize("start_s, says", [
    ({"min": 100.0, "max": 1200.0}, None),  # draws stay below 1,200 s
    ([100.0, 1100.0], None),
    ({"min": 1100.0, "max": 1300.0},
     "start_s range max = 1300: not before the end of the run (duration_s = 1200)"),
    ([100.0, 1200.0], "start_s[#2] = 1200: not before the end of the run (duration_s = 1200)"),
    (1250.0, "start_s = 1250: not before the end of the run (duration_s = 1200)"),
])
def test_a_faults_latest_start_is_checked_against_the_run(start_s: Any, says: str | None) -> None:
    spec = FaultSpec.model_validate({**FAULT, "start_s": start_s})
    if says is None:
        spec.check_within(1200.0)
        return
    with pytest.raises(ValueError) as e:
        spec.check_within(1200.0)
    assert str(e.value) == says


HOSTS = {"name": "m", "hosts": [
    {"name": "ground", "address": "10.77.0.1", "nodes": ["ground", "recorder", "sim"]},
    {"name": "sca", "address": "10.77.0.11", "nodes": ["sc1"]}]}


@pytest.mark.parametrize("event, duration_s, says", [
    ({"at_s": 100.0, "duration_s": 5000.0}, 1200.0, None),  # may outlast the run
    ({"at_s": 1199.9, "duration_s": 5.0}, 1200.0, None),
    ({"at_s": 1200.0, "duration_s": 5.0}, 1200.0,
     "host map m: events[#1] (host sca) at_s = 1200: not before the end of the run "
     "(duration_s = 1200)"),
    ({"at_s": 5000.0, "duration_s": 10.0}, 600.0,
     "host map m: events[#1] (host sca) at_s = 5000: not before the end of the run "
     "(duration_s = 600)"),
])
def test_link_events_are_checked_against_the_run(event: dict[str, float], duration_s: float,
                                                 says: str | None) -> None:
    host_map = parse_host_map({**HOSTS, "events": [{"host": "sca", "cut": True, **event}]},
                              "m.toml")
    if says is None:
        host_map.check_run(["sc1", "ground"], duration_s)
        return
    with pytest.raises(HostMapError) as e:
        host_map.check_run(["sc1", "ground"], duration_s)
    assert str(e.value) == says
