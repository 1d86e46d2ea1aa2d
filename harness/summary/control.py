"""summary.json's ``gnc`` section: each observer's orbit and attitude control from a run's
archive, against the sim's truth."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from pydantic import Field
from scipy.spatial.transform import Rotation

from gnc import hcw
from gnc.mission import MissionConstants
from harness.archive.reader import RunArchive
from harness.summary.records import Figure, SummaryRecord
from harness.summary.truth_table import TIME_DECIMALS, TruthTable
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import AttitudeEstimate
from interfaces.contracts.scenario import Scenario


class GncStats(SummaryRecord):
    """One observer's guidance and attitude figures (``harness.summary.control``)."""

    dv_delivered_l1_mps: float = Field(description="Δv delivered, L1 norm, m/s")
    dv_commanded_l1_mps: float = Field(description="Δv commanded, L1 norm, m/s")
    dv_planned_l1_mps: float = Field(description="Δv of the planned transfers, L1 norm, m/s")
    transfers: int = Field(ge=0, description="transfers planned and solved")
    min_range_m: Figure = Field(description="closest approach to the target, m")
    hold_samples: int = Field(ge=0, description="samples of PRO station-keeping")
    hold_error_rms_m: Figure = Field(description="PRO hold error, RMS, m")
    hold_error_max_m: Figure = Field(description="PRO hold error, max, m")
    pointing_samples_track: int = Field(ge=0, description="attitude samples in track mode")
    pointing_error_mean_deg: Figure = Field(description="in track mode, deg")
    pointing_error_p95_deg: Figure = Field(description="in track mode, deg")
    pointing_error_max_deg: Figure = Field(description="in track mode, deg")
    fraction_tracking: float = Field(description="share of attitude samples in track mode")
    knowledge_error_rms_arcsec: Figure = Field(description="attitude knowledge error, arcsec")


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


def gnc_series(archive: RunArchive, scenario: Scenario, mission: str,
               truth: TruthTable | None = None) -> dict[int, GncSeries]:
    """Per observer, the GNC series compared with the truth (``truth``: the run's truth table
    if already built, else built from ``archive``)."""
    if truth is None:
        truth = TruthTable.from_archive(archive, mission)
    out = {i: GncSeries() for i in range(1, scenario.observers.count + 1)}
    t_flying = (scenario.phases[0].start_s if scenario.observers.start == "deploy"
                and scenario.phases else 0.0)
    flying = truth.t_s >= t_flying
    if flying.any():
        closest = np.linalg.norm(truth.r_m[flying], axis=2).min(axis=0)
        for j, sc in enumerate(truth.spacecraft):
            out[sc].range_min_m = float(closest[j])
    _delta_v(truth, out, scenario.rates.mid_hz)
    _hold_errors(archive, scenario, mission, truth, out)
    for plan in archive.of(cat.TRANSFER_PLAN, mission):
        if plan.spacecraft in out and not plan.refused:
            out[plan.spacecraft].dv_planned_mps += plan.dv_mps
            out[plan.spacecraft].transfers += 1
    _pointing(archive, scenario, mission, truth, out)
    return out


def _delta_v(truth: TruthTable, out: dict[int, GncSeries], mid_hz: float) -> None:
    """Delivered Δv series (sampled at ω_mid to keep it small)."""
    if not truth.has_attitude:
        return
    step = 1.0 / mid_hz
    t = np.round(truth.t_s, TIME_DECIMALS)
    order = np.argsort(t, kind="stable")
    keep = order[np.abs(t[order] / step - np.round(t[order] / step)) <= 1e-6]
    for j, sc in enumerate(truth.spacecraft):
        out[sc].dv_t_s.extend(t[keep].tolist())
        out[sc].dv_mps.extend(truth.dv_mps[keep, j].tolist())


def _hold_errors(archive: RunArchive, scenario: Scenario, mission: str, truth: TruthTable,
                 out: dict[int, GncSeries]) -> None:
    """Commanded Δv, and the distance of the true position from the assigned PRO while
    guidance holds it (from the assignment's arrival time on)."""
    n = MissionConstants.of(scenario).n_rad_s
    assignments = {(a.spacecraft, a.assignment_id): a
                   for m in archive.of(cat.ASSIGNMENTS, mission) for a in m.assignments}
    for st in archive.of(cat.GUIDANCE_STATUS, mission):
        s = out.get(st.spacecraft)
        if s is None:
            continue
        s.dv_commanded_mps = max(s.dv_commanded_mps, st.dv_commanded_mps)
        a = assignments.get((st.spacecraft, st.assignment_id))
        i, j = truth.row(st.t_sim), truth.column(st.spacecraft)
        if st.mode != "hold" or a is None or st.t_sim < a.t_arrive_s or i is None or j is None:
            continue
        pro = a.pro
        ref = hcw.pro_state(n, pro.rho_x_m, pro.alpha_x_rad, pro.rho_y_m, pro.rho_z_m,
                            pro.alpha_z_rad, st.t_sim)
        s.hold_t_s.append(st.t_sim)
        s.hold_error_m.append(float(np.linalg.norm(truth.r_m[i, j] - ref[:3])))


def _pointing(archive: RunArchive, scenario: Scenario, mission: str, truth: TruthTable,
              out: dict[int, GncSeries]) -> None:
    """Pointing error (true boresight against the true line of sight to the commanded target)
    and attitude knowledge error, per attitude estimate, all of an observer's at once."""
    if not truth.has_attitude:
        return
    bore = np.array(scenario.attitude.boresight_body, dtype=float)
    by_sc: dict[int, list[tuple[int, AttitudeEstimate]]] = {}
    for est in archive.of(cat.ATTITUDE_ESTIMATE, mission):
        i = truth.row(est.t_sim)
        if est.spacecraft in out and i is not None and truth.column(est.spacecraft) is not None:
            by_sc.setdefault(est.spacecraft, []).append((i, est))
    for sc, pairs in by_sc.items():
        j = truth.column(sc)
        rows = np.array([i for i, _ in pairs])
        ests = [e for _, e in pairs]
        r_true = Rotation.from_quat(truth.q_lvlh_body[rows, j])
        los = np.array([e.target_lvlh_m for e in ests]) - truth.r_m[rows, j]
        cos = np.einsum("ij,ij->i", r_true.apply(bore), los) / np.maximum(
            1e-12, np.linalg.norm(los, axis=1))
        knowledge = (Rotation.from_quat([e.q_lvlh_body for e in ests]).inv() * r_true).magnitude()
        s = out[sc]
        s.point_t_s.extend(e.t_sim for e in ests)
        s.pointing_error_rad.extend(np.arccos(np.clip(cos, -1.0, 1.0)).tolist())
        s.knowledge_error_rad.extend(np.atleast_1d(knowledge).tolist())
        s.modes.extend(e.mode for e in ests)


def gnc_summary(series: dict[int, GncSeries]) -> dict[str, GncStats]:
    """summary.json ``gnc`` section: per observer Δv (m/s), PRO hold error (m), min range (m),
    pointing error in track mode (deg) and attitude knowledge error (arcsec)."""
    out: dict[str, GncStats] = {}
    for sc, s in series.items():
        track = np.array([m == "track" for m in s.modes], dtype=bool)
        pe = np.degrees(np.array(s.pointing_error_rad))[track] if track.size else np.array([])
        ke = np.degrees(np.array(s.knowledge_error_rad)) * 3600.0
        he = np.array(s.hold_error_m)
        out[str(sc)] = GncStats(
            dv_delivered_l1_mps=s.dv_mps[-1] if s.dv_mps else 0.0,
            dv_commanded_l1_mps=s.dv_commanded_mps,
            dv_planned_l1_mps=s.dv_planned_mps,
            transfers=s.transfers,
            min_range_m=s.range_min_m if np.isfinite(s.range_min_m) else None,
            hold_samples=int(he.size),
            hold_error_rms_m=float(np.sqrt(np.mean(he**2))) if he.size else None,
            hold_error_max_m=float(he.max()) if he.size else None,
            pointing_samples_track=int(pe.size),
            pointing_error_mean_deg=float(pe.mean()) if pe.size else None,
            pointing_error_p95_deg=float(np.percentile(pe, 95)) if pe.size else None,
            pointing_error_max_deg=float(pe.max()) if pe.size else None,
            fraction_tracking=float(track.mean()) if track.size else 0.0,
            knowledge_error_rms_arcsec=float(np.sqrt(np.mean(ke**2))) if ke.size else None,
        )
    return out
