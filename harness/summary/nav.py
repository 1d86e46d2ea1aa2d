"""summary.json's ``nav`` section: each observer's navigation error against the sim's truth,
from its archive."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np
from pydantic import (
    BeforeValidator,
    Field,
    SerializerFunctionWrapHandler,
    WrapSerializer,
)

from gnc.chi2 import chi2_quantile
from gnc.kalman import nees
from harness.archive.reader import RunArchive
from harness.summary.records import Figure, SummaryRecord
from harness.summary.truth_table import TruthTable
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    StateEstimate,
)


class NavStats(SummaryRecord):
    """One observer's navigation errors after the filter's first seconds
    (``harness.summary.build.NAV_SETTLE_S``)."""

    samples: int = Field(ge=0, description="estimates compared with the truth")
    pos_rms_m: float
    pos_max_m: float
    vel_rms_mps: float
    nees_mean: float = Field(description="mean normalised estimation error squared (6 dof)")
    nees_in_95_bounds: float = Field(description="share of NEES within the χ²(6) 95% bounds")
    nis_mean: Figure = Field(description="mean normalised innovation squared (null: none)")


def _none_if_empty(v: Any) -> Any:
    return None if v == {} else v


def _empty_if_none(v: NavStats | None, handler: SerializerFunctionWrapHandler) -> Any:
    return {} if v is None else handler(v)


NavEntry = Annotated[NavStats | None, BeforeValidator(_none_if_empty),
                     WrapSerializer(_empty_if_none)]
"""An observer's nav statistics; None (``{}`` on disk) when it has no estimate after the
settling time."""


@dataclass(frozen=True)
class NavErrors:
    """Estimate minus truth of one spacecraft at each estimate time."""

    t_s: np.ndarray  # (K,)
    error: np.ndarray  # (K, 6) m, m/s
    sigma: np.ndarray  # (K, 6) sqrt(diag P)
    nees: np.ndarray  # (K,)
    nis: np.ndarray  # (K,) NaN where no update

    def stats(self, skip_s: float = 0.0) -> dict[str, float]:
        """RMS/max errors and consistency figures after ``skip_s`` seconds."""
        m = self.t_s >= skip_s
        if not m.any():
            return {}
        e, q = self.error[m], self.nees[m]
        pos, vel = np.linalg.norm(e[:, :3], axis=1), np.linalg.norm(e[:, 3:], axis=1)
        lo, hi = chi2_quantile([0.025, 0.975], 6)
        nis = self.nis[m][np.isfinite(self.nis[m])]
        return {
            "samples": int(m.sum()),
            "pos_rms_m": float(np.sqrt(np.mean(pos**2))),
            "pos_max_m": float(pos.max()),
            "vel_rms_mps": float(np.sqrt(np.mean(vel**2))),
            "nees_mean": float(q.mean()),
            "nees_in_95_bounds": float(np.mean((q >= lo) & (q <= hi))),
            "nis_mean": float(nis.mean()) if nis.size else float("nan"),
        }


def nav_errors(archive: RunArchive, mission: str,
               truth: TruthTable | None = None) -> dict[int, NavErrors]:
    """Per spacecraft, the state estimates compared with the truth at the same sim time
    (``truth``: the run's truth table if already built, else built from ``archive``)."""
    if truth is None:
        truth = TruthTable.from_archive(archive, mission)
    by_sc: dict[int, list[StateEstimate]] = {}
    for est in archive.of(cat.NAV_ESTIMATE, mission):
        by_sc.setdefault(est.spacecraft, []).append(est)
    out: dict[int, NavErrors] = {}
    for sc, ests in sorted(by_sc.items()):
        j = truth.column(sc)
        rows = []
        for est in ests:
            i = truth.row(est.t_sim)
            if i is None or j is None:
                continue
            x_true = np.concatenate([truth.r_m[i, j], truth.v_mps[i, j]])
            x, P = np.array(est.x), np.array(est.P)
            rows.append((est.t_sim, x - x_true, np.sqrt(np.diag(P)), nees(x, P, x_true),
                         np.nan if est.nis is None else est.nis))
        if rows:
            t, e, sd, q, nis = zip(*rows, strict=True)
            out[sc] = NavErrors(np.array(t), np.array(e), np.array(sd), np.array(q), np.array(nis))
    return out


def nav_stats(stats: dict[str, float]) -> NavStats | None:
    """An observer's nav statistics (None: no estimate after the settling time)."""
    return NavStats.model_validate(stats) if stats else None
