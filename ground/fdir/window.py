"""The window context: one observer's FDI window [a, b) as the FDIR pipeline's stages see it
(docs/fdir.md, "The pipeline") -- the ground's map settled at a (ψ, φ, the observer's H_i),
and the images the information test judges with the poses at their times (the plan's
position, the reported attitude and nav).

Which images are judged: those whose observations reached the ground, taken while the
observer reports it tracks (not a slew, nor within ``fdir.settle_s`` of its end), at times a
known plan covers (a transfer whose plan was lost is not).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gnc.poi_map import PoiMap
from gnc.window_test import Observation, WindowPose
from ground.fdir.observer import ObserverState
from interfaces.contracts.messages import PoiObservations, Unjudged
from interfaces.contracts.timing import TIME_TOL_S


@dataclass(frozen=True)
class SettledMap:
    """The ground's fused map at a window's start a (every image taken before a): ψ, the
    squared fused variance per POI (Eq. 8), the weights φ, and each observer's precision F."""

    psi: np.ndarray
    phi: np.ndarray
    precision: np.ndarray
    """(observers, POIs) fused precision F_i"""

    @classmethod
    def of(cls, poi_map: PoiMap) -> SettledMap:
        return cls(poi_map.variance() ** 2, poi_map.phi, poi_map.F)

    def h_prev(self, spacecraft: int) -> float:
        """Observer ``spacecraft``'s contribution H_i at the window's start (Eq. 8)."""
        return float(np.sum(self.phi * self.psi * self.precision[spacecraft - 1]))


@dataclass(frozen=True)
class WindowContext:
    """One observer's window: its bounds (s), the map settled at ``a``, the judged images in
    time order and, at their times (K rows), the plan's positions (LVLH, m), whether any falls
    on a transfer, the reported attitude rows (``ObserverState.attitude``; None when stale),
    nav positions (LVLH, m; None when stale) and nav 1σ, and what each image saw."""

    spacecraft: int
    a: float
    b: float
    settled: SettledMap
    images: list[PoiObservations]
    times: np.ndarray
    planned: np.ndarray
    moving: bool
    attitude: np.ndarray | None
    nav: np.ndarray | None
    nav_sigma: np.ndarray | None
    """the nav's reported position 1σ (K, 1), m (None when stale)"""
    seen: list[Observation]
    """each image's observed POIs and their precisions σ⁻¹"""
    h_prev: float
    """the observer's contribution H_i at a (Eq. 8)"""

    @property
    def psi(self) -> np.ndarray:
        return self.settled.psi

    @property
    def phi(self) -> np.ndarray:
        return self.settled.phi

    def pose(self) -> WindowPose:
        """The window's planned and reported pose, as the window test reads it."""
        att = self.attitude
        return WindowPose(self.planned, att[:, 4:7] if att is not None else None, self.nav,
                          self.nav_sigma, att[:, 3] if att is not None else None,
                          att[:, 7] if att is not None else None, self.moving)

    def since(self, t: float) -> WindowContext:
        """The same window's judged images taken at or after ``t`` (s), with their poses: the
        part of the window a change that began at ``t`` shows in (the map still the one
        settled at ``a``)."""
        keep = self.times >= t - TIME_TOL_S
        rows = np.flatnonzero(keep)
        return replace(self, images=[m for m in self.images if m.image_t_s >= t - TIME_TOL_S],
                       times=self.times[keep],
                       planned=self.planned[keep],
                       attitude=None if self.attitude is None else self.attitude[keep],
                       nav=None if self.nav is None else self.nav[keep],
                       nav_sigma=None if self.nav_sigma is None else self.nav_sigma[keep],
                       seen=[self.seen[i] for i in rows])



def window_context(spacecraft: int, obs: ObserverState, images: list[PoiObservations],
                   a: float, b: float, settled: SettledMap, n: float, settle_s: float,
                   grid: np.ndarray | None = None
                   ) -> tuple[WindowContext | None, int, Unjudged | None]:
    """The context of a window with a plan and images (``images``: those received, in time
    order), the count of images the window message reports, and why there is no context when
    none can be judged.  ``n``: the mean motion (rad/s) the plans' PROs fly; ``grid``: the
    window's image times (s), over which the plans are evaluated once
    (``ObserverState.planned_on``; None: at the images' times)."""
    received = len(images)
    images = [m for m in images if obs.tracking_at(m.image_t_s, settle_s)]
    if not images:
        return None, 0, "not_tracking"
    at = np.array([m.image_t_s for m in images])
    planned = obs.planned(n, at) if grid is None else obs.planned_on(n, at, grid)
    if planned is None:  # no plan in force at an image time: nothing to compare with
        return None, received, "no_plan"
    pos, moving, known = planned  # unknown: on a transfer whose plan was lost
    images = [m for m, k in zip(images, known, strict=True) if k]
    if not images:
        return None, 0, "plan_unknown"
    times = np.array([m.image_t_s for m in images])
    return WindowContext(spacecraft, a, b, settled, images, times, pos[known],
                         bool(moving[known].any()), obs.attitude.at(times),
                         obs.nav.at(times), obs.nav_sigma.at(times), [m.arrays() for m in images],
                         settled.h_prev(spacecraft)), len(images), None
