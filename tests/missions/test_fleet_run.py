"""Spacecraft that share a process step together (interfaces/runtime/fleet.py): what each
spacecraft's apps see and publish is the same whether it steps in a fleet or alone."""

from __future__ import annotations

from collections import defaultdict
from typing import Any

from deploy.inproc import run_inproc
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import Message
from interfaces.contracts.scenario import Scenario
from interfaces.runtime.transport import Sample
from tests.conftest import small_scenario


def _what_each_key_carries(scenario: Scenario, fleet: bool) -> dict[str, list[dict[str, Any]]]:
    """Every message of an in-process run by key, in order, without its wall-clock fields
    (and without the executives' own statistics, which are wall times)."""
    out: dict[str, list[dict[str, Any]]] = defaultdict(list)

    def tap(sample: Sample) -> None:
        msg = sample.message
        assert msg is not None
        if cat.topic_of(sample.key) is not cat.EXEC_STATS:
            out[sample.key].append(_timeless(msg))

    run_inproc(scenario, sample_tap=tap, fleet=fleet)
    return out


def _timeless(msg: Message) -> dict[str, Any]:
    return msg.model_dump(exclude={"t_wall", *getattr(msg, "WALL_CLOCK_FIELDS", ())})


def test_a_fleet_changes_no_message_any_spacecraft_sees_or_publishes() -> None:
    """The same run with the spacecraft stepping together and each alone: every key carries
    the same messages in the same order (only their interleaving across keys differs)."""
    scenario = small_scenario("fleet", duration_s=40.0)
    together = _what_each_key_carries(scenario, fleet=True)
    alone = _what_each_key_carries(scenario, fleet=False)
    assert together.keys() == alone.keys()
    assert any(k.endswith("/camera/observations") for k in together)
    for key in together:
        assert together[key] == alone[key], key
