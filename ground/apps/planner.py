"""Mission planner: the central agent's PRO assignments (Fig. 7 phases, Sec. II.C).

Rate group low.  Input: the observations of every observer (the ground is reached through the
target, so it hears every observer in range of it), fused into the ground's POI map.  Outputs:
``ProAssignments`` (every observer's current assignment) on ``ground/planner/assignments`` and
each information-driven ``AssignmentDecision`` on ``ground/planner/decisions``.

What to fly comes from :class:`ground.planning.mission_plan.MissionPlan`: the scenario's phases,
with ``assign = "information"`` phases chosen by expected information gain and reassigned when
the set's gain saturates, and -- with ``fdir.recovery`` -- a recovery assignment when the FDIR
reports an identified camera or actuator fault (input ``ground/fdir/report``), or a spacecraft's
onboard FDIR asks for a new plan naming one (input ``sc/N/fdir/event``, ``plan_request``).  An
assignment is uplinked from ``UPLINK_LEAD_S`` before its departure and repeated every cycle
until the next one supersedes it, so a command lost on the range-limited, lossy link is simply
received later (a spacecraft acts on a new ``assignment_id`` once).
"""

from __future__ import annotations

from gnc.poi_map import PoiMap
from ground.planning.mission_plan import MissionPlan
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    AssignmentDecision,
    FaultReport,
    OnboardFdirEvent,
    PoiObservations,
    ProAssignment,
    ProAssignments,
)
from interfaces.runtime.app import App, AppContext, Input, Output


class MissionPlanner(App):
    NAME = "planner"
    RATE = "low"
    INPUTS = (
        Input(cat.OBSERVATIONS, "on_observations", every_spacecraft=True),
        Input(cat.FAULT_REPORT, "on_fault"),
        Input(cat.FDIR_EVENT, "on_onboard", every_spacecraft=True),
    )
    OUTPUTS = (Output("assignments", cat.ASSIGNMENTS), Output("decisions", cat.DECISIONS))
    CRITICAL = ("plan", "map", "_decisions_sent", "_faults")

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        sc = ctx.scenario
        self.plan = MissionPlan(sc, ctx.constants)
        self.map = PoiMap.uniform(sc.target.pois, sc.target.prior_variance, sc.observers.count)
        self._decisions_sent = 0
        self._faults: list[tuple[int, str | None, dict[str, float]]] = []
        """(observer, class, evidence) to recover from at the next step"""

    def on_observations(self, msg: PoiObservations) -> None:
        if msg.spacecraft <= self.map.n_agents:
            self.map.add(msg.spacecraft, *msg.arrays())

    def on_fault(self, msg: FaultReport) -> None:
        if self.ctx.scenario.fdir.recovery and msg.spacecraft >= 1:  # 0: the constellation's
            self._faults.append((msg.spacecraft, msg.fault_class, dict(msg.evidence)))

    def on_onboard(self, msg: OnboardFdirEvent) -> None:
        """A spacecraft's plan request: recovered from as a declaration of its class (each
        observer is replanned once per class, whoever asks: ``MissionPlan.recover``)."""
        if (self.ctx.scenario.fdir.recovery and msg.event == "plan_request"
                and msg.fault_class is not None and msg.spacecraft <= self.map.n_agents):
            self._faults.append((msg.spacecraft, msg.fault_class, {}))

    def step(self, t: float) -> None:
        self.plan.update(t, self.map)
        faults, self._faults = self._faults, []
        if faults:
            try:
                if self.plan.recover(t, faults, self.map):
                    self.log.warning("recovery: replanned around %s", ", ".join(
                        f"sc{sc} ({c})" for sc, c, _ in faults))
            except ValueError as e:
                self.log.error("recovery impossible, plan unchanged: %s", e)
        for d in self.plan.decisions[self._decisions_sent:]:
            self.log.info("%s at %.0f s (%s): PROs %s, expected gain %.4g (bound %.4g, "
                          "current %s), %s", d.phase, d.t_s, d.reason, d.library_indices,
                          d.expected_gain, d.upper_bound,
                          "-" if d.current_gain is None else f"{d.current_gain:.4g}",
                          "issued" if d.switched else "kept the current set")
            self.publish("decisions", AssignmentDecision(
                sender=self.ctx.node, t_sim=t, phase=d.phase, reason=d.reason,
                library_indices=list(d.library_indices), expected_gain=d.expected_gain,
                upper_bound=d.upper_bound,
                ratio_bound=min(1.0, d.expected_gain / d.upper_bound) if d.upper_bound else 1.0,
                current_gain=d.current_gain, measured_gains=list(d.measured_gains),
                switched=d.switched))
        self._decisions_sent = len(self.plan.decisions)
        a = self.plan.current
        if a is None:
            return
        self.publish("assignments", ProAssignments(sender=self.ctx.node, t_sim=t, assignments=[
            ProAssignment(spacecraft=sc, assignment_id=a.id, phase=a.phase, pro=pro,
                          t_depart_s=a.t_depart_s, t_arrive_s=a.t_arrive_s)
            for sc, pro in a.pros.items()]))
