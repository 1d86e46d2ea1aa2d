"""summary.json's ``ground_contact`` section: when the ground heard the constellation and what
waited for it, present when the scenario has ground passes (``[ground] contact = "passes"``);
from the scenario's pass table (``gnc.passes``) and the links' last counters."""

from __future__ import annotations

from pydantic import Field

from gnc.passes import ContactPlan, scenario_pass_table
from harness.summary.records import SummaryRecord
from interfaces.contracts.messages import LinkCounter, StoreCounter
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topics import GROUND


class PassRecord(SummaryRecord):
    """One pass of a station over the target (``gnc.passes.ContactWindow``), clipped to the
    run."""

    station: str
    aos_s: float = Field(description="acquisition of signal, sim s")
    los_s: float = Field(description="loss of signal, sim s")
    duration_s: float
    tca_s: float = Field(description="time of the highest elevation, sim s")
    max_elevation_deg: float


class GroundContact(SummaryRecord):
    """The pass table, the longest time the ground heard nothing, and each spacecraft's
    onboard store and uplink waits at the end of the run (the ground's channel counters)."""

    passes: list[PassRecord]
    longest_gap_s: float = Field(description="longest time without contact in the run, s")
    downlink_bps: float
    store_bytes: int
    stores: dict[str, StoreCounter] = Field(description="by spacecraft node")
    uplink_held: dict[str, int] = Field(
        description="by spacecraft node: messages that waited on the ground for a pass")


def ground_contact(scenario: Scenario, links: list[LinkCounter]) -> GroundContact | None:
    """The section for a scenario with ground passes (None without)."""
    plan = ContactPlan.of(scenario)
    if plan is None:
        return None
    table = scenario_pass_table(scenario)
    return GroundContact(
        passes=[PassRecord(station=w.station, aos_s=round(w.aos_s, 3), los_s=round(w.los_s, 3),
                           duration_s=round(w.duration_s, 3), tca_s=round(w.tca_s, 3),
                           max_elevation_deg=round(w.max_elevation_deg, 2)) for w in table],
        longest_gap_s=round(longest_gap(plan, scenario.duration_s), 3),
        downlink_bps=scenario.ground.downlink_bps, store_bytes=scenario.ground.store_bytes,
        stores={c.src: c.store for c in links if c.dst == GROUND and c.store is not None},
        uplink_held={c.dst: c.held for c in links if c.src == GROUND and c.held is not None})


def longest_gap(plan: ContactPlan, duration_s: float) -> float:
    """The longest stretch of [0, duration_s] out of contact, s."""
    edges = [0.0, *(t for w in plan.windows for t in w), duration_s]
    return max((b - a for a, b in zip(edges[0::2], edges[1::2], strict=False)), default=duration_s)
