"""Replay (harness/replay.py) without a run: what it drops unread no ground app reads, and
settings that would change what was flown are refused (replays of a recorded run:
tests/missions/test_replay.py)."""

from __future__ import annotations

import pytest

from harness.replay import UNREAD, with_settings
from interfaces.contracts import catalogue as cat
from interfaces.contracts.apps import GROUND_APPS
from interfaces.contracts.scenario import Scenario, ScenarioError
from interfaces.runtime.assembly import app_class
from tests.conftest import small_scenario


def _scenario(**fdir: object) -> Scenario:
    """The scenario the replays fly (tests/missions/test_replay.py): lossy, range-limited and cut
    links and three faults, judged by the window test (whose persistence a replay varies;
    the sequential test's replay: tests/missions/test_fdir_sequential_run.py), with ``fdir``
    settings."""
    return small_scenario(
        "replay", duration_s=400.0, target={"pois": 1000},
        rates={"high_hz": 5.0, "fdi_period_s": 50.0},
        observers={"count": 3, "initial_attitude": "lvlh"},
        comms={"range_m": 39.0, "packet_loss": 0.15, "burst": {"mean_length_packets": 3.0},
               "cuts": [{"a": "sc3", "b": "ground", "start_s": 120.0, "end_s": 180.0}]},
        faults=[{"spacecraft": 2, "kind": "camera_degradation", "start_s": 0.0, "magnitude": 0.5},
                {"spacecraft": 1, "kind": "faulty_data", "start_s": 150.0, "magnitude": 2.0},
                {"spacecraft": 3, "kind": "link_loss", "start_s": 250.0, "end_s": 330.0}],
        fdir={"detector": "window", **fdir})


def test_what_a_replay_drops_unread_no_ground_app_reads() -> None:
    """The ground's own channel counters (which the FDIR reads with ground passes) are made
    again by the replay's own channel stage, from the archive's messages: the archived ones
    are not needed."""
    ground_inputs = {i.topic for app in map(app_class, GROUND_APPS) for i in app.INPUTS}
    assert ground_inputs and not (ground_inputs - {cat.LINK_STATS}) & set(UNREAD)
    assert cat.TRUTH not in UNREAD and cat.TICK not in UNREAD


def test_settings_that_change_the_flight_are_refused() -> None:
    sc = _scenario()
    assert with_settings(sc, {"fdir.floor": "0.07"}).fdir.floor == 0.07
    assert with_settings(sc, {"rates.fdi_period_s": "25"}).rates.fdi_period_s == 25.0
    with pytest.raises(ScenarioError, match="changes what was flown"):
        with_settings(sc, {"comms.packet_loss": "0.5"})
    with pytest.raises(ScenarioError, match="no such setting"):
        with_settings(sc, {"fdir.nope": "1"})
    with pytest.raises(ScenarioError, match="greater than or equal"):
        with_settings(sc, {"fdir.floor": "-1"})
