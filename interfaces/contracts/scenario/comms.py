"""The links between nodes, as the channel stage models them (``links/channel.py``):
range, loss, bursts, delay, scheduled cuts."""

from __future__ import annotations

import math
import re

from pydantic import ConfigDict, Field, model_validator

from interfaces.contracts.scenario.base import Section


class Burst(Section):
    """Gilbert-Elliott burst loss: the average loss rate is ``comms.packet_loss``; losses come in
    bursts of geometric length with this mean (packets)."""

    mean_length_packets: float = Field(ge=1.0)


class LinkCut(Section):
    """Cut the link between nodes ``a`` and ``b`` ("sc<N>", "ground" or "*" for any) over
    [start_s, end_s)."""

    a: str
    b: str = "*"
    start_s: float = Field(default=0.0, ge=0.0)
    end_s: float = math.inf

    @model_validator(mode="after")
    def _nodes(self) -> LinkCut:
        for n in (self.a, self.b):
            if not re.fullmatch(r"sc\d+|ground|\*", n):
                raise ValueError(f"link cut end {n!r}: expected 'sc<N>', 'ground' or '*'")
        if self.end_s <= self.start_s:
            raise ValueError("link cut end_s must be after start_s")
        return self

    model_config = ConfigDict(extra="forbid", allow_inf_nan=True, frozen=True)


class Comms(Section):
    """Inter-spacecraft and spacecraft-ground links.  The ground is reached through the target
    spacecraft (the mothership relay at the LVLH origin), so a spacecraft is in ground contact when
    it is within ``range_m`` of the target."""

    range_m: float = Field(default=200.0, gt=0.0)
    packet_loss: float = Field(default=0.0, ge=0.0, lt=1.0)
    burst: Burst | None = None
    delay_s: float = Field(default=0.0, ge=0.0)
    cuts: list[LinkCut] = Field(default_factory=list)
