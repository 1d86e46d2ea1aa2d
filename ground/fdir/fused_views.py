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
    """The precision each observer has fused per POI (N, M), its own and its neighbours'."""

    range_m: float
    fused: np.ndarray

    @classmethod
    def of(cls, observers: int, pois: int, range_m: float) -> FusedViews:
        return cls(range_m, np.zeros((observers, pois)))

    def add(self, msg: PoiObservations, observers: dict[int, ObserverState]) -> None:
        """Image ``msg`` joins its observer's view, and the view of every observer that was in
        range of it at the image time (both nav positions known: ``ObserverState.nav``)."""
        idx, prec = msg.arrays()
        t = np.array([msg.image_t_s])
        here = observers[msg.spacecraft].nav.at(t)
        for sc, obs in observers.items():
            if sc != msg.spacecraft:
                there = obs.nav.at(t)
                if here is None or there is None or (
                        float(np.linalg.norm(there - here)) > self.range_m):
                    continue
            self.fused[sc - 1, idx] += prec

    def contributions(self, settled: PoiMap, lost: np.ndarray) -> np.ndarray:
        """Each observer's H_i (N,) on its own view: ψ from what it fused, its own precision
        scaled up by the share of its observations lost on the way to the ground (``lost``,
        capped at ``MAX_JUDGED_LOSS``: such an observer is not judged), as it holds them all."""
        scale = 1.0 / (1.0 - np.minimum(lost, MAX_JUDGED_LOSS))
        own = settled.F * scale[:, None]
        view = self.fused + settled.F * (scale - 1.0)[:, None]
        psi = 1.0 / (settled.w_inv[None, :] + view) ** 2
        return np.einsum("im,im->i", own, psi * settled.phi[None, :])
