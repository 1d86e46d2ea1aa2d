"""An observer's knowledge of the target's POIs: the accumulated precision of every observer
whose observations it has received (its own and its neighbours'), and the information cost of
that fused view (Eq. 4, 7, 8 through ``gnc.infocost``).  No bus, no I/O."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from gnc import infocost
from gnc.checks import finite_array
from gnc.fusion_kernels import ADDED, add_checked

FloatArray = npt.NDArray[np.float64]


@dataclass(eq=False)
class PoiMap:
    """Fused POI precision of one observer.

    Attributes:
        phi: POI importance φ (M,).
        w_inv: prior inverse variance w⁻¹ (M,), > 0.
        n_agents: number of observers (rows of F; observer ids 1..n_agents).
        F: accumulated precision per observer (n_agents, M): row j - 1 holds every observation
            of observer j fused here.
    """

    phi: FloatArray
    w_inv: FloatArray
    n_agents: int
    F: FloatArray = field(init=False)

    def __post_init__(self) -> None:
        m = len(self.phi)
        self.phi = finite_array("phi", self.phi, (m,))
        self.w_inv = finite_array("w_inv", self.w_inv, (m,))
        if (self.phi < 0).any() or (self.w_inv <= 0).any():
            raise ValueError("phi must be >= 0 and w_inv > 0")
        self.F = np.zeros((self.n_agents, m))

    @classmethod
    def uniform(cls, pois: int, prior_variance: float, n_agents: int) -> PoiMap:
        """Equal importance φ = 1/M (so H starts at w) and equal prior variance w."""
        return cls(np.full(pois, 1.0 / pois), np.full(pois, 1.0 / prior_variance), n_agents)

    def add(self, agent: int, poi: npt.ArrayLike, precision: npt.ArrayLike) -> None:
        """Fuse the observations of observer ``agent`` (1-based): precision σ⁻¹ ≥ 0 on POIs
        ``poi`` (indices; repeated indices add up).  An image's arrays (int64 and float64
        vectors) are checked and added in one compiled pass (``gnc.fusion_kernels``, the same
        sums); anything else, or anything it refuses, goes the numpy way (:meth:`add_numpy`,
        which raises the error)."""
        if (type(poi) is np.ndarray and type(precision) is np.ndarray
                and poi.dtype == np.int64 and precision.dtype == np.float64
                and poi.ndim == 1 and poi.shape == precision.shape
                and poi.flags.c_contiguous and precision.flags.c_contiguous
                and 1 <= agent <= self.n_agents
                and add_checked(self.F[agent - 1], poi, precision) == ADDED):
            return
        self.add_numpy(agent, poi, precision)

    def add_numpy(self, agent: int, poi: npt.ArrayLike, precision: npt.ArrayLike) -> None:
        """:meth:`add` in numpy: the tested reference."""
        idx = np.asarray(poi, dtype=np.int64)
        prec = finite_array("precision", precision, (len(idx),))
        if not 1 <= agent <= self.n_agents:
            raise ValueError(f"agent {agent} outside 1..{self.n_agents}")
        if len(idx) and (idx.min() < 0 or idx.max() >= len(self.phi) or (prec < 0).any()):
            raise ValueError("POI index out of range or negative precision")
        row = self.F[agent - 1]
        if len(idx) < 2 or bool((idx[1:] > idx[:-1]).all()):  # distinct (an image's POIs)
            row[idx] += prec
        else:
            np.add.at(row, idx, prec)

    def variance(self) -> FloatArray:
        """Fused variance H_POI per POI (M,)."""
        return infocost.h_poi(self.w_inv, self.F)

    def cost(self) -> float:
        """Information cost H of the fused view."""
        return infocost.information_cost(self.phi, self.w_inv, self.F)

    def contributions(self) -> FloatArray:
        """H_j of every observer (n_agents,) (Eq. 8)."""
        return infocost.agent_contributions(self.phi, self.w_inv, self.F)

    def prior_term(self) -> float:
        """Σ φψw⁻¹, so that prior_term + Σ H_j = H."""
        return infocost.prior_term(self.phi, self.w_inv, self.F)

    def seen(self, agent: int | None = None) -> int:
        """POIs observed at least once (by ``agent``, or by anyone fused here)."""
        f = self.F if agent is None else self.F[agent - 1:agent]
        return int(np.count_nonzero(f.sum(axis=0)))
