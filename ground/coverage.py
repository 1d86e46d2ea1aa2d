"""Inspection coverage of a run from its archive: the information cost of everything the
cameras saw (the sim's images, the truth of what was observed) and the observers' own H_i
telemetry (Eq. 4, 8)."""

from __future__ import annotations

from dataclasses import dataclass, field

from fsw.lib.poi_map import PoiMap
from ground.reader import RunArchive
from interfaces import topics
from interfaces.messages import AssignmentDecision, CameraImage, InfoCostTelemetry
from interfaces.scenario import Scenario


@dataclass
class Coverage:
    """H(t) of all images fused (sampled at each image time, s) and each observer's reported
    H_i(t)."""

    t_s: list[float] = field(default_factory=list)
    h: list[float] = field(default_factory=list)
    h_i: dict[int, tuple[list[float], list[float]]] = field(default_factory=dict)
    h_initial: float = 0.0
    fraction_observed: float = 0.0
    decisions: list[AssignmentDecision] = field(default_factory=list)


def coverage(archive: RunArchive, scenario: Scenario, mission: str,
             sample_every_s: float = 10.0) -> Coverage:
    """Fuse every camera image in time order; sample H every ``sample_every_s``."""
    tgt = scenario.target
    fused = PoiMap.uniform(tgt.pois, tgt.prior_variance, scenario.observers.count)
    out = Coverage(h_initial=fused.cost())
    images = sorted(archive.messages(f"{topics.ROOT}/{mission}/sim/sensors/*/camera", CameraImage),
                    key=lambda m: (m.t_sim, m.spacecraft))
    next_sample = 0.0
    for img in images:
        if img.t_sim >= next_sample - 1e-9:
            out.t_s.append(img.t_sim)
            out.h.append(fused.cost())
            next_sample = img.t_sim + sample_every_s
        fused.add(img.spacecraft, img.poi, img.precision)
    out.t_s.append(images[-1].t_sim if images else 0.0)
    out.h.append(fused.cost())
    out.fraction_observed = fused.seen() / tgt.pois
    for tm in archive.messages(topics.all_spacecraft(mission, "infocost", "telemetry"),
                               InfoCostTelemetry):
        ts, hs = out.h_i.setdefault(tm.spacecraft, ([], []))
        ts.append(tm.t_sim)
        hs.append(tm.h_i)
    out.decisions = archive.messages(topics.assignment_decisions(mission), AssignmentDecision)
    return out


def coverage_summary(c: Coverage) -> dict[str, float | dict[str, float]]:
    """summary.json ``coverage``: H_initial, H_final, fraction of POIs observed, each
    observer's last reported H_i, and the ground's information-driven orbit decisions."""
    return {
        "H_initial": c.h_initial,
        "H_final": c.h[-1] if c.h else c.h_initial,
        "fraction_observed": c.fraction_observed,
        "H_i_final": {str(sc): hs[-1] for sc, (_, hs) in sorted(c.h_i.items()) if hs},
        "H_reduction_fraction": float(1.0 - (c.h[-1] if c.h else c.h_initial) / c.h_initial),
        "assignment_decisions": [d.model_dump(exclude={"sender", "seq", "t_wall"})
                                 for d in c.decisions],
    }

