"""What every section of summary.json shares: the record base class, the fields older
summaries lack (filled in on load, and named), and the JSON form they are written in.

A field that older summaries lack is listed in its record's ``FILLABLE`` and has a default:
loading such a summary fills the default in, and :func:`filled_fields` names every field so
filled.  The JSON written holds the fields that were given, by the builder or by the file
read: a filled field is not written back, so a summary read and written again is unchanged.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator, Sequence
from typing import Annotated, Any, ClassVar, TypeVar

from pydantic import AfterValidator, BaseModel, ConfigDict

B = TypeVar("B", bound=BaseModel)


class SummaryRecord(BaseModel):
    """Base of summary.json's records: unknown fields are an error, not ignored."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True)
    FILLABLE: ClassVar[tuple[str, ...]] = ()
    """Fields older summaries lack: their default is filled in on load (and named)."""

    def to_json(self, indent: int = 2) -> str:
        """The record as summary.json holds it (:func:`json_text`)."""
        return json_text(self, indent)


def _none_if_not_finite(v: float | None) -> float | None:
    return None if v is not None and not math.isfinite(v) else v


Figure = Annotated[float | None, AfterValidator(_none_if_not_finite)]
"""A figure that may be undefined (no samples, no nominal cycle...): None, never NaN or inf
(JSON has neither; null on disk)."""


def filled_fields(value: object, path: str = "") -> Iterator[str]:
    """The dotted paths of the fields filled in on load in ``value`` and the records it holds
    (``[]``: any item of a list; a dict's keys as path parts), in the order met, repeated."""
    if isinstance(value, BaseModel):
        fillable = getattr(type(value), "FILLABLE", ())
        for name in fillable:
            if name not in value.model_fields_set:
                yield f"{path}.{name}" if path else name
        for name, v in value.__dict__.items():
            if isinstance(v, (BaseModel, list, dict)):
                yield from filled_fields(v, f"{path}.{name}" if path else name)
    elif isinstance(value, list):
        for v in value:
            if isinstance(v, (BaseModel, list, dict)):
                yield from filled_fields(v, path + "[]")
    elif isinstance(value, dict):
        for k, v in value.items():
            if isinstance(v, (BaseModel, list, dict)):
                yield from filled_fields(v, f"{path}.{k}")


def json_text(record: BaseModel, indent: int = 2) -> str:
    """``record`` as summary.json holds it: the fields given (not those filled in on load),
    by their JSON names, non-finite floats as null (no trailing newline)."""
    data = record.model_dump(mode="python", exclude_unset=True, by_alias=True)
    return json.dumps(_finite(data), indent=indent, allow_nan=False)


def _finite(o: Any) -> Any:
    """JSON has no NaN/inf: non-finite floats become null."""
    if isinstance(o, float):
        return o if math.isfinite(o) else None
    if isinstance(o, dict):
        return {k: _finite(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_finite(v) for v in o]
    return o


def given_copies(records: Sequence[B], exclude_none: bool = False) -> list[B]:
    """Copies of ``records`` with every field given (as written: a message decoded from the
    bus holds only the fields its sender gave, and a summary writes the fields given); with
    ``exclude_none``, those that are None are left unset (not written)."""
    return [type(r).model_validate(r.model_dump(exclude_none=exclude_none)) for r in records]
