"""summary.json's ``coverage`` section: the inspection coverage of a run from its archive."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from pydantic import Field

from gnc.poi_map import PoiMap
from harness.archive.reader import Record, RunArchive
from harness.summary.archive_info import BUS_HEADER
from harness.summary.records import SummaryRecord
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import AssignmentDecision, CameraImage
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.timing import TIME_TOL_S


class AssignmentRecord(SummaryRecord):
    """An orbit assignment decision of the ground (an ``AssignmentDecision`` less its bus
    header)."""

    t_sim: float = Field(description="when decided, sim s")
    phase: str
    reason: Literal["phase", "saturated", "recovery"]
    library_indices: list[int] = Field(
        description="candidate PRO of observer 1, 2, ... (-1: kept its PRO)")
    expected_gain: float = Field(description="expected information gain (H, dimensionless)")
    upper_bound: float = Field(description="its online upper bound, same unit")
    ratio_bound: float = Field(description="expected_gain / upper_bound")
    current_gain: float | None = Field(description="expected gain of the current PROs")
    measured_gains: list[float] = Field(description="H decrease per check window")
    switched: bool = Field(description="whether it was flown")


class CoverageSummary(SummaryRecord):
    """``coverage``: the inspection's information cost H (dimensionless, Eq. 8)."""

    H_initial: float = Field(description="H before any image")
    H_final: float = Field(description="H at the end")
    fraction_observed: float = Field(description="share of the POIs observed at least once")
    H_i_final: dict[str, float] = Field(description="each observer's last reported H_i")
    H_reduction_fraction: float = Field(description="1 - H_final / H_initial")
    assignment_decisions: list[AssignmentRecord]


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
