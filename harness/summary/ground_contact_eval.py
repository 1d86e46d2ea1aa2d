"""The ``ground_contact`` section of summary.json (``run_summary/passes.py``) from the
scenario's pass table (``gnc.passes``) and the links' last counters."""

from __future__ import annotations

from gnc.passes import ContactPlan, scenario_pass_table
from harness.summary.ground_contact import GroundContact, PassRecord
from interfaces.contracts.messages import LinkCounter
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topics import GROUND


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
    return max((b - a for a, b in zip(edges[0::2], edges[1::2])), default=duration_s)
