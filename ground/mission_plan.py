"""The central agent's mission plan: which PRO each observer flies, and when (Fig. 7 phases,
hierarchical planner of Sec. II.C).

Scenario phases (``assign = "scenario"``) give their PROs directly.  Information phases
(``assign = "information"``) are decided when they are uplinked, from the ground's fused view of
the POIs at that moment: the greedy set of :func:`ground.orbit_assignment.greedy_assignment`,
matched to the observers by :func:`ground.orbit_assignment.match_to_observers`.  While an
information phase is the latest one, the plan measures how much the fused cost H falls in each
``check_period_s`` window after arrival, and when the set's gain saturates
(:func:`ground.orbit_assignment.gain_saturated`) it chooses a new set; the new set is flown only
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

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from fsw.lib.hcw import mean_motion
from fsw.lib.infocost import Camera
from fsw.lib.poi_map import PoiMap
from fsw.lib.pro import Pro, min_distance_between, min_distance_to_origin
from ground.orbit_assignment import (
    expected_precision,
    gain_saturated,
    greedy_assignment,
    match_to_observers,
    pro_library,
    set_gain,
)
from interfaces.messages import ProElements
from interfaces.scenario import Phase, Scenario

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


def elements(pro: Pro) -> ProElements:
    """The uplink form of a PRO."""
    return ProElements(rho_x_m=pro.rho_x_m, alpha_x_rad=pro.alpha_x_rad, rho_y_m=pro.rho_y_m,
                       rho_z_m=pro.rho_z_m, alpha_z_rad=pro.alpha_z_rad)


def _scenario_pros(phase: Phase, count: int) -> dict[int, ProElements]:
    return {i: elements(Pro(*phase.pro_of(i, count))) for i in range(1, count + 1)}


@dataclass
class MissionPlan:
    """The ground's plan, advanced by :meth:`update`.

    Attributes:
        scenario: the mission.
        poi_pos, poi_normal: the target model (M, 3), m; the planner's camera model sees every
            ``assignment.poi_stride``-th of them (expected gains are scaled accordingly).
        issued: every assignment issued so far, in order (the last one is current).
        decisions: every information-driven decision, in order.
    """

    scenario: Scenario
    poi_pos: npt.NDArray[np.float64]
    poi_normal: npt.NDArray[np.float64]
    issued: list[PlannedAssignment] = field(default_factory=list)
    decisions: list[Decision] = field(default_factory=list)

    def __post_init__(self) -> None:
        sc = self.scenario
        a = sc.assignment
        self.n = mean_motion(sc.orbit.altitude_km * 1e3)
        self.count = sc.observers.count
        self.camera = Camera(math.radians(sc.camera.half_angle_deg), sc.camera.max_range_m,
                             sc.camera.k)
        self._stride = a.poi_stride
        self._plan_pos = self.poi_pos[::a.poi_stride]
        self._plan_normal = self.poi_normal[::a.poi_stride]
        self.library = pro_library(
            a.rho_x_m, a.rho_z_m, np.linspace(0.0, 2.0 * math.pi, a.phases, endpoint=False),
            cross_phase_offsets_rad=[math.radians(d) for d in a.cross_phase_offsets_deg])
        self._next_phase = 0
        self._current_indices: tuple[int, ...] | None = None  # library PRO of each observer
        self._gains: list[float] = []
        self._last_check: tuple[float, float] | None = None  # (time s, H) of the last check
        self._info_phase = ""
        self._reassignments = 0
        self.dropped: set[int] = set()  # observers untasked (failed camera)
        self.impaired: dict[int, float] = {}  # observer -> keep-out it needs (actuator), m
        if sc.observers.start == "pro":
            self._issue("initial", {i: elements(Pro(*sc.observers.pro(i)))
                                    for i in range(1, self.count + 1)}, 0.0, 0.0)

    @property
    def current(self) -> PlannedAssignment | None:
        """The assignment being uplinked now (the latest issued)."""
        return self.issued[-1] if self.issued else None

    def update(self, t: float, fused: PoiMap) -> None:
        """Issue every phase whose uplink time has come, then check the current information
        set for saturation.  ``fused``: the ground's fused POI map at ``t``."""
        phases = self.scenario.phases
        while (self._next_phase < len(phases)
               and phases[self._next_phase].start_s - UPLINK_LEAD_S <= t + 1e-9):
            self._start_phase(phases[self._next_phase], t, fused)
            self._next_phase += 1
        self._check_saturation(t, fused)

    # ------------------------------------------------------------------------- internals

    def _issue(self, phase: str, pros: dict[int, ProElements], t_depart: float,
               t_arrive: float) -> None:
        self.issued.append(PlannedAssignment(len(self.issued) + 1, phase, pros, t_depart,
                                             t_arrive))
        self._gains, self._last_check = [], None

    def _start_phase(self, phase: Phase, t: float, fused: PoiMap) -> None:
        t_depart = phase.start_s  # a late uplink is the guidance's to absorb
        if phase.assign == "scenario":
            self._issue(phase.name, _scenario_pros(phase, self.count), t_depart,
                        t_depart + phase.transfer_s)
            self._current_indices = None
            return
        self._info_phase, self._reassignments = phase.name, 0
        self._decide(t, phase.name, "phase", t_depart, phase.transfer_s, fused, force=True)

    def _check_saturation(self, t: float, fused: PoiMap) -> None:
        cur = self.current
        if cur is None or self._current_indices is None or t < cur.t_arrive_s - 1e-9:
            return
        a = self.scenario.assignment
        if self._last_check is None:
            self._last_check = (t, fused.cost())
            return
        t_last, h_last = self._last_check
        if t - t_last < a.check_period_s - 1e-9:
            return
        h = fused.cost()
        self._gains.append(h_last - h)
        self._last_check = (t, h)
        if not gain_saturated(self._gains, a.saturation_fraction):
            return
        t_depart = t + UPLINK_LEAD_S
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
        k = self._stride  # planning subsample: every k-th POI standing for k of them
        w_now = (fused.w_inv + fused.F.sum(axis=0))[::k]
        phi = fused.phi[::k] * k
        keep_out = self.scenario.guidance.keep_out_m + a.keep_out_margin_m
        choice = greedy_assignment(self.library, self.count, self.n, t_arrive, a.window_s,
                                   a.samples, self._plan_pos, self._plan_normal, phi, w_now,
                                   self.camera, a.min_separation_m, keep_out)
        current_gain = None
        if self._current_indices is not None:
            prec = np.array([expected_precision(self.library[i], self.n, t_arrive, a.window_s,
                                                a.samples, self._plan_pos, self._plan_normal,
                                                self.camera) for i in self._current_indices])
            current_gain = set_gain(prec, phi, w_now)
        switch = force or current_gain is None or \
            choice.gain > (1.0 + a.min_improvement) * current_gain
        states = self._states_at(t_depart)
        order = match_to_observers(states, choice.pros, self.n, t_depart)
        per_observer = tuple(choice.indices[j] for j in order)
        self.decisions.append(Decision(t, phase, reason, per_observer, choice.gain,
                                       choice.upper_bound, current_gain, tuple(self._gains),
                                       switch))
        if not switch:
            self._gains, self._last_check = [], (t, fused.cost())
            return
        self._issue(phase, {i + 1: elements(self.library[k]) for i, k in enumerate(per_observer)},
                    t_depart, t_arrive)
        self._current_indices = per_observer

    def recover(self, t: float, spacecraft: int, fault_class: str | None,
                evidence: dict[str, float], fused: PoiMap) -> bool:
        """Replan after a fault identified on ``spacecraft`` (module docstring).  ``evidence``:
        the FDIR's (``nav_vs_plan_m``, ``pointing_error_deg``).  Returns whether a new
        assignment was issued (once per observer and class; link, state-sensor and
        data-integrity faults are not replanned)."""
        if self.current is None or not 1 <= spacecraft <= self.count:
            return False
        if fault_class == "camera" and spacecraft not in self.dropped:
            self.dropped.add(spacecraft)
        elif fault_class == "actuator" and spacecraft not in self.impaired:
            self.impaired[spacecraft] = self._holdable_keep_out(evidence)
        else:
            return False
        if len(self.dropped) >= self.count:
            return False
        a = self.scenario.assignment
        t_depart = t + UPLINK_LEAD_S
        t_arrive = t_depart + a.transfer_s
        k = self._stride
        w_now = (fused.w_inv + fused.F.sum(axis=0))[::k]
        phi = fused.phi[::k] * k
        cur = self.current.pros
        fixed = {i: cur[i] for i in sorted(self.dropped)}
        chosen: dict[int, int] = {}  # observer -> library index
        gain = bound = 0.0
        groups = [[i for i in sorted(self.impaired) if i not in self.dropped],
                  [i for i in range(1, self.count + 1)
                   if i not in self.dropped and i not in self.impaired]]
        for group in groups:
            if not group:
                continue
            keep_out = max([self.scenario.guidance.keep_out_m + a.keep_out_margin_m]
                           + [self.impaired.get(i, 0.0) for i in group])
            around = [_pro(e) for e in fixed.values()] + [self.library[j] for j in chosen.values()]
            picks, g, ub = self._greedy_around(len(group), around, keep_out, t_arrive, w_now, phi)
            states = self._states_at(t_depart)[[i - 1 for i in group]]
            order = match_to_observers(states, [self.library[j] for j in picks], self.n, t_depart)
            chosen.update({sc: picks[j] for sc, j in zip(group, order)})
            gain, bound = gain + g, bound + ub
        pros = {**fixed, **{i: elements(self.library[j]) for i, j in chosen.items()}}
        name = f"recovery-{len(self.dropped) + len(self.impaired)}"
        self.decisions.append(Decision(
            t, name, "recovery", tuple(chosen.get(i, -1) for i in range(1, self.count + 1)),
            gain, max(bound, gain), None, tuple(self._gains), True))
        self._issue(name, dict(sorted(pros.items())), t_depart, t_arrive)
        self._current_indices = None  # a recovery set is not re-optimised as a whole
        return True

    def _holdable_keep_out(self, evidence: dict[str, float]) -> float:
        """The keep-out an actuator-impaired observer needs, m (``recover``)."""
        sc = self.scenario
        base = sc.guidance.keep_out_m + sc.assignment.keep_out_margin_m
        need = base + 2.0 * evidence.get("nav_vs_plan_m", 0.0)
        theta = math.radians(evidence.get("pointing_error_deg", 0.0))
        half = math.radians(sc.camera.half_angle_deg)
        if theta > math.radians(sc.fdir.pointing_tol_deg):
            fit = sc.target.radius_m / math.sin(half - theta) if half > theta else math.inf
            need = max(need, fit)
        farthest = max(min_distance_to_origin(p, self.n)[0] for p in self.library)
        return min(need, farthest)

    def _greedy_around(self, count: int, around: list[Pro], keep_out: float, t_arrive: float,
                       w_now: npt.NDArray[np.float64], phi: npt.NDArray[np.float64]
                       ) -> tuple[list[int], float, float]:
        """Greedy set of ``count`` library PROs clear of the PROs ``around`` (separation) and
        of ``keep_out``, counting the coverage those bring: (library indices, gain, bound)."""
        a = self.scenario.assignment
        free = [i for i, p in enumerate(self.library)
                if all(min_distance_between(p, q, self.n)[0] >= a.min_separation_m
                       for q in around)]
        w = w_now + sum((expected_precision(q, self.n, t_arrive, a.window_s, a.samples,
                                            self._plan_pos, self._plan_normal, self.camera)
                         for q in around), np.zeros_like(w_now))
        choice = greedy_assignment([self.library[i] for i in free], count, self.n, t_arrive,
                                   a.window_s, a.samples, self._plan_pos, self._plan_normal,
                                   phi, w, self.camera, a.min_separation_m, keep_out)
        return [free[j] for j in choice.indices], choice.gain, choice.upper_bound

    def _states_at(self, t: float) -> npt.NDArray[np.float64]:
        """Where the plan has each observer at ``t``: on its current PRO (the target centre
        before any assignment, i.e. right after deployment)."""
        cur = self.current
        out = np.zeros((self.count, 6))
        if cur is None:
            return out
        for i in range(self.count):
            e = cur.pros.get(i + 1)
            if e is not None:
                out[i] = _pro(e).state(self.n, t)
        return out


def _pro(e: ProElements) -> Pro:
    return Pro(e.rho_x_m, e.alpha_x_rad, e.rho_y_m, e.rho_z_m, e.alpha_z_rad)
