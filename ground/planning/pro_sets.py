"""The choice of one assignment's PRO set: every observer's PRO from the candidate library, by
expected information gain (the hierarchical planner of Sec. II.C, with the information cost of
Sec. II.D, Eq. 4-5), around the observers whose PROs are fixed.

The library is :func:`ground.planning.orbit_assignment.pro_library` of the scenario's
``[assignment]``; the gains are computed on a subsample of the POIs (every ``poi_stride``-th,
standing for that many) from the ground's fused POI map; the set is
:func:`ground.planning.orbit_assignment.greedy_assignment`'s, matched to the observers by
:func:`ground.planning.orbit_assignment.match_to_observers`.  An observer whose camera failed
keeps its PRO (untasked), its coverage counted and its PRO kept clear by the separation rule;
an actuator-impaired one gets a PRO clear of the keep-out it needs.  Which of them are so, and
when to choose, is the mission plan's (:mod:`ground.planning.mission_plan`).

Pure logic: no bus, no I/O.  Units: s, m, rad; gains in information-cost units (H decrease).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from gnc.mission import MissionConstants
from gnc.poi_map import PoiMap
from gnc.pro import Pro, min_distance_between
from ground.planning.orbit_assignment import (
    expected_precision,
    greedy_assignment,
    match_to_observers,
    pro_library,
    set_gain,
)
from interfaces.contracts.messages import ProElements
from interfaces.contracts.scenario import Scenario

log = logging.getLogger(__name__)

FloatArray = npt.NDArray[np.float64]


def elements(pro: Pro) -> ProElements:
    """The uplink form of a PRO (the inverse of ``Pro.of``)."""
    return ProElements(rho_x_m=pro.rho_x_m, alpha_x_rad=pro.alpha_x_rad, rho_y_m=pro.rho_y_m,
                       rho_z_m=pro.rho_z_m, alpha_z_rad=pro.alpha_z_rad)


@dataclass
class ProSetPlanner:
    """The PRO sets of ``scenario``'s assignments.

    Attributes:
        scenario: the mission.
        constants: the mission's constants (``gnc/mission.py``): mean motion, the camera
            model, the target's POIs, of which the planner sees every
            ``assignment.poi_stride``-th (expected gains are scaled accordingly).
        library: the candidate PROs (set in construction).
    """

    scenario: Scenario
    constants: MissionConstants

    def __post_init__(self) -> None:
        a = self.scenario.assignment
        self.n = self.constants.n_rad_s
        self.count = self.scenario.observers.count
        self.camera = self.constants.camera
        self._stride = a.poi_stride
        self._plan_pos = self.constants.poi_pos[::a.poi_stride]
        self._plan_normal = self.constants.poi_normal[::a.poi_stride]
        self.library = pro_library(
            a.rho_x_m, a.rho_z_m, np.linspace(0.0, 2.0 * math.pi, a.phases, endpoint=False),
            cross_phase_offsets_rad=[math.radians(d) for d in a.cross_phase_offsets_deg])

    def expected(self, pro: Pro, t_arrive: float) -> FloatArray:
        """The precision ``pro`` is expected to add to each planning POI over the planning
        window after ``t_arrive`` (s)."""
        a = self.scenario.assignment
        return expected_precision(pro, self.n, t_arrive, a.window_s, a.samples, self._plan_pos,
                                  self._plan_normal, self.camera)

    def gain(self, indices: tuple[int, ...], t_arrive: float, w: FloatArray,
             phi: FloatArray) -> float:
        """Expected gain of flying the library PROs ``indices`` (-1: none) from ``t_arrive``;
        ``w``, ``phi``: as :meth:`weights` gives them."""
        prec = np.array([self.expected(self.library[i], t_arrive) for i in indices if i >= 0])
        return set_gain(prec, phi, w)

    def weights(self, t_arrive: float, fused: PoiMap, dropped: set[int],
                pros: dict[int, ProElements]) -> tuple[FloatArray, FloatArray]:
        """(w⁻¹, φ) of the planning subsample (every ``poi_stride``-th POI standing for that
        many): the fused precision now plus what the untasked (``dropped``) observers still
        bring from their PROs (``pros``, the current assignment's) over the planning window."""
        k = self._stride
        w = (fused.w_inv + fused.F.sum(axis=0))[::k]
        for i in sorted(dropped):
            if i in pros:
                w = w + self.expected(Pro.of(pros[i]), t_arrive)
        return w, fused.phi[::k] * k

    def plan_set(self, t_depart: float, t_arrive: float, w: FloatArray, phi: FloatArray,
                 dropped: set[int], impaired: dict[int, float], pros: dict[int, ProElements]
                 ) -> tuple[dict[int, ProElements], tuple[int, ...], float, float]:
        """Every observer's PRO for an assignment arriving at ``t_arrive``: the ``dropped``
        ones keep theirs (in ``pros``, the current assignment's; untasked); the ``impaired``
        ones, then the healthy ones, get the greedy set of library PROs
        (``greedy_assignment``) clear of the keep-out they need and separated from the PROs
        already fixed, matched to the observers by ``match_to_observers``; ``w``, ``phi``: as
        :meth:`weights` gives them.  Returns (PROs by observer, library index per observer or
        -1, expected gain, online bound).  An impaired group with no feasible set falls back
        to the nominal keep-out (logged)."""
        a = self.scenario.assignment
        nominal = self.scenario.guidance.keep_out_m + a.keep_out_margin_m
        fixed = {i: pros[i] for i in sorted(dropped) if i in pros}
        chosen: dict[int, int] = {}
        gain = bound = 0.0
        tasked = [i for i in range(1, self.count + 1) if i not in fixed]
        groups = ([i for i in tasked if i in impaired], [i for i in tasked if i not in impaired])
        for group in groups:
            if not group:
                continue
            keep_out = max([nominal] + [impaired.get(i, 0.0) for i in group])
            around = ([Pro.of(e) for e in fixed.values()]
                      + [self.library[j] for j in chosen.values()])
            try:
                picks, g, ub = self._greedy_around(len(group), around, keep_out, t_arrive, w, phi)
            except ValueError:
                if keep_out <= nominal:
                    raise
                log.warning("no PRO set clears %.1f m for observers %s: nominal keep-out", keep_out,
                            group)
                picks, g, ub = self._greedy_around(len(group), around, nominal, t_arrive, w, phi)
            for j in picks:
                w = w + self.expected(self.library[j], t_arrive)
            states = self._states_at(t_depart, pros)[[i - 1 for i in group]]
            order = match_to_observers(states, [self.library[j] for j in picks], self.n, t_depart)
            chosen.update({sc: picks[j] for sc, j in zip(group, order, strict=True)})
            gain, bound = gain + g, bound + ub
        out = {**fixed, **{i: elements(self.library[j]) for i, j in chosen.items()}}
        per_observer = tuple(chosen.get(i, -1) for i in range(1, self.count + 1))
        return dict(sorted(out.items())), per_observer, gain, max(bound, gain)

    def _greedy_around(self, count: int, around: list[Pro], keep_out: float, t_arrive: float,
                       w: FloatArray, phi: FloatArray) -> tuple[list[int], float, float]:
        """Greedy set of ``count`` library PROs clear of ``keep_out`` and separated from the
        PROs ``around`` (whose coverage ``w`` already counts): (library indices, gain,
        bound)."""
        a = self.scenario.assignment
        free = [i for i, p in enumerate(self.library)
                if all(min_distance_between(p, q, self.n)[0] >= a.min_separation_m
                       for q in around)]
        choice = greedy_assignment([self.library[i] for i in free], count, self.n, t_arrive,
                                   a.window_s, a.samples, self._plan_pos, self._plan_normal,
                                   phi, w, self.camera, a.min_separation_m, keep_out)
        return [free[j] for j in choice.indices], choice.gain, choice.upper_bound

    def _states_at(self, t: float, pros: dict[int, ProElements]) -> FloatArray:
        """Where the observers are at ``t`` on their PROs ``pros`` (the target centre for one
        without, e.g. right after deployment)."""
        out = np.zeros((self.count, 6))
        for i in range(self.count):
            e = pros.get(i + 1)
            if e is not None:
                out[i] = Pro.of(e).state(self.n, t)
        return out
