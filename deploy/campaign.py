"""Campaign files: a base scenario plus dispersions, expanded into a deterministic list of runs
(docs/contracts.md "Campaigns"; issue 6).

A campaign TOML names a base scenario and groups of runs::

    name = "paper"
    base = "../scenarios/nominal.toml"    # relative to this file
    seeds = { first = 1, count = 10 }     # or a list: [1, 2, 3]
    duration_s = 800.0                    # optional override of every run

    [[groups]]
    name = "fig23"
    scenario = "../scenarios/paper_fig23.toml"   # optional, default: base
    [[groups.faults]]                     # replaces the scenario's faults
    spacecraft = [2, 4]                   # a list is a grid axis: one run per value
    kind = "thruster_bias"
    start_s = { min = 200.0, max = 600.0 }   # a range is drawn uniformly, per run
    magnitude = [0.3, 0.5]

    [[groups]]
    name = "nominal"
    nominal = true                        # no fault at all

``study = "formations"`` (optional) also writes the formation study (Sec. III.G) beside the
report (harness/campaign/formation_study.py).

``[[variants]]`` (optional) flies every group once per variant, each with its own scenario
overrides, the same seeds and the same drawn faults: group ``g`` becomes ``g-<variant>``::

    [[variants]]
    name = "central"
    overrides = { neighbours = { enabled = false } }
    [[variants]]
    name = "neighbours"
    overrides = { neighbours = { enabled = true } }

Each group expands to (its seeds) × (the Cartesian product of every list-valued fault field,
in file order); every range is then drawn from a generator seeded by (campaign name, group,
run index), so the list is the same on every machine and every restart.  A group may also
override scenario sections (``[groups.overrides]``, e.g. ``fdir = { floor = 0.04 }``).
Unknown fields, bad values and runs whose scenario does not validate are errors, raised by
:func:`load_campaign` before any run starts.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import logging
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from harness.summary import RunSummary
from interfaces.contracts.scenario import FaultKind, Scenario


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Range(_Strict):
    """A value drawn uniformly in [min, max] for each run."""

    min: float
    max: float

    @model_validator(mode="after")
    def _order(self) -> Range:
        if not self.max >= self.min:
            raise ValueError(f"range max {self.max} is below min {self.min}")
        return self


class Seeds(_Strict):
    """Seeds first, first + 1, ..., first + count - 1."""

    first: int = Field(ge=0)
    count: int = Field(ge=1, le=100_000)

    def values(self) -> list[int]:
        return list(range(self.first, self.first + self.count))


Number = float | list[float] | Range


class FaultSpec(_Strict):
    """One injected fault per run, its fields fixed, gridded (lists) or drawn (ranges)."""

    spacecraft: int | list[int]
    kind: FaultKind | list[FaultKind]
    start_s: Number
    end_s: Number | None = None
    magnitude: Number | None = None
    velocity_mps: Number | None = None
    disturbance: Literal["bias", "noise"] | list[Literal["bias", "noise"]] | None = None


class Group(_Strict):
    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$", max_length=64)
    scenario: str | None = None
    seeds: Annotated[list[int], Field(min_length=1)] | Seeds | None = None
    nominal: bool = False
    faults: list[FaultSpec] = Field(default_factory=list)
    overrides: dict[str, dict[str, Any]] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _nominal(self) -> Group:
        if self.nominal and self.faults:
            raise ValueError(f"group {self.name}: nominal = true with faults")
        return self


class Variant(_Strict):
    """One way every group is flown (``[[variants]]``): its name and scenario overrides."""

    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$", max_length=32)
    overrides: dict[str, dict[str, Any]] = Field(default_factory=dict)


class Campaign(_Strict):
    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$", max_length=64)
    base: str
    seeds: Annotated[list[int], Field(min_length=1)] | Seeds = Field(default_factory=lambda: [1])
    duration_s: float | None = Field(default=None, gt=0.0)
    study: Literal["formations", "neighbours"] | None = None
    """a study report written beside report.md (``formations``: study.md,
    harness/campaign/formation_study.py; ``neighbours``: study.md,
    harness/campaign/neighbours_study.py)"""
    groups: list[Group] = Field(min_length=1)
    variants: list[Variant] = Field(default_factory=list)

    @model_validator(mode="after")
    def _unique(self) -> Campaign:
        names = [g.name for g in self.groups]
        if len(set(names)) != len(names):
            raise ValueError(f"group names must be unique: {names}")
        variants = [v.name for v in self.variants]
        if len(set(variants)) != len(variants):
            raise ValueError(f"variant names must be unique: {variants}")
        return self


class CampaignError(ValueError):
    """A campaign file that cannot be read, does not validate, or expands into an invalid run."""


@dataclass(frozen=True)
class RunSpec:
    """One run of a campaign: its id (``<group>-<index>``, also its directory name), group,
    and the validated scenario it runs (with its seed)."""

    id: str
    group: str
    scenario: Scenario

    @property
    def seed(self) -> int:
        return self.scenario.seed


def _seeds(value: list[int] | Seeds) -> list[int]:
    return value.values() if isinstance(value, Seeds) else list(value)


def _axes(faults: list[FaultSpec]) -> list[tuple[int, str, list[Any]]]:
    """(fault index, field, values) of every list-valued field, in file order."""
    out = []
    for i, f in enumerate(faults):
        for name in FaultSpec.model_fields:
            v = getattr(f, name)
            if isinstance(v, list):
                out.append((i, name, v))
    return out


def _rng(campaign: str, group: str, index: int) -> np.random.Generator:
    digest = hashlib.sha256(f"{campaign}/{group}/{index}".encode()).digest()
    return np.random.default_rng(int.from_bytes(digest[:8], "little"))


def _fault(spec: FaultSpec, chosen: dict[str, Any], rng: np.random.Generator) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name in FaultSpec.model_fields:
        v = chosen.get(name, getattr(spec, name))
        if isinstance(v, Range):
            v = float(rng.uniform(v.min, v.max))
        if v is not None:
            out[name] = v
    return out


def _read_toml(path: Path) -> dict[str, Any]:
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise CampaignError(f"cannot read {path}: {e.strerror}") from e
    except tomllib.TOMLDecodeError as e:
        raise CampaignError(f"{path}: not valid TOML: {e}") from e


def _merge(data: dict[str, Any], overrides: dict[str, dict[str, Any]]) -> dict[str, Any]:
    out = dict(data)
    for section, values in overrides.items():
        base = out.get(section, {})
        if not isinstance(base, dict):
            raise CampaignError(f"overrides.{section}: not a scenario table")
        out[section] = {**base, **values}
    return out


def expand(campaign: Campaign, root: Path) -> list[RunSpec]:
    """The campaign's runs, in a deterministic order (module docstring); ``root``: the
    directory scenario paths are relative to."""
    runs: list[RunSpec] = []
    for group in campaign.groups:
        for variant in campaign.variants or [None]:
            runs += _expand_group(campaign, group, variant, root)
    return runs


def _expand_group(campaign: Campaign, group: Group, variant: Variant | None,
                  root: Path) -> list[RunSpec]:
    """One group's runs, flown as ``variant`` (None: the campaign has no variants); the fault
    draws depend on the group and the run's index, never on the variant."""
    label = group.name if variant is None else f"{group.name}-{variant.name}"
    base = _merge(_read_toml(root / (group.scenario or campaign.base)),
                  variant.overrides if variant is not None else {})
    axes = _axes(group.faults)
    combos = list(itertools.product(*(values for _, _, values in axes))) or [()]
    runs: list[RunSpec] = []
    for seed in _seeds(group.seeds if group.seeds is not None else campaign.seeds):
        for combo in combos:
            chosen: dict[int, dict[str, Any]] = {}
            for (i, field_name, _), value in zip(axes, combo, strict=True):
                chosen.setdefault(i, {})[field_name] = value
            data = _merge(base, group.overrides)
            data["seed"] = seed
            if campaign.duration_s is not None:
                data["duration_s"] = campaign.duration_s
            if group.nominal:
                data["faults"] = []
            elif group.faults:
                rng = _rng(campaign.name, group.name, len(runs))
                data["faults"] = [_fault(f, chosen.get(i, {}), rng)
                                  for i, f in enumerate(group.faults)]
            run_id = f"{label}-{len(runs):04d}"
            data["name"] = f"{campaign.name}-{run_id}"
            runs.append(RunSpec(run_id, label, _validated(run_id, data)))
    return runs


def _validated(run_id: str, data: dict[str, Any]) -> Scenario:
    """Run ``run_id``'s scenario; CampaignError says what is wrong with it."""
    try:
        scenario = Scenario.model_validate(data)
        late = [f for f in scenario.faults if f.start_s >= scenario.duration_s]
        if late:
            raise ValueError(f"a fault starts at {late[0].start_s:g} s, not before "
                             f"the end of the run ({scenario.duration_s:g} s)")
    except ValueError as e:
        if not isinstance(e, ValidationError):
            raise CampaignError(f"run {run_id}: {e}") from None
        raise CampaignError(f"run {run_id}: invalid scenario: "
                            + "; ".join(f"{'.'.join(map(str, err['loc']))}: {err['msg']}"
                                        for err in e.errors())) from None
    return scenario


def load_campaign(path: str | Path) -> tuple[Campaign, list[RunSpec]]:
    """Read, validate and expand a campaign file; CampaignError names what is wrong."""
    p = Path(path)
    data = _read_toml(p)
    try:
        campaign = Campaign.model_validate(data)
    except ValidationError as e:
        lines = [f"{p}: invalid campaign:"]
        for err in e.errors():
            lines.append(f"  {'.'.join(map(str, err['loc'])) or '(top level)'}: {err['msg']}")
        raise CampaignError("\n".join(lines)) from None
    return campaign, expand(campaign, p.parent)


def execute_run(spec: RunSpec, out_root: str, transport: str = "inproc") -> dict[str, Any]:
    """Run one campaign run into ``<out_root>/runs/<id>/`` (run.mcap, summary.json, a log) and
    return {id, status, error, wall_s}.  The run is written under ``<id>.partial-<random>`` and
    renamed when complete, so a run directory exists only for a finished run; a crash is caught
    and recorded as a failed run with its error.  ``transport``: ``inproc`` (this process) or
    ``zenoh`` (deploy/run_constellation.py as a child, one process per node, on a free
    loopback port and its own mission key space, so runs on one machine never cross).  A
    module-level function, so a Dask worker can import it."""
    runs = Path(out_root) / "runs"
    final, partial = runs / spec.id, _attempt_dir(runs, spec.id, "partial")
    if transport == "zenoh":
        summary = _zenoh_run(spec, partial)
    elif transport == "inproc":
        summary = _inproc_run(spec, partial)
    else:
        raise ValueError(f"unknown transport {transport!r}")
    _finish(spec, partial, final, transport)
    return {"id": spec.id, "status": summary.status, "error": summary.error,
            "wall_s": summary.wall_s}


def _attempt_dir(runs: Path, run_id: str, kind: str) -> Path:
    """A fresh directory of its own for one attempt at a run (``<id>.<kind>-<random>``), after
    removing what earlier attempts left.  Its own, because an attempt can outlive its campaign:
    a Dask task cancelled by an interrupt runs on to the end, and must not write into, or
    rename, the directory of the attempt that a restarted campaign makes meanwhile."""
    import shutil
    import uuid

    for pattern in (f"{run_id}.partial*", f"{run_id}.failed*"):
        for stale in runs.glob(pattern):
            shutil.rmtree(stale, ignore_errors=True)
    d = runs / f"{run_id}.{kind}-{uuid.uuid4().hex[:8]}"
    d.mkdir(parents=True)
    return d


def fingerprint(spec: RunSpec) -> str:
    """A hash of the run's resolved scenario: a finished run directory is reused on resume only
    for the same run (an edited campaign file changes it)."""
    return hashlib.sha256(spec.scenario.model_dump_json().encode()).hexdigest()[:16]


def finished(spec: RunSpec, out_root: Path) -> bool:
    """Whether ``<out_root>/runs/<id>`` holds this very run, finished."""
    d = out_root / "runs" / spec.id
    try:
        meta = json.loads((d / "campaign.json").read_text())
    except (OSError, ValueError):
        return False
    return (d / "summary.json").exists() and meta.get("fingerprint") == fingerprint(spec)


def _finish(spec: RunSpec, partial: Path, final: Path, transport: str) -> None:
    import shutil

    from ground.archive.metadata import software_version

    (partial / "campaign.json").write_text(json.dumps(
        {"run": spec.id, "group": spec.group, "seed": spec.seed, "transport": transport,
         "fingerprint": fingerprint(spec), "software_version": software_version()},
        indent=2) + "\n")
    shutil.rmtree(final, ignore_errors=True)
    partial.rename(final)


def record_failure(spec: RunSpec, out_root: str, error: str) -> dict[str, Any]:
    """Record a run whose job died outside the run itself (a worker killed, a disk full...) as
    finished and failed, with its error; returns its result."""

    runs = Path(out_root) / "runs"
    partial = _attempt_dir(runs, spec.id, "failed")
    RunSummary(scenario=spec.scenario.name, seed=spec.seed, status="failed", error=error,
               injected_faults=[f.model_dump() for f in spec.scenario.faults]
               ).write(partial / "summary.json")
    _finish(spec, partial, runs / spec.id, "-")
    return {"id": spec.id, "status": "failed", "error": error, "wall_s": None}


def _inproc_run(spec: RunSpec, out: Path) -> RunSummary:
    import time
    import traceback

    from deploy.inproc import run_inproc
    from ground.archive.metadata import run_metadata
    from ground.archive.recorder import McapRecorder
    from harness.foxglove_layout import write_layout
    from harness.summary.build import write_summary
    from harness.summary.digest import LiveDigest, RunDigest

    handler = logging.FileHandler(out / "run.log")
    handler.setFormatter(logging.Formatter("%(asctime)s %(name)s %(levelname)s %(message)s"))
    root = logging.getLogger()
    level = root.level
    root.addHandler(handler)
    root.setLevel(logging.INFO)  # the run's log keeps its INFO lines (slews, assignments...)
    t0 = time.monotonic()
    status, error = "completed", None
    digest: RunDigest | None = None  # a failed run's summary reads what its archive holds
    try:
        note = f"# campaign run {spec.id} (group {spec.group}, seed {spec.seed}): resolved_json\n"
        metadata = run_metadata(spec.scenario, "inproc", note)
        live = LiveDigest(spec.scenario, spec.scenario.name, out / "run.mcap", metadata)
        with McapRecorder(out / "run.mcap", metadata) as rec:
            run_inproc(spec.scenario, sample_tap=live.tap(rec))
        digest = live.finish()
    except Exception as e:  # noqa: BLE001 - a crashed run is a result, not the campaign's end
        status, error = "failed", f"{type(e).__name__}: {e}\n{traceback.format_exc()}"
        logging.getLogger("insp.campaign").error("run %s failed: %s", spec.id, error)
    finally:
        root.removeHandler(handler)
        root.setLevel(level)
        handler.close()
    summary = write_summary(out, spec.scenario, "inproc", time.monotonic() - t0, status, error,
                            digest=digest)
    write_layout(out, spec.scenario)
    return summary


def _zenoh_run(spec: RunSpec, out: Path) -> RunSummary:
    import socket
    import subprocess
    import sys

    from deploy.processes import die_with_parent
    from harness.summary.build import write_summary

    scenario = out / "scenario.json"
    scenario.write_text(spec.scenario.model_dump_json(indent=1))
    for _attempt in range(3):  # a free port can be taken before the launcher binds it
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        cmd = [sys.executable, str(Path(__file__).resolve().parent / "run_constellation.py"),
               "--scenario", str(scenario), "--out", str(out), "--no-report",
               "--endpoint", f"tcp/127.0.0.1:{port}", "--mission", f"{spec.scenario.name}-{port}"]
        with open(out / "launcher.log", "w") as log_file:
            try:
                subprocess.run(cmd, stdout=log_file, stderr=subprocess.STDOUT, check=False,
                               timeout=max(600.0, 5.0 * spec.scenario.duration_s),
                               preexec_fn=die_with_parent if sys.platform.startswith("linux")
                               else None)  # a killed worker takes its run down with it
            except subprocess.TimeoutExpired:
                pass  # recorded below from what the launcher left
        if "cannot listen on" not in (out / "launcher.log").read_text(errors="replace"):
            break
    summary_path = out / "summary.json"
    if summary_path.exists():
        return RunSummary.read(summary_path)
    return write_summary(out, spec.scenario, "zenoh", 0.0, "failed",
                         "the launcher left no summary (see launcher.log)")
