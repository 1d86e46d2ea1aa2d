"""Campaign files: a base scenario plus dispersions, expanded into a deterministic list of runs
(docs/contracts.md "Campaigns"; issue 6).

A campaign TOML names a base scenario and groups of runs::

    name = "paper"
    base = "../scenarios/nominal.toml"    # relative to this file
    seeds = { first = 1, count = 10 }     # or a list: [1, 2, 3]
    duration_s = 800.0                    # optional override of every run
    extend_to_pass_s = 6000.0             # optional: with passes, lengthen a run (by at most
                                          # this) until the ground hears its fault's windows

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
overrides, the same seeds, the same drawn set-up and the same drawn faults: group ``g``
becomes ``g-<variant>``::

    [[variants]]
    name = "central"
    overrides = { neighbours = { enabled = false } }
    [[variants]]
    name = "neighbours"
    overrides = { neighbours = { enabled = true } }

Each group expands to (its seeds) × (the Cartesian product of every list-valued fault field,
in file order); every range is then drawn from a generator seeded by (campaign name, group,
run index), so the list is the same on every machine and every restart.  A group may also
override scenario sections (``[groups.overrides]``, e.g. ``fdir = { floor = 0.04 }``), and so
may the campaign for every group (a top-level ``[overrides]``) and a variant; a group's
override wins over a variant's, a variant's over the campaign's.

**Drawn set-ups.**  Any override value may be drawn per run (``deploy/draws.py``): a range
``{ min = a, max = b }`` (an integer when both bounds are), a choice ``{ choose = [...] }``,
or a subset ``{ choose = [...], count = n or { min, max } }`` (distinct values, in list
order); and a group's ``scenario`` (or the campaign's ``base``) may be a choice of files, the
``mission`` (each keeps its own duration unless the campaign sets ``duration_s``)::

    [overrides]
    observers = { count = { min = 2, max = 8 } }
    [overrides.ground]
    contact = { choose = ["continuous", "passes"] }
    [overrides.ground.stations]
    count = { min = 1, max = 3 }
    choose = [{ name = "Kiruna", latitude_deg = 67.86, longitude_deg = 20.96 }, ...]
    [[groups]]
    name = "anything"
    scenario = { choose = ["../scenarios/nominal.toml", "../scenarios/default.toml"] }
    [[groups.faults]]
    spacecraft = "any"                    # one of the run's observers
    kind = { choose = ["thruster_bias", "link_loss"] }
    start_s = { during = ["transfer", "inspection", "after_pass"] }
    magnitude = { per_kind = { thruster_bias = { min = 0.1, max = 0.7 } } }

Each drawn setting has a generator of its own (seeded by campaign, group, run index and the
setting's path), apart from the faults' generator: adding a drawn setting changes no other
draw.  The set-up is drawn first, so a fault may depend on it: ``spacecraft = "any"``,
``start_s = { during = [...] }`` (deployment, transfer, inspection, after_pass:
``deploy/onsets.py``; a phase the set-up lacks is re-drawn among those it has),
``kind = { choose }`` and ``magnitude = { per_kind }`` (``deploy/campaign_file.py``).  Each
run records what it drew (:attr:`RunSpec.drawn`: ``mission``, ``observers.count``,
``ground.stations`` (the count) and ``ground.stations.names``, ``fault.phase``, ``fault.kind``,
...; ``drawn.json`` in its directory), and the report breaks every figure down by each drawn
dimension.

Unknown fields, bad values (a range whose min exceeds its max, an empty choice, a count out of
its list, a setting the scenario does not have, a spacecraft index above the smallest drawn
observer count) and runs whose scenario does not validate are errors, raised by
:func:`load_campaign` before any run starts.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import logging
import shutil
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from pydantic import ValidationError

from deploy.campaign_file import Campaign, Group, ScenarioChoice, draw_fault, grid_axes, seeds
from deploy.disk_space import is_disk_full
from deploy.draws import (
    Choice,
    DrawError,
    Record,
    Uniform,
    check_settings,
    draw_tree,
    parse_tree,
    rng_for,
)
from deploy.onsets import OnsetError, heard_by_s
from deploy.recorder_guard import DISK_FULL, disk_full_cause
from harness.summary import RunSummary
from interfaces.contracts.errors import lines
from interfaces.contracts.scenario import Scenario

if TYPE_CHECKING:
    from harness.summary.digest import RunDigest


class CampaignError(ValueError):
    """A campaign file that cannot be read, does not validate, or expands into an invalid run."""


@dataclass(frozen=True)
class RunSpec:
    """One run of a campaign: its id (``<group>-<index>``, also its directory name), group,
    the validated scenario it runs (with its seed), what it drew (dimension → value: the
    drawn settings by dotted path, ``mission``, ``fault.phase``...) and each drawn
    dimension's domain (``deploy/draws.py``)."""

    id: str
    group: str
    scenario: Scenario
    drawn: dict[str, Any] = field(default_factory=dict)
    domains: dict[str, dict[str, Any]] = field(default_factory=dict)

    @property
    def seed(self) -> int:
        return self.scenario.seed


def _read_toml(path: Path) -> dict[str, Any]:
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise CampaignError(f"cannot read {path}: {e.strerror}") from e
    except tomllib.TOMLDecodeError as e:
        raise CampaignError(f"{path}: not valid TOML: {e}") from e


def _merge(data: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """``data`` with each section of ``overrides`` merged into its own (a whole section drawn:
    replaced)."""
    out = dict(data)
    for section, values in overrides.items():
        base = out.get(section, {})
        if not isinstance(base, dict):
            raise CampaignError(f"overrides.{section}: not a scenario table")
        out[section] = {**base, **values} if isinstance(values, dict) else values
    return out


@dataclass(frozen=True)
class GroupDraws:
    """What a group, flown as one variant, draws for each run: its base scenario (one file, or
    a choice of them: ``mission``) and its overrides, with their drawn values parsed."""

    campaign: str
    group: str
    scenarios: tuple[str, ...]
    drawn_scenario: bool
    files: dict[str, dict[str, Any]]
    overrides: dict[str, Any]

    def draw(self, index: int) -> tuple[dict[str, Any], Record]:
        """Run ``index``'s scenario table (its faults not drawn yet) and what it drew."""
        record = Record()

        def stream(path: str) -> np.random.Generator:
            return rng_for(self.campaign, self.group, index, "setup", path)

        path = self.scenarios[0]
        if self.drawn_scenario:
            path = self.scenarios[int(stream("mission").integers(len(self.scenarios)))]
            record.add("mission", Path(path).stem,
                       {"choose": [Path(p).stem for p in self.scenarios]})
        return _merge(self.files[path], draw_tree(self.overrides, stream, record)), record


def _parsed(tree: dict[str, Any], where: str) -> dict[str, Any]:
    """An overrides table with its drawn values parsed, every setting checked against the
    scenario; DrawError names the first bad one (``where``: its place in the file)."""
    parsed = parse_tree(tree, where)
    check_settings(parsed, where)
    return parsed


def _group_draws(campaign: Campaign, gi: int, layers: dict[str, Any], root: Path
                 ) -> GroupDraws:
    """Group ``gi``'s draws over the overrides ``layers`` (the campaign's, merged with the
    variant's, parsed), checked: DrawError names the first bad drawn value or setting."""
    group = campaign.groups[gi]
    spec = _merge(layers, _parsed(group.overrides, f"groups[{gi}].overrides"))
    _check_spacecraft(campaign, gi, spec)
    scenario = group.scenario or campaign.base
    paths = tuple(scenario.choose) if isinstance(scenario, ScenarioChoice) else (scenario,)
    return GroupDraws(campaign.name, group.name, paths, isinstance(scenario, ScenarioChoice),
                      {p: _read_toml(root / p) for p in dict.fromkeys(paths)}, spec)


def _check_spacecraft(campaign: Campaign, gi: int, spec: dict[str, Any]) -> None:
    """No fault of group ``gi`` names a spacecraft above the smallest observer count drawn."""
    observers = spec.get("observers")
    count = observers.get("count") if isinstance(observers, dict) else None
    if isinstance(count, Uniform):
        lowest = count.low
    elif isinstance(count, Choice) and count.count is None:
        lowest = min((v for v in count.values if isinstance(v, int)), default=None)
    else:
        lowest = None
    if lowest is None:
        return
    for j, f in enumerate(campaign.groups[gi].faults):
        over = [sc for sc in f.fixed_spacecraft() if sc > lowest]
        if over:
            raise DrawError(f"groups[{gi}].faults[{j}].spacecraft: {over[0]} but observers.count "
                            f"is drawn from {lowest:g}: use spacecraft = \"any\" or an index "
                            "every drawn count has")


def expand(campaign: Campaign, root: Path) -> list[RunSpec]:
    """The campaign's runs, in a deterministic order (module docstring); ``root``: the
    directory scenario paths are relative to."""
    try:
        common = _parsed(campaign.overrides, "overrides")
        layers: dict[int | None, dict[str, Any]] = {
            vi: _merge(common, _parsed(v.overrides, f"variants[{vi}].overrides"))
            for vi, v in enumerate(campaign.variants)} or {None: common}
    except DrawError as e:
        raise CampaignError(str(e)) from None
    runs: list[RunSpec] = []
    for gi, group in enumerate(campaign.groups):
        for vi, layer in layers.items():
            try:
                draws = _group_draws(campaign, gi, layer, root)
            except DrawError as e:
                raise CampaignError(f"group {group.name}: {e}") from None
            runs += _expand_group(campaign, group, vi, draws)
    return runs


def _expand_group(campaign: Campaign, group: Group, vi: int | None,
                  draws: GroupDraws) -> list[RunSpec]:
    """One group's runs, flown as variant ``vi`` (None: the campaign has no variants); the
    draws depend on the group and the run's index, never on the variant."""
    label = group.name if vi is None else f"{group.name}-{campaign.variants[vi].name}"
    axes = grid_axes(group.faults)
    combos = list(itertools.product(*(values for _, _, values in axes))) or [()]
    runs: list[RunSpec] = []
    for seed in seeds(group.seeds if group.seeds is not None else campaign.seeds):
        for combo in combos:
            chosen: dict[int, dict[str, Any]] = {}
            for (i, field_name, _), value in zip(axes, combo, strict=True):
                chosen.setdefault(i, {})[field_name] = value
            run_id = f"{label}-{len(runs):04d}"
            data, record = draws.draw(len(runs))
            data["seed"] = seed
            if campaign.duration_s is not None:
                data["duration_s"] = campaign.duration_s
            _check_within(group, float(data.get("duration_s",
                                                Scenario.model_fields["duration_s"].default)))
            data["name"] = f"{campaign.name}-{run_id}"
            if group.nominal:
                data["faults"] = []
            elif group.faults:
                data["faults"] = _faults(campaign, group, len(runs), chosen, data, run_id,
                                         record)
                _lengthen(campaign, run_id, data, record)
            runs.append(RunSpec(run_id, label, _validated(run_id, data, record),
                                record.values, record.domains))
    return runs


def _check_within(group: Group, duration_s: float) -> None:
    """Every fault of ``group`` starts, as written (any draw), before the run ends."""
    for j, f in enumerate(group.faults, 1):
        try:
            f.check_within(duration_s)
        except ValueError as e:
            raise CampaignError(f"groups[{group.name}].faults[#{j}]: {e}") from None


def _faults(campaign: Campaign, group: Group, index: int, chosen: dict[int, dict[str, Any]],
            data: dict[str, Any], run_id: str, record: Record) -> list[dict[str, Any]]:
    """Run ``index``'s faults, drawn against its set-up ``data`` (validated first when a fault
    depends on it)."""
    rng = rng_for(campaign.name, group.name, index)
    setup = _validated(run_id, {**data, "faults": []}, record) \
        if any(f.needs_setup() for f in group.faults) else None
    prefixes = ["fault"] if len(group.faults) == 1 else \
        [f"fault{i + 1}" for i in range(len(group.faults))]
    try:
        return [draw_fault(f, chosen.get(i, {}), rng, setup, record, prefix)
                for i, (f, prefix) in enumerate(zip(group.faults, prefixes, strict=True))]
    except OnsetError as e:
        raise CampaignError(f"run {run_id}: {e}{_drawn_text(record)}") from None


def _lengthen(campaign: Campaign, run_id: str, data: dict[str, Any], record: Record) -> None:
    """With ``extend_to_pass_s``, lengthen the run until the ground has heard the windows after
    its faults' onsets (``deploy.onsets.heard_by_s``), recorded as ``run.lengthened_s``."""
    if campaign.extend_to_pass_s is None:
        return
    scenario = _validated(run_id, data, record)
    end = heard_by_s(scenario, [f.start_s for f in scenario.faults], campaign.extend_to_pass_s)
    if end > scenario.duration_s:
        record.add("run.lengthened_s", round(end - scenario.duration_s, 3), None)
        data["duration_s"] = end


def _drawn_text(record: Record) -> str:
    """`` (drawn: a = 1, ...)``, or nothing when the run drew no set-up."""
    if not record.values:
        return ""
    return " (drawn: " + ", ".join(f"{k} = {v}" for k, v in record.values.items()) + ")"


def _validated(run_id: str, data: dict[str, Any], record: Record | None = None) -> Scenario:
    """Run ``run_id``'s scenario; CampaignError says what is wrong with it (and what the run
    drew)."""
    drawn = _drawn_text(record) if record is not None else ""
    try:
        return Scenario.model_validate(data)
    except ValidationError as e:
        raise CampaignError(f"run {run_id}: invalid scenario: "
                            + "; ".join(lines(e, "", Scenario, data)) + drawn) from None


def load_campaign(path: str | Path) -> tuple[Campaign, list[RunSpec]]:
    """Read, validate and expand a campaign file; CampaignError names what is wrong."""
    p = Path(path)
    data = _read_toml(p)
    try:
        campaign = Campaign.model_validate(data)
    except ValidationError as e:
        raise CampaignError(lines(e, str(p), Campaign, data)[0]) from None
    return campaign, expand(campaign, p.parent)


def execute_run(spec: RunSpec, out_root: str, transport: str = "inproc") -> dict[str, Any]:
    """Run one campaign run into ``<out_root>/runs/<id>/`` (run.mcap, summary.json, a log) and
    return {id, status, error, wall_s}.  The run is written under ``<id>.partial-<random>`` and
    renamed when complete, so a run directory exists only for a finished run; a crash is caught
    and recorded as a failed run with its error.  A run stopped by its host rather than by
    itself (a full disk, a signal) is not finished: its attempt is removed and the result's
    status is ``retry``, for a resumed campaign to fly it again.  ``transport``: ``inproc``
    (this process) or ``zenoh`` (deploy/run_constellation.py as a child, one process per node,
    on a free loopback port and its own mission key space, so runs on one machine never
    cross).  A module-level function, so a Dask worker can import it."""
    runs = Path(out_root) / "runs"
    final, partial = runs / spec.id, _attempt_dir(runs, spec.id, "partial")
    try:
        if transport == "zenoh":
            summary = _zenoh_run(spec, partial)
        elif transport == "inproc":
            summary = _inproc_run(spec, partial)
        else:
            raise ValueError(f"unknown transport {transport!r}")
        cause = host_fault(summary)
        if cause is None:
            _finish(spec, partial, final, transport)
    except OSError as e:
        if not is_disk_full(e):
            raise
        summary, cause = None, f"{DISK_FULL} while writing the run: {e.strerror or e}"
    if cause is not None:
        return record_retry(spec, out_root, cause)
    return {"id": spec.id, "status": summary.status, "error": summary.error,
            "wall_s": summary.wall_s}


def host_fault(summary: RunSummary) -> str | None:
    """Why a run ended by a fault of its host, not of the run (None: it ended by itself): a
    full disk, or a signal that interrupted it."""
    if disk_full_cause(summary.error):
        return summary.error
    if summary.status == "interrupted":
        return summary.error or "interrupted"
    return None


def record_retry(spec: RunSpec, out_root: str, cause: str) -> dict[str, Any]:
    """A run stopped by its host (a full disk, a dead worker, a signal): what its attempts
    left is removed, so that the run is not finished and a resumed campaign flies it again;
    returns its result, status ``retry`` with the cause."""
    runs = Path(out_root) / "runs"
    for pattern in (f"{spec.id}.partial*", f"{spec.id}.failed*"):
        for stale in runs.glob(pattern):
            shutil.rmtree(stale, ignore_errors=True)
    return {"id": spec.id, "status": "retry", "error": cause, "wall_s": None}


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
    """A hash of the run's resolved scenario and, when it drew its set-up, of its record
    (``drawn.json``): a finished run directory is reused on resume only for the same run (an
    edited campaign file changes it)."""
    text = spec.scenario.model_dump_json()
    if spec.drawn:
        text += json.dumps(_drawn_json(spec), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _drawn_json(spec: RunSpec) -> dict[str, Any]:
    """``drawn.json``: what the run drew and each drawn dimension's domain."""
    return {"drawn": spec.drawn, "domains": spec.domains}


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
    if spec.drawn:
        (partial / "drawn.json").write_text(json.dumps(_drawn_json(spec), indent=1) + "\n")
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

    from harness.foxglove_layout import write_layout
    from harness.summary.build import write_summary

    handler = logging.FileHandler(out / "run.log")
    handler.setFormatter(logging.Formatter("%(asctime)s %(name)s %(levelname)s %(message)s"))
    root = logging.getLogger()
    level = root.level
    root.addHandler(handler)
    root.setLevel(logging.INFO)  # the run's log keeps its INFO lines (slews, assignments...)
    t0 = time.monotonic()
    digest: RunDigest | None = None  # a failed run's summary reads what its archive holds
    try:
        status, error, digest = _fly_inproc(spec, out)
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


def _fly_inproc(spec: RunSpec, out: Path) -> tuple[str, str | None, RunDigest | None]:
    """Fly ``spec`` in this process, recording into ``out/run.mcap``: its status, error and
    digest (None when the recorder failed: the summary then reads what the archive holds)."""
    import threading

    from deploy.inproc import run_inproc
    from deploy.recorder_guard import RecorderGuard
    from ground.archive.metadata import run_metadata
    from ground.archive.recorder import McapRecorder
    from harness.summary.digest import LiveDigest

    note = f"# campaign run {spec.id} (group {spec.group}, seed {spec.seed}): resolved_json\n"
    metadata = run_metadata(spec.scenario, "inproc", note)
    live = LiveDigest(spec.scenario, spec.scenario.name, out / "run.mcap", metadata)
    stop = threading.Event()
    guard = RecorderGuard(lambda _: None, stop)
    try:
        with McapRecorder(out / "run.mcap", metadata) as rec:
            guard = RecorderGuard(live.tap(rec), stop)
            run_inproc(spec.scenario, sample_tap=guard, stop=stop)
    except OSError as e:  # the archive's end not written: a full disk, most likely
        if guard.error is None and not is_disk_full(e):
            raise
        guard.error = guard.error or e
    if guard.cause is not None:
        return "failed", guard.cause, None
    return "completed", None, live.finish()


def _zenoh_run(spec: RunSpec, out: Path) -> RunSummary:
    import socket
    import subprocess
    import sys

    from deploy.processes import die_with_parent
    from harness.summary.build import write_summary

    launch = out.with_name(out.name + ".launch")  # beside: the launcher's --out stays empty
    launch.mkdir(exist_ok=True)
    scenario = launch / "scenario.json"
    scenario.write_text(spec.scenario.model_dump_json(indent=1))
    for attempt in range(3):  # a free port can be taken before the launcher binds it
        if attempt:  # what the refused launcher left: the next one starts from an empty --out
            shutil.rmtree(out)
            out.mkdir()
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        cmd = [sys.executable, str(Path(__file__).resolve().parent / "run_constellation.py"),
               "--scenario", str(scenario), "--out", str(out), "--no-report",
               "--endpoint", f"tcp/127.0.0.1:{port}", "--mission", f"{spec.scenario.name}-{port}",
               "--skip-disk-check"]  # the campaign checks its disk, and stops when it fills
        with open(launch / "launcher.log", "w") as log_file:
            try:
                subprocess.run(cmd, stdout=log_file, stderr=subprocess.STDOUT, check=False,
                               timeout=max(600.0, 5.0 * spec.scenario.duration_s),
                               preexec_fn=die_with_parent if sys.platform.startswith("linux")
                               else None)  # a killed worker takes its run down with it
            except subprocess.TimeoutExpired:
                pass  # recorded below from what the launcher left
        said = (launch / "launcher.log").read_text(errors="replace")
        if not any(t in said for t in ("the address is in use", "another run using it")):
            break
    for name in ("scenario.json", "launcher.log"):  # into the run's folder, as before
        (launch / name).replace(out / name)
    launch.rmdir()
    summary_path = out / "summary.json"
    if summary_path.exists():
        return RunSummary.read(summary_path)
    return write_summary(out, spec.scenario, "zenoh", 0.0, "failed",
                         "the launcher left no summary (see launcher.log)")
