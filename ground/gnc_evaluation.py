"""Evaluation of orbit and attitude control from a run's archive, against the sim's truth.

* Δv per observer, all L1 (Σ over axes of |Δv_j|): delivered (sim truth, body axes), commanded
  (guidance, LVLH) and planned (SCP transfers that were flown).
* PRO holding: distance of the true position from the assigned PRO while guidance holds it, from
  the assignment's arrival time on.
* Safety: the smallest true range to the target's centre once flying (from the first departure;
  a deployment starts inside the keep-out sphere by design).
* Pointing: angle between the true camera boresight and the true line of sight to the commanded
  pointing target, and the attitude knowledge error (estimate against truth).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from fsw.lib import hcw
from ground.reader import RunArchive
from interfaces import catalogue as cat
from interfaces.messages import (
    TruthState,
)
from interfaces.scenario import Scenario


@dataclass
class GncSeries:
    """Time series of one observer (s, m, rad) used by the summary and the report plots."""

    hold_t_s: list[float] = field(default_factory=list)
    hold_error_m: list[float] = field(default_factory=list)
    point_t_s: list[float] = field(default_factory=list)
    pointing_error_rad: list[float] = field(default_factory=list)
    knowledge_error_rad: list[float] = field(default_factory=list)
    modes: list[str] = field(default_factory=list)
    dv_t_s: list[float] = field(default_factory=list)
    dv_mps: list[float] = field(default_factory=list)
    range_min_m: float = float("inf")
    dv_planned_mps: float = 0.0
    dv_commanded_mps: float = 0.0
    transfers: int = 0


def _truth_by_time(archive: RunArchive, mission: str) -> dict[float, TruthState]:
    return {round(m.t_sim, 6): m for m in archive.of(cat.TRUTH, mission)}


def gnc_series(archive: RunArchive, scenario: Scenario, mission: str) -> dict[int, GncSeries]:
    """Per observer, the GNC series compared with the truth."""
    n = hcw.mean_motion(scenario.orbit.altitude_km * 1e3)
    bore = np.array(scenario.attitude.boresight_body, dtype=float)
    truth = _truth_by_time(archive, mission)
    out = {i: GncSeries() for i in range(1, scenario.observers.count + 1)}
    t_flying = (scenario.phases[0].start_s if scenario.observers.start == "deploy"
                and scenario.phases else 0.0)
    for ts in truth.values():
        if ts.t_sim < t_flying:
            continue
        for j, sc in enumerate(ts.spacecraft):
            s = out[sc]
            s.range_min_m = min(s.range_min_m, float(np.linalg.norm(ts.r_lvlh_m[j])))
    _delta_v(truth, out, scenario.rates.mid_hz)
    assignments = {(a.spacecraft, a.assignment_id): a
                   for m in archive.of(cat.ASSIGNMENTS, mission)
                   for a in m.assignments}
    for st in archive.of(cat.GUIDANCE_STATUS, mission):
        s = out.get(st.spacecraft)
        tr = truth.get(round(st.t_sim, 6))
        if s is None:
            continue
        s.dv_commanded_mps = max(s.dv_commanded_mps, st.dv_commanded_mps)
        a = assignments.get((st.spacecraft, st.assignment_id))
        if (st.mode != "hold" or a is None or st.t_sim < a.t_arrive_s or tr is None
                or st.spacecraft not in tr.spacecraft):
            continue
        pro = a.pro
        ref = hcw.pro_state(n, pro.rho_x_m, pro.alpha_x_rad, pro.rho_y_m, pro.rho_z_m,
                            pro.alpha_z_rad, st.t_sim)
        r = np.array(tr.r_lvlh_m[tr.spacecraft.index(st.spacecraft)])
        s.hold_t_s.append(st.t_sim)
        s.hold_error_m.append(float(np.linalg.norm(r - ref[:3])))
    for plan in archive.of(cat.TRANSFER_PLAN, mission):
        if plan.spacecraft in out and plan.status == "solved":
            out[plan.spacecraft].dv_planned_mps += plan.dv_mps
            out[plan.spacecraft].transfers += 1
    for est in archive.of(cat.ATTITUDE_ESTIMATE, mission):
        s = out.get(est.spacecraft)
        tr = truth.get(round(est.t_sim, 6))
        if s is None or tr is None or est.spacecraft not in tr.spacecraft or not tr.q_lvlh_body:
            continue
        j = tr.spacecraft.index(est.spacecraft)
        r_true = Rotation.from_quat(tr.q_lvlh_body[j])
        los = np.array(est.target_lvlh_m) - np.array(tr.r_lvlh_m[j])
        b = r_true.apply(bore)
        cos = float(b @ los) / max(1e-12, float(np.linalg.norm(los)))
        s.point_t_s.append(est.t_sim)
        s.pointing_error_rad.append(float(np.arccos(np.clip(cos, -1.0, 1.0))))
        s.knowledge_error_rad.append((Rotation.from_quat(est.q_lvlh_body).inv() * r_true).magnitude())
        s.modes.append(est.mode)
    return out


def _delta_v(truth: dict[float, TruthState], out: dict[int, GncSeries], mid_hz: float) -> None:
    """Delivered Δv series (sampled at ω_mid to keep it small)."""
    step = 1.0 / mid_hz
    for t, ts in sorted(truth.items()):
        if not ts.dv_mps or abs(t / step - round(t / step)) > 1e-6:
            continue
        for j, sc in enumerate(ts.spacecraft):
            out[sc].dv_t_s.append(t)
            out[sc].dv_mps.append(ts.dv_mps[j])


def gnc_summary(series: dict[int, GncSeries]) -> dict[str, dict[str, float | int | None]]:
    """summary.json ``gnc`` section: per observer Δv (m/s), PRO hold error (m), min range (m),
    pointing error in track mode (deg) and attitude knowledge error (arcsec)."""
    out: dict[str, dict[str, float | int | None]] = {}
    for sc, s in series.items():
        track = np.array([m == "track" for m in s.modes], dtype=bool)
        pe = np.degrees(np.array(s.pointing_error_rad))[track] if track.size else np.array([])
        ke = np.degrees(np.array(s.knowledge_error_rad)) * 3600.0
        he = np.array(s.hold_error_m)
        out[str(sc)] = {
            "dv_delivered_l1_mps": s.dv_mps[-1] if s.dv_mps else 0.0,
            "dv_commanded_l1_mps": s.dv_commanded_mps,
            "dv_planned_l1_mps": s.dv_planned_mps,
            "transfers": s.transfers,
            "min_range_m": s.range_min_m if np.isfinite(s.range_min_m) else None,
            "hold_samples": int(he.size),
            "hold_error_rms_m": float(np.sqrt(np.mean(he**2))) if he.size else None,
            "hold_error_max_m": float(he.max()) if he.size else None,
            "pointing_samples_track": int(pe.size),
            "pointing_error_mean_deg": float(pe.mean()) if pe.size else None,
            "pointing_error_p95_deg": float(np.percentile(pe, 95)) if pe.size else None,
            "pointing_error_max_deg": float(pe.max()) if pe.size else None,
            "fraction_tracking": float(track.mean()) if track.size else 0.0,
            "knowledge_error_rms_arcsec": float(np.sqrt(np.mean(ke**2))) if ke.size else None,
        }
    return out
