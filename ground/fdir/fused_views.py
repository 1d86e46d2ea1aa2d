"""What each observer has fused, as the ground reconstructs it (docs/fdir.md, "Link and data
faults"): its own observations, and those of every other observer that was within crosslink
range (``comms.range_m``) when the image was taken, by the nav positions both reported.

An observer reports its H_i (Eq. 8) on its own fused map: ψ comes from what it fused, not from
the ground's map of everything.  The views differ by the range-limited sharing: observers
that hold distant PROs for long share little, and on the default mission under ground passes
(the re-plans held for a pass) the relative difference reached 21% with every report honest,
above ``fdir.integrity_tol``.  Recomputed on each observer's own view the difference is what
the crosslinks' loss and the nav's error near the range's edge leave.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gnc.poi_map import PoiMap
from ground.fdir.observer import MAX_JUDGED_LOSS, ObserverState
from interfaces.contracts.messages import PoiObservations


@dataclass
class FusedViews:
    """The precision each observer has fused per POI (N, M), its own and its neighbours', and
    how many of each observer's images each fused (N receivers, N observers)."""

    range_m: float
    fused: np.ndarray
    images: np.ndarray

    @classmethod
    def of(cls, observers: int, pois: int, range_m: float) -> FusedViews:
        return cls(range_m, np.zeros((observers, pois)), np.zeros((observers, observers)))

    def add(self, images: list[PoiObservations], observers: dict[int, ObserverState]) -> None:
        """``images`` join their observers' views, and the view of every observer that was in
        range of theirs at the image time (both nav positions known: ``ObserverState.nav``,
        looked up once per observer for all the images)."""
        if not images:
            return
        times = np.array([m.image_t_s for m in images])
        pos = np.full((len(self.fused), len(images), 3), np.nan)
        for sc, obs in observers.items():
            values = obs.nav.at_each(times)
            if values is not None:
                pos[sc - 1] = values
        k = np.arange(len(images))
        own = np.array([m.spacecraft - 1 for m in images])
        reach = np.linalg.norm(pos - pos[own, k][None, :, :], axis=2) <= self.range_m
        reach[own, k] = True
        for m, rows in zip(images, reach.T, strict=True):
            idx, prec = m.arrays()
            self.fused[np.ix_(np.flatnonzero(rows), idx)] += prec
            self.images[rows, m.spacecraft - 1] += 1

    def contributions(self, settled: PoiMap, lost: np.ndarray,
                      shared: np.ndarray | None = None) -> np.ndarray:
        """Each observer's H_i (N,) on its own view: ψ from what it fused, every observer's
        precision scaled up by the share of its observations lost on the way to the ground
        (``lost``, capped at ``MAX_JUDGED_LOSS``: such an observer is not judged), in each
        view by the share of its images that view holds.  With ``shared`` (N,), the
        neighbours' images each observer says it fused (``InfoCostTelemetry.shared_received``;
        NaN: not known), the neighbours' part of its view is thinned to that count
        (:func:`thinned`): what the crosslinks lost into it."""
        extra = 1.0 / (1.0 - np.minimum(lost, MAX_JUDGED_LOSS)) - 1.0
        held = np.divide(self.images, np.diag(self.images)[None, :],
                         out=np.zeros_like(self.images), where=np.diag(self.images) > 0)
        view = self.fused + (held * extra[None, :]) @ settled.F
        if shared is not None:
            view = thinned(view, settled.F * (1.0 + extra)[:, None],
                           self.images * (1.0 + extra)[None, :], shared)
        psi = 1.0 / (settled.w_inv[None, :] + view) ** 2
        own = settled.F * (1.0 + extra)[:, None]
        return np.einsum("im,im->i", own, psi * settled.phi[None, :])


MAX_THINNING = 2.0
"""The largest factor :func:`thinned` applies (an observer that fused more of its neighbours'
images than the ground counts in range: the range's edge, by the nav positions)."""


def thinned(view: np.ndarray, own: np.ndarray, counted: np.ndarray,
            shared: np.ndarray) -> np.ndarray:
    """Each observer's view (N, M) with its neighbours' part scaled by the share of their
    images it says it fused: ``shared[i]`` (NaN: unknown, unscaled) over the ground's count
    of their images in its range (``counted[i, j]``, j ≠ i, lost ones included); ``own``
    (N, M) is each observer's own part of its view.  The crosslinks lose images uniformly
    over time and POIs, so the scaling rebuilds the view the observer fused (at 15% loss,
    an observer lacks 15% of every neighbour's precision)."""
    expected = counted.sum(axis=1) - np.diag(counted)
    known = np.isfinite(shared) & (expected > 0)
    ratio = np.ones(len(view))
    ratio[known] = np.clip(shared[known] / expected[known], 0.0, MAX_THINNING)
    return own + ratio[:, None] * (view - own)
