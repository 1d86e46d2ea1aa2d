"""Mission planner: the central agent's PRO assignments (Fig. 7 phases, Sec. II.C).

Rate group low.  Input: the observations of every observer (the ground is reached through the
target, so it hears every observer in range of it), fused into the ground's POI map.  Outputs:
``ProAssignments`` (every observer's current assignment) on ``ground/planner/assignments`` and
each information-driven ``AssignmentDecision`` on ``ground/planner/decisions``.

What to fly comes from :class:`ground.planning.mission_plan.MissionPlan`: the scenario's phases,
with ``assign = "information"`` phases chosen by expected information gain and reassigned when
the set's gain saturates, and -- with ``fdir.recovery`` -- a recovery assignment when the FDIR
reports an identified camera or actuator fault (input ``ground/fdir/report``).  A spacecraft's
onboard FDIR may ask for a new plan (input ``sc/N/fdir/event``, ``plan_request``): the ground's
FDIR, not the request, decides a recovery; a request from a spacecraft in safe hold that no new
assignment answers in the same cycle is answered by the current plan issued again
(``MissionPlan.reissue``), so that safe hold, which only a newer assignment ends, always
ends; a request from a watchpoint trip is logged.  An
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
    CRITICAL = ("plan", "map", "_decisions_sent", "_faults", "_requests")

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        sc = ctx.scenario
        self.plan = MissionPlan(sc, ctx.constants)
        self.map = PoiMap.uniform(sc.target.pois, sc.target.prior_variance, sc.observers.count)
        self._decisions_sent = 0
        self._faults: list[tuple[int, str | None, dict[str, float]]] = []
        """(observer, class, evidence) to recover from at the next step"""
        self._requests: list[int] = []
        """observers in safe hold that asked for a plan since the last step"""

    def on_observations(self, msg: PoiObservations) -> None:
        if msg.spacecraft <= self.map.n_agents:
            self.map.add(msg.spacecraft, *msg.arrays())

    def _recover(self, t: float) -> None:
        """Replan around the faults the FDIR identified since the last step."""
        faults, self._faults = self._faults, []
        if not faults:
            return
        try:
            if self.plan.recover(t, faults, self.map):
                self.log.warning("recovery: replanned around %s", ", ".join(
                    f"sc{sc} ({c})" for sc, c, _ in faults))
        except ValueError as e:
            self.log.error("recovery impossible, plan unchanged: %s", e)

    def on_fault(self, msg: FaultReport) -> None:
        if self.ctx.scenario.fdir.recovery and msg.spacecraft >= 1:  # 0: the constellation's
            self._faults.append((msg.spacecraft, msg.fault_class, dict(msg.evidence)))

    def on_onboard(self, msg: OnboardFdirEvent) -> None:
        """A spacecraft's plan request (module docstring)."""
        if msg.event != "plan_request" or not 1 <= msg.spacecraft <= self.map.n_agents:
            return
        if msg.name == "safe_hold" and self.ctx.scenario.fdir.recovery:
            self._requests.append(msg.spacecraft)
        else:
            self.log.info("sc%d asks for a new plan (%s, %s): the ground's FDIR decides",
                          msg.spacecraft, msg.name, msg.fault_class)

    def step(self, t: float) -> None:
        self.plan.update(t, self.map)
        issued = len(self.plan.issued)
        self._recover(t)
        requests, self._requests = self._requests, []
        if requests and len(self.plan.issued) == issued and self.plan.reissue(t):
            self.log.warning("plan issued again for sc%s in safe hold",
                             ", sc".join(map(str, sorted(set(requests)))))
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
