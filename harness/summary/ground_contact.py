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
from links.data_budget import budget


class PassRecord(SummaryRecord):
    """One pass of a station over the target (``gnc.passes.ContactWindow``), clipped to the
    run."""

    station: str
    aos_s: float = Field(description="acquisition of signal, sim s")
    los_s: float = Field(description="loss of signal, sim s")
    duration_s: float
    tca_s: float = Field(description="time of the highest elevation, sim s")
    max_elevation_deg: float


class DataBudgetRecord(SummaryRecord):
    """Each observer's data budget (``links.data_budget``): the design's estimate, and each
    store's measured bytes per second by topic over the run."""

    estimated_Bps: dict[str, float] = Field(
        description="bytes per second one observer stores for the ground, by topic, estimated "
                    "from the scenario before the run")
    estimated_peak_bytes: float = Field(description="the store's estimated peak over the run")
    holds: bool = Field(description="the store holds the estimated peak")
    measured_Bps: dict[str, dict[str, float]] = Field(
        description="by spacecraft node, then topic: bytes per second offered to its store")
    measured_peak_bytes: dict[str, int] = Field(
        description="by spacecraft node: the most its store held at once")


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
    data_budget: DataBudgetRecord | None = Field(
        default=None, description="absent from summaries before the data budget")


def ground_contact(scenario: Scenario, links: list[LinkCounter]) -> GroundContact | None:
    """The section for a scenario with ground passes (None without)."""
    plan = ContactPlan.of(scenario)
    if plan is None:
        return None
    table = scenario_pass_table(scenario)
    stores = {c.src: c.store for c in links if c.dst == GROUND and c.store is not None}
    return GroundContact(
        passes=[PassRecord(station=w.station, aos_s=round(w.aos_s, 3), los_s=round(w.los_s, 3),
                           duration_s=round(w.duration_s, 3), tca_s=round(w.tca_s, 3),
                           max_elevation_deg=round(w.max_elevation_deg, 2)) for w in table],
        longest_gap_s=round(longest_gap(plan, scenario.duration_s), 3),
        downlink_bps=scenario.ground.downlink_bps, store_bytes=scenario.ground.store_bytes,
        stores=stores,
        uplink_held={c.dst: c.held for c in links if c.src == GROUND and c.held is not None},
        data_budget=data_budget_record(scenario, stores))


def data_budget_record(scenario: Scenario, stores: dict[str, StoreCounter]
                       ) -> DataBudgetRecord | None:
    """The ``data_budget`` of a run with ground passes (None without)."""
    estimate = budget(scenario)
    if estimate is None:
        return None
    per_s = 1.0 / scenario.duration_s
    return DataBudgetRecord(
        estimated_Bps={k: round(v, 1) for k, v in estimate.rates_Bps.items()},
        estimated_peak_bytes=round(estimate.peak_bytes), holds=estimate.holds,
        measured_Bps={src: {k: round(v * per_s, 1) for k, v in c.offered_bytes_by_topic.items()}
                      for src, c in stores.items()},
        measured_peak_bytes={src: c.peak_bytes for src, c in stores.items()})


def longest_gap(plan: ContactPlan, duration_s: float) -> float:
    """The longest stretch of [0, duration_s] out of contact, s."""
    edges = [0.0, *(t for w in plan.windows for t in w), duration_s]
    return max((b - a for a, b in zip(edges[0::2], edges[1::2], strict=False)), default=duration_s)
