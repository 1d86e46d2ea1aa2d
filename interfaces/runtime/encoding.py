"""The bytes of a message on the wire and in the archive: its JSON, exactly as pydantic writes it
(``model_dump_json``), made at about half the cost.

pydantic stays the schema of record: the models, their JSON Schemas in MCAP and the validation
where bytes come in are unchanged.  Only the encoding of a message already valid is done by
orjson, which writes the same JSON for the values messages hold (field order, floats in the
shortest round-trip form, strings with the same escapes; ``tests/missions/test_encoding_run.py``
compares the two on every message type of a run, ``tests/interfaces/runtime/test_encoding.py``
on floats across the whole exponent range).  Anything
orjson does not write the same way (an integer beyond 64 bits, a value of a type it does not
know) makes it raise, and pydantic's encoder is used for that message.
"""

from __future__ import annotations

import orjson
from pydantic import BaseModel

from interfaces.contracts.messages import Message


def encode(msg: Message) -> bytes:
    """The JSON bytes of ``msg``: those of ``msg.model_dump_json()``."""
    try:
        return orjson.dumps(msg, default=_fields)
    except TypeError:  # orjson.JSONEncodeError is a TypeError
        return msg.model_dump_json().encode()


def _fields(value: object) -> dict[str, object]:
    """A model's fields in declaration order (its ``__dict__``; private attributes live apart)."""
    if isinstance(value, BaseModel):
        return value.__dict__
    raise TypeError(f"no JSON form for {type(value).__name__}")
