"""The FDIR pipeline's sequential test (issue 41; docs/fdir.md, "The sequential test"): with
``fdir.detector = "sequential"``, each observer's images are scored as they reach the ground,
each against the nominal twin at the plan (Eq. 9 image by image), and the scan over the
newest images (``gnc/sequential_test.py``) declares the moment it crosses its threshold,
instead of waiting for the window's end.

The images of window [a, b) are scored (``gnc/image_scan.py``, the scan the neighbours' judge
runs too) once the ground's map is settled at a (window k − 1 judged), with ψ held at a as the
window test holds it.  An observer whose fault is declared is not scored until its episode
ends; its scan then starts afresh.

With ``fdir.fuse_nis``, the nav's NIS is scanned the same way, update by update
(``gnc.sequential_test.chi2_scan``): the window's NIS test is the same sum over a window's
updates (against χ²(6N)); its shorter spans declare an orbit actuator fault, whose
innovations grow within seconds, before the window ends.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from gnc.hardware_threshold import clipped_noise_moments
from gnc.image_scan import Crossing, ImageScans, step_false_alarm
from gnc.sequential_test import (
    SCAN_LENGTHS,
    chi2_scan,
    chi2_span_limit,
)
from gnc.sequential_test import scan_threshold as scan_threshold_for
from gnc.twin import TwinModel
from gnc.window_test import WindowTestSettings
from ground.fdir.baselines import NIS_DOF
from ground.fdir.window import WindowContext
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.timing import TIME_TOL_S


@dataclass
class _NisScan:
    """One observer's newest NIS values (oldest first, at most the longest span) and the time
    of the last update looked at."""

    values: list[float] = field(default_factory=list)
    times: list[float] = field(default_factory=list)
    """the values' times (s)"""
    last_t: float = -math.inf
    window: tuple[float, float] | None = None
    """the start of the window its last updates were scored in (s) and their largest z"""
    latest: tuple[float, float] | None = None
    """the newest update scored: its time (s) and the scan statistic at it"""


def image_false_alarm(scenario: Scenario, tests: int) -> float:
    """The sequential test's false-alarm probability per image: its share (one of ``tests``
    fused tests) of ``fdir.false_alarms_per_observer_hour`` over the images of an hour (one
    every ω_mid period)."""
    return step_false_alarm(scenario.fdir.false_alarms_per_observer_hour, tests,
                            scenario.rates.mid_hz)


class SequentialTest(ImageScans):
    """The scans of every observer: its images against the nominal ``twin``
    (``gnc.image_scan.ImageScans``, threshold c) and its nav's NIS (threshold c_nis), both
    from the per-step false-alarm probability ``q_image`` (:func:`image_false_alarm`)."""

    def __init__(self, scenario: Scenario, twin: TwinModel, q_image: float) -> None:
        super().__init__(WindowTestSettings.of(scenario), twin,
                         clipped_noise_moments(scenario.camera.noise_frac)[1],
                         scan_threshold_for(q_image), 1.0 / scenario.rates.mid_hz,
                         (scenario.seed,))
        self.c_nis = scan_threshold_for(q_image, sides=1)
        self._nis: dict[int, _NisScan] = {}

    def score(self, ctx: WindowContext, plan: np.ndarray | None) -> Crossing | None:
        """Score ``ctx``'s images (those of its observer not yet scored, in time order): the
        first at which the scan crosses c, or None (``ImageScans.score_images``)."""
        return self.score_images(ctx.spacecraft, (ctx.a, ctx.b), ctx.times, ctx.seen,
                                 ctx.pose(), ctx.psi, ctx.phi, plan)

    def score_nis(self, spacecraft: int, updates: list[tuple[float, float]], judged: bool,
                  a: float) -> Crossing | None:
        """Observer ``spacecraft``'s nav updates ``updates`` ((time s, NIS), time order) not
        yet looked at pushed onto its NIS scan one by one (docs/fdir.md, "The nav's NIS,
        scanned too"), to the first at which the scan crosses ``c_nis`` (that update's
        crossing), or None; each counted in the record of the window starting at ``a`` (s),
        the one being collected.  ``judged`` False (its fault declared): looked at, not
        scored, and its scan starts afresh."""
        scan = self._nis.setdefault(spacecraft, _NisScan())
        fresh = [(t, v) for t, v in updates if t > scan.last_t + TIME_TOL_S]
        if fresh:
            scan.last_t = fresh[-1][0]
        if not judged:
            scan.values, scan.times = [], []
            return None
        keep = max(SCAN_LENGTHS) - 1
        for t, v in fresh:
            scan.values = [*scan.values[-keep:], v]
            scan.times = [*scan.times[-keep:], t]
            result = chi2_scan(scan.values, NIS_DOF)
            z = result.z if result is not None else 0.0
            held = scan.window if scan.window is not None and abs(scan.window[0] - a) <= \
                TIME_TOL_S else (a, 0.0)
            scan.window = (a, max(held[1], z))
            scan.latest = (t, z)
            if result is not None and result.z > self.c_nis:
                n = result.span
                mean = float(np.mean(scan.values[-n:])) / NIS_DOF
                since = scan.times[-n]
                scan.values, scan.times = [], []  # its evidence spent
                return Crossing(t, result, mean,
                                chi2_span_limit(self.c_nis, NIS_DOF, n) / (n * NIS_DOF), "nis",
                                since)
        return None

    def status(self, spacecraft: int) -> dict[str, float]:
        """The scans' newest statistics of observer ``spacecraft``, as ``ScanStatus``'s
        fields, with ``t_s`` the time of the newer (empty: nothing scored yet)."""
        out: dict[str, float] = {}
        image = self.latest(spacecraft)
        if image is not None:
            out |= {"t_s": image[0], "image_z": image[1], "image_threshold": self.c}
        nis = self._nis.get(spacecraft)
        if nis is not None and nis.latest is not None:
            out |= {"t_s": max(out.get("t_s", -math.inf), nis.latest[0]),
                    "nis_z": nis.latest[1], "nis_threshold": self.c_nis}
        return out

    def window_fields(self, spacecraft: int, a: float) -> dict[str, float]:
        """The scans' record of observer ``spacecraft``'s window starting at ``a`` (s), the
        latest it scored (docs/fdir.md, "Each fault against the bound"), as
        ``FdirWindow``'s ``scan_z_max``, ``scan_threshold`` and ``image_sigma`` (none when no
        image of it was scored), ``nis_scan_z_max`` and ``nis_scan_threshold`` (none when no
        nav update)."""
        out = self.image_fields(spacecraft, a)
        nis = self._nis.get(spacecraft)
        if nis is not None and nis.window is not None and abs(nis.window[0] - a) <= TIME_TOL_S:
            out |= {"nis_scan_z_max": nis.window[1], "nis_scan_threshold": self.c_nis}
        return out


def decided(crossings: dict[int, Crossing], scored: list[int], looked_s: dict[int, float],
            final: bool) -> list[int] | None:
    """Which observers' ``crossings`` (pending, by observer) are decided now, given the
    observers ``scored`` in the window (their images scored in it, not declared) and the time
    of the last image looked at of each (``looked_s``): a crossing waits until every other
    scored observer has been looked at past its image, unless the window's data is all in
    (``final``).  None when every scored observer (two or more) crossed the same way: a
    change no single observer explains, left to the window's global check (Eq. 6)."""
    ways = {c.direction for c in crossings.values()}
    if len(scored) > 1 and set(scored) <= set(crossings) and len(ways) == 1:
        return None
    return sorted(sc for sc, crossing in crossings.items()
                  if final or all(looked_s[o] >= crossing.image_t_s
                                  for o in scored if o != sc))
