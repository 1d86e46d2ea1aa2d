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

from gnc.fusion_kernels import add_to_rows
from gnc.poi_map import PoiMap
from ground.fdir.observer import MAX_JUDGED_LOSS, ObserverState
from interfaces.contracts.messages import PoiObservations


@dataclass
class FusedViews:
    """The precision each observer has fused per POI from each observer's images, its own and
    its neighbours' (``by_source``: N receivers, N sources, M POIs), and how many of each
    observer's images each fused (N receivers, N observers)."""

    range_m: float
    by_source: np.ndarray
    images: np.ndarray

    @classmethod
    def of(cls, observers: int, pois: int, range_m: float) -> FusedViews:
        return cls(range_m, np.zeros((observers, observers, pois)),
                   np.zeros((observers, observers)))

    def add(self, images: list[PoiObservations], observers: dict[int, ObserverState]) -> None:
        """``images`` join their observers' views, and the view of every observer that was in
        range of theirs at the image time (both nav positions known: ``ObserverState.nav``,
        looked up once per observer for all the images)."""
        if not images:
            return
        times = np.array([m.image_t_s for m in images])
        pos = np.full((len(self.images), len(images), 3), np.nan)
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
            receivers = np.flatnonzero(rows)
            if not add_to_rows(self.by_source, receivers, m.spacecraft - 1, idx, prec):
                self.by_source[receivers[:, None], m.spacecraft - 1, idx[None, :]] += prec
            self.images[rows, m.spacecraft - 1] += 1

    def contributions(self, settled: PoiMap, lost: np.ndarray,
                      shared: np.ndarray | None = None) -> np.ndarray:
        """Each observer's H_i (N,) on its own view: ψ from what it fused, every observer's
        precision scaled up by the share of its observations lost on the way to the ground
        (``lost``, capped at ``MAX_JUDGED_LOSS``: such an observer is not judged), in each
        view by the share of its images that view holds.  With ``shared`` (N, N), the count
        of each neighbour's images each observer says it fused (``InfoCostTelemetry.
        shared_by``; NaN: not known), each neighbour's part of each view is scaled to that
        count (:func:`fused_shares`): what the crosslinks lost into it, neighbour by
        neighbour."""
        extra, counted = self._counted(lost)
        diag = np.diag(self.images)
        held = np.divide(self.images, diag[None, :], out=np.zeros_like(self.images),
                         where=diag > 0)
        share = np.ones_like(counted) if shared is None else fused_shares(counted, shared)
        # Σ_j share_ij (by_source_ijm + held_ij extra_j F_jm), without an (N, N, M) temporary:
        # one row-by-matrix product per view, and the lost shares as one (N, N) @ (N, M)
        view = (np.matmul(share[:, None, :], self.by_source)[:, 0, :]
                + (share * held * extra[None, :]) @ settled.F)
        psi = 1.0 / (settled.w_inv[None, :] + view) ** 2
        own = settled.F * (1.0 + extra)[:, None]
        return np.einsum("im,im->i", own, psi * settled.phi[None, :])

    def fused_fraction(self, lost: np.ndarray, shared: np.ndarray) -> np.ndarray:
        """Each observer's share (N,) of its neighbours' images that it says it fused
        (``shared``, as :meth:`contributions` takes it) of those the ground counts in its range,
        lost ones included; 1 where the ground counts none or the counts are unknown."""
        _, counted = self._counted(lost)
        off = ~np.eye(len(counted), dtype=bool)
        total = np.sum(counted * off, axis=1)
        fused = np.sum(np.minimum(fused_shares(counted, shared), 1.0) * counted * off, axis=1)
        return np.divide(fused, total, out=np.ones_like(total), where=total > 0)

    def _counted(self, lost: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The factor each observer's lost share adds to its images (N,), and the images of
        each observer j in each view i, lost ones included (N, N)."""
        extra = 1.0 / (1.0 - np.minimum(lost, MAX_JUDGED_LOSS)) - 1.0
        return extra, self.images * (1.0 + extra)[None, :]


MAX_SHARE = 2.0
"""The largest factor :func:`fused_shares` gives (an observer that fused more of a
neighbour's images than the ground counts in range: the range's edge, by the nav positions)."""


def fused_shares(counted: np.ndarray, shared: np.ndarray) -> np.ndarray:
    """The factor (N, N) on each source's part of each observer's view: ``shared[i, j]``, the
    images of observer j that observer i says it fused (NaN: unknown), over the ground's count
    of them in i's range, lost ones included (``counted[i, j]``), within [0, MAX_SHARE]; 1 on
    the diagonal (its own images), where unknown, and where the ground counts none.  The
    crosslinks lose a neighbour's images evenly over time and POIs, so the factor rebuilds
    the view the observer fused (a packet-loss fault on one observer starves every other's
    view of its images alone)."""
    out = np.ones_like(counted, dtype=float)
    known = np.isfinite(shared) & (counted > 0)
    np.fill_diagonal(known, False)
    out[known] = np.clip(shared[known] / counted[known], 0.0, MAX_SHARE)
    return out
