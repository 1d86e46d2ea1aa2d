"""One message as one flat row of named columns, shaped by its model's declared types.

The convention (the DataFrames and Parquet files of ``harness.archive.frame``):

* a nested model or a dict becomes dotted names: ``groups.high.runs`` (ExecStats),
  ``evidence.nis`` (FaultReport);
* a list whose length the model fixes (``min_length == max_length``: Position, Quat, State6,
  Mat6...) becomes one column per element, the index appended: ``x.0`` ... ``x.5``,
  ``P.0.0`` ... ``P.5.5``, ``q_lvlh_body.3``;
* any other list (its length varies with the message: ``t_s``, ``assignments``,
  TruthState's ``r_lvlh_m``) stays one column holding the whole list, as plain Python values
  (nested models as dicts);
* the packed POI set and precisions of an image or its observations (``poi_packed``,
  ``precision_packed``) are the lists they pack, in columns ``poi`` and ``precision``;
* anything else (numbers, strings, None) is a column of its own;
* an optional model or fixed-length list left out (None) gives None in each of its columns.

The shape comes from the model, not from the values, so a topic has the same columns in every
run (a dict's columns are its keys, which the values decide).
"""

from __future__ import annotations

import types
import typing
from dataclasses import dataclass
from typing import Annotated, Any, Union, get_args, get_origin

from annotated_types import MaxLen, MinLen
from pydantic import BaseModel
from pydantic.fields import FieldInfo

from interfaces.contracts.messages.base import PoiPrecisions


@dataclass(frozen=True, slots=True)
class Leaf:
    """One column holding the value as it is."""


@dataclass(frozen=True, slots=True)
class Fixed:
    """A list of ``length`` items: one column per item, named by its index."""

    length: int
    item: Shape


@dataclass(frozen=True, slots=True)
class Fields:
    """A model: one group of columns per field, named by the field."""

    fields: tuple[tuple[str, Shape], ...]


@dataclass(frozen=True, slots=True)
class Keyed:
    """A dict: one group of columns per key, each value shaped as ``value``."""

    value: Shape


Shape = Leaf | Fixed | Fields | Keyed
"""How a value of a declared type becomes columns."""


def _unwrap(annotation: Any, metadata: list[Any]) -> Any:
    """``annotation`` without ``Annotated`` (its constraints appended to ``metadata``) and
    without an ``Optional`` (None is then a plain value: one column)."""
    while True:
        if get_origin(annotation) is Annotated:
            for m in annotation.__metadata__:
                metadata.extend(m.metadata if isinstance(m, FieldInfo) else (m,))
            annotation = get_args(annotation)[0]
            continue
        if get_origin(annotation) in (Union, types.UnionType):
            others = [a for a in get_args(annotation) if a is not type(None)]
            if len(others) == 1:
                annotation = others[0]
                continue
        return annotation


def _fixed_length(metadata: list[Any]) -> int | None:
    """The length a list's constraints fix (``min_length == max_length``), else None."""
    low = [m.min_length for m in metadata if isinstance(m, MinLen)]
    high = [m.max_length for m in metadata if isinstance(m, MaxLen)]
    return low[-1] if low and high and low[-1] == high[-1] else None


def shape_of(annotation: Any, metadata: typing.Sequence[Any] = ()) -> Shape:
    """The shape of a value declared as ``annotation`` with the constraints ``metadata`` (as
    pydantic's ``FieldInfo`` holds them)."""
    found = list(metadata)
    base = _unwrap(annotation, found)
    if isinstance(base, type) and issubclass(base, BaseModel):
        return model_shape(base)
    origin, args = get_origin(base), get_args(base)
    if origin is dict and len(args) == 2:
        return Keyed(shape_of(args[1]))
    if origin is list and len(args) == 1:
        length = _fixed_length(found)
        if length is not None:
            return Fixed(length, shape_of(args[0]))
    return Leaf()


def model_shape(model: type[BaseModel]) -> Fields:
    """The shape of a model: its fields in declaration order."""
    return Fields(tuple((name, shape_of(info.annotation, info.metadata))
                        for name, info in model.model_fields.items()))


def _join(prefix: str, name: str) -> str:
    return f"{prefix}.{name}" if prefix else name


def flatten_into(value: Any, shape: Shape, name: str, row: dict[str, Any]) -> None:
    """Put the columns of ``value`` (plain Python, as ``model_dump()`` gives it) shaped as
    ``shape`` into ``row``, their names prefixed by ``name``.  None in place of a model or a
    fixed-length list (an optional field left out) gives None in each of its columns, so they
    are the same whether it is there or not; a value of any other unexpected shape is one
    column."""
    if isinstance(shape, Fields) and (value is None or isinstance(value, dict)):
        for field, sub in shape.fields:
            flatten_into(None if value is None else value.get(field), sub, _join(name, field),
                         row)
    elif isinstance(shape, Fixed) and (
            value is None or (isinstance(value, list) and len(value) == shape.length)):
        for i in range(shape.length):
            flatten_into(None if value is None else value[i], shape.item, _join(name, str(i)),
                         row)
    elif isinstance(shape, Keyed) and isinstance(value, dict):
        for k, v in value.items():
            flatten_into(v, shape.value, _join(name, str(k)), row)
    elif not (isinstance(shape, Keyed) and value is None):  # a missing dict has no columns
        row[name] = value


class RowFlattener:
    """Flat rows of messages; each model's shape is worked out once per flattener."""

    def __init__(self) -> None:
        self._shapes: dict[type[BaseModel], Fields] = {}

    def row(self, message: BaseModel) -> dict[str, Any]:
        """Column name -> value of ``message`` (see the module docstring)."""
        model = type(message)
        shape = self._shapes.get(model)
        if shape is None:
            shape = self._shapes[model] = model_shape(model)
        row: dict[str, Any] = {}
        flatten_into(message.model_dump(), shape, "", row)
        if isinstance(message, PoiPrecisions):
            return _unpacked(row, message)
        return row


def _unpacked(row: dict[str, Any], message: PoiPrecisions) -> dict[str, Any]:
    """``row`` with the packed POI set and precisions as the lists they pack, in their place
    (``poi``, ``precision``)."""
    lists = {"poi_packed": ("poi", message.poi.tolist()),
             "precision_packed": ("precision", message.precision.tolist())}
    return dict(lists.get(name, (name, value)) for name, value in row.items())


__all__ = ["Fields", "Fixed", "Keyed", "Leaf", "RowFlattener", "Shape", "flatten_into",
           "model_shape", "shape_of"]
