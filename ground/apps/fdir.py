"""Ground FDIR: detect and isolate faulty observers from their information gain (paper
Sec. III.B-E; DESIGN.md "Information cost and FDIR").

Rate group mid.  Inputs: every observer's POI observations (the images that reached the
ground), its transfer plans, its nav, attitude, guidance and H_i telemetry, and the ground's
own PRO assignments.  Outputs: one
``FdirWindow`` per observer and FDI window on ``ground/fdir/window``, and a ``FaultReport`` on
``ground/fdir/report`` when a fault is declared.

Each window [a, b) (length ``rates.fdi_period_s``) is evaluated ``fdir.latency_s`` after it
closes.  For observer i, with ψ the squared fused variance of the ground's map settled at a
(every observation with image time < a):

* ΔH_i = Σ φψ σ⁻¹ over the observations of its images taken in [a, b) (``twin.delta_h``);
* ΔH_i^pred: the same sum for the same image times from the nominal twin — the planned
  position (assigned PRO, or the published transfer plan), the camera on the aim point the
  observer reports (the target centre by default), the nominal camera model (β = 1);
* H_m,i (Eq. 9), τ_i from ``fdir.samples`` pointings within ``fdir.eps_deg`` of the planned
  ones (Eq. 11-12) with the floor ``fdir.floor``, direction by Table 3;
* a fault is declared after ``fdir.persistence`` exceedances in a row (``Persistence``); an
  observer with a plan whose images stay missing for ``fdir.silent_windows`` windows is
  declared a link fault — missing data is never read as zero information gain;
* a declared performance fault is identified (``ground/fdir/identify.py``): the camera's
  position and health located from the images themselves, the nav estimate and the reported
  attitude against the plan, the twin re-run at the reported pose (the gradient test), the
  seen POIs against those that pose would see, and the Δv it commands on station;
* the H_i an observer reports (``InfoCostTelemetry``) is checked against the ground's
  recomputation from its observations: inconsistent for ``fdir.persistence`` windows, a
  data-integrity fault;
* more of an observer's observations missing by sequence number than the link's nominal loss
  (``comms.packet_loss``) plus ``fdir.loss_tol``, for ``fdir.persistence`` windows: a link
  fault (packet loss), as is silence.

Only lost images are missing from both sides of the comparison; images taken while the
observer reports a slew (its attitude plan, not a pointing), or within ``fdir.settle_s`` of the
end of one (the loop's transient), are left out of both; a window
without any image or any plan gives no decision.  The twin points where the observer says
its camera policy aims (the target centre by default); it does not model the attitude loop's
tracking error, which with ``max_variance`` pointing and a camera narrower than the target
reaches about a degree during retargets.
"""

from __future__ import annotations

import bisect
import math

import numpy as np

from fsw.lib import quat
from fsw.lib.hcw import mean_motion
from fsw.lib.infocost import Camera
from fsw.lib.poi import sphere_pois
from fsw.lib.poi_map import PoiMap
from ground.fdir.identify import Tolerances, classify, window_evidence
from ground.fdir.metric import direction, metric
from ground.fdir.observer import (
    MAX_JUDGED_LOSS,
    ObserverState,
    ground_contributions,
    loss_limit,
)
from ground.fdir.threshold import Persistence, sampled_threshold
from ground.fdir.twin import FlightPlan, Transfer, TwinModel, delta_h, planned_boresights
from ground.planning.mission_plan import pro_of
from interfaces import catalogue as cat
from interfaces.app import App, AppContext, Input, Output
from interfaces.fdi_schedule import FdiSchedule
from interfaces.messages import (
    AttitudeEstimate,
    FaultReport,
    FdirWindow,
    GuidanceStatus,
    InfoCostTelemetry,
    PoiObservations,
    ProAssignments,
    StateEstimate,
    TransferPlanMsg,
)


class FdirApp(App):
    NAME = "fdir"
    RATE = "mid"
    INPUTS = (
        Input(cat.OBSERVATIONS, "on_observations", every_spacecraft=True),
        Input(cat.TRANSFER_PLAN, "on_transfer", every_spacecraft=True),
        Input(cat.ASSIGNMENTS, "on_assignments"),
        Input(cat.ATTITUDE_ESTIMATE, "on_attitude", every_spacecraft=True),
        Input(cat.INFO_COST, "on_telemetry", every_spacecraft=True),
        Input(cat.NAV_ESTIMATE, "on_nav", every_spacecraft=True),
        Input(cat.GUIDANCE_STATUS, "on_guidance", every_spacecraft=True),
    )
    OUTPUTS = (Output("window", cat.FDIR_WINDOW), Output("report", cat.FAULT_REPORT))

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        sc = ctx.scenario
        self.cfg = sc.fdir
        self.period = sc.rates.fdi_period_s
        self.schedule = FdiSchedule(self.period)
        self.n = mean_motion(sc.orbit.altitude_km * 1e3)
        camera = Camera(math.radians(sc.camera.half_angle_deg), sc.camera.max_range_m,
                        sc.camera.k)
        self.twin = TwinModel(*sphere_pois(sc.target.pois, sc.target.radius_m), camera,
                              sc.target.radius_m)
        self.settled = PoiMap.uniform(sc.target.pois, sc.target.prior_variance,
                                      sc.observers.count)
        self.pending: list[PoiObservations] = []
        self.observers = {i: ObserverState() for i in range(1, sc.observers.count + 1)}
        self.persistence = Persistence(self.cfg.persistence, self.cfg.persistence_window)
        self.integrity = Persistence(self.cfg.persistence)
        self.loss = Persistence(self.cfg.persistence)
        self.boresight_body = np.array(sc.attitude.boresight_body, dtype=float)
        self.boresight_body /= np.linalg.norm(self.boresight_body)
        self.tol = Tolerances.of(self.cfg)
        self._reported: dict[tuple[int, int], float] = {}  # (observer, boundary) -> H_i
        self.next_window = 0
        """the next FDI window to judge (``interfaces.fdi_schedule``)"""
        self.rejected = 0
        self._transfers: dict[tuple[int, int], Transfer] = {}

    # --- inputs ---------------------------------------------------------------------------

    def on_observations(self, msg: PoiObservations) -> None:
        if msg.spacecraft not in self.observers:
            return
        if msg.poi and (min(msg.poi) < 0 or max(msg.poi) >= len(self.twin.poi_pos)):
            self.rejected += 1
            self.log.error("FDIR: dropped observations of sc%d with POI indices outside the "
                           "%d of the target (%d dropped)", msg.spacecraft, len(self.twin.poi_pos),
                           self.rejected)
            return
        if msg.image_t_s >= self.window_start:
            self.pending.append(msg)
        else:  # too late for its window's verdict, not for the ground's map
            self.settled.add(msg.spacecraft, *msg.arrays())

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
        j = self.schedule.boundary_at(msg.t_sim)
        if msg.spacecraft in self.observers and j is not None and j > self.next_window:
            self._reported[(msg.spacecraft, j)] = msg.h_i

    def on_attitude(self, msg: AttitudeEstimate) -> None:
        obs = self.observers.get(msg.spacecraft)
        if obs is None:
            return
        if not obs.modes or obs.modes[-1][1] != msg.mode:
            bisect.insort(obs.modes, (msg.t_sim, msg.mode))
        if msg.t_sim >= self.window_start:
            bore = quat.rotate(np.array(msg.q_lvlh_body), self.boresight_body)
            obs.attitude.add(msg.t_sim, np.concatenate(
                (bore, [msg.pointing_error_rad], msg.target_lvlh_m)))

    def on_nav(self, msg: StateEstimate) -> None:
        obs = self.observers.get(msg.spacecraft)
        if obs is not None and msg.t_sim >= self.window_start:
            obs.nav.add(msg.t_sim, np.array(msg.x[:3]))

    def on_guidance(self, msg: GuidanceStatus) -> None:
        obs = self.observers.get(msg.spacecraft)
        if obs is not None and msg.t_sim >= self.window_start - self.period:
            bisect.insort(obs.guidance, (msg.t_sim, msg.dv_commanded_mps, msg.mode == "hold"))

    def on_assignments(self, msg: ProAssignments) -> None:
        for a in msg.assignments:
            obs = self.observers.get(a.spacecraft)
            if obs is None or a.assignment_id in obs.plans:
                continue
            obs.plans[a.assignment_id] = FlightPlan(
                a.t_depart_s, pro_of(a.pro), self._transfers.get((a.spacecraft, a.assignment_id)))

    # --- cycle ----------------------------------------------------------------------------

    @property
    def window_start(self) -> float:
        """Start of the next window to judge (s): later data is still to come."""
        return self.schedule.start(self.next_window)

    def step(self, t: float) -> None:
        while t >= self.schedule.end(self.next_window) + self.cfg.latency_s - 1e-9:
            k = self.next_window
            self.next_window += 1  # first: a failing window is not retried forever
            self._evaluate(k)

    def _evaluate(self, k: int) -> None:
        a, b = self.schedule.start(k), self.schedule.end(k)
        inside = [m for m in self.pending if a <= m.image_t_s < b]
        psi = self.settled.variance() ** 2
        phi = self.settled.phi
        for sc, obs in self.observers.items():
            mine = sorted((m for m in inside if m.spacecraft == sc), key=lambda m: m.image_t_s)
            lost = self._check_loss(sc, obs, mine, b)
            self._judge(sc, obs, mine, a, b, psi, phi, lost)
            obs.forget_modes_before(b)
            obs.nav.forget_before(b)
            obs.attitude.forget_before(b)
            obs.forget_guidance_before(b)
        for m in inside:
            self.settled.add(m.spacecraft, *m.arrays())
        self.pending = [m for m in self.pending if m.image_t_s >= b]
        self._check_reports(k + 1, b)

    def _check_reports(self, j: int, b: float) -> None:
        """Data integrity: each observer's H_i reported at b against the contribution the
        ground computes from the observations it received (its map now holds every image
        before b), with every observer's precision scaled up by the share of its observations
        lost on the way (sequence gaps), so ψ is as consistent as the ground can make it: the
        observer's H_i holds all of its images.  The two views then differ only by what each
        has fused (range-limited sharing), so a relative difference above
        ``fdir.integrity_tol`` is an inconsistent report.  An observer with more than
        ``MAX_JUDGED_LOSS`` of its observations missing cannot be judged."""
        lost = np.array([o.lost_fraction() for o in self.observers.values()])
        ground = ground_contributions(self.settled, lost)
        for sc in self.observers:
            reported = self._reported.pop((sc, j), None)
            mine = float(ground[sc - 1])
            if reported is None or mine <= 0.0 or lost[sc - 1] > MAX_JUDGED_LOSS:
                continue
            deviation = abs(reported / mine - 1.0)
            if self.integrity.update(sc, deviation > self.cfg.integrity_tol):
                self.log.warning("FDIR: sc%d reports H_i %.4g, observations give %.4g: "
                                 "data integrity", sc, reported, mine)
                self.publish("report", FaultReport(
                    sender=self.ctx.node, t_sim=b, spacecraft=sc, fault_class="data_integrity",
                    metric=deviation, threshold=self.cfg.integrity_tol, window_end_s=b))
        self._reported = {k: v for k, v in self._reported.items() if k[1] > j}

    def _loss_limit(self, sent: int) -> float:
        """The link's loss limit for ``sent`` observations (``observer.loss_limit``)."""
        comms = self.ctx.scenario.comms
        burst = comms.burst.mean_length_packets if comms.burst else 1.0
        return loss_limit(comms.packet_loss, burst, self.cfg.loss_tol, sent)

    def _check_loss(self, sc: int, obs: ObserverState, images: list[PoiObservations],
                    b: float) -> int:
        """Observations of the window missing by sequence number (the observer numbers every
        message it publishes on its key); more than ``_loss_limit`` of them for
        ``fdir.persistence`` windows is a link fault.  Returns the count lost."""
        if not images:
            return 0
        seqs = sorted(m.seq for m in images)
        lost = obs.count_observations(seqs)
        if obs.silent:  # the gap is the silence already judged (a link fault), not loss
            return 0
        fraction = lost / (lost + len(seqs))
        limit = self._loss_limit(lost + len(seqs))
        if self.loss.update(sc, fraction > limit):
            self.log.warning("FDIR: sc%d lost %.0f%% of its observations: link fault", sc,
                             100.0 * fraction)
            self.publish("report", FaultReport(
                sender=self.ctx.node, t_sim=b, spacecraft=sc, fault_class="link",
                metric=fraction, threshold=limit, window_end_s=b))
        return lost

    def _judge(self, sc: int, obs: ObserverState, images: list[PoiObservations], a: float,
               b: float, psi: np.ndarray, phi: np.ndarray, lost: int) -> None:
        plan = obs.plan_at(a)
        window = FdirWindow(sender=self.ctx.node, t_sim=b, spacecraft=sc, t_start_s=a,
                            t_end_s=b, images=len(images), lost=lost)
        if plan is not None and not images:
            self._silence(sc, obs, b)
        if plan is None or not images:
            self.publish("window", window)
            return
        obs.silent, obs.link_declared = 0, False
        images = [m for m in images if obs.tracking_at(m.image_t_s, self.cfg.settle_s)]
        window = window.model_copy(update={"images": len(images)})
        if not images:
            self.publish("window", window)
            return
        seen = [m.arrays() for m in images]
        dh = sum(delta_h(psi[poi], phi[poi], prec) for poi, prec in seen)
        times = np.array([m.image_t_s for m in images])
        pos = plan.positions(self.n, times)
        att = obs.attitude.at(times)
        bore = planned_boresights(att, pos)
        dh_pred = self.twin.predicted(pos, bore, psi, phi)
        h_prev = float(np.sum(phi * psi * self.settled.F[sc - 1]))
        m_val = metric(dh, dh_pred, h_prev)
        rng = np.random.default_rng([self.ctx.scenario.seed, sc, int(round(a))])
        tau = sampled_threshold(self.twin, pos, bore, psi, phi, h_prev,
                                math.radians(self.cfg.eps_deg), self.cfg.samples, self.cfg.floor,
                                rng)
        exceeded = None if m_val is None or tau is None else m_val > tau
        dirn = direction(dh, dh_pred, h_prev)
        ev = window_evidence(self.twin, seen, obs.nav.at(times), att, pos, psi, phi,
                             (dh, dh_pred) if exceeded else None, obs.dv_rate(a, b))
        self.publish("window", window.model_copy(update={
            "dh": dh, "dh_pred": dh_pred, "metric": m_val, "threshold": tau,
            "direction": dirn, "exceeded": exceeded, "evidence": ev.as_dict()}))
        if self.persistence.update(sc, exceeded):
            cls = classify(ev, self.tol)
            self.log.warning("FDIR: fault declared on sc%d at %.0f s (H_m %.3g > τ %.3g, %s): "
                             "%s", sc, b, m_val, tau, dirn, cls or "unidentified")
            self.publish("report", FaultReport(
                sender=self.ctx.node, t_sim=b, spacecraft=sc, fault_class=cls, direction=dirn,
                metric=m_val, threshold=tau, window_end_s=b, evidence=ev.as_dict()))

    def _silence(self, sc: int, obs: ObserverState, b: float) -> None:
        """An observer with a plan sent no image this window: after ``silent_windows`` in a
        row, a link fault (once per episode)."""
        obs.silent += 1
        if obs.silent >= self.cfg.silent_windows and not obs.link_declared:
            obs.link_declared = True
            self.log.warning("FDIR: sc%d silent for %d windows: link fault", sc, obs.silent)
            self.publish("report", FaultReport(sender=self.ctx.node, t_sim=b, spacecraft=sc,
                                               fault_class="link", window_end_s=b))
