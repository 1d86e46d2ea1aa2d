"""Information-cost app: the spacecraft's share of the inspection (paper Eq. 8, Sec. III.A).

Rate group mid (ω_mid). Input: the observations of every observer (its own, and a neighbour's
only while in communication range: the channel decides), leaving out an observer this
spacecraft's neighbours' FDIR declared until the ground overrules it
(``fsw/apps/neighbours.py``). Output: at every FDI window boundary
(``interfaces.contracts.fdi_schedule``, every ``rates.fdi_period_s``) the information-cost
telemetry to the ground — its contribution H_i, the cost H and prior term of its fused view,
every contribution H_j as fused here, and counts."""

from __future__ import annotations

from collections.abc import Callable

from fsw.lib.neighbour_judge import Exclusions
from gnc.poi_map import PoiMap
from interfaces.contracts import catalogue as cat
from interfaces.contracts.fdi_schedule import FdiSchedule
from interfaces.contracts.messages import (
    InfoCostTelemetry,
    NeighbourDeclaration,
    NeighbourRuling,
    PoiObservations,
)
from interfaces.runtime.app import App, AppContext, Input, Output


class InfoCostApp(App):
    NAME = "infocost"
    RATE = "mid"
    INPUTS = (Input(cat.OBSERVATIONS, "on_observations", every_spacecraft=True),
              Input(cat.NEIGHBOUR_DECLARATION, "on_declaration"),
              Input(cat.NEIGHBOUR_RULING, "on_ruling"))
    OUTPUTS = (Output("telemetry", cat.INFO_COST),)
    CRITICAL = ("map", "last_boundary", "images", "shared", "shared_by", "rejected",
                "exclusions")
    REBUILT = ("report_factor",)  # the software-fault hook, set at start (fsw/spacecraft.py)

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        sc = ctx.scenario
        self.sc_id = ctx.spacecraft or 0
        self.map = PoiMap.uniform(sc.target.pois, sc.target.prior_variance, sc.observers.count)
        self.schedule = FdiSchedule(sc.rates.fdi_period_s)
        self.last_boundary = -1
        """the FDI window boundary last reported (``interfaces.contracts.fdi_schedule``)"""
        self.images = 0
        self.shared = 0
        self.shared_by: dict[int, int] = {}
        """the neighbours' images fused, by spacecraft id"""
        self.rejected = 0
        """observations dropped for naming a spacecraft outside the constellation"""
        self.exclusions = Exclusions()
        """observers left out of the fusion since the neighbours declared them"""
        self.report_factor: Callable[[float], float] = lambda t: 1.0
        """Factor on the reported H_i at time t: 1 unless the harness injects ``faulty_data``
        (faults/software.py)."""

    def on_observations(self, msg: PoiObservations) -> None:
        if msg.spacecraft > self.map.n_agents:  # a hostile or corrupted id: dropped, counted
            self.rejected += 1
            self.log.warning("dropped observations of spacecraft %d: the constellation has %d "
                             "(%d dropped)", msg.spacecraft, self.map.n_agents, self.rejected)
            return
        if msg.spacecraft != self.sc_id and not self.exclusions.admits(msg):
            return
        self.map.add(msg.spacecraft, *msg.arrays())
        if msg.spacecraft == self.sc_id:
            self.images += 1
        else:
            self._shared(msg.spacecraft)

    def on_declaration(self, msg: NeighbourDeclaration) -> None:
        self.exclusions.declared(msg, self.sc_id)

    def on_ruling(self, msg: NeighbourRuling) -> None:
        for m in self.exclusions.ruled(msg):
            self.map.add(m.spacecraft, *m.arrays())
            self._shared(m.spacecraft)

    def step(self, t: float) -> None:
        j = self.schedule.boundary_at(t)
        if j is None or j <= self.last_boundary:
            return
        self.last_boundary = j
        h_j = self.map.contributions()
        self.publish("telemetry", InfoCostTelemetry(
            sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id,
            h_i=float(h_j[self.sc_id - 1]) * self.report_factor(t),
            h_local=self.map.cost(), prior_term=self.map.prior_term(),
            contributions={str(j + 1): float(h) for j, h in enumerate(h_j)},
            pois_seen_own=self.map.seen(self.sc_id), pois_seen_fused=self.map.seen(),
            images=self.images, shared_received=self.shared,
            shared_by={str(k): n for k, n in sorted(self.shared_by.items())}))

    def _shared(self, source: int) -> None:
        """Count a neighbour's image fused."""
        self.shared += 1
        self.shared_by[source] = self.shared_by.get(source, 0) + 1
