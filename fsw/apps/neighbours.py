"""Neighbours' FDIR app: this observer judges every neighbour it hears, and declares a fault by
their agreement (docs/fdir.md, "Neighbours judge each other"; ``[neighbours]``).

Rate group mid.  Inputs: every observer's shared observations (a neighbour's only within
range, each with its reported pose), every observer's guidance status (the assignment, mode
and PRO it flies: the plan in force as flown, whenever the ground's uplink reached it), every
observer's judgements (its own come back through the bus), and the ground's rulings.  Outputs: this
observer's ``NeighbourJudgement`` of each FDI window, on the crosslinks, and a
``NeighbourDeclaration`` when the judgements of a neighbour's window agree
(``fsw/lib/neighbour_judge.py``), sent to every app of this spacecraft and to the ground.

Timing, per window [a, b): judged ``fdir.latency_s`` after b (the neighbours' observations up to
b are in); the judgements of the others arrive one tick later, and the agreement is applied
one ω_mid cycle after the judging.  With ``fdir.detector = "sequential"`` each neighbour's
images of the window are also scanned as they come (once window k − 1 is judged), the
crossings shared at once and agreed on each ω_mid step.  ψ is held at a on this observer's
own fused map, which takes each window's observations once the window is judged, leaving out
the observers its neighbours declared (until the ground overrules them, or ``[neighbours]
clear_windows`` of their windows in a row are agreed passing: a declared observer is still
judged).
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np

from fsw.lib.neighbour_judge import (
    Exclusions,
    FlownReport,
    agreed,
    cleared,
    held_pro,
    judge,
    reported_pose,
)
from gnc.hardware_threshold import clipped_noise_moments
from gnc.image_scan import Crossing, ImageScans, step_false_alarm
from gnc.poi_map import PoiMap
from gnc.pro import Pro
from gnc.sequential_test import scan_threshold
from gnc.twin import TwinModel
from gnc.window_test import WindowTestSettings
from interfaces.contracts import catalogue as cat
from interfaces.contracts.fdi_schedule import FdiSchedule
from interfaces.contracts.messages import (
    GuidanceStatus,
    NeighbourCrossing,
    NeighbourDeclaration,
    NeighbourJudgement,
    NeighbourRuling,
    PoiObservations,
    Unjudged,
)
from interfaces.contracts.timing import TIME_TOL_S
from interfaces.runtime.app import App, AppContext, Input, Output


class NeighboursApp(App):
    NAME = "neighbours"
    RATE = "mid"
    INPUTS = (
        Input(cat.OBSERVATIONS, "on_observations", every_spacecraft=True),
        Input(cat.GUIDANCE_STATUS, "on_guidance", every_spacecraft=True),
        Input(cat.NEIGHBOUR_JUDGEMENT, "on_judgement", every_spacecraft=True),
        Input(cat.NEIGHBOUR_RULING, "on_ruling"),
    )
    OUTPUTS = (Output("judgement", cat.NEIGHBOUR_JUDGEMENT),
               Output("declaration", cat.NEIGHBOUR_DECLARATION))
    CRITICAL = ("map", "pending", "flown", "verdicts", "exclusions", "declared", "passing",
                "next_judge", "next_decide", "crossed", "crossed_at", "scans._scans",
                "scans._models")

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        sc, k = ctx.scenario, ctx.constants
        self.sc_id = ctx.spacecraft or 0
        self.n = k.n_rad_s
        self.map = PoiMap.uniform(sc.target.pois, sc.target.prior_variance, sc.observers.count)
        self.twin = TwinModel(k.poi_pos, k.poi_normal, k.camera, sc.target.radius_m,
                              sc.camera.noise_frac)
        self.cfg = WindowTestSettings.of(sc)
        self.agree = sc.neighbours.agree
        self.schedule = FdiSchedule(sc.rates.fdi_period_s)
        self.latency_s = sc.fdir.latency_s
        self.decide_after_s = 1.0 / sc.rates.mid_hz
        self.seed = sc.seed
        self.pending: list[PoiObservations] = []
        self.flown: dict[int, list[FlownReport]] = defaultdict(list)
        """what each observer's guidance status says it flies, in time order"""
        self.max_gap_s = 2.0 / sc.rates.low_hz + TIME_TOL_S
        """reports further apart than two of their periods leave the plan unknown"""
        self.clear_windows = sc.neighbours.clear_windows
        self.passing: dict[int, int] = {}
        """declared subjects: their windows agreed passing in a row"""
        self.verdicts: dict[tuple[int, int], dict[int, bool | None]] = {}
        """(window index, subject) -> judge -> exceeded"""
        self.exclusions = Exclusions()
        self.declared: set[int] = set()
        """subjects declared aboard (an episode: until the ground overrules)"""
        self.next_judge = 0
        self.next_decide = 0
        self.sequential = sc.fdir.detector == "sequential"
        self.tests = 2 if self.sequential else 1
        """the statistical tests sharing the false-alarm budget: the window test, the scan"""
        self.scans = ImageScans(self.cfg, self.twin,
                                clipped_noise_moments(sc.camera.noise_frac)[1],
                                scan_threshold(step_false_alarm(
                                    sc.fdir.false_alarms_per_observer_hour, self.tests,
                                    sc.rates.mid_hz)),
                                1.0 / sc.rates.mid_hz, (sc.seed, self.sc_id))
        """with the sequential test, this judge's scan of each neighbour's images"""
        self.crossed: dict[int, dict[int, float]] = {}
        """subject -> judge -> the image at which its scan crossed (s), over the last FDI
        period"""
        self.crossed_at: dict[int, float] = {}
        """subjects declared on their judges' scans: when the first crossed (s)"""

    # --- inputs -------------------------------------------------------------------------------

    def on_observations(self, msg: PoiObservations) -> None:
        if 1 <= msg.spacecraft <= self.map.n_agents:
            self.pending.append(msg)

    def on_guidance(self, msg: GuidanceStatus) -> None:
        if 1 <= msg.spacecraft <= self.map.n_agents:
            reports = self.flown[msg.spacecraft]
            reports.append(FlownReport.of(msg))
            if len(reports) > 1 and reports[-2].t_s > msg.t_sim:
                reports.sort(key=lambda r: r.t_s)

    def on_judgement(self, msg: NeighbourJudgement) -> None:
        k = self.schedule.boundary_at(msg.t_start_s)  # window k starts at boundary k
        if k is None:  # not a window of this schedule: dropped
            return
        for v in msg.verdicts:
            if v.subject != msg.spacecraft:
                self.verdicts.setdefault((k, v.subject), {})[msg.spacecraft] = v.exceeded
        for c in msg.crossings:
            if c.subject != msg.spacecraft:
                self.crossed.setdefault(c.subject, {})[msg.spacecraft] = c.t_s

    def on_ruling(self, msg: NeighbourRuling) -> None:
        if msg.verdict == "overruled" and msg.subject in self.declared:
            self._readmit(msg.subject)
            self.log.warning("the ground overruled the neighbours on sc%d: fused again",
                             msg.subject)

    def _readmit(self, subject: int) -> None:
        """``subject``'s declaration ends: it is fused again, with what was held of it."""
        self.declared.discard(subject)
        self.passing.pop(subject, None)
        self.crossed_at.pop(subject, None)
        self.scans.reset(subject)  # scanned afresh
        self.pending += self.exclusions.readmit(subject)

    # --- the cycle ----------------------------------------------------------------------------

    def step(self, t: float) -> None:
        while t >= self.schedule.end(self.next_decide) + self.latency_s \
                + self.decide_after_s - TIME_TOL_S and self.next_decide < self.next_judge:
            self._decide(self.next_decide, t)
            self.next_decide += 1
        while t >= self.schedule.end(self.next_judge) + self.latency_s - TIME_TOL_S:
            self._judge(self.next_judge, t)
            self.next_judge += 1
        if self.sequential:
            self._decide_crossings(t)
            self._scan(self.next_judge, t)

    def _judge(self, k: int, t: float) -> None:
        """Judge window k's neighbours, then fuse its observations into this observer's map."""
        a, b = self.schedule.start(k), self.schedule.end(k)
        inside = [m for m in self.pending if a <= m.image_t_s < b]
        psi, phi = self.map.variance() ** 2, self.map.phi
        verdicts = []
        for subject in sorted({m.spacecraft for m in inside} - {self.sc_id}):
            images = sorted((m for m in inside if m.spacecraft == subject),
                            key=lambda m: m.image_t_s)
            rng = np.random.default_rng([self.seed, self.sc_id, subject, k])
            verdicts.append(judge(subject, images, self._pro(subject, a, b), psi, phi,
                                  self.twin, self.n, self.cfg, rng, self.tests))
        if verdicts:
            self.publish("judgement", NeighbourJudgement(
                sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id, t_start_s=a, t_end_s=b,
                verdicts=verdicts))
        for m in inside:
            if m.spacecraft == self.sc_id or self.exclusions.admits(m):
                self.map.add(m.spacecraft, *m.arrays())
        self.pending = [m for m in self.pending if m.image_t_s >= b]
        for subject, reports in self.flown.items():  # keep what the next window needs
            self.flown[subject] = [r for r in reports if r.t_s >= b - self.max_gap_s]

    def _scan(self, k: int, t: float) -> None:
        """With the sequential test: window k's images of each neighbour come since the last
        step scored on its scan (``gnc/image_scan.py``, the ground's), on this observer's map
        at the window's start (window k − 1 judged), against the PRO it reports holding since
        then; the crossings shared at once (docs/fdir.md, "Neighbours judge each other")."""
        a, b = self.schedule.start(k), self.schedule.end(k)
        crossings = []
        held: tuple[np.ndarray, np.ndarray] | None = None  # ψ and φ, once a step
        for subject in sorted({m.spacecraft for m in self.pending} - {self.sc_id}):
            fresh = sorted((m for m in self.pending if m.spacecraft == subject
                            and a <= m.image_t_s < b
                            and m.image_t_s > self.scans.last_scored_s(subject) + TIME_TOL_S),
                           key=lambda m: m.image_t_s)
            if not fresh or subject in self.declared:
                continue
            held = held or (self.map.variance() ** 2, self.map.phi)
            crossing = self._score(subject, fresh, (a, b), held)
            if crossing is not None:
                self.scans.reset(subject)  # its evidence shared: a later crossing is new
                crossings.append(NeighbourCrossing(
                    subject=subject, t_s=crossing.image_t_s, z=crossing.scan.z,
                    span=crossing.scan.span, shift=crossing.shift, limit=crossing.limit,
                    direction=crossing.direction or "degraded"))
        if crossings:
            self.publish("judgement", NeighbourJudgement(
                sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id, t_start_s=a, t_end_s=b,
                crossings=crossings))

    def _score(self, subject: int, fresh: list[PoiObservations], window: tuple[float, float],
               held: tuple[np.ndarray, np.ndarray]) -> Crossing | None:
        """``subject``'s images ``fresh`` (time order) of ``window`` on its scan, with ψ and
        φ ``held`` at the window's start: passed over where none is judgeable (not tracking
        long enough, no PRO held)."""
        usable = [m for m in fresh if m.pose is not None
                  and m.pose.tracking_s >= self.cfg.settle_s]
        pro = self._pro(subject, window[0], fresh[-1].image_t_s)
        if not usable or not isinstance(pro, Pro):
            self.scans.passed(subject, fresh[-1].image_t_s)
            return None
        times = np.array([m.image_t_s for m in usable])
        pose = reported_pose(pro.states(self.n, times)[:, :3],
                             [m.pose for m in usable if m.pose is not None])
        plan = (None if self.scans.modelled(subject, window[0])
                else pro.states(self.n, self.scans.plan_times(*window))[:, :3])
        crossing = self.scans.score_images(subject, window, times,
                                           [m.arrays() for m in usable], pose, *held, plan)
        self.scans.passed(subject, fresh[-1].image_t_s)
        return crossing

    def _decide_crossings(self, t: float) -> None:
        """With the sequential test: a neighbour is declared at once when ``agree`` judges'
        scans crossed on it within one FDI period, whatever windows their images fell in (the
        window's verdicts decide otherwise, as without), on the window of the first."""
        period = self.schedule.period_s
        for subject, by_judge in sorted(self.crossed.items()):
            recent = {j: c for j, c in by_judge.items() if c >= t - period - self.latency_s}
            self.crossed[subject] = recent
            if subject in self.declared or len(recent) < self.agree:
                continue
            first = min(recent.values())
            judges = sorted(recent)
            self._declare(int(first // period), subject, judges, judges, t, first)
            self.crossed_at[subject] = first
        self.crossed = {subject: v for subject, v in self.crossed.items() if v}

    def _pro(self, subject: int, a: float, b: float) -> Pro | Unjudged:
        """The PRO ``subject`` held over all of [a, b] (s) by its own guidance reports, or why
        none (``fsw.lib.neighbour_judge.held_pro``)."""
        return held_pro(self.flown.get(subject, []), a, b, self.max_gap_s)

    def _decide(self, k: int, t: float) -> None:
        """Apply the agreement rule to window k's judgements."""
        b = self.schedule.end(k)
        for (kk, subject), by_judge in sorted(self.verdicts.items()):
            if kk != k:
                continue
            if subject in self.declared:
                if self.schedule.start(k) >= self.crossed_at.get(subject, -1.0) - TIME_TOL_S:
                    self._still_declared(subject, by_judge, b)  # not one begun before its scans
                continue
            judges = agreed(by_judge, self.agree)
            if judges is not None:
                self._declare(k, subject, judges,
                              sorted(j for j, v in by_judge.items() if v is not None), t)
        self.verdicts = {key: v for key, v in self.verdicts.items() if key[0] > k}

    def _declare(self, k: int, subject: int, judges: list[int], decided: list[int], t: float,
                 crossed_s: float | None = None) -> None:
        """``subject`` declared on window k by ``judges`` of ``decided``: left out of this
        observer's fusion from the window's end (from its start, ``crossed_s`` the first of
        the judges' scans crossing mid-window, s) and the declaration sent."""
        a, b = self.schedule.start(k), self.schedule.end(k)
        self.declared.add(subject)
        self.scans.reset(subject)  # its evidence spent
        if subject != self.sc_id:
            self.exclusions.exclude(subject, b if crossed_s is None else a)
        self.log.warning("neighbours declare sc%d at %.0f s (%s of %s found its window "
                         "failed%s)", subject, b if crossed_s is None else crossed_s, judges,
                         decided, "" if crossed_s is None else ", their scans crossing")
        self.publish("declaration", NeighbourDeclaration(
            sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id, subject=subject,
            t_start_s=a, t_end_s=b, judges=judges, decided=decided, crossed_s=crossed_s))

    def _still_declared(self, subject: int, by_judge: dict[int, bool | None], b: float) -> None:
        """A declared subject's window, judged again: ``clear_windows`` in a row agreed
        passing clear the declaration aboard (a later fault is then declared anew)."""
        if not cleared(by_judge, self.agree):
            self.passing[subject] = 0
            return
        self.passing[subject] = self.passing.get(subject, 0) + 1
        if self.passing[subject] >= self.clear_windows:
            self._readmit(subject)
            self.log.warning("neighbours clear sc%d at %.0f s: %d windows in a row passed",
                             subject, b, self.clear_windows)
