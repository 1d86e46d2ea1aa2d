"""A campaign file's tables (``deploy/campaign.py``'s docstring gives the syntax), and the
drawing of one run's fault.

A fault's fields are each fixed, gridded (a list: one run per value) or drawn per run.

Drawn fields take their values from the run's fault generator (seeded by campaign, group and
run index), in the order kind, spacecraft, start_s, end_s, magnitude, velocity_mps: a range
``{ min, max }`` uniformly; ``kind = { choose = [...] }`` one kind; ``spacecraft = "any"`` one
of the run's observers 1..count (0 for a common-mode kind); ``start_s = { during = [...] }`` a
phase of the run's own set-up, then a time in it (``deploy/onsets.py``); ``magnitude =
{ per_kind = { <kind> = value or range, ... } }`` the entry of the run's kind.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from deploy.draws import Record, Uniform
from deploy.onsets import OnsetPhase, draw_onset
from interfaces.contracts.errors import reason
from interfaces.contracts.scenario import COMMON_MODE_KINDS, Fault, FaultKind, Scenario
from interfaces.contracts.scenario.faults import MAGNITUDES, NO_MAGNITUDE


class Strict(BaseModel):
    """A table of the campaign file: unknown keys and non-finite numbers are errors, values
    are frozen."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class Range(Strict):
    """A value drawn uniformly in [min, max] for each run."""

    min: float
    max: float

    @model_validator(mode="after")
    def _order(self) -> Range:
        if not self.max >= self.min:
            raise ValueError(f"range max {self.max} is below min {self.min}")
        return self


class KindChoice(Strict):
    """``kind = { choose = [...] }``: one kind drawn per run."""

    choose: list[FaultKind] = Field(min_length=1)


class During(Strict):
    """``start_s = { during = [...] }``: a phase of the run's set-up drawn, then an onset in
    it (``deploy/onsets.py``)."""

    during: list[OnsetPhase] = Field(min_length=1)


class PerKind(Strict):
    """``magnitude = { per_kind = { <kind> = value or { min, max } } }``: the magnitude of the
    run's kind (each kind with a magnitude needs an entry)."""

    per_kind: dict[FaultKind, float | Range]


Number = float | list[float] | Range


class FaultSpec(Strict):
    """One injected fault per run, its fields fixed, gridded (lists) or drawn (module
    docstring)."""

    spacecraft: int | list[int] | Literal["any"]
    kind: FaultKind | list[FaultKind] | KindChoice
    start_s: Number | During
    end_s: Number | None = None
    magnitude: Number | PerKind | None = None
    velocity_mps: Number | None = None
    disturbance: Literal["bias", "noise"] | list[Literal["bias", "noise"]] | None = None

    @model_validator(mode="after")
    def _per_kind(self) -> FaultSpec:
        if isinstance(self.magnitude, PerKind):
            missing = [k for k in self.kinds()
                       if k not in self.magnitude.per_kind and k not in NO_MAGNITUDE]
            if missing:
                raise ValueError(f"magnitude.per_kind has no entry for kind {', '.join(missing)}")
        return self

    @model_validator(mode="after")
    def _limits(self) -> FaultSpec:
        """Every value the fault may take -- a range's both bounds, as written, a grid's every
        value -- within the limits of each kind it may be (``Fault``'s own checks)."""
        kinds = self.kinds()
        for kind in kinds:
            for name in ("magnitude", "velocity_mps", "start_s", "end_s"):
                trial = self._trial(kind) | ({"start_s": 0.0} if name == "start_s" else {})
                for label, written, value in bounds(self._of(name, kind)):
                    why = _refusal(trial, name, written, value)
                    if why is not None:
                        of_kind = f" (kind {kind})" if len(kinds) > 1 else ""
                        raise ValueError(f"{name}{label} = {written:g}{of_kind}: {why}")
        return self

    def _of(self, name: str, kind: str) -> Any:
        """Field ``name`` as written, for ``kind`` (a per-kind magnitude: its entry)."""
        value = getattr(self, name)
        return value.per_kind.get(kind) if isinstance(value, PerKind) else value

    def _trial(self, kind: str) -> dict[str, Any]:
        """A valid fault of ``kind``, against which one field's values are tried: every field
        at a value of its own limits (the middle of the kind's magnitudes; a disturbance of
        1 m and 0.01 m/s), but ``start_s`` at the latest written (an end is tried after it)."""
        trial: dict[str, Any] = {"spacecraft": 0 if kind in COMMON_MODE_KINDS else 1,
                                 "kind": kind, "start_s": 0.0}
        limits = MAGNITUDES[kind]
        if kind == "state_disturbance":
            trial |= {"magnitude": 1.0, "velocity_mps": 0.01}
        elif limits is not None:
            trial["magnitude"] = (limits.low + limits.high) / 2.0
        starts = [v for _, _, v in bounds(self.start_s)]
        if starts:
            trial["start_s"] = max(starts)
        disturbance = self.disturbance
        if disturbance is not None:
            trial["disturbance"] = disturbance[0] if isinstance(disturbance, list) \
                else disturbance
        return trial

    def check_within(self, duration_s: float) -> None:
        """Refuse a start the fault may take (a range's max, as written) at or after the end
        of a run of ``duration_s`` (s); ValueError naming it."""
        for label, written, value in bounds(self.start_s):
            if value >= duration_s:
                raise ValueError(f"start_s{label} = {written:g}: not before the end of the run "
                                 f"(duration_s = {duration_s:g})")

    def kinds(self) -> list[str]:
        """Every kind the fault may take."""
        k = self.kind
        if isinstance(k, KindChoice):
            return list(k.choose)
        return list(k) if isinstance(k, list) else [k]

    def needs_setup(self) -> bool:
        """Whether drawing it needs the run's drawn set-up (its observers or phases)."""
        return self.spacecraft == "any" or isinstance(self.start_s, During)

    def fixed_spacecraft(self) -> list[int]:
        """The spacecraft indices given in the file (none for ``"any"``)."""
        sc = self.spacecraft
        if sc == "any":
            return []
        return list(sc) if isinstance(sc, list) else [sc]


def bounds(value: Any) -> list[tuple[str, float, float]]:
    """The values a fault's field may take, as (label, as written, value to check): a range's
    extremes (its max as the largest draw below it, ``deploy.draws.Uniform.extremes``), a
    grid's values, a fixed value; none for a field drawn otherwise or not given."""
    if isinstance(value, Range):
        return [(f" range {name}", written, v)
                for name, written, v in Uniform(value.min, value.max, False).extremes()]
    if isinstance(value, list):
        return [(f"[#{i}]", v, v) for i, v in enumerate(value, 1)]
    return [] if value is None or isinstance(value, During) else [("", value, value)]


def _refusal(trial: dict[str, Any], name: str, written: float, value: float) -> str | None:
    """Why a fault ``trial`` with ``name`` at ``value`` is not one (None: it is), said of the
    value as ``written``."""
    try:
        Fault.model_validate({**trial, name: value})
    except ValidationError as e:
        try:
            Fault.model_validate({**trial, name: written})
        except ValidationError as said:
            return reason(said)
        return reason(e)
    return None


class Seeds(Strict):
    """Seeds first, first + 1, ..., first + count - 1."""

    first: int = Field(ge=0)
    count: int = Field(ge=1, le=100_000)

    def values(self) -> list[int]:
        return list(range(self.first, self.first + self.count))


class ScenarioChoice(Strict):
    """``scenario = { choose = [files] }``: the base scenario drawn per run (``mission``)."""

    choose: list[str] = Field(min_length=1)


Overrides = dict[str, dict[str, Any]]


class Group(Strict):
    """``[[groups]]``: runs of one scenario (or a choice of them), seeds, faults or none, and
    scenario overrides."""

    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$", max_length=64)
    scenario: str | ScenarioChoice | None = None
    seeds: Annotated[list[int], Field(min_length=1)] | Seeds | None = None
    nominal: bool = False
    faults: list[FaultSpec] = Field(default_factory=list)
    overrides: Overrides = Field(default_factory=dict)

    @model_validator(mode="after")
    def _nominal(self) -> Group:
        if self.nominal and self.faults:
            raise ValueError(f"group {self.name}: nominal = true with faults")
        return self


class Variant(Strict):
    """One way every group is flown (``[[variants]]``): its name and scenario overrides."""

    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$", max_length=32)
    overrides: Overrides = Field(default_factory=dict)


class Campaign(Strict):
    """The whole campaign file."""

    name: str = Field(pattern=r"^[A-Za-z0-9_\-]+$", max_length=64)
    base: str | ScenarioChoice
    seeds: Annotated[list[int], Field(min_length=1)] | Seeds = Field(default_factory=lambda: [1])
    duration_s: float | None = Field(default=None, gt=0.0)
    extend_to_pass_s: float | None = Field(default=None, gt=0.0)
    """with ground passes, lengthen a run by at most this (s) until the ground has heard the
    windows after its faults' onsets (``deploy.onsets.heard_by_s``; None: never)"""
    study: Literal["formations", "neighbours"] | None = None
    """a study report written beside report.md (``formations``: study.md,
    harness/campaign/formation_study.py; ``neighbours``: study.md,
    harness/campaign/neighbours_study.py)"""
    overrides: Overrides = Field(default_factory=dict)
    """scenario overrides of every group (a group's and a variant's win over them)"""
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


def seeds(value: list[int] | Seeds) -> list[int]:
    """The seeds a ``seeds`` entry names."""
    return value.values() if isinstance(value, Seeds) else list(value)


def grid_axes(faults: list[FaultSpec]) -> list[tuple[int, str, list[Any]]]:
    """(fault index, field, values) of every list-valued field, in file order."""
    out = []
    for i, f in enumerate(faults):
        for name in FaultSpec.model_fields:
            v = getattr(f, name)
            if isinstance(v, list):
                out.append((i, name, v))
    return out


def draw_fault(spec: FaultSpec, chosen: dict[str, Any], rng: np.random.Generator,
               setup: Scenario | None, record: Record, prefix: str) -> dict[str, Any]:
    """One run's fault (a scenario ``[[faults]]`` table): the grid values ``chosen`` for its
    list fields, the rest drawn from ``rng`` (module docstring) against the run's ``setup``
    (the drawn scenario, without faults; needed when :meth:`FaultSpec.needs_setup`); what is
    drawn beyond ranges goes in ``record`` as ``<prefix>.kind``, ``.spacecraft``, ``.phase``.
    Raises OnsetError when the set-up has none of the onset phases asked for."""
    v = {name: chosen.get(name, getattr(spec, name)) for name in FaultSpec.model_fields}
    kind = v["kind"]
    if isinstance(kind, KindChoice):
        kind = kind.choose[int(rng.integers(len(kind.choose)))]
        record.add(f"{prefix}.kind", kind, {"choose": spec.kinds()})
    out: dict[str, Any] = {"kind": kind, "spacecraft": _spacecraft(v["spacecraft"], kind, rng,
                                                                   setup, record, prefix)}
    for name in ("start_s", "end_s", "magnitude", "velocity_mps", "disturbance"):
        x = v[name]
        if isinstance(x, During):
            domain = {"choose": list(dict.fromkeys(x.during))}
            phase, x = draw_onset(_needed(setup), x.during, rng)
            record.add(f"{prefix}.phase", phase, domain)
        if isinstance(x, PerKind):
            x = x.per_kind.get(kind)
        if isinstance(x, Range):
            x = float(rng.uniform(x.min, x.max))
        if x is not None:
            out[name] = x
    return out


def _spacecraft(sc: int | Literal["any"], kind: str, rng: np.random.Generator,
                setup: Scenario | None, record: Record, prefix: str) -> int:
    """The fault's spacecraft: as given, or for ``"any"`` one of the run's observers (0, every
    observer, for a common-mode kind)."""
    if sc != "any":
        return sc
    drawn = 0 if kind in COMMON_MODE_KINDS else \
        int(rng.integers(1, _needed(setup).observers.count + 1))
    record.add(f"{prefix}.spacecraft", drawn, None)
    return drawn


def _needed(setup: Scenario | None) -> Scenario:
    if setup is None:
        raise ValueError("this fault depends on the run's set-up, which was not given")
    return setup
