"""Set-ups drawn per run: the values of a campaign's scenario overrides that are not fixed
(``deploy/campaign.py``'s docstring gives the file syntax).

In an ``overrides`` table, at any depth, a value may be

* a range ``{ min = a, max = b }``: drawn uniformly in [a, b] per run, an integer when both
  bounds are integers; both bounds are checked at load against the setting's own limits (a
  float's draws lie below ``b``, so ``b`` may be a limit the setting excludes: 360° for an
  angle in [0°, 360°));
* a choice ``{ choose = [v1, v2, ...] }``: one value drawn uniformly per run (any TOML values,
  taken as they are; each checked at load as a value of the setting);
* a subset ``{ choose = [...], count = n }`` (``count`` an integer or a range of integers):
  that many distinct values drawn, in list order (for a list setting, such as
  ``[[ground.stations]]``).

Each drawn setting has its own generator, seeded by sha256 of (campaign, group, run index,
``setup``, the setting's dotted path): a run's draws do not depend on which other settings are
drawn, nor on the variant flown, nor on the faults' generator (seeded by campaign, group and
run index alone), so adding a drawn setting to a campaign changes nothing else.

Every run records what was drawn (:class:`Record`): the setting's dotted path and the value
(a table chosen: its ``name``; a subset: the count, and the names under ``<path>.names``), and
the dimension's domain, which the campaign report bins (``harness/campaign/dimensions.py``):
``{"min", "max", "integer"}`` for a range (and a subset's count), ``{"choose": [...]}`` for a
choice.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import math
import types
import typing
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Annotated, Any

import numpy as np
from pydantic import BaseModel, ConfigDict, TypeAdapter, ValidationError
from pydantic.fields import FieldInfo

from interfaces.contracts.errors import did_you_mean, reason
from interfaces.contracts.scenario import Scenario


class DrawError(ValueError):
    """A drawn value that cannot be drawn, or names a setting the scenario does not have; the
    message names where it is in the campaign file."""


def rng_for(*parts: object) -> np.random.Generator:
    """The generator seeded by sha256 of ``parts`` joined by ``/`` (the campaign's streams:
    (campaign, group, index) for the faults, plus ``setup`` and a path for a drawn setting)."""
    digest = hashlib.sha256("/".join(map(str, parts)).encode()).digest()
    return np.random.default_rng(int.from_bytes(digest[:8], "little"))


def label(value: Any) -> Any:
    """What a run's record says a drawn value was: a table's ``name`` (or the table as
    compact JSON), a scalar as it is."""
    if isinstance(value, dict):
        return value["name"] if "name" in value else json.dumps(value, sort_keys=True)
    if isinstance(value, list):
        return json.dumps(value, sort_keys=True)
    return value


@dataclass(frozen=True)
class Uniform:
    """A value drawn uniformly in [low, high] (an integer one when ``integer``)."""

    low: float
    high: float
    integer: bool

    def draw(self, rng: np.random.Generator) -> float | int:
        if self.integer:
            return int(rng.integers(int(self.low), int(self.high) + 1))
        return float(rng.uniform(self.low, self.high))

    def domain(self) -> dict[str, Any]:
        return {"min": self.low, "max": self.high, "integer": self.integer}

    def extremes(self) -> tuple[tuple[str, float, float], ...]:
        """(bound, as written, the draw nearest it): ``min`` itself; ``max`` itself for an
        integer range, else the largest float below it (numpy's uniform draws in [low,
        high)), so that a range up to an excluded limit (an angle below 360°) is one."""
        top = self.high if self.integer or self.high == self.low else \
            math.nextafter(self.high, self.low)
        return ("min", self.low, self.low), ("max", self.high, top)


@dataclass(frozen=True)
class Choice:
    """One of ``values`` drawn uniformly, or with ``count`` (a number, or a :class:`Uniform`
    of integers) that many distinct ones, in list order."""

    values: tuple[Any, ...]
    count: int | Uniform | None = None

    def draw(self, rng: np.random.Generator) -> Any:
        if self.count is None:
            return self.values[int(rng.integers(len(self.values)))]
        n = self.count.draw(rng) if isinstance(self.count, Uniform) else self.count
        picked = sorted(int(i) for i in rng.choice(len(self.values), size=int(n), replace=False))
        return [self.values[i] for i in picked]

    def domain(self) -> dict[str, Any] | None:
        """A choice's labels; a subset's count's range (None for a fixed count)."""
        if self.count is None:
            return {"choose": [label(v) for v in self.values]}
        return self.count.domain() if isinstance(self.count, Uniform) else None


Draw = Uniform | Choice
DRAW_KEYS = frozenset({"min", "max", "choose"})
"""The keys that make a table a drawn value (no scenario table has them; ``count`` alone is
``observers.count``)."""


def is_draw(value: Any) -> bool:
    """Whether ``value`` is written as a drawn value (a range, a choice or a subset)."""
    return isinstance(value, dict) and bool(DRAW_KEYS & value.keys())


def _number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def parse_range(spec: Mapping[str, Any], where: str) -> Uniform:
    """``{min, max}``; DrawError naming ``where`` for anything else."""
    if set(spec) != {"min", "max"}:
        raise DrawError(f"{where}: a range is {{ min = a, max = b }}, got keys {sorted(spec)}")
    lo, hi = spec["min"], spec["max"]
    if not (_number(lo) and _number(hi)):
        raise DrawError(f"{where}: range bounds must be finite numbers, got {lo!r} and {hi!r}")
    if lo > hi:
        raise DrawError(f"{where}: range min {lo} exceeds max {hi}")
    return Uniform(lo, hi, isinstance(lo, int) and isinstance(hi, int))


def parse_draw(spec: Mapping[str, Any], where: str) -> Draw:
    """A range, a choice or a subset, checked; DrawError naming ``where`` if it is not one."""
    if "choose" not in spec:
        return parse_range(spec, where)
    if not set(spec) <= {"choose", "count"}:
        raise DrawError(f"{where}: a choice is {{ choose = [...], count = n (optional) }}, "
                        f"got keys {sorted(spec)}")
    values = spec["choose"]
    if not isinstance(values, list) or not values:
        raise DrawError(f"{where}.choose: must be a non-empty list, got {values!r}")
    count = spec.get("count")
    if count is None:
        return Choice(tuple(values))
    return Choice(tuple(values), _count(count, len(values), f"{where}.count"))


def _count(count: Any, n: int, where: str) -> int | Uniform:
    """A subset's count, an integer or a range of integers within [1, n]."""
    if isinstance(count, dict):
        parsed: int | Uniform = parse_range(count, where)
    elif isinstance(count, int) and not isinstance(count, bool):
        parsed = count
    else:
        raise DrawError(f"{where}: must be an integer or {{ min, max }}, got {count!r}")
    if isinstance(parsed, Uniform) and not parsed.integer:
        raise DrawError(f"{where}: a count's bounds must be integers")
    lo, hi = (parsed, parsed) if isinstance(parsed, int) else (int(parsed.low), int(parsed.high))
    if lo < 1 or hi > n:
        text = str(lo) if lo == hi else f"{lo} to {hi}"
        raise DrawError(f"{where}: {text} of a list of {n}: a count must be between 1 and "
                        f"the list's length")
    return parsed


def parse_tree(tree: Any, where: str) -> Any:
    """``tree`` (an overrides table) with every drawn value replaced by its :data:`Draw`;
    DrawError names the first bad one (``where`` and its dotted path)."""
    if is_draw(tree):
        return parse_draw(tree, where)
    if isinstance(tree, dict):
        return {k: parse_tree(v, f"{where}.{k}") for k, v in tree.items()}
    return tree


@dataclass
class Record:
    """What a run drew: the value of each drawn setting (by dotted path) and its dimension's
    domain (none for what is only recorded: a subset's names, a fixed count)."""

    values: dict[str, Any] = field(default_factory=dict)
    domains: dict[str, dict[str, Any]] = field(default_factory=dict)

    def add(self, path: str, value: Any, domain: dict[str, Any] | None) -> None:
        self.values[path] = value
        if domain is not None:
            self.domains[path] = domain


def draw_tree(tree: Any, stream: Callable[[str], np.random.Generator], record: Record,
              path: str = "") -> Any:
    """``tree`` with every :data:`Draw` drawn from ``stream(its dotted path)``, each recorded
    in ``record``."""
    if isinstance(tree, Choice) and tree.count is not None:
        picked = tree.draw(stream(path))
        record.add(path, len(picked), tree.domain())
        record.add(f"{path}.names", [label(v) for v in picked], None)
        return picked
    if isinstance(tree, Uniform | Choice):
        value = tree.draw(stream(path))
        record.add(path, label(value), tree.domain())
        return value
    if isinstance(tree, dict):
        return {k: draw_tree(v, stream, record, f"{path}.{k}" if path else k)
                for k, v in tree.items()}
    return tree


def check_settings(tree: Mapping[str, Any], where: str) -> None:
    """Every key of an overrides ``tree`` (drawn or not, down to the values of a choice) is a
    setting of the scenario, and every value of a setting of its own (a number, a name; not a
    table) within the setting's limits -- a range's both bounds, as written, so that no draw
    can fall outside them; DrawError names the first that is not (``where`` and its path)."""
    _check(Scenario, dict(tree), where)


def _check(annotation: Any, value: Any, where: str, setting: FieldInfo | None = None) -> None:
    if isinstance(value, Uniform):
        _within(setting, value.extremes(), where, "range ")
        return
    if isinstance(value, Choice):
        _check_choice(annotation, value, where, setting)
        return
    model = _model_of(annotation)
    if model is not None and isinstance(value, dict):
        for key, v in value.items():
            if key not in model.model_fields:
                raise DrawError(f"{where}.{key}: the scenario has no such setting"
                                f"{did_you_mean(key, model.model_fields)} ("
                                f"{', '.join(model.model_fields)})")
            _check(model.model_fields[key].annotation, v, f"{where}.{key}",
                   model.model_fields[key])
        return
    if not isinstance(value, list | dict):
        _within(setting, (("", value, value),), where, "")
    if isinstance(value, list):
        _check_items(_inner(annotation, list), enumerate(value, 1), where, "[#{}]")
    elif isinstance(value, dict):
        _check_items(_inner(annotation, dict), value.items(), where, ".{}")


def _check_items(inner: Any, items: Iterable[tuple[Any, Any]], where: str, key: str) -> None:
    """Each item of a list or a dict setting against its element type (None: unchecked)."""
    if inner is not None:
        for k, v in items:
            _check(inner, v, where + key.format(k))


def _within(setting: FieldInfo | None, values: tuple[tuple[str, Any, Any], ...], where: str,
            what: str) -> None:
    """Each of ``values`` ((name, as written, value checked): a range's extremes, or a value)
    a value of ``setting`` (its type and limits; a setting holding tables is left to the
    scenario's own check); DrawError naming the first that is not, as written."""
    if setting is None or _model_of(setting.annotation) is not None or \
            _inner(setting.annotation, list) is not None:
        return
    check = TypeAdapter(Annotated[setting.annotation, setting],
                        config=ConfigDict(allow_inf_nan=False))
    for name, written, v in values:
        try:
            check.validate_python(v)
        except ValidationError as e:
            said = f"{where}: {what}{name} = " if name else f"{where} = "
            raise DrawError(f"{said}{written!r}: {reason(e)}") from None


def _check_choice(annotation: Any, choice: Choice, where: str,
                  setting: FieldInfo | None) -> None:
    """A choice's values are each a value of the setting; a subset's, each an element of it."""
    element = annotation
    if choice.count is not None:
        element, setting = _inner(annotation, list), None
        if element is None:
            raise DrawError(f"{where}: a subset (count) of a setting that is not a list")
    for k, v in enumerate(choice.values, 1):
        _check(element, v, f"{where}.choose[#{k}]", setting)


def _members(annotation: Any) -> tuple[Any, ...]:
    """The types a (possibly optional or union) annotation admits."""
    if isinstance(annotation, types.UnionType) or typing.get_origin(annotation) is typing.Union:
        return typing.get_args(annotation)
    return (annotation,)


def _model_of(annotation: Any) -> type[BaseModel] | None:
    """The scenario table type an annotation holds, if any."""
    return next((m for m in _members(annotation)
                 if inspect.isclass(m) and issubclass(m, BaseModel)), None)


def _inner(annotation: Any, container: type) -> Any:
    """The element type of a ``list[X]`` (``container`` list) or the value type of a
    ``dict[str, X]`` (dict) the annotation holds; None if it holds none."""
    for m in _members(annotation):
        if typing.get_origin(m) is container:
            return typing.get_args(m)[-1]
    return None
