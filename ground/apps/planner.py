"""Mission planner: the central agent's PRO assignments (Fig. 7 phase sequence).

Rate group low.  Output: ``ProAssignments`` (every observer's current assignment) on
``ground/planner/assignments``.  The plan comes from the scenario: observers that start on a
PRO are first told to hold it; each ``[[phases]]`` entry then moves every observer to its PRO of
that phase (depart at ``start_s``, arrive ``transfer_s`` later).  An assignment is uplinked from
``UPLINK_LEAD_S`` before its departure and repeated every cycle until the next one supersedes it,
so a command lost on the range-limited, lossy link is simply received later (the spacecraft acts
on a new ``assignment_id`` once).  Issue 4's information-driven assignment replaces the scenario
schedule as the source of the PROs; the uplink stays the same.
"""

from __future__ import annotations

from dataclasses import dataclass

from interfaces import topics
from interfaces.app import App, AppContext, Output
from interfaces.messages import ProAssignment, ProAssignments, ProElements
from interfaces.scenario import Scenario


@dataclass(frozen=True)
class PlannedAssignment:
    """One entry of the schedule: assignment ``id`` of the phase ``phase``."""

    id: int
    phase: str
    pros: dict[int, ProElements]
    t_depart_s: float
    t_arrive_s: float


def schedule(scenario: Scenario) -> list[PlannedAssignment]:
    """The assignments of a scenario in time order (ids 1, 2, ...)."""
    count = scenario.observers.count

    def elements(formation_pro: tuple[float, float, float, float, float]) -> ProElements:
        rx, ax, ry, rz, az = formation_pro
        return ProElements(rho_x_m=rx, alpha_x_rad=ax, rho_y_m=ry, rho_z_m=rz, alpha_z_rad=az)

    out: list[PlannedAssignment] = []
    if scenario.observers.start == "pro":
        out.append(PlannedAssignment(
            id=1, phase="initial", t_depart_s=0.0, t_arrive_s=0.0,
            pros={i: elements(scenario.observers.pro(i)) for i in range(1, count + 1)}))
    for phase in scenario.phases:
        out.append(PlannedAssignment(
            id=len(out) + 1, phase=phase.name, t_depart_s=phase.start_s,
            t_arrive_s=phase.start_s + phase.transfer_s,
            pros={i: elements(phase.pro_of(i, count)) for i in range(1, count + 1)}))
    return out


class MissionPlanner(App):
    NAME = "planner"
    RATE = "low"
    INPUTS = ()
    OUTPUTS = (
        Output("assignments", lambda c: topics.assignments(c.mission), ProAssignments),
    )
    UPLINK_LEAD_S = 60.0
    """Assignments are uplinked from this long before their departure time, s."""

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        self.schedule = schedule(ctx.scenario)

    def step(self, t: float) -> None:
        current = [a for a in self.schedule if a.t_depart_s - self.UPLINK_LEAD_S <= t]
        if not current:
            return
        a = current[-1]
        self.publish("assignments", ProAssignments(sender=self.ctx.node, t_sim=t, assignments=[
            ProAssignment(spacecraft=sc, assignment_id=a.id, phase=a.phase, pro=pro,
                          t_depart_s=a.t_depart_s, t_arrive_s=a.t_arrive_s)
            for sc, pro in a.pros.items()]))
