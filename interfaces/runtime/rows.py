"""Fleet-owned arrays: the hot state of an app class, one row per spacecraft, so that the apps
of the spacecraft one process hosts step together over arrays (``App.step_all``) while each
app still reads and writes its own state as attributes (docs/architecture.md, "Apps stepped
as arrays").

A :class:`Rows` block holds named fields, each an array whose first axis is the row; an
optional field (a state that may be "not yet": ``None``) has a flag per row.  An app alone
owns a block of one row; the first time its class steps a fleet's apps together, their rows
are joined into one block (:meth:`Rows.join`) and each app points at its row of it.  A
:class:`Row` descriptor makes a field an attribute of the app: reading gives the app's row (a
view of an array field, a float of a scalar one, ``None`` for an optional field not set),
writing copies into it.  So per-spacecraft code, checkpoints and restores work as they did
with plain attributes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np


@dataclass(frozen=True)
class Field:
    """A field of a :class:`Rows` block: the shape of one row's value (``()``: a scalar),
    its dtype, and whether it is optional (a flag per row says whether it is set)."""

    shape: tuple[int, ...] = ()
    dtype: type = float
    optional: bool = False


class Rows:
    """``n`` rows of the fields ``spec`` (zeros, optional fields not set)."""

    def __init__(self, spec: dict[str, Field], n: int) -> None:
        self.spec = spec
        self.n = n
        self.data: dict[str, np.ndarray] = {
            name: np.zeros((n, *f.shape), dtype=f.dtype) for name, f in spec.items()}
        self.is_set: dict[str, np.ndarray] = {
            name: np.zeros(n, dtype=bool) for name, f in spec.items() if f.optional}

    @classmethod
    def join(cls, members: Sequence[tuple[Rows, int]]) -> Rows:
        """One block of the rows ``members`` ((block, row) each, in order), all of one spec;
        a field whose rows differ in shape (a variable length: a plan's nodes) is padded with
        zeros to the largest."""
        spec = members[0][0].spec
        out = cls(spec, len(members))
        for name in spec:
            rows = [block.data[name][i] for block, i in members]
            shape = np.max([r.shape for r in rows], axis=0) if rows[0].ndim else ()
            out.data[name] = np.zeros((len(rows), *shape), dtype=spec[name].dtype)
            for j, r in enumerate(rows):
                out.data[name][(j, *(slice(0, s) for s in r.shape))] = r
            if name in out.is_set:
                out.is_set[name][:] = [block.is_set[name][i] for block, i in members]
        return out

    def fit(self, name: str, shape: tuple[int, ...]) -> None:
        """Grow field ``name`` so that one row holds ``shape`` (zeros padded)."""
        old = self.data[name]
        want = tuple(max(a, b) for a, b in zip(old.shape[1:], shape, strict=True))
        if want != old.shape[1:]:
            self.data[name] = np.zeros((self.n, *want), dtype=old.dtype)
            self.data[name][(slice(None), *(slice(0, s) for s in old.shape[1:]))] = old


class HasRows(Protocol):
    """What a :class:`Row` attribute needs of its owner: its block and its row in it."""

    rows: Rows
    row: int


class Row:
    """An attribute held in the owner's row of field ``name`` of its block (module
    docstring)."""

    def __init__(self, name: str) -> None:
        self.name = name

    def __get__(self, owner: HasRows | None, kind: type | None = None) -> Any:
        if owner is None:
            return self
        block, i = owner.rows, owner.row
        flags = block.is_set.get(self.name)
        if flags is not None and not flags[i]:
            return None
        value = block.data[self.name][i]
        return value.item() if value.ndim == 0 else value

    def __set__(self, owner: HasRows, value: Any) -> None:
        block, i = owner.rows, owner.row
        flags = block.is_set.get(self.name)
        if flags is not None:
            flags[i] = value is not None
            if value is None:
                return
        block.data[self.name][i] = value


def joined(owners: Sequence[HasRows]) -> Rows:
    """The one block ``owners`` (the apps of one class in a fleet) have their rows in, in
    their order: joined first (:meth:`Rows.join`) unless they have it already."""
    block = owners[0].rows
    if block.n != len(owners) or any(o.rows is not block or o.row != i
                                     for i, o in enumerate(owners)):
        block = Rows.join([(o.rows, o.row) for o in owners])
        for i, o in enumerate(owners):
            o.rows, o.row = block, i
    return block
