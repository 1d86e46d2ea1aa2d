"""``ground_contact``: when the ground heard the constellation and what waited for it, present
when the scenario has ground passes (``[ground] contact = "passes"``)."""

from __future__ import annotations

from pydantic import Field

from harness.summary.records import SummaryRecord
from interfaces.contracts.messages import StoreCounter


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
