"""Ground FDIR: detect and isolate faulty observers from their information gain (paper
Sec. III.B-E; DESIGN.md "Information cost and FDIR").

Rate group mid.  Inputs: every observer's POI observations (the images that reached the
ground), its transfer plans, and the ground's own PRO assignments.  Outputs: one
``FdirWindow`` per observer and FDI window on ``ground/fdir/window``, and a ``FaultReport`` on
``ground/fdir/report`` when a fault is declared.

Each window [a, b) (length ``rates.fdi_period_s``) is evaluated ``fdir.latency_s`` after it
closes.  For observer i, with ψ the squared fused variance of the ground's map settled at a
(every observation with image time < a):

* ΔH_i = Σ φψ σ⁻¹ over the observations of its images taken in [a, b) (``twin.delta_h``);
* ΔH_i^pred: the same sum for the same image times from the nominal twin — the planned
  position (assigned PRO, or the published transfer plan), the camera on the target centre,
  the nominal camera model (β = 1);
* H_m,i (Eq. 9), τ_i from ``fdir.samples`` pointings within ``fdir.eps_deg`` of the planned
  ones (Eq. 11-12) with the floor ``fdir.floor``, direction by Table 3;
* a fault is declared after ``fdir.persistence`` exceedances in a row (``Persistence``); an
  observer with a plan whose images stay missing for ``fdir.silent_windows`` windows is
  declared a link fault — missing data is never read as zero information gain;
* the H_i an observer reports (``InfoCostTelemetry``) is checked against the ground's
  recomputation from its observations: inconsistent for ``fdir.persistence`` windows, a
  data-integrity fault.

Only lost images are missing from both sides of the comparison; images taken while the
observer reports a slew (its attitude plan, not a pointing) are left out of both; a window
without any image or any plan gives no decision.  The twin models centre pointing (the
default camera policy).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

import numpy as np

from fsw.lib.hcw import mean_motion
from fsw.lib.infocost import Camera
from fsw.lib.poi import sphere_pois
from fsw.lib.poi_map import PoiMap
from fsw.lib.pro import Pro
from ground.fdir.metric import direction, metric
from ground.fdir.threshold import Persistence, adaptive_threshold
from ground.fdir.twin import (
    FlightPlan,
    Transfer,
    centre_boresights,
    delta_h,
    perturbed_boresights,
    predicted_delta_h,
)
from interfaces import topics
from interfaces.app import App, AppContext, Input, Output
from interfaces.messages import (
    AttitudeEstimate,
    FaultReport,
    FdirWindow,
    InfoCostTelemetry,
    PoiObservations,
    ProAssignments,
    TransferPlanMsg,
)


@dataclass
class _Observer:
    """The FDIR's knowledge of one observer: its plans (by assignment id), the times its
    attitude mode changed (as reported), and its silence count."""

    plans: dict[int, FlightPlan] = field(default_factory=dict)
    modes: list[tuple[float, str]] = field(default_factory=list)
    silent: int = 0
    link_declared: bool = False

    def forget_modes_before(self, t: float) -> None:
        """Drop mode changes no later window needs (keep the one in force at t)."""
        i = bisect.bisect_right(self.modes, (t, "~")) - 1
        del self.modes[:max(i, 0)]

    def tracking_at(self, t: float) -> bool:
        """Whether the last reported attitude mode at or before t is ``track``."""
        i = bisect.bisect_right(self.modes, (t, "~")) - 1
        return i >= 0 and self.modes[i][1] == "track"

    def plan_at(self, t: float) -> FlightPlan | None:
        valid = [p for p in self.plans.values() if p.t_from_s <= t]
        return max(valid, key=lambda p: p.t_from_s) if valid else None


THRESHOLD_IMAGES = 20
"""The threshold's pointing samples use at most this many of a window's images (cost)."""


class FdirApp(App):
    NAME = "fdir"
    RATE = "mid"
    INPUTS = (
        Input(lambda c: topics.all_spacecraft(c.mission, "camera", "observations"),
              PoiObservations, "on_observations"),
        Input(lambda c: topics.all_spacecraft(c.mission, "guidance", "plan"), TransferPlanMsg,
              "on_transfer"),
        Input(lambda c: topics.assignments(c.mission), ProAssignments, "on_assignments"),
        Input(lambda c: topics.all_spacecraft(c.mission, "attitude", "estimate"),
              AttitudeEstimate, "on_attitude"),
        Input(lambda c: topics.all_spacecraft(c.mission, "infocost", "telemetry"),
              InfoCostTelemetry, "on_telemetry"),
    )
    OUTPUTS = (
        Output("window", lambda c: topics.key(c.mission, c.node, "fdir", "window"), FdirWindow),
        Output("report", lambda c: topics.key(c.mission, c.node, "fdir", "report"), FaultReport),
    )

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        sc = ctx.scenario
        self.cfg = sc.fdir
        self.period = sc.rates.fdi_period_s
        self.n = mean_motion(sc.orbit.altitude_km * 1e3)
        self.camera = Camera(math.radians(sc.camera.half_angle_deg), sc.camera.max_range_m,
                             sc.camera.k)
        self.poi_pos, self.poi_normal = sphere_pois(sc.target.pois, sc.target.radius_m)
        self.settled = PoiMap.uniform(sc.target.pois, sc.target.prior_variance,
                                      sc.observers.count)
        self.pending: list[PoiObservations] = []
        self.observers = {i: _Observer() for i in range(1, sc.observers.count + 1)}
        self.persistence = Persistence(self.cfg.persistence)
        self.integrity = Persistence(self.cfg.persistence)
        self._reported: dict[tuple[int, float], float] = {}  # (observer, t) -> reported H_i
        self.window_start = 0.0
        self._transfers: dict[tuple[int, int], Transfer] = {}

    # --- inputs ---------------------------------------------------------------------------

    def on_observations(self, msg: PoiObservations) -> None:
        if msg.spacecraft not in self.observers:
            return
        if msg.image_t_s >= self.window_start:
            self.pending.append(msg)
        else:  # too late for its window's verdict, not for the ground's map
            self.settled.add(msg.spacecraft, msg.poi, msg.precision)

    def on_transfer(self, msg: TransferPlanMsg) -> None:
        if msg.spacecraft not in self.observers or len(msg.t_s) < 2:
            return
        tr = Transfer(np.array(msg.t_s), np.array(msg.x), np.array(msg.u_mps2))
        self._transfers[(msg.spacecraft, msg.assignment_id)] = tr
        obs = self.observers[msg.spacecraft]
        plan = obs.plans.get(msg.assignment_id)
        if plan is not None:
            obs.plans[msg.assignment_id] = FlightPlan(plan.t_from_s, plan.pro, tr)

    def on_telemetry(self, msg: InfoCostTelemetry) -> None:
        if msg.spacecraft in self.observers and msg.t_sim >= self.window_start:
            self._reported[(msg.spacecraft, round(msg.t_sim, 6))] = msg.h_i

    def on_attitude(self, msg: AttitudeEstimate) -> None:
        obs = self.observers.get(msg.spacecraft)
        if obs is not None and (not obs.modes or obs.modes[-1][1] != msg.mode):
            bisect.insort(obs.modes, (msg.t_sim, msg.mode))

    def on_assignments(self, msg: ProAssignments) -> None:
        for a in msg.assignments:
            obs = self.observers.get(a.spacecraft)
            if obs is None or a.assignment_id in obs.plans:
                continue
            e = a.pro
            obs.plans[a.assignment_id] = FlightPlan(
                a.t_depart_s, Pro(e.rho_x_m, e.alpha_x_rad, e.rho_y_m, e.rho_z_m, e.alpha_z_rad),
                self._transfers.get((a.spacecraft, a.assignment_id)))

    # --- cycle ----------------------------------------------------------------------------

    def step(self, t: float) -> None:
        while t >= self.window_start + self.period + self.cfg.latency_s - 1e-9:
            self._evaluate(self.window_start, self.window_start + self.period)
            self.window_start += self.period

    def _evaluate(self, a: float, b: float) -> None:
        inside = [m for m in self.pending if a <= m.image_t_s < b]
        psi = self.settled.variance() ** 2
        phi = self.settled.phi
        for sc, obs in self.observers.items():
            mine = sorted((m for m in inside if m.spacecraft == sc), key=lambda m: m.image_t_s)
            self._judge(sc, obs, mine, a, b, psi, phi)
            obs.forget_modes_before(b)
        for m in inside:
            self.settled.add(m.spacecraft, m.poi, m.precision)
        self.pending = [m for m in self.pending if m.image_t_s >= b]
        self._check_reports(b)

    def _check_reports(self, b: float) -> None:
        """Data integrity: each observer's H_i reported at b against the contribution the
        ground computes from the observations it received (its map now holds every image
        before b).  The two views differ only by what each has fused (range-limited sharing),
        so a relative difference above ``fdir.integrity_tol`` is an inconsistent report."""
        ground = self.settled.contributions()
        for sc in self.observers:
            reported = self._reported.pop((sc, round(b, 6)), None)
            mine = float(ground[sc - 1])
            if reported is None or mine <= 0.0:
                continue
            deviation = abs(reported / mine - 1.0)
            if self.integrity.update(sc, deviation > self.cfg.integrity_tol):
                self.log.warning("FDIR: sc%d reports H_i %.4g, observations give %.4g: "
                                 "data integrity", sc, reported, mine)
                self.publish("report", FaultReport(
                    sender=self.ctx.node, t_sim=b, spacecraft=sc, fault_class="data_integrity",
                    metric=deviation, threshold=self.cfg.integrity_tol, window_end_s=b))
        self._reported = {k: v for k, v in self._reported.items() if k[1] > b}

    def _judge(self, sc: int, obs: _Observer, images: list[PoiObservations], a: float,
               b: float, psi: np.ndarray, phi: np.ndarray) -> None:
        plan = obs.plan_at(a)
        window = FdirWindow(sender=self.ctx.node, t_sim=b, spacecraft=sc, t_start_s=a,
                            t_end_s=b, images=len(images))
        if plan is not None and not images:
            self._silence(sc, obs, b)
        if plan is None or not images:
            self.publish("window", window)
            return
        obs.silent, obs.link_declared = 0, False
        images = [m for m in images if obs.tracking_at(m.image_t_s)]  # slews are not predicted
        window = window.model_copy(update={"images": len(images)})
        if not images:
            self.publish("window", window)
            return
        dh = sum(delta_h(psi[m.poi], phi[m.poi], np.array(m.precision)) for m in images)
        times = np.array([m.image_t_s for m in images])
        pos = plan.positions(self.n, times)
        bore = centre_boresights(pos)
        dh_pred = predicted_delta_h(pos, bore, self.poi_pos, self.poi_normal, self.camera,
                                    psi, phi)
        h_prev = float(np.sum(phi * psi * self.settled.F[sc - 1]))
        m_val = metric(dh, dh_pred, h_prev)
        tau = self._threshold(sc, a, pos, bore, psi, phi, h_prev)
        exceeded = None if m_val is None or tau is None else m_val > tau
        dirn = direction(dh, dh_pred, h_prev)
        self.publish("window", window.model_copy(update={
            "dh": dh, "dh_pred": dh_pred, "metric": m_val, "threshold": tau,
            "direction": dirn, "exceeded": exceeded}))
        if self.persistence.update(sc, exceeded):
            self.log.warning("FDIR: fault declared on sc%d at %.0f s (H_m %.3g > τ %.3g, %s)",
                             sc, b, m_val, tau, dirn)
            self.publish("report", FaultReport(sender=self.ctx.node, t_sim=b, spacecraft=sc,
                                               fault_class=None, direction=dirn, metric=m_val,
                                               threshold=tau, window_end_s=b))

    def _threshold(self, sc: int, a: float, pos: np.ndarray, bore: np.ndarray, psi: np.ndarray,
                   phi: np.ndarray, h_prev: float) -> float | None:
        """τ_i (Eq. 11-12) from ``fdir.samples`` ε-cone pointings of (at most
        ``THRESHOLD_IMAGES``, evenly spread) planned images, each compared with the prediction
        for the same images; floored at ``fdir.floor``.  Seeded by (seed, observer, window)."""
        k = max(1, math.ceil(len(pos) / THRESHOLD_IMAGES))
        pos, bore = pos[::k], bore[::k]
        ref = predicted_delta_h(pos, bore, self.poi_pos, self.poi_normal, self.camera, psi, phi)
        rng = np.random.default_rng([self.ctx.scenario.seed, sc, int(round(a))])
        eps = math.radians(self.cfg.eps_deg)
        samples = [predicted_delta_h(pos, perturbed_boresights(bore, eps, len(bore), rng),
                                     self.poi_pos, self.poi_normal, self.camera, psi, phi)
                   for _ in range(self.cfg.samples)]
        return adaptive_threshold(samples, ref, h_prev / k, self.cfg.floor)  # subset: ~1/k of the gain

    def _silence(self, sc: int, obs: _Observer, b: float) -> None:
        """An observer with a plan sent no image this window: after ``silent_windows`` in a
        row, a link fault (once per episode)."""
        obs.silent += 1
        if obs.silent >= self.cfg.silent_windows and not obs.link_declared:
            obs.link_declared = True
            self.log.warning("FDIR: sc%d silent for %d windows: link fault", sc, obs.silent)
            self.publish("report", FaultReport(sender=self.ctx.node, t_sim=b, spacecraft=sc,
                                               fault_class="link", window_end_s=b))
