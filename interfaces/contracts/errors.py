"""Validation errors as a user reads them: one line per error, naming the key and the value.

Pydantic reports an error in a union field once per branch of the union (``magnitude`` as a
number, a list, a range, a per-kind table: four reports of one mistake), with the input as a
dict and a link to its documentation.  :func:`describe` keeps, at each union, only the branch
the input was written for -- the branch whose own checks ran (a validator's message, a bound),
then the one whose literal matched the input's type, then the deepest -- and says each error
in one line: ``<source>: <key path>[ = <value>]: <what is wrong>``, with "did you mean" for a
misspelt key or choice (``difflib.get_close_matches``).  List items are named by their
``name`` where they have one, else counted from 1 (``faults[#1]`` is the first fault).  No
input dicts, links or terminal colour codes.
"""

from __future__ import annotations

import difflib
import inspect
import re
import types
import typing
from collections.abc import Iterable, Mapping
from typing import Any

from pydantic import BaseModel, ValidationError
from pydantic_core import ErrorDetails

_TAG = re.compile(r"^(?:[a-z-]+\[.*\]|[A-Z]\w*|float|int|str|bool|none|bytes)$")
"""What pydantic puts in an error's location for the branch of a union (``float``,
``list[float]``, ``function-after[_order(), Range]``, ``KindChoice``): never a key."""
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")
_SHAPE = frozenset({"missing", "extra_forbidden"})
"""Errors of a table whose keys are not the branch's: a branch written for other input."""
_SHOWN_KEYS = 12
"""At most this many known keys are listed after an unknown one with no close match."""
CLOSE_ENOUGH = 0.7
"""How alike (``difflib`` ratio) a name must be to a known one to be offered in its place."""


def closest(name: str, known: Iterable[str]) -> str | None:
    """The known name ``name`` is most likely a misspelling of, if any."""
    close = difflib.get_close_matches(name, list(known), n=1, cutoff=CLOSE_ENOUGH)
    return close[0] if close else None


def did_you_mean(name: str, known: Iterable[str]) -> str:
    """``; did you mean 'x'?`` for the closest known name to ``name``, else nothing."""
    close = closest(name, known)
    return f"; did you mean {close!r}?" if close else ""


def describe(error: ValidationError, source: str = "", model: type[BaseModel] | None = None,
             data: Any = None) -> str:
    """``error`` as lines (module docstring), each starting with ``source`` (a file, an
    option); ``model``, the validated class, lets an unknown key name the known ones;
    ``data``, the validated input, lets a list item be named by its ``name``."""
    return "\n".join(lines(error, source, model, data))


def lines(error: ValidationError, source: str = "", model: type[BaseModel] | None = None,
          data: Any = None) -> list[str]:
    """The lines of :func:`describe`, the first error that matters first."""
    errors = _unfold(list(error.errors(include_url=False)))
    errors = _merge_misspelt(errors, model)
    head = f"{source}: " if source else ""
    return [_clean(head + _line(err, model, data)) for err in errors]


def _is_tag(part: object) -> bool:
    return isinstance(part, str) and bool(_TAG.match(part))


def _unfold(errors: list[ErrorDetails], start: int = 0) -> list[ErrorDetails]:
    """``errors`` with only the chosen branch of each union (from location index ``start``)."""
    out: list[ErrorDetails] = []
    unions: dict[tuple[Any, ...], dict[str, list[ErrorDetails]]] = {}
    for err in errors:
        loc = err["loc"]
        i = next((k for k in range(start, len(loc)) if _is_tag(loc[k])), None)
        if i is None:
            out.append(err)
        else:
            unions.setdefault(tuple(loc[:i]), {}).setdefault(str(loc[i]), []).append(err)
    for site, branches in unions.items():
        out += _unfold(min(branches.values(), key=_score), len(site) + 1)
    order = {id(e): k for k, e in enumerate(errors)}
    return sorted(out, key=lambda e: order[id(e)])


def _score(branch: list[ErrorDetails]) -> tuple[int, int]:
    """How far the input went into a branch (lower: further): its best error's rank, then
    its depth."""
    return min((_rank(e), -len(e["loc"])) for e in branch)


def _rank(err: ErrorDetails) -> int:
    """0: the branch's own checks ran (a validator, a bound); 1: a choice of the input's type
    missed; 2: a table with other keys; 3: input of another type altogether."""
    kind = err["type"]
    if kind in ("literal_error", "enum"):
        return 1 if isinstance(err.get("input"), str | int | float) else 3
    if kind in _SHAPE:
        return 2
    if kind.endswith(("_type", "_parsing")) or kind in ("is_instance_of", "union_tag_invalid"):
        return 3
    return 0


def _merge_misspelt(errors: list[ErrorDetails], model: type[BaseModel] | None
                    ) -> list[ErrorDetails]:
    """A required key reported missing beside an unknown key that is its misspelling: the
    unknown key alone (which says "did you mean" it)."""
    unknown = [e for e in errors if e["type"] == "extra_forbidden"]
    def misspelt(err: ErrorDetails) -> bool:
        parent, name = _path(err["loc"])[:-1], _path(err["loc"])[-1:]
        return bool(name) and any(
            _path(u["loc"])[:-1] == parent
            and closest(str(_path(u["loc"])[-1]), [str(name[0])])
            for u in unknown)
    return [e for e in errors if not (e["type"] == "missing" and misspelt(e))]


def _path(loc: Iterable[Any]) -> tuple[Any, ...]:
    """A location without its union branches and dict-key markers."""
    return tuple(p for p in loc if not _is_tag(p) and p != "[key]")


def _line(err: ErrorDetails, model: type[BaseModel] | None, data: Any) -> str:
    """One error: where, the value given, what is wrong."""
    where = _where(_path(err["loc"]), data)
    why = _reason(err, model)
    if err["type"] == "value_error":  # a validator's message, which may name its own key
        return f"{where}: {why}" if where and not why.startswith(where) else why
    value = err.get("input")
    given = f" = {value!r}" if where and _scalar(value) and err["type"] not in _SHAPE else ""
    return f"{where}{given}: {why}" if where else why


def reason(error: ValidationError) -> str:
    """What is wrong, for the first error that matters, without where or the value (for a
    caller that says those itself)."""
    return _reason(_unfold(list(error.errors(include_url=False)))[0], None)


def _reason(err: ErrorDetails, model: type[BaseModel] | None) -> str:
    kind, value = err["type"], err.get("input")
    if kind == "extra_forbidden":
        return "unknown key" + _suggest(str(_path(err["loc"])[-1]), _keys(model, err["loc"]))
    if kind == "missing":
        return "missing (required)"
    if kind in ("literal_error", "enum"):
        choices = re.findall(r"'([^']*)'", str(err.get("ctx", {}).get("expected", "")))
        hint = did_you_mean(str(value), choices)
        return f"unknown{hint}" if hint else f"one of {', '.join(choices)}"
    msg = str(err["msg"]).removeprefix("Value error, ").removeprefix("Assertion failed, ")
    return _clean(msg.replace("Input should", "should"))


def _scalar(value: Any) -> bool:
    return isinstance(value, str | int | float | bool) and len(repr(value)) <= 60


def _suggest(name: str, known: list[str]) -> str:
    """"; did you mean 'x'?" for the closest of ``known``, else the known names (at most
    ``_SHOWN_KEYS``), else nothing."""
    if closest(name, known):
        return did_you_mean(name, known)
    if known and len(known) <= _SHOWN_KEYS:
        return f" (known: {', '.join(known)})"
    return ""


def _where(path: tuple[Any, ...], data: Any) -> str:
    """``a.b[name].c`` / ``a.b[#1].c``: list items by their name, else counted from 1."""
    out = ""
    for part in path:
        if isinstance(part, int):
            item = data[part] if isinstance(data, list) and part < len(data) else None
            name = item.get("name") if isinstance(item, Mapping) else None
            out += f"[{name}]" if isinstance(name, str) and name else f"[#{part + 1}]"
            data = item
        else:
            out += f".{part}" if out else str(part)
            data = data.get(part) if isinstance(data, Mapping) else None
    return out


def _keys(model: type[BaseModel] | None, loc: tuple[Any, ...]) -> list[str]:
    """The keys the table holding ``loc``'s last key takes (none when unknown)."""
    found = _model_at(model, loc[:-1]) if model is not None else None
    return list(found.model_fields) if found is not None else []


def _model_at(annotation: Any, loc: tuple[Any, ...]) -> type[BaseModel] | None:
    """The model class at ``loc`` under ``annotation`` (through fields, list items, dict
    values and union branches named by their class)."""
    for part in loc:
        model = _model_in(annotation, str(part) if _is_tag(part) else None)
        if _is_tag(part):
            annotation = model if model is not None else annotation
        elif model is not None and isinstance(part, str) and part in model.model_fields:
            annotation = model.model_fields[part].annotation
        else:
            annotation = _element(annotation)
    return _model_in(annotation, None)


def _members(annotation: Any) -> tuple[Any, ...]:
    if typing.get_origin(annotation) is typing.Annotated:
        annotation = typing.get_args(annotation)[0]
    if isinstance(annotation, types.UnionType) or typing.get_origin(annotation) is typing.Union:
        return typing.get_args(annotation)
    return (annotation,)


def _model_in(annotation: Any, tag: str | None) -> type[BaseModel] | None:
    """The model a (union) annotation holds: the one ``tag`` names, else the first."""
    models = [m for m in _members(annotation) if inspect.isclass(m) and issubclass(m, BaseModel)]
    if tag is not None:
        models = [m for m in models if re.search(rf"\b{m.__name__}\b", tag)]
    return models[0] if models else None


def _element(annotation: Any) -> Any:
    """The item type of a list, the value type of a dict, in the annotation (else None)."""
    for m in _members(annotation):
        if typing.get_origin(m) in (list, dict):
            return typing.get_args(m)[-1]
    return None


def _clean(text: str) -> str:
    """One line, without terminal colour codes."""
    return " ".join(_ANSI.sub("", text).split())
