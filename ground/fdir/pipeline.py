"""The ground FDIR as a pipeline (paper Sec. III.B-E; docs/fdir.md, "The pipeline"): what the
FDIR knows of each observer, fed message by message, and every FDI window judged through its
stages, in this order:

1. **link checks** (``link_checks.py``): observations missing by sequence number, silence
   (and, with ground passes, out of the windows: silence in a pass, a dump's loss, as the
   pass and the store's accounting come);
2. **information test** (``information.py``) on the window's context (``window.py``: a, b,
   ψ, φ, h_prev, the judged images and their poses), with the identification evidence;
3. **global check** (``global_check.py``, Eq. 6) over the observers the test judged;
4. **declaration and identification** (``declaration.py``);
5. **data integrity** (``integrity.py``) of the H_i reported at the window's end, once the
   window's images are in the ground's map.

Each window [a, b) (length ``rates.fdi_period_s``) is judged ``fdir.latency_s`` after it
closes, with ψ the squared fused variance of the ground's map settled at a (every observation
with image time < a).  Only lost images are missing from both sides of the comparison; a window
without any image or any plan gives no decision.  The stages return the messages to publish,
in order; the app (``ground/apps/fdir.py``) publishes them.
"""

from __future__ import annotations

import bisect
import logging
import math

import numpy as np

from gnc import quat
from gnc.image_scan import Crossing
from gnc.mission import MissionConstants
from gnc.passes import ContactPlan
from gnc.poi_map import PoiMap
from gnc.twin import FlightPlan, Transfer, TwinModel
from ground.fdir.declaration import Declarer
from ground.fdir.fused_views import FusedViews
from ground.fdir.global_check import GlobalCheck
from ground.fdir.information import IDENTIFY_IMAGES, IDENTIFY_STEP, InformationTest, Judgement
from ground.fdir.integrity import IntegrityCheck
from ground.fdir.link_checks import LinkChecks
from ground.fdir.neighbour_rulings import NeighbourRulings
from ground.fdir.observer import ObserverState
from ground.fdir.sequential import SequentialTest, decided, image_false_alarm
from ground.fdir.window import SettledMap, window_context
from interfaces.contracts.catalogue import FDIR_DOWNLINK_TOPICS, OBSERVATIONS
from interfaces.contracts.fdi_schedule import FdiSchedule
from interfaces.contracts.messages import (
    AttitudeEstimate,
    FaultReport,
    FdirWindow,
    GuidanceStatus,
    InfoCostTelemetry,
    LinkStats,
    Message,
    NeighbourDeclaration,
    OnboardFdirEvent,
    PoiObservations,
    ProAssignments,
    ScanStatus,
    StateEstimate,
    TransferPlanMsg,
    Unjudged,
)
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.timing import TIME_TOL_S
from interfaces.contracts.topics import spacecraft_of


class FdirPipeline:
    """The FDIR's state and its window-by-window judgement, for ``scenario`` (whose constants
    are ``constants``) on node ``node``."""

    def __init__(self, scenario: Scenario, constants: MissionConstants, node: str,
                 log: logging.Logger) -> None:
        sc, cfg = scenario, scenario.fdir
        self.node, self.log, self.settle_s, self.latency_s = node, log, cfg.settle_s, cfg.latency_s
        self.schedule = FdiSchedule(sc.rates.fdi_period_s)
        self._tick = (sc.rates.dt_s, sc.rates.ticks_per("mid"))
        """the tick (s) and the ticks per image (ω_mid): an image's time is its tick's, k dt"""
        self._grid: tuple[float, np.ndarray] | None = None
        """the start (s) of the window whose image times were made last, and those times"""
        self.contact = ContactPlan.of(sc)
        """when the ground hears (None: continuously)"""
        self.n = constants.n_rad_s
        self.twin = TwinModel(constants.poi_pos, constants.poi_normal, constants.camera,
                              sc.target.radius_m, sc.camera.noise_frac)
        self.settled = PoiMap.uniform(sc.target.pois, sc.target.prior_variance,
                                      sc.observers.count)
        self.views = FusedViews.of(sc.observers.count, sc.target.pois, sc.comms.range_m)
        """what each observer fused, for the data-integrity check"""
        self.pending: list[PoiObservations] = []
        self.observers = {i: ObserverState() for i in range(1, sc.observers.count + 1)}
        self.boresight_body = constants.boresight_body
        self.links = LinkChecks(sc, node, log)
        self.information = InformationTest(sc, self.twin)
        self.sequential = (SequentialTest(sc, self.twin,
                                          image_false_alarm(sc, self.information.tests))
                           if cfg.detector == "sequential" else None)
        """the sequential test on each image as it comes (None: the windows alone)"""
        self._identify_tries: dict[int, tuple[float, int]] = {}
        """each observer's last try at identifying on part of a window: its start (s) and the
        images tried"""
        self._status_s: dict[int, float] = {}
        """each observer's time of the newest statistics sent out (``ScanStatus``), s"""
        self._crossings: dict[int, Crossing] = {}
        """the sequential test's crossings waiting for the other observers' images"""
        self.global_check = GlobalCheck(cfg, self.information.q_window, node, log)
        self.declarer = Declarer(cfg, node, log)
        self.integrity = IntegrityCheck(cfg, node, log, sc.rates.fdi_period_s,
                                        sc.comms.packet_loss)
        self.rulings = NeighbourRulings(node, log)
        self.next_window = 0
        """the next FDI window to judge (``interfaces.contracts.fdi_schedule``)"""
        self.rejected = 0
        self._transfers: dict[tuple[int, int], Transfer] = {}
        self._dump_reports: list[FaultReport] = []
        """link faults the dumps' accounting declared, out with the next ``due``"""

    # --- what the observers report ---------------------------------------------------------

    def observations(self, msg: PoiObservations) -> None:
        if msg.spacecraft not in self.observers:
            return
        poi = msg.poi
        if len(poi) and int(poi.max()) >= len(self.twin.poi_pos):
            self.rejected += 1
            self.log.error("FDIR: dropped observations of sc%d with POI indices outside the "
                           "%d of the target (%d dropped)", msg.spacecraft, len(self.twin.poi_pos),
                           self.rejected)
            return
        self.observers[msg.spacecraft].heard(msg.t_sim)
        if msg.image_t_s >= self.window_start:
            self.pending.append(msg)
        else:  # too late for its window's verdict, not for the ground's map
            self.settled.add(msg.spacecraft, *msg.arrays())
            self.views.add([msg], self.observers)

    def transfer(self, msg: TransferPlanMsg) -> None:
        """A transfer an observer planned, the path it flies to its assignment's PRO; or its
        refusal of the assignment (it keeps the plan before, which its windows are then
        judged against)."""
        obs = self.observers.get(msg.spacecraft)
        if obs is not None and msg.refused:
            obs.refused.add(msg.assignment_id)
            if obs.plans.pop(msg.assignment_id, None) is not None:
                self.log.warning("FDIR: sc%d refused assignment %d (%s): judged on the plan it "
                                 "keeps", msg.spacecraft, msg.assignment_id, msg.status)
            return
        if obs is None or len(msg.t_s) < 2:
            return
        tr = Transfer(np.array(msg.t_s), np.array(msg.x), np.array(msg.u_mps2))
        self._transfers[(msg.spacecraft, msg.assignment_id)] = tr
        plan = obs.plans.get(msg.assignment_id)
        if plan is not None:
            obs.plans[msg.assignment_id] = FlightPlan(plan.t_from_s, plan.pro, tr,
                                                      plan.t_arrive_s)

    def assignments(self, msg: ProAssignments) -> None:
        """The ground's own assignments.  With ground passes one sent out of contact waits for
        the next pass (``ContactPlan.uplinked_s``: not one sent at the start, loaded before the
        run), so the plan is in force from then at the earliest; of those held for
        the same pass an observer flies only the newest, so an older plan that would start no
        earlier than a newer one is dropped (superseded before it started)."""
        reach = self.contact.uplinked_s(msg.t_sim) if self.contact is not None else 0.0
        for a in msg.assignments:
            obs = self.observers.get(a.spacecraft)
            if obs is None or a.assignment_id in obs.plans or a.assignment_id in obs.refused:
                continue
            plan = FlightPlan.of(a, max(a.t_depart_s, reach),
                                 self._transfers.get((a.spacecraft, a.assignment_id)))
            obs.plans = {k: p for k, p in obs.plans.items()
                         if k > a.assignment_id or p.starts_s < plan.starts_s - TIME_TOL_S}
            obs.plans[a.assignment_id] = plan

    def telemetry(self, msg: InfoCostTelemetry) -> None:
        j = self.schedule.boundary_at(msg.t_sim)
        if msg.spacecraft in self.observers and j is not None and j > self.next_window:
            self.integrity.reported(msg, j)

    def attitude(self, msg: AttitudeEstimate) -> None:
        obs = self.observers.get(msg.spacecraft)
        if obs is None:
            return
        obs.heard(msg.t_sim)
        if not obs.modes or obs.modes[-1][1] != msg.mode:
            bisect.insort(obs.modes, (msg.t_sim, msg.mode))
        if msg.t_sim >= self.window_start:
            bore = quat.rotate(np.array(msg.q_lvlh_body), self.boresight_body)
            obs.attitude.add(msg.t_sim, np.concatenate(
                (bore, [msg.pointing_error_rad], msg.target_lvlh_m, [msg.sigma_att_rad])))

    def nav(self, msg: StateEstimate) -> None:
        obs = self.observers.get(msg.spacecraft)
        if obs is not None:
            obs.heard(msg.t_sim)
        if obs is not None and msg.t_sim >= self.window_start:
            obs.nav.add(msg.t_sim, np.array(msg.x[:3]))
            obs.nav_sigma.add(msg.t_sim, np.array([msg.position_sigma_m()]))
            if msg.nis is not None:
                obs.nis.append((msg.t_sim, msg.nis))

    def onboard(self, msg: OnboardFdirEvent) -> None:
        """An onboard FDIR event: a ``camera_off`` sequence means the observer stopped imaging
        on purpose (its agent-level FDIR acting on a camera fault), so no image is expected of
        it from then on (docs/fdir.md, "Link and data faults")."""
        obs = self.observers.get(msg.spacecraft)
        if obs is not None and msg.event == "sequence" and msg.name == "camera_off":
            obs.camera_off_s = min(msg.t_sim, obs.camera_off_s or math.inf)

    def neighbours(self, msg: NeighbourDeclaration) -> None:
        """A fault the observers' neighbours declared aboard: ruled on when the ground has
        judged its subject (``ground/fdir/neighbour_rulings.py``)."""
        if msg.subject in self.observers and msg.spacecraft in self.observers:
            self.rulings.declaration(msg)

    def link_stats(self, msg: LinkStats) -> None:
        """The ground's own channel counters: with ground passes, each observer's onboard store
        as its housekeeping reports it in a pass (docs/fdir.md, "Ground passes"): the FDIR
        topics' overflow runs, the observations lost to overflow, and the oldest report the
        FDIR judges still aboard; and the dump's loss (``LinkChecks.dump``)."""
        for c in msg.links:
            sc = spacecraft_of(c.src) or 0
            obs = self.observers.get(sc)
            if obs is None or c.dst != self.node or c.store is None:
                continue
            self._dump_reports += self.links.dump(sc, obs, c.store, msg.t_sim)
            runs = c.store.overflow_runs
            obs.overflow = [(r.first_s, r.last_s) for r in runs if r.topic in FDIR_DOWNLINK_TOPICS]
            obs.overflow_observations = sum(r.count for r in runs if r.topic == OBSERVATIONS.path)
            if c.store.dumped > obs.dumped_seen and self.contact is not None:
                # what is aboard is known from what comes down: a cut link tells nothing
                obs.dumped_seen, obs.aboard_since_s = c.store.dumped, c.store.judged_since_s
                obs.aboard_pass = self.contact.pass_index(msg.t_sim)

    def guidance(self, msg: GuidanceStatus) -> None:
        obs = self.observers.get(msg.spacecraft)
        if obs is not None and msg.t_sim >= self.window_start - self.schedule.period_s:
            bisect.insort(obs.guidance, (msg.t_sim, msg.dv_commanded_mps, msg.mode == "hold"))

    # --- the windows ------------------------------------------------------------------------

    @property
    def window_start(self) -> float:
        """Start of the next window to judge (s): later data is still to come."""
        return self.schedule.start(self.next_window)

    def due(self, t: float) -> list[Message]:
        """Judge every window due by time t (s): ``fdir.latency_s`` after it closed; with the
        link faults the dumps' accounting declared since the last call."""
        out: list[Message] = [*self._dump_reports]
        self._dump_reports = []
        if self.contact is not None:
            now = self.contact.pass_index(t)
            for o in self.observers.values():
                o.heard_pass = now if o.fresh else o.heard_pass
                o.fresh = False
                if o.aboard_pass < now:  # not heard of in this pass: not known to be aboard
                    o.aboard_since_s = None
            out += self._pass_silences(t, now)
        while (t >= self.schedule.end(self.next_window) + self.latency_s - TIME_TOL_S
               and self._data_in(self.next_window, t)):
            k = self.next_window
            out += self._scan(k, final=True)
            self.next_window += 1  # first: a failing window is not retried forever
            out += self.evaluate(k)
        out += self._scan(self.next_window, final=False)
        out += self._identify_part(self.next_window)
        return [m.model_copy(update={"declared_s": t}) if isinstance(m, FaultReport) else m
                for m in out]

    def _data_in(self, k: int, t: float) -> bool:
        """Whether window k's data is in by t (s).  Always, for a ground that hears
        continuously.  With ground passes: once every observer has been heard from at or after
        the window's end (its store dumps the FDIR's topics in send order), except one declared
        silent of which nothing came down in this pass; or, for a window some observer's data
        did not reach, at the end of the first pass after the window's end plus
        ``fdir.latency_s`` (docs/fdir.md, "Ground passes").  An observer declared silent whose
        dump comes down later is waited for again: judged on half its dump, the H_i it reports
        first (priority 0) would not match the images still aboard."""
        if self.contact is None:
            return True
        b, now = self.schedule.end(k), self.contact.pass_index(t)
        if all(o.heard_s >= b - TIME_TOL_S or (o.link_declared and o.heard_pass < now)
               for o in self.observers.values()):
            return True
        return t >= self.contact.contact_end(b + self.latency_s) - TIME_TOL_S

    def evaluate(self, k: int) -> list[Message]:
        """Window k through every stage; the window's images then join the ground's map."""
        a, b = self.schedule.start(k), self.schedule.end(k)
        inside = [m for m in self.pending if a <= m.image_t_s < b]
        settled = SettledMap.of(self.settled)
        out: list[Message] = []
        judged: dict[int, Judgement] = {}
        for sc, obs in self.observers.items():
            mine = sorted((m for m in inside if m.spacecraft == sc), key=lambda m: m.image_t_s)
            window = FdirWindow(sender=self.node, t_sim=b, spacecraft=sc, t_start_s=a,
                                t_end_s=b, images=len(mine),
                                **(self.sequential.window_fields(sc, a)
                                   if self.sequential is not None else {}))
            lost_aboard = self._lost_aboard(sc, obs, a, b)
            if lost_aboard is not None:  # data lost or still aboard, of known cause
                out += [*lost_aboard[1], window.model_copy(update={"unjudged": lost_aboard[0]})]
                obs.last_image_s = None  # no silence is measured across a window not judged
                continue
            imaging = not obs.camera_off_before(b)
            planned = obs.plan_at(a) is not None and imaging
            reach = self.links.in_reach(obs, self.n, a, b)
            lost, reports = self.links.judge(sc, obs, mine, imaging, b, reach)
            out += reports
            window = window.model_copy(update={"lost": lost})
            ctx, images, why = (window_context(sc, obs, mine, a, b, settled, self.n,
                                               self.settle_s)
                                if planned and mine else (None, len(mine), None))
            if ctx is None:
                out.append(window.model_copy(update={
                    "images": images,
                    "unjudged": why or _unplanned(obs, b, mine, reach)}))
                continue
            judged[sc] = self.information.judge(
                ctx, obs, window.model_copy(update={"images": images}),
                self.declarer.identifying(sc), self.declarer.naming(sc),
                self.declarer.change_s(sc))
        common, messages = self.global_check.check(a, b, judged, self._cost())
        out += messages
        for sc, j in judged.items():
            out += self.declarer.declare(sc, j, common, self.global_check.way)
        out += self.rulings.rule(b, {w.spacecraft: w.exceeded for w in out
                                     if isinstance(w, FdirWindow)},
                                 [sc for sc in judged if self.declarer.declared(sc)])
        self._settle(inside, b)
        reports, unjudged = self.integrity.check(k + 1, b, self.settled, self.views,
                                                 self.observers, self.rulings.excludes)
        return [m.model_copy(update={"integrity_unjudged": unjudged[m.spacecraft]})
                if isinstance(m, FdirWindow) and m.spacecraft in unjudged else m
                for m in out] + reports

    def _scan(self, k: int, final: bool) -> list[Message]:
        """With the sequential test: window k's images come so far and not yet scored, each
        observer's in time order, against the map settled at the window's start (windows
        before k judged), and the crossings then decided (:meth:`_decide_crossings`;
        ``final``: window k's data is all in).  docs/fdir.md, "The sequential test"."""
        if self.sequential is None:
            return []
        a, b = self.schedule.start(k), self.schedule.end(k)
        settled: SettledMap | None = None
        own: list[Message] = []
        for sc, obs in self.observers.items():
            if self.declarer.declared(sc):  # scored afresh once its episode ends
                self.sequential.reset(sc)
                continue
            if sc in self._crossings:
                continue  # its crossing waits: scored again once decided
            last = self.sequential.last_scored_s(sc) + TIME_TOL_S
            mine = sorted((m for m in self.pending
                           if m.spacecraft == sc and a <= m.image_t_s < b and m.image_t_s > last),
                          key=lambda m: m.image_t_s)
            if not mine:
                continue
            settled = settled or SettledMap.of(self.settled)
            ctx = (window_context(sc, obs, mine, a, b, settled, self.n, self.settle_s,
                                  self._image_times(a, b))[0]
                   if obs.plan_at(a) is not None and not obs.camera_off_before(b) else None)
            plan = (obs.planned(self.n, self.sequential.plan_times(a, b))
                    if ctx is not None and not self.sequential.modelled(sc, a) else None)
            crossing = (self.sequential.score(ctx, plan[0] if plan is not None and plan[2].all()
                                              else None)
                        if ctx is not None else None)
            if crossing is None:
                self.sequential.passed(sc, mine[-1].image_t_s)
            elif crossing.test == "pointing":  # its own attitude: declared at once
                self.sequential.reset(sc)
                own.append(self.declarer.declare_crossing(sc, crossing, b))
            else:  # the images after it are scored once it is decided
                self._crossings[sc] = crossing
        return (own + self._scan_nis(a, b) + self._decide_crossings(a, b, final)
                + self._statuses())

    def _image_times(self, a: float, b: float) -> np.ndarray:
        """The times (s) of the images window [a, b) can hold: one every ω_mid period, each
        its tick's time k·dt as the sim makes it (made once a window)."""
        if self._grid is None or self._grid[0] != a:
            dt, every = self._tick
            first, end = math.ceil(a / dt - 0.5), math.ceil(b / dt - 0.5)
            self._grid = (a, np.array([k * dt for k in range(first, end) if k % every == 0]))
        return self._grid[1]

    def _identify_part(self, k: int) -> list[Message]:
        """With the sequential test: each declared fault still without a class judged, as a
        window of its own, on the newest ``IDENTIFY_IMAGES`` images of window k come so far
        since its change (the scan's estimate, or the window's start), each time
        ``IDENTIFY_STEP`` more have come (docs/fdir.md, "Identification after a crossing"):
        its class as soon as the evidence names one, not at the window's end.  The newest,
        not all since the change: a drift (a leak) is the farther off the later."""
        if self.sequential is None:
            return []
        a, b = self.schedule.start(k), self.schedule.end(k)
        out: list[Message] = []
        for sc, obs in self.observers.items():
            if not self.declarer.identifying(sc) or obs.plan_at(a) is None:
                continue
            since = max(self.declarer.change_s(sc) or a, a)
            mine = sorted((m for m in self.pending
                           if m.spacecraft == sc and since <= m.image_t_s < b),
                          key=lambda m: m.image_t_s)
            if not self._identify_due(sc, a, len(mine)):
                continue
            newest = mine[-IDENTIFY_IMAGES:]  # a drift shows most in the newest
            ctx = window_context(sc, obs, newest, newest[0].image_t_s, newest[-1].image_t_s,
                                 SettledMap.of(self.settled), self.n, self.settle_s)[0]
            if ctx is None or len(ctx.times) < IDENTIFY_IMAGES:
                continue
            window = FdirWindow(sender=self.node, t_sim=ctx.b, spacecraft=sc, t_start_s=ctx.a,
                                t_end_s=ctx.b, images=len(ctx.times))
            j = self.information.judge(ctx, obs, window, True, True)
            report = self.declarer.identify_part(sc, j, ctx.b, b)
            out += [report] if report is not None else []
        return out

    def _identify_due(self, sc: int, a: float, images: int) -> bool:
        """Whether observer ``sc``'s ``images`` since its change in the window starting at
        ``a`` (s) are enough, and enough more than at the last try, for a try."""
        held = self._identify_tries.get(sc)
        tried = held[1] if held is not None and abs(held[0] - a) < TIME_TOL_S else 0
        if images < max(IDENTIFY_IMAGES, tried + IDENTIFY_STEP):
            return False
        self._identify_tries[sc] = (a, images)
        return True

    def _statuses(self) -> list[Message]:
        """Each observer's newest scan statistics, where something was scored since the last
        (``ScanStatus``: the operator sees evidence build before a declaration)."""
        assert self.sequential is not None
        out: list[Message] = []
        for sc in self.observers:
            fields = self.sequential.status(sc)
            t = fields.pop("t_s", None)
            if t is None or t <= self._status_s.get(sc, -math.inf) + TIME_TOL_S:
                continue
            self._status_s[sc] = t
            out.append(ScanStatus(sender=self.node, t_sim=t, spacecraft=sc, **fields))
        return out

    def _scan_nis(self, a: float, b: float) -> list[Message]:
        """With ``fdir.fuse_nis``: each observer's nav updates come since the last call and
        before ``b`` (s; the end of the window [a, b) being collected, whose verdict comes next) on
        its NIS scan, not scored while its fault is declared; a crossing is declared at once
        (the observer's own nav: nothing common to the constellation), in place of a crossing
        of its information scan still waiting, and that scan starts afresh."""
        test = self.sequential
        if test is None or not self.information.cfg.fuse_nis:
            return []
        out: list[Message] = []
        for sc, obs in self.observers.items():
            crossing = test.score_nis(sc, [u for u in obs.nis if u[0] < b],
                                      not self.declarer.declared(sc), a)
            if crossing is not None:
                self._crossings.pop(sc, None)
                test.reset(sc)
                out.append(self.declarer.declare_crossing(sc, crossing, b))
        return out

    def _decide_crossings(self, a: float, b: float, final: bool) -> list[Message]:
        """The pending crossings of window [a, b) declared once decided
        (:func:`ground.fdir.sequential.decided`; ``final``: the window's data is all in), or,
        when common to every observer scored in it, declared on the constellation (the global
        check's verdict, Eq. 6, reached at once: ``GlobalCheck.declare_crossings``); one the
        way of a common-mode episode still declared is the constellation's, dropped.  An
        observer whose images were passed over (no plan, camera off) has no say."""
        if self.sequential is None:
            return []
        test = self.sequential
        for sc in [sc for sc, c in self._crossings.items() if self.global_check.explains(c)]:
            del self._crossings[sc]  # the constellation's declared common mode, not its own
            test.reset(sc)
        scored = [sc for sc in self.observers
                  if test.evidence_since(sc, a) and not self.declarer.declared(sc)]
        now = decided(self._crossings, scored,
                      {sc: test.last_scored_s(sc) for sc in self.observers}, final)
        out: list[Message] = []
        if now is None:  # every scored observer crossed the same way: the constellation's
            together = [self._crossings[sc] for sc in scored]
            out += self.global_check.declare_crossings(
                together, max(c.image_t_s for c in together), b)
        for sc in list(self._crossings) if now is None else now:
            crossing = self._crossings.pop(sc)
            test.reset(sc)  # its evidence spent: a later crossing is a new one
            if now is not None:
                out.append(self.declarer.declare_crossing(sc, crossing, b))
        return out

    def _pass_silences(self, t: float, now: int) -> list[FaultReport]:
        """With ground passes, by ``t`` (s) in pass ``now``: the observers of which nothing
        came down an FDI period and the FDIR's latency after its acquisition, while others
        were heard in it (``LinkChecks.pass_silence``)."""
        assert self.contact is not None
        if now < 0 or not self.contact.in_contact(t):
            return []
        if t < self.contact.windows[now][0] + self.schedule.period_s + self.latency_s:
            return []
        heard = {sc for sc, o in self.observers.items() if o.heard_pass == now}
        if not heard:  # nobody heard: the ground's own link, or nothing to say
            return []
        since = t - self.schedule.period_s
        return [r for sc, o in self.observers.items()
                if sc not in heard and not (o.link_declared or o.dump_declared)
                and self.links.in_reach(o, self.n, since, t)
                for r in self.links.pass_silence(sc, o, t)]

    def _lost_aboard(self, sc: int, obs: ObserverState, a: float, b: float
                     ) -> tuple[Unjudged, list[FaultReport]] | None:
        """Why observer ``sc``'s window [a, b) cannot be judged on what came down, with the
        ground passes: its store lost its reports (a link fault of known cause, once per
        episode) or still holds some (docs/fdir.md, "Lost is not corrupt"); None: neither."""
        if obs.overflowed(a, b):
            obs.lossy = True  # the window's data lost: no view rebuilt on it
            return "store_overflow", self.links.overflow(sc, obs, b)
        if obs.aboard_before(b):  # what came down is counted afresh once it is all in
            obs.resync = True
            return "aboard", []
        return None

    def _settle(self, inside: list[PoiObservations], b: float) -> None:
        """The judged window's images join the ground's map and the views their observers
        fused (by the nav positions of the window: first); what no later window needs goes."""
        for m in inside:
            self.settled.add(m.spacecraft, *m.arrays())
        self.views.add(inside, self.observers)
        for obs in self.observers.values():
            obs.forget_before(b)
        self.pending = [m for m in self.pending if m.image_t_s >= b]

    def _cost(self) -> float:
        """H of the ground's fused map (Eq. 4, 7)."""
        return float(np.sum(self.settled.phi * self.settled.variance()))


def _unplanned(obs: ObserverState, b: float, images: list[PoiObservations],
               reach: bool = True) -> Unjudged:
    """Why a window without a context was not judged, before its images were looked at
    (``reach``: whether the plan kept the observer in the relay's reach)."""
    if obs.camera_off_before(b):
        return "camera_off"
    if not reach and not images:
        return "out_of_range"
    return "no_images" if not images else "no_plan"
