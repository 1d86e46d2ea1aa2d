"""The FDIR pipeline's declaration and identification (docs/fdir.md): a fault is declared on
an observer after ``fdir.persistence`` failed windows (``Persistence``), and identified
(``ground/fdir/identify.py``) on the declaring window or, when that shows no class, a later
one of the episode: while its windows fail, and on the first that passes.

An information test failed by every observer together is the constellation's (common mode,
the global check's verdict), not held against any observer.
"""

from __future__ import annotations

import logging

from gnc.image_scan import Crossing
from gnc.window_test import exceeded as window_exceeded
from ground.fdir.constellation import ConstellationVerdict
from ground.fdir.identify import Evidence, Tolerances, classify, classify_part
from ground.fdir.information import Judgement
from ground.fdir.threshold import Persistence
from interfaces.contracts.messages import FaultReport, FdirWindow, Message
from interfaces.contracts.scenario import FdirSettings


class Declarer:
    """The declaration state of every observer: its persistence counter and whether its
    declared fault still awaits a class."""

    def __init__(self, cfg: FdirSettings, node: str, log: logging.Logger) -> None:
        self.tol = Tolerances.of(cfg)
        self.persistence = Persistence(cfg.persistence, cfg.persistence_window)
        self.node = node
        self.log = log
        self._unidentified: set[int] = set()
        self._nis_span: dict[int, int] = {}
        """observers whose latest episode the NIS scan declared, with the number of nav
        updates its crossing spanned (``ground.fdir.identify.classify_part``; read while the
        fault has no class)"""
        self._change_s: dict[int, float] = {}
        """observers declared by a scan and not yet identified, with the time the change
        began as the scan estimated it (s)"""

    def identifying(self, sc: int) -> bool:
        """Whether observer ``sc``'s declared fault still has no class."""
        return sc in self._unidentified

    def change_s(self, sc: int) -> float | None:
        """When observer ``sc``'s fault still without a class began, as the scan that declared
        it estimated (s; ``gnc.image_scan.Crossing.change_s``); None: not declared by a scan,
        or identified."""
        return self._change_s.get(sc) if sc in self._unidentified else None

    def naming(self, sc: int) -> bool:
        """Whether a failed window of ``sc`` would have to name a class (no fault declared, or
        one still without a class)."""
        return sc in self._unidentified or not self.persistence.declared(sc)

    def declare(self, sc: int, j: Judgement, common: ConstellationVerdict | None,
                common_way: str | None = None) -> list[Message]:
        """The window's verdict (``exceeded`` set) and the fault reports it brings.  Its
        information test failed is not held against the observer when the window's global
        check found common mode (``common``), or the window went the way (``common_way``) of
        a common-mode episode declared on the constellation and still going on."""
        shared = (common is not None and common.common_mode) or (
            common_way is not None and j.window.direction == common_way)
        failed = [f for f in j.window.failed if not (f == "information" and shared)]
        exceeded = window_exceeded(failed, j.decided)
        w = j.window.model_copy(update={"exceeded": exceeded})
        out: list[Message] = [w]
        counted = self.persistence.counted(sc, exceeded, w.t_start_s)
        if self.persistence.update(sc, counted):
            self._change_s.pop(sc, None)  # declared by the windows: a scan's estimate is old
            self._nis_span.pop(sc, None)
            cls, ev = self._classify(sc, j, failed)
            self.log.warning("FDIR: fault declared on sc%d at %.0f s (failed %s; H_m %s, τ %s, "
                             "%s): %s", sc, w.t_end_s, "+".join(failed), _g(w.metric),
                             _g(w.threshold), w.direction, cls or "unidentified")
            out.append(self._report(sc, cls, w, ev))
            if cls is None:
                self._unidentified.add(sc)
        elif sc in self._unidentified:
            cls, ev = self._classify(sc, j, failed)
            if cls is not None or counted is False:
                self._unidentified.discard(sc)
            if cls is not None:
                self.log.warning("FDIR: sc%d identified at %.0f s: %s", sc, w.t_end_s, cls)
                out.append(self._report(sc, cls, w, ev))
        return out

    def identify_part(self, sc: int, j: Judgement, t_s: float, window_end_s: float
                      ) -> FaultReport | None:
        """Observer ``sc``'s declared fault, still without a class, classified on the part of
        the window being collected (ending at ``window_end_s``) since its change, judged as a
        window (``j``: the part's tests and evidence) at its last image's time ``t_s`` (s;
        docs/fdir.md, "Identification after a crossing"): the report naming the class, or
        None when the evidence names none yet."""
        cls = classify_part(j.evidence, self.tol, j.window.failed, self._nis_span.get(sc))
        if cls is None:
            return None
        self._unidentified.discard(sc)
        self.log.warning("FDIR: sc%d identified at %.0f s on its images since %.0f s: %s", sc,
                         t_s, j.window.t_start_s, cls)
        w = j.window
        return FaultReport(sender=self.node, t_sim=t_s, spacecraft=sc, fault_class=cls,
                           direction=w.direction, metric=w.metric, threshold=w.threshold,
                           window_end_s=window_end_s, detector="sequential",
                           evidence={**j.evidence.as_dict(), "since_s": w.t_start_s})

    def _classify(self, sc: int, j: Judgement, failed: list[str]
                  ) -> tuple[str | None, Evidence]:
        """The class observer ``sc``'s ``j`` names, with ``failed`` its tests failed, and the
        evidence that named it: its images since the change first (``classify_part``), else
        the whole window's (``classify``)."""
        if j.part is not None:
            cls = classify_part(j.part, self.tol, failed, self._nis_span.get(sc))
            if cls is not None:
                return cls, j.part
        return classify(j.evidence, self.tol, failed), j.evidence

    def declared(self, sc: int) -> bool:
        """Whether observer ``sc``'s declared fault's episode is going on."""
        return self.persistence.declared(sc)

    def declare_crossing(self, sc: int, crossing: Crossing, window_end_s: float
                         ) -> FaultReport:
        """A fault declared by the sequential test at an image (docs/fdir.md, "The sequential
        test"), in the window ending at ``window_end_s``: without a class, which the windows
        of its episode then look for."""
        self.persistence.declare(sc, crossing.image_t_s)
        self._unidentified.add(sc)
        self._change_s[sc] = crossing.change_s
        self._nis_span.pop(sc, None)
        if crossing.test == "nis":  # the crossing's shape: a step or a ramp
            self._nis_span[sc] = crossing.scan.span
        self.log.warning("FDIR: fault declared on sc%d at %.0f s (sequential, %s scan: |Z| "
                         "%.3g over %d, mean %.3g against %.3g%s)", sc, crossing.image_t_s,
                         crossing.test, crossing.scan.z, crossing.scan.span, crossing.shift,
                         crossing.limit, f", {crossing.direction}" if crossing.direction else "")
        which = {f"{crossing.test}_scan": 1.0} if crossing.test != "information" else {}
        return FaultReport(sender=self.node, t_sim=crossing.image_t_s, spacecraft=sc,
                           fault_class=None, direction=crossing.direction,
                           metric=abs(crossing.shift), threshold=crossing.limit,
                           window_end_s=window_end_s, detector="sequential",
                           evidence={"z": crossing.scan.z, "span": float(crossing.scan.span),
                                     **which})

    def _report(self, sc: int, cls: str | None, w: FdirWindow, ev: Evidence) -> FaultReport:
        return FaultReport(sender=self.node, t_sim=w.t_end_s, spacecraft=sc, fault_class=cls,
                           direction=w.direction, metric=w.metric, threshold=w.threshold,
                           window_end_s=w.t_end_s, evidence=ev.as_dict())


def _g(value: float | None) -> str:
    return "-" if value is None else f"{value:.3g}"
