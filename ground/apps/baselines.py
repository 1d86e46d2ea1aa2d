"""Baseline detectors beside the ground FDIR, on the same windows (ground/fdir/baselines.py).

Rate group mid.  Inputs: the FDIR's per-window verdicts (``FdirWindow``: ΔH_i, ΔH_i^pred,
H_m,i) and every observer's nav estimate (its NIS).  Output: one ``BaselineVerdict`` per
detector, observer and FDI window on ``ground/fdir/baseline``; ``alarm`` marks the window that
declares a fault (``chi2_nis`` and ``fixed_threshold`` after ``fdir.persistence`` exceedances
in a row for the first, at once for the second, as a plain limit check; ``cusum`` when its sum
first crosses ``fdir.cusum_threshold``, once per episode).  summary.json scores each like the
main detector.  With the sequential test as the main detector (``fdir.detector``), the window
test alone is one more baseline, ``window``: the FDIR's own window verdicts (Eq. 9 and its
fused tests, at the budget share the sequential test leaves it), declared after
``fdir.persistence`` failed windows, without the scans: the chapter's detector beside the one
that replaced it.
"""

from __future__ import annotations

from typing import Literal

from ground.fdir.baselines import Cusum, nis_window_test
from ground.fdir.threshold import Persistence
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import BaselineVerdict, FdirWindow, StateEstimate
from interfaces.runtime.app import App, AppContext, Input, Output

Detector = Literal["chi2_nis", "cusum", "fixed_threshold", "window"]


class BaselinesApp(App):
    NAME = "baselines"
    RATE = "mid"
    INPUTS = (
        Input(cat.FDIR_WINDOW, "on_window"),
        Input(cat.NAV_ESTIMATE, "on_nav", every_spacecraft=True),
    )
    OUTPUTS = (Output("verdict", cat.BASELINE),)
    CRITICAL = ("nis", "windows", "cusum", "chi2_persistence", "fixed_persistence",
                "window_persistence")

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        self.cfg = ctx.scenario.fdir
        self.count = ctx.scenario.observers.count
        self.nis: dict[int, list[tuple[float, float]]] = {}
        self.windows: list[FdirWindow] = []
        self.cusum = Cusum(self.cfg.cusum_drift, self.cfg.cusum_threshold)
        self.chi2_persistence = Persistence(self.cfg.persistence)
        self.fixed_persistence = Persistence(1)
        self.window_persistence = (Persistence(self.cfg.persistence, self.cfg.persistence_window)
                                   if self.cfg.detector == "sequential" else None)

    def on_nav(self, msg: StateEstimate) -> None:
        if msg.nis is not None and 1 <= msg.spacecraft <= self.count:
            self.nis.setdefault(msg.spacecraft, []).append((msg.t_sim, msg.nis))

    def on_window(self, msg: FdirWindow) -> None:
        self.windows.append(msg)

    def step(self, t: float) -> None:
        windows, self.windows = self.windows, []
        for w in sorted(windows, key=lambda w: (w.t_end_s, w.spacecraft)):
            if not 1 <= w.spacecraft <= self.count or w.t_end_s < w.t_start_s:
                self.log.warning("baseline: window of sc%d [%.1f, %.1f) s ignored", w.spacecraft,
                                 w.t_start_s, w.t_end_s)
                continue
            self._chi2(w)
            self._information(w)
            self._window(w)

    def _verdict(self, detector: Detector, w: FdirWindow, statistic: float | None,
                 threshold: float | None, exceeded: bool | None, alarm: bool) -> None:
        if alarm:
            self.log.info("baseline %s would declare sc%d at %.0f s (a baseline, scored "
                          "beside the FDIR: nothing declared)", detector, w.spacecraft,
                          w.t_end_s)
        self.publish("verdict", BaselineVerdict(
            sender=self.ctx.node, t_sim=w.t_end_s, detector=detector,
            spacecraft=w.spacecraft, t_start_s=w.t_start_s, t_end_s=w.t_end_s,
            statistic=statistic, threshold=threshold, exceeded=exceeded, alarm=alarm))

    def _chi2(self, w: FdirWindow) -> None:
        """Σ NIS of the window's nav updates against its χ² quantile."""
        mine = self.nis.get(w.spacecraft, [])
        inside = [v for t, v in mine if w.t_start_s <= t < w.t_end_s]
        self.nis[w.spacecraft] = [(t, v) for t, v in mine if t >= w.t_end_s]
        test = nis_window_test(inside, self.cfg.nis_alpha)
        if test is None:
            self._verdict("chi2_nis", w, None, None, None, False)
            return
        exceeded = test[0] > test[1]
        alarm = self.chi2_persistence.update(w.spacecraft, exceeded)
        self._verdict("chi2_nis", w, test[0], test[1], exceeded, alarm)

    def _information(self, w: FdirWindow) -> None:
        """CUSUM on r = 1 − ΔH_i/ΔH_i^pred and the fixed H_m,i level, on the FDIR's windows
        with a decision."""
        if w.metric is None or w.dh is None or not w.dh_pred:
            self._verdict("cusum", w, None, None, None, False)
            self._verdict("fixed_threshold", w, None, None, None, False)
            return
        stat, above, alarm = self.cusum.update(w.spacecraft, 1.0 - w.dh / w.dh_pred)
        self._verdict("cusum", w, stat, self.cfg.cusum_threshold, above, alarm)
        exceeded = w.metric > self.cfg.fixed_threshold
        alarm = self.fixed_persistence.update(w.spacecraft, exceeded)
        self._verdict("fixed_threshold", w, w.metric, self.cfg.fixed_threshold, exceeded, alarm)

    def _window(self, w: FdirWindow) -> None:
        """The window test's own verdict on the window, where the scans declare too."""
        if self.window_persistence is None:
            return
        alarm = self.window_persistence.update(w.spacecraft, w.exceeded)
        self._verdict("window", w, w.metric, w.threshold, w.exceeded, alarm)
