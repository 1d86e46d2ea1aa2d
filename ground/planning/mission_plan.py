"""The central agent's mission plan: which PRO each observer flies, and when (Fig. 7 phases,
hierarchical planner of Sec. II.C).

Scenario phases (``assign = "scenario"``) give their PROs directly.  A phase is uplinked
``UPLINK_LEAD_S`` before it starts; with ground passes and observers released from the target,
the first phase is issued at the start, loaded aboard before the run, when no pass comes before
its uplink time (the later ones wait for a pass, as the ground's plan depends on what it saw).
With ground passes no assignment departs before ``UPLINK_LEAD_S`` after its uplink reaches the
spacecraft: one held for a pass, a phase's or a re-plan's, leaves after that pass (its transfer
as long as asked), so no observer is asked to fly a transfer already under way.
Information phases (``assign = "information"``) are decided when they are uplinked, from the
ground's fused view of the POIs at that moment: the greedy set of
:func:`ground.planning.orbit_assignment.greedy_assignment`, matched to the observers by
:func:`ground.planning.orbit_assignment.match_to_observers`.  While an
information phase is the latest one, the plan measures how much the fused cost H falls in each
``check_period_s`` window after arrival, and when the set's gain saturates
(:func:`ground.planning.orbit_assignment.gain_saturated`) it chooses a new set; the new set is
flown only
if its expected gain beats keeping the current one by ``min_improvement`` (a transfer costs
fuel and time).  Every decision is kept with its figures (expected gain, online bound) for the
archive.

Recovery (:meth:`MissionPlan.recover`, on a fault the FDIR has identified): an observer whose
camera failed is dropped from the inspection task -- it stays on its PRO, untasked -- and the
healthy ones are reassigned by expected gain around it (its PRO kept clear by the separation
rule, the coverage it still brings counted); an observer with an actuator fault gets a PRO it
can still hold: one whose minimum distance from the target leaves room for the deviation the
FDIR measured (twice it, beyond the keep-out), or, for a pointing fault of θ, keeps the whole
target in a camera of half-angle α (distance ≥ R / sin(α − θ); the farthest candidate when none
does).

Pure logic: no bus, no I/O; the planner app feeds it time and the fused POI map.
Units: s, m, rad; gains in information-cost units (H decrease).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from gnc.mission import MissionConstants
from gnc.passes import ContactPlan
from gnc.poi_map import PoiMap
from gnc.pro import Pro, min_distance_to_origin
from ground.planning.orbit_assignment import gain_saturated
from ground.planning.pro_sets import ProSetPlanner, elements
from interfaces.contracts.messages import ProElements
from interfaces.contracts.scenario import Phase, Scenario
from interfaces.contracts.timing import TIME_TOL_S

log = logging.getLogger(__name__)

UPLINK_LEAD_S = 60.0
"""Assignments are uplinked from this long before their departure time, s."""


@dataclass(frozen=True)
class PlannedAssignment:
    """Assignment ``id`` (1, 2, ... in issue order) of phase ``phase``: every observer's PRO,
    leaving at ``t_depart_s`` and arriving at ``t_arrive_s`` (s)."""

    id: int
    phase: str
    pros: dict[int, ProElements]
    t_depart_s: float
    t_arrive_s: float


@dataclass(frozen=True)
class Decision:
    """One information-driven choice, as archived.

    Attributes:
        t_s: decision time, s.
        phase: the phase (reassignments are named ``<phase>-r<k>``).
        reason: ``"phase"`` (an information phase began) or ``"saturated"``.
        library_indices: the greedy set, per observer (observer i flies entry i - 1).
        expected_gain: expected H decrease of the greedy set over the planning window.
        upper_bound: online bound on the best possible expected gain of N candidates.
        current_gain: expected gain of keeping the current PROs over the same window (None
            when the current PROs are not all in the library, e.g. after a scenario phase).
        measured_gains: H decrease of the fused view in each check window since arrival.
        switched: whether the new set was issued (False: the current set is kept).
    """

    t_s: float
    phase: str
    reason: str
    library_indices: tuple[int, ...]
    expected_gain: float
    upper_bound: float
    current_gain: float | None
    measured_gains: tuple[float, ...]
    switched: bool


def _scenario_pros(phase: Phase, count: int) -> dict[int, ProElements]:
    return {i: elements(Pro(*phase.pro_of(i, count))) for i in range(1, count + 1)}


@dataclass
class MissionPlan:
    """The ground's plan, advanced by :meth:`update`.

    Attributes:
        scenario: the mission.
        constants: the mission's constants (``gnc/mission.py``), handed to its PRO-set
            planner (``ground/planning/pro_sets.py``).
        issued: every assignment issued so far, in order (the last one is current).
        decisions: every information-driven decision, in order.

    Each assignment's PRO set is chosen by ``sets`` (:mod:`ground.planning.pro_sets`), whose
    candidate ``library``, mean motion ``n`` and ``camera`` the plan shares.
    """

    scenario: Scenario
    constants: MissionConstants
    issued: list[PlannedAssignment] = field(default_factory=list)
    decisions: list[Decision] = field(default_factory=list)

    def __post_init__(self) -> None:
        sc = self.scenario
        self.sets = ProSetPlanner(sc, self.constants)
        self.n, self.camera, self.library = self.sets.n, self.sets.camera, self.sets.library
        self.count = sc.observers.count
        self._next_phase = 0
        self._current_indices: tuple[int, ...] | None = None  # library PRO of each observer
        self._gains: list[float] = []
        self._last_check: tuple[float, float] | None = None  # (time s, H) of the last check
        self._info_phase = ""
        self._reassignments = 0
        self._recoveries = 0
        self._contact = ContactPlan.of(sc)
        self.dropped: set[int] = set()  # observers untasked (failed camera)
        self.impaired: dict[int, float] = {}  # observer -> keep-out it needs (actuator), m
        if sc.observers.start == "pro":
            self._issue("initial", {i: elements(Pro(*sc.observers.pro(i)))
                                    for i in range(1, self.count + 1)}, 0.0, 0.0)

    @property
    def current(self) -> PlannedAssignment | None:
        """The assignment being uplinked now (the latest issued)."""
        return self.issued[-1] if self.issued else None

    @property
    def _current_pros(self) -> dict[int, ProElements]:
        """The current assignment's PROs by observer (none before the first)."""
        cur = self.current
        return cur.pros if cur is not None else {}

    def update(self, t: float, fused: PoiMap) -> None:
        """Issue every phase whose uplink time has come, then check the current information
        set for saturation.  ``fused``: the ground's fused POI map at ``t``."""
        phases = self.scenario.phases
        while (self._next_phase < len(phases)
               and (phases[self._next_phase].start_s - UPLINK_LEAD_S <= t + TIME_TOL_S
                    or self._preloads(t))):
            self._start_phase(phases[self._next_phase], t, fused)
            self._next_phase += 1
        self._check_saturation(t, fused)

    # ------------------------------------------------------------------------- internals

    def _preloads(self, t: float) -> bool:
        """Whether the first phase is loaded aboard before the run (issued at t = 0): with
        ground passes, when no pass comes before its uplink time and nothing else is issued
        at the start (a spacecraft holds one assignment pending; ``ContactPlan.uplinked_s``:
        what is sent at t = 0 is aboard from the start)."""
        if t > TIME_TOL_S or self._next_phase or self.issued or self._contact is None:
            return False
        uplink = self.scenario.phases[0].start_s - UPLINK_LEAD_S
        return self._contact.uplinked_s(max(uplink, TIME_TOL_S * 2)) > uplink + TIME_TOL_S

    def _departure(self, t: float, t_depart: float) -> float:
        """The departure (s) of an assignment issued at ``t`` (s) that asks for ``t_depart``:
        with ground passes, one held for a pass (``ContactPlan.uplinked_s``) leaves
        ``UPLINK_LEAD_S`` after that pass's acquisition at the earliest, with the whole
        transfer time it asks for; one sent at once keeps its time, as does one with no pass
        to follow (it never arrives)."""
        reach = self._contact.uplinked_s(t) if self._contact is not None else t
        if reach <= t + TIME_TOL_S or not math.isfinite(reach):
            return t_depart
        return max(t_depart, reach + UPLINK_LEAD_S)

    def _issue(self, phase: str, pros: dict[int, ProElements], t_depart: float,
               t_arrive: float) -> None:
        self.issued.append(PlannedAssignment(len(self.issued) + 1, phase, pros, t_depart,
                                             t_arrive))
        self._gains, self._last_check = [], None

    def _start_phase(self, phase: Phase, t: float, fused: PoiMap) -> None:
        t_depart = self._departure(t, phase.start_s)
        if phase.assign == "scenario":
            self._issue(phase.name, _scenario_pros(phase, self.count), t_depart,
                        t_depart + phase.transfer_s)
            self._current_indices = None
            return
        self._info_phase, self._reassignments = phase.name, 0
        self._decide(t, phase.name, "phase", t_depart, phase.transfer_s, fused, force=True)

    def _check_saturation(self, t: float, fused: PoiMap) -> None:
        cur = self.current
        if cur is None or self._current_indices is None or t < cur.t_arrive_s - TIME_TOL_S:
            return
        a = self.scenario.assignment
        if self._last_check is None:
            self._last_check = (t, fused.cost())
            return
        t_last, h_last = self._last_check
        if t - t_last < a.check_period_s - TIME_TOL_S:
            return
        h = fused.cost()
        self._gains.append(h_last - h)
        self._last_check = (t, h)
        if not gain_saturated(self._gains, a.saturation_fraction):
            return
        t_depart = self._departure(t, t + UPLINK_LEAD_S)
        upcoming = self.scenario.phases[self._next_phase:]
        if upcoming and upcoming[0].start_s < t_depart + a.transfer_s:
            return  # the next phase comes first
        self._reassignments += 1
        self._decide(t, f"{self._info_phase}-r{self._reassignments}", "saturated", t_depart,
                     a.transfer_s, fused, force=False)

    def _decide(self, t: float, phase: str, reason: str, t_depart: float, transfer_s: float,
                fused: PoiMap, *, force: bool) -> None:
        """Choose a set for the window after arrival; issue it when ``force`` or when it beats
        the current set by the margin."""
        a = self.scenario.assignment
        t_arrive = t_depart + transfer_s
        w, phi = self.sets.weights(t_arrive, fused, self.dropped, self._current_pros)
        pros, per_observer, gain, bound = self.sets.plan_set(
            t_depart, t_arrive, w, phi, self.dropped, self.impaired, self._current_pros)
        current_gain = None
        if self._current_indices is not None:
            current_gain = self.sets.gain(self._current_indices, t_arrive, w, phi)
        switch = force or current_gain is None or gain > (1.0 + a.min_improvement) * current_gain
        self.decisions.append(Decision(t, phase, reason, per_observer, gain, bound, current_gain,
                                       tuple(self._gains), switch))
        if not switch:
            self._gains, self._last_check = [], (t, fused.cost())
            return
        self._issue(phase, pros, t_depart, t_arrive)
        self._current_indices = per_observer

    def recover(self, t: float, faults: Sequence[tuple[int, str | None, dict[str, float]]],
                fused: PoiMap) -> bool:
        """Replan after faults the FDIR identified (module docstring): ``faults`` holds
        (observer, class, evidence) -- the evidence's ``nav_vs_plan_m`` and
        ``pointing_error_deg`` size what an impaired observer can hold.  One assignment for
        all of them; returns whether one was issued (an observer is replanned once per class;
        link, state-sensor, data-integrity and unidentified faults are not replanned).

        Raises:
            ValueError: no set clears the keep-out and separation rules even at the nominal
                keep-out (the plan is left as it was).
        """
        if self.current is None:
            return False
        dropped, impaired = set(self.dropped), dict(self.impaired)
        for sc, fault_class, evidence in faults:
            if not 1 <= sc <= self.count:
                continue
            if fault_class == "camera":
                dropped.add(sc)
            elif fault_class == "actuator" and sc not in impaired:
                impaired[sc] = self._holdable_keep_out(evidence)
        if (dropped, impaired) == (self.dropped, self.impaired) or len(dropped) >= self.count:
            return False
        a = self.scenario.assignment
        t_depart = self._departure(t, t + UPLINK_LEAD_S)
        t_arrive = t_depart + a.transfer_s
        w, phi = self.sets.weights(t_arrive, fused, dropped, self._current_pros)
        pros, per_observer, gain, bound = self.sets.plan_set(t_depart, t_arrive, w, phi, dropped,
                                                             impaired, self._current_pros)
        self.dropped, self.impaired = dropped, impaired
        self._recoveries += 1
        name = f"recovery-{self._recoveries}"
        self.decisions.append(Decision(t, name, "recovery", per_observer, gain, bound, None,
                                       tuple(self._gains), True))
        info_phase = self._current_indices is not None
        self._issue(name, pros, t_depart, t_arrive)
        # an information phase goes on re-optimising around the faulty; a scenario one holds
        self._current_indices = per_observer if info_phase else None
        return True

    def reissue(self, t: float) -> bool:
        """Issue the current assignment's PROs again under a new id, leaving
        ``UPLINK_LEAD_S`` from ``t`` and arriving ``assignment.transfer_s`` later (a transfer
        planned afresh from where each observer is); False before the first assignment."""
        cur = self.current
        if cur is None:
            return False
        t_depart = self._departure(t, t + UPLINK_LEAD_S)
        self._issue(cur.phase, dict(cur.pros), t_depart,
                    t_depart + self.scenario.assignment.transfer_s)
        return True

    def _holdable_keep_out(self, evidence: dict[str, float]) -> float:
        """The keep-out an actuator-impaired observer needs, m (``recover``): the nominal one
        plus twice the deviation the FDIR measured; for a pointing fault of θ at least
        R / sin(α − θ), capped at the farthest candidate the library has."""
        sc = self.scenario
        base = sc.guidance.keep_out_m + sc.assignment.keep_out_margin_m
        need = base + 2.0 * evidence.get("nav_vs_plan_m", 0.0)
        theta = math.radians(evidence.get("pointing_error_deg", 0.0))
        half = math.radians(sc.camera.half_angle_deg)
        if theta > math.radians(sc.fdir.pointing_tol_deg):
            fit = sc.target.radius_m / math.sin(half - theta) if half > theta else math.inf
            need = max(need, fit)
        farthest = max(min_distance_to_origin(p, self.n)[0] for p in self.library)
        if need > farthest:
            log.warning("an impaired observer needs %.1f m from the target; the farthest "
                        "candidate PRO keeps %.1f m", need, farthest)
        return min(need, farthest)
