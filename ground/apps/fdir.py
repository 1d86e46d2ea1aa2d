"""Ground FDIR: detect and isolate faulty observers from their information gain (paper
Sec. III.B-E; docs/fdir.md).

Rate group mid.  Inputs: every observer's POI observations (the images that reached the
ground), its transfer plans, its nav, attitude, guidance and H_i telemetry, and the ground's
own PRO assignments.  Outputs: one ``FdirWindow`` per observer and FDI window on
``ground/fdir/window``, one ``ConstellationWindow`` per FDI window on
``ground/fdir/constellation``, and a ``FaultReport`` on ``ground/fdir/report`` when a fault is
declared.

Each window [a, b) (length ``rates.fdi_period_s``) is evaluated ``fdir.latency_s`` after it
closes.  For observer i, with ψ the squared fused variance of the ground's map settled at a
(every observation with image time < a):

* ΔH_i = Σ φψ σ⁻¹ over the observations of its images taken in [a, b) (``twin.delta_h``);
* ΔH_i^pred: the same sum for the same image times from the nominal twin — each image at the
  position the plan in force at its time gives (assigned PRO, or the published transfer
  plan), the camera on the aim point the observer reports (the target centre by default), the
  nominal camera model (β = 1);
* H_m,i (Eq. 9) against the threshold in force (``WindowThreshold``): by default the hardware
  model's quantile (``ground/fdir/hardware_threshold.py``), else Eq. 11-12's (``fdir.samples``
  pointings within ``fdir.eps_deg``), both archived, with the floor guard ``fdir.floor``;
  direction by Table 3; with ``fdir.fuse_guidance`` the window also fails on the nav-vs-plan,
  pointing and Δv-rate tests, and with ``fdir.fuse_nis`` on the Σ NIS of the observer's nav
  updates in the window against its χ² quantile (``ground/fdir/consistency.py``);
* the global check (Eq. 6, ``ground/fdir/constellation.py``): the constellation's ratio
  against its model; an information excess no single observer explains is declared once on the
  constellation (spacecraft 0, ``common_mode``) and not held against any observer;
* a fault is declared after ``fdir.persistence`` failed windows (``Persistence``); an
  observer with a plan whose images stay missing for ``fdir.silent_windows`` windows is
  declared a link fault — missing data is never read as zero information gain;
* a declared performance fault is identified (``ground/fdir/identify.py``), on the declaring
  window or, when that shows no class, a later one of the episode: the camera's
  position and health located from the images themselves, the nav estimate and the reported
  attitude against the plan, the twin re-run at the reported pose (the gradient test), the
  seen POIs against those that pose would see, and the Δv it commands on station;
* the H_i an observer reports (``InfoCostTelemetry``) is checked against the ground's
  recomputation from its observations: inconsistent for ``fdir.checks_persistence``
  windows, a data-integrity fault;
* more of an observer's observations missing by sequence number than the link's nominal loss
  (``comms.packet_loss``) plus ``fdir.loss_tol``, for ``fdir.checks_persistence`` windows: a
  link fault (packet loss), as is silence.

Only lost images are missing from both sides of the comparison; images taken while the
observer reports a slew (its attitude plan, not a pointing), or within ``fdir.settle_s`` of the
end of one (the loop's transient), are left out of both; a window
without any image or any plan gives no decision.  The twin points where the observer says
its camera policy aims (the target centre by default); the attitude loop's tracking error is
in the hardware threshold's pointing jitter, not in the prediction.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np

from gnc import quat
from gnc.hcw import mean_motion
from gnc.infocost import Camera
from gnc.poi import sphere_pois
from gnc.poi_map import PoiMap
from ground.fdir.consistency import failed_tests, nis_test
from ground.fdir.constellation import ConstellationVerdict, ObserverGain, constellation_check
from ground.fdir.hardware_threshold import position_sigma, ratio_model, window_false_alarm
from ground.fdir.identify import Evidence, Tolerances, classify, window_evidence
from ground.fdir.metric import direction, metric
from ground.fdir.observer import (
    ObserverState,
    ground_contributions,
    loss_limit,
)
from ground.fdir.threshold import Persistence, WindowThreshold, sampled_threshold
from ground.fdir.twin import FlightPlan, Transfer, TwinModel, delta_h, planned_boresights
from ground.planning.mission_plan import pro_of
from interfaces.contracts import catalogue as cat
from interfaces.contracts.fdi_schedule import FdiSchedule
from interfaces.contracts.messages import (
    AttitudeEstimate,
    ConstellationWindow,
    FaultReport,
    FdirWindow,
    GuidanceStatus,
    InfoCostTelemetry,
    PoiObservations,
    ProAssignments,
    StateEstimate,
    TransferPlanMsg,
)
from interfaces.runtime.app import App, AppContext, Input, Output


@dataclass(frozen=True)
class Judgement:
    """One observer's judged window before the constellation check: the window message (its
    ``exceeded`` still unset), the identification evidence, the thresholds, and whether the
    information test could decide."""

    window: FdirWindow
    evidence: Evidence
    threshold: WindowThreshold

    @property
    def decided(self) -> bool:
        """Whether the information test could decide (a metric and a threshold)."""
        return self.window.metric is not None and self.window.threshold is not None


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
    OUTPUTS = (Output("window", cat.FDIR_WINDOW), Output("report", cat.FAULT_REPORT),
               Output("constellation", cat.CONSTELLATION_WINDOW))

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
                              sc.target.radius_m, sc.camera.noise_frac)
        self.settled = PoiMap.uniform(sc.target.pois, sc.target.prior_variance,
                                      sc.observers.count)
        self.pending: list[PoiObservations] = []
        self.observers = {i: ObserverState() for i in range(1, sc.observers.count + 1)}
        self.persistence = Persistence(self.cfg.persistence, self.cfg.persistence_window)
        self.integrity = Persistence(self.cfg.checks_persistence)
        self.integrity_unjudged = 0
        self.loss = Persistence(self.cfg.checks_persistence)
        self.boresight_body = np.array(sc.attitude.boresight_body, dtype=float)
        self.boresight_body /= np.linalg.norm(self.boresight_body)
        self.tol = Tolerances.of(self.cfg)
        self.q_window = window_false_alarm(self.cfg.false_alarms_per_observer_hour, self.period,
                                           self.cfg.persistence, 2 if self.cfg.fuse_nis else 1)
        """per-window false-alarm probability of the hardware threshold and of the NIS test"""
        self._reported: dict[tuple[int, int], float] = {}  # (observer, boundary) -> H_i
        self.next_window = 0
        """the next FDI window to judge (``interfaces.contracts.fdi_schedule``)"""
        self.rejected = 0
        self.shortfall = 0.0
        """Σ over judged windows of (ΔH^pred − ΔH) over the constellation: the running integral
        of Eq. 6's H − H_nom to first order"""
        self._unidentified: set[int] = set()
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
            obs.plans[msg.assignment_id] = FlightPlan(plan.t_from_s, plan.pro, tr,
                                                      plan.t_arrive_s)

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
                (bore, [msg.pointing_error_rad], msg.target_lvlh_m, [msg.sigma_att_rad])))

    def on_nav(self, msg: StateEstimate) -> None:
        obs = self.observers.get(msg.spacecraft)
        if obs is not None and msg.t_sim >= self.window_start:
            obs.nav.add(msg.t_sim, np.array(msg.x[:3]))
            obs.nav_sigma.add(msg.t_sim, np.array([math.sqrt(max(
                (msg.P[0][0] + msg.P[1][1] + msg.P[2][2]) / 3.0, 0.0))]))
            if msg.nis is not None:
                obs.nis.append((msg.t_sim, msg.nis))

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
                a.t_depart_s, pro_of(a.pro), self._transfers.get((a.spacecraft, a.assignment_id)),
                a.t_arrive_s if a.t_arrive_s > a.t_depart_s else None)

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
        judged: dict[int, Judgement] = {}
        for sc, obs in self.observers.items():
            mine = sorted((m for m in inside if m.spacecraft == sc), key=lambda m: m.image_t_s)
            lost = self._check_loss(sc, obs, mine, b)
            verdict = self._judge(sc, obs, mine, a, b, psi, phi, lost)
            if isinstance(verdict, FdirWindow):
                self.publish("window", verdict)
            else:
                judged[sc] = verdict
        common = self._constellation(a, b, judged)
        for sc, j in judged.items():
            self._declare(sc, j, common)
        for obs in self.observers.values():
            obs.forget_before(b)
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
        ``fdir.integrity_tol`` is an inconsistent report (``fdir.checks_persistence`` windows
        in a row: a data-integrity fault).

        The recomputation holds only while the ground has nearly every observation: ψ depends
        on every observer's images, and lost ones are lost in bursts, from particular views,
        which no uniform rescaling restores (at 30% loss in bursts of 50 packets a healthy
        report differed from it by a median 11%, up to 55%).  While more than
        ``fdir.integrity_max_loss`` of any observer's observations are missing, no report is
        judged (counted in ``integrity_unjudged``, logged)."""
        lost = np.array([o.lost_fraction() for o in self.observers.values()])
        ground = ground_contributions(self.settled, lost)
        judgeable = float(lost.max(initial=0.0)) <= self.cfg.integrity_max_loss
        for sc in self.observers:
            reported = self._reported.pop((sc, j), None)
            mine = float(ground[sc - 1])
            if reported is None or mine <= 0.0:
                continue
            if not judgeable:
                self._unjudged_integrity(sc, lost)
                continue
            deviation = abs(reported / mine - 1.0)
            if self.integrity.update(sc, deviation > self.cfg.integrity_tol):
                self.log.warning("FDIR: sc%d reports H_i %.4g, observations give %.4g: "
                                 "data integrity", sc, reported, mine)
                self.publish("report", FaultReport(
                    sender=self.ctx.node, t_sim=b, spacecraft=sc, fault_class="data_integrity",
                    metric=deviation, threshold=self.cfg.integrity_tol, window_end_s=b))
        self._reported = {k: v for k, v in self._reported.items() if k[1] > j}

    def _unjudged_integrity(self, sc: int, lost: np.ndarray) -> None:
        self.integrity_unjudged += 1
        if self.integrity_unjudged == 1 or self.integrity_unjudged % 100 == 0:
            self.log.info("FDIR: sc%d's H_i report not judged: %.0f%% of sc%d's observations "
                          "lost (data integrity needs at most %.0f%%; %d unjudged so far)", sc,
                          100 * lost.max(), int(np.argmax(lost)) + 1,
                          100 * self.cfg.integrity_max_loss, self.integrity_unjudged)

    def _loss_limit(self, sent: int) -> float:
        """The link's loss limit for ``sent`` observations (``observer.loss_limit``)."""
        comms = self.ctx.scenario.comms
        burst = comms.burst.mean_length_packets if comms.burst else 1.0
        return loss_limit(comms.packet_loss, burst, self.cfg.loss_tol, sent)

    def _check_loss(self, sc: int, obs: ObserverState, images: list[PoiObservations],
                    b: float) -> int:
        """Observations of the window missing by sequence number (the observer numbers every
        message it publishes on its key); more than ``_loss_limit`` of them for
        ``fdir.checks_persistence`` windows is a link fault.  Returns the count lost."""
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
               b: float, psi: np.ndarray, phi: np.ndarray, lost: int) -> FdirWindow | Judgement:
        """One observer's window: its information test, thresholds and consistency tests (a
        bare ``FdirWindow`` when nothing can be judged)."""
        plan = obs.plan_at(a)
        window = FdirWindow(sender=self.ctx.node, t_sim=b, spacecraft=sc, t_start_s=a,
                            t_end_s=b, images=len(images), lost=lost)
        if plan is not None and not images:
            self._silence(sc, obs, b)
        if plan is None or not images:
            return window
        obs.silent, obs.link_declared = 0, False
        images = [m for m in images if obs.tracking_at(m.image_t_s, self.cfg.settle_s)]
        if not images:
            return window.model_copy(update={"images": 0})
        planned = obs.planned(self.n, np.array([m.image_t_s for m in images]))
        if planned is None:  # no plan in force at an image time: nothing to compare with
            return window
        pos, moving, known = planned  # unknown: on a transfer whose plan was lost
        images = [m for m, k in zip(images, known) if k]
        pos, moving = pos[known], moving[known]
        window = window.model_copy(update={"images": len(images)})
        if not images:
            return window
        seen = [m.arrays() for m in images]
        dh = sum(delta_h(psi[poi], phi[poi], prec) for poi, prec in seen)
        times = np.array([m.image_t_s for m in images])
        att = obs.attitude.at(times)
        prec = self.twin.precision(pos, planned_boresights(att, pos))
        dh_pred = delta_h(psi, phi, prec)
        h_prev = float(np.sum(phi * psi * self.settled.F[sc - 1]))
        m_val = metric(dh, dh_pred, h_prev)
        th = self._threshold(sc, obs, bool(moving.any()), times, pos, att, prec,
                             (psi, phi, h_prev), a)
        nav, dv_rate = obs.nav.at(times), obs.dv_rate(a, b)
        ev = window_evidence(self.twin, seen, nav, att, pos, psi, phi, None, dv_rate)
        failed = [] if m_val is None or th.tau is None or m_val <= th.tau else ["information"]
        if self.cfg.fuse_guidance:
            failed += failed_tests(ev, self.tol)
        nis = nis_test(obs.nis_between(a, b), self.q_window) if self.cfg.fuse_nis else None
        if nis is not None and nis[0] > nis[1]:
            failed.append("nis")
        if failed or sc in self._unidentified:
            naming = sc in self._unidentified or not self.persistence.declared(sc)
            ev = window_evidence(self.twin, seen, nav, att, pos, psi, phi, (dh, dh_pred), dv_rate,
                                 fit_boresight=naming)
        window = window.model_copy(update={
            "dh": dh, "dh_pred": dh_pred, "metric": m_val, "threshold": th.tau,
            "direction": direction(dh, dh_pred, h_prev), "evidence": ev.as_dict(),
            "threshold_model": th.model_tau, "threshold_sampled": th.sampled,
            "threshold_by": th.by, "failed": failed,
            "nis_sum": nis[0] if nis else None, "nis_limit": nis[1] if nis else None,
            "ratio_mean": th.model.mean if th.model else None,
            "ratio_std": th.model.std if th.model else None})
        return Judgement(window, ev, th)

    def _constellation(self, a: float, b: float, judged: dict[int, Judgement]
                       ) -> ConstellationVerdict | None:
        """The global check (Eq. 6, ``ground/fdir/constellation.py``) over the judged
        observers; a fault no single observer explains is declared on the constellation
        (spacecraft 0) once per episode."""
        gains = [ObserverGain(sc, j.window.dh, j.window.dh_pred, j.threshold.model)
                 for sc, j in judged.items()
                 if j.threshold.model is not None and j.window.dh_pred is not None
                 and j.window.dh is not None]
        verdict = constellation_check(gains, self.q_window)
        self.shortfall += sum(g.dh_pred - g.dh for g in gains)
        self.publish("constellation", ConstellationWindow(
            sender=self.ctx.node, t_sim=b, t_start_s=a, t_end_s=b, observers=len(gains),
            ratio=verdict.ratio if verdict else None,
            ratio_mean=verdict.model.mean if verdict else None,
            ratio_std=verdict.model.std if verdict else None,
            threshold=verdict.threshold if verdict else None,
            exceeded=verdict.exceeded if verdict else None,
            explained_by=verdict.explained_by if verdict else None,
            common_mode=verdict.common_mode if verdict else None,
            cost=self._cost(), shortfall=self.shortfall))
        if self.persistence.update(0, verdict.common_mode if verdict else None) and verdict:
            self.log.warning("FDIR: constellation fault at %.0f s: ΣΔH/ΣΔH_pred %.3g off its "
                             "nominal %.3g by more than τ %.3g on every observer: common mode",
                             b, verdict.ratio, verdict.model.mean, verdict.threshold)
            self.publish("report", FaultReport(
                sender=self.ctx.node, t_sim=b, spacecraft=0, fault_class="common_mode",
                direction="degraded" if verdict.ratio < verdict.model.mean else "improved",
                metric=abs(1.0 - verdict.ratio), threshold=verdict.threshold, window_end_s=b))
        return verdict

    def _cost(self) -> float:
        """H of the ground's fused map (Eq. 4, 7)."""
        return float(np.sum(self.settled.phi * self.settled.variance()))

    def _declare(self, sc: int, j: Judgement, common: ConstellationVerdict | None) -> None:
        """Publish the window's verdict and declare a fault on the observer after
        ``fdir.persistence`` failed windows.  An information test failed by every observer
        together is the constellation's (common mode), not this observer's.  A fault declared
        without a class is identified on a later window of the episode (while its windows fail,
        and on the first that passes) when its evidence shows one."""
        failed = [f for f in j.window.failed
                  if not (f == "information" and common is not None and common.common_mode)]
        exceeded = bool(failed) if failed or j.decided else None
        w = j.window.model_copy(update={"exceeded": exceeded})
        self.publish("window", w)
        b = w.t_end_s
        if self.persistence.update(sc, exceeded):
            cls = classify(j.evidence, self.tol, failed)
            self.log.warning("FDIR: fault declared on sc%d at %.0f s (failed %s; H_m %s, τ %s, "
                             "%s): %s", sc, b, "+".join(failed), _g(w.metric), _g(w.threshold),
                             w.direction, cls or "unidentified")
            self._report(sc, cls, w, j.evidence)
            if cls is None:
                self._unidentified.add(sc)
        elif sc in self._unidentified:
            cls = classify(j.evidence, self.tol, failed)
            if cls is not None or not exceeded:
                self._unidentified.discard(sc)
            if cls is not None:
                self.log.warning("FDIR: sc%d identified at %.0f s: %s", sc, b, cls)
                self._report(sc, cls, w, j.evidence)

    def _report(self, sc: int, cls: str | None, w: FdirWindow, ev: Evidence) -> None:
        self.publish("report", FaultReport(
            sender=self.ctx.node, t_sim=w.t_end_s, spacecraft=sc, fault_class=cls,
            direction=w.direction, metric=w.metric, threshold=w.threshold,
            window_end_s=w.t_end_s, evidence=ev.as_dict()))

    def _threshold(self, sc: int, obs: ObserverState, moving: bool, times: np.ndarray,
                   pos: np.ndarray, att: np.ndarray | None, prec: np.ndarray,
                   state: tuple[np.ndarray, np.ndarray, float], a: float) -> WindowThreshold:
        """Both thresholds of the window -- Eq. 11-12's ε-sampling and the hardware model's
        quantile -- and the one in force: the selected one (``fdir.threshold``), raised to the
        floor guard where it is below.  The model's pointing spread is the loop's jitter, the
        reported attitude knowledge and the pointing error the observer reports in the window
        (up to ``fdir.pointing_tol_deg``, beyond which the pointing test decides): the first
        window after the initial acquisition still holds the loop's transient (0.13° against
        0.01° later), which the jitter alone does not cover."""
        cfg, seed = self.cfg, self.ctx.scenario.seed
        psi, phi, h_prev = state
        bore = planned_boresights(att, pos)
        sampled = sampled_threshold(self.twin, pos, bore, psi, phi, h_prev,
                                    math.radians(cfg.eps_deg), cfg.samples, 0.0,
                                    np.random.default_rng([seed, sc, int(round(a))]))
        aims = att[:, 4:7] if att is not None else np.zeros_like(pos)
        nav_sigma, nav = obs.nav_sigma.at(times), obs.nav.at(times)
        knowledge = float(np.mean(att[:, 7])) if att is not None else 0.0
        tracking = min(float(np.median(att[:, 3])) if att is not None else 0.0,
                       math.radians(cfg.pointing_tol_deg))  # beyond: the pointing test's
        model = ratio_model(
            self.twin, pos, aims, psi, phi,
            position_sigma(cfg.transfer_sigma_m if moving else cfg.track_sigma_m,
                           float(np.mean(nav_sigma)) if nav_sigma is not None else 0.0,
                           None if nav is None else nav - pos, cfg.position_tol_m),
            math.hypot(math.radians(cfg.pointing_jitter_deg), knowledge, tracking),
            self.ctx.scenario.camera.noise_frac, cfg.model_samples,
            np.random.default_rng([seed, sc, int(round(a)), 1]), prec)
        model_tau = model.threshold(self.q_window) if model is not None else None
        return WindowThreshold.choose(model, model_tau, sampled,
                                      model_tau if cfg.threshold == "hardware" else sampled,
                                      "model" if cfg.threshold == "hardware" else "sampled",
                                      cfg.floor)

    def _silence(self, sc: int, obs: ObserverState, b: float) -> None:
        """An observer with a plan sent no image this window: after ``silent_windows`` in a
        row, a link fault (once per episode)."""
        obs.silent += 1
        if obs.silent >= self.cfg.silent_windows and not obs.link_declared:
            obs.link_declared = True
            self.log.warning("FDIR: sc%d silent for %d windows: link fault", sc, obs.silent)
            self.publish("report", FaultReport(sender=self.ctx.node, t_sim=b, spacecraft=sc,
                                               fault_class="link", window_end_s=b))


def _g(value: float | None) -> str:
    return "-" if value is None else f"{value:.3g}"
