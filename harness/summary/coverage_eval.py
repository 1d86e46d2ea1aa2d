"""Inspection coverage of a run from its archive: the information cost of everything the
cameras saw (the sim's images, the truth of what was observed) and the observers' own H_i
telemetry (Eq. 4, 8)."""

from __future__ import annotations

from dataclasses import dataclass, field

from gnc.poi_map import PoiMap
from harness.summary import BUS_HEADER, AssignmentRecord, CoverageSummary
from harness.archive.reader import Record, RunArchive
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import AssignmentDecision, CameraImage
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.timing import TIME_TOL_S


@dataclass
class Coverage:
    """H(t) of all images fused (sampled at each image time, s), each observer's H_j(t) on that
    fused map (Eq. 8: the centralized decomposition, sampled with H) and each observer's
    reported H_i(t)."""

    t_s: list[float] = field(default_factory=list)
    h: list[float] = field(default_factory=list)
    h_j: list[list[float]] = field(default_factory=list)
    """per sample, every observer's contribution H_j on the map of all images (Eq. 8)"""
    h_i: dict[int, tuple[list[float], list[float]]] = field(default_factory=dict)
    h_initial: float = 0.0
    fraction_observed: float = 0.0
    decisions: list[AssignmentDecision] = field(default_factory=list)


def camera_images(mission: str) -> str:
    """Key expression of the sim's camera images (the truth of what was observed)."""
    return cat.CAMERA_IMAGE.every(mission)


@dataclass
class CoverageFuser:
    """Fuses camera images one at a time, in time order, into the coverage H(t): the images of a
    long run need not be held at once (``load_run(stream={camera_images(m): fuser.add_record})``;
    the sim publishes them in time order, spacecraft by spacecraft, and the archive keeps that
    order)."""

    scenario: Scenario
    sample_every_s: float = 10.0

    def __post_init__(self) -> None:
        tgt = self.scenario.target
        self.fused = PoiMap.uniform(tgt.pois, tgt.prior_variance, self.scenario.observers.count)
        self.out = Coverage(h_initial=self.fused.cost())
        self._next_sample = 0.0
        self._last_t = 0.0

    def add(self, img: CameraImage) -> None:
        """Fuse one image (H is sampled before the first image at or after each sample time)."""
        if img.t_sim >= self._next_sample - TIME_TOL_S:
            self.out.t_s.append(img.t_sim)
            self._sample()
            self._next_sample = img.t_sim + self.sample_every_s
        self.fused.add(img.spacecraft, *img.arrays())
        self._last_t = img.t_sim

    def _sample(self) -> None:
        """H and every H_j of the images fused so far (the time is appended by the caller)."""
        self.out.h.append(self.fused.cost())
        self.out.h_j.append(self.fused.contributions().tolist())

    def add_record(self, rec: Record) -> None:
        """Decode an archived image and fuse it."""
        self.add(rec.decode(CameraImage))

    def finish(self, archive: RunArchive, mission: str) -> Coverage:
        """The coverage, with each observer's H_i telemetry and the ground's orbit decisions
        from ``archive``."""
        out = self.out
        out.t_s.append(self._last_t)
        self._sample()
        out.fraction_observed = self.fused.seen() / self.scenario.target.pois
        for tm in archive.of(cat.INFO_COST, mission):
            ts, hs = out.h_i.setdefault(tm.spacecraft, ([], []))
            ts.append(tm.t_sim)
            hs.append(tm.h_i)
        out.decisions = archive.of(cat.DECISIONS, mission)
        return out


def coverage(archive: RunArchive, scenario: Scenario, mission: str,
             sample_every_s: float = 10.0) -> Coverage:
    """Fuse every camera image in time order; sample H every ``sample_every_s``."""
    fuser = CoverageFuser(scenario, sample_every_s)
    for img in sorted(archive.messages(camera_images(mission), CameraImage),
                      key=lambda m: (m.t_sim, m.spacecraft)):
        fuser.add(img)
    return fuser.finish(archive, mission)


def coverage_summary(c: Coverage) -> CoverageSummary:
    """summary.json ``coverage``: H_initial, H_final, fraction of POIs observed, each
    observer's last reported H_i, and the ground's information-driven orbit decisions."""
    return CoverageSummary(
        H_initial=c.h_initial,
        H_final=c.h[-1] if c.h else c.h_initial,
        fraction_observed=c.fraction_observed,
        H_i_final={str(sc): hs[-1] for sc, (_, hs) in sorted(c.h_i.items()) if hs},
        H_reduction_fraction=float(1.0 - (c.h[-1] if c.h else c.h_initial) / c.h_initial),
        assignment_decisions=[AssignmentRecord.model_validate(d.model_dump(exclude=BUS_HEADER))
                              for d in c.decisions],
    )

