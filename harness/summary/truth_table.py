"""The sim's truth of a run as arrays: one row per TruthState, one column per observer.

A two-orbit run archives 113,000 TruthState messages; decoded and held as messages they took
about 1 GB (every coordinate a Python float) and were looked up by float time in dictionaries.
The table keeps the same numbers in float64 arrays (about 60 MB for that run) and is built as
the records stream past (``TruthTableBuilder`` is a ``load_run`` record sink), so the summary and
the report never hold the messages.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from harness.archive.reader import ArchiveError, Record, RunArchive
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import TruthState

TIME_DECIMALS = 6
"""Times are matched to the truth rounded to this many decimals of a second (1 µs)."""


@dataclass(frozen=True)
class TruthTable:
    """True states at the sim's ticks: ``t_s`` (N,), ``spacecraft`` ids (S,), ``r_m`` and
    ``v_mps`` (N, S, 3) in the target's LVLH frame, ``q_lvlh_body`` (N, S, 4, scalar last),
    ``w_body_radps`` (N, S, 3) and ``dv_mps`` (N, S, delivered L1 Δv) — the last three with
    S = 0 columns when the sim had no attitude."""

    t_s: np.ndarray
    spacecraft: tuple[int, ...]
    r_m: np.ndarray
    v_mps: np.ndarray
    q_lvlh_body: np.ndarray
    w_body_radps: np.ndarray
    dv_mps: np.ndarray
    _rows: dict[float, int] = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        self._rows.update((round(float(t), TIME_DECIMALS), i) for i, t in enumerate(self.t_s))

    def __len__(self) -> int:
        return int(self.t_s.size)

    @property
    def has_attitude(self) -> bool:
        return self.q_lvlh_body.shape[1] == len(self.spacecraft) > 0

    def row(self, t_s: float) -> int | None:
        """The row of sim time ``t_s`` (s, to 1 µs), or None if the truth has no such time."""
        return self._rows.get(round(t_s, TIME_DECIMALS))

    def column(self, spacecraft: int) -> int | None:
        """The column of observer ``spacecraft``, or None if the truth does not carry it."""
        try:
            return self.spacecraft.index(spacecraft)
        except ValueError:
            return None

    @classmethod
    def from_messages(cls, messages: Iterable[TruthState]) -> TruthTable:
        builder = TruthTableBuilder()
        for msg in messages:
            builder.add(msg)
        return builder.finish()

    @classmethod
    def from_archive(cls, archive: RunArchive, mission: str) -> TruthTable:
        return cls.from_messages(archive.of(cat.TRUTH, mission))


@dataclass
class TruthTableBuilder:
    """Collects TruthState rows (as a ``load_run`` sink: ``add_record``) into a TruthTable."""

    _t: list[float] = field(default_factory=list)
    _rows: list[np.ndarray] = field(default_factory=list)
    _ids: tuple[int, ...] | None = None
    _attitude: bool = False

    def add_record(self, rec: Record) -> None:
        self.add(rec.decode(TruthState))

    def add(self, msg: TruthState) -> None:
        ids = tuple(msg.spacecraft)
        if self._ids is None:
            self._ids, self._attitude = ids, bool(msg.q_lvlh_body)
        if ids != self._ids or bool(msg.q_lvlh_body) != self._attitude:
            raise ArchiveError(f"truth at t={msg.t_sim} s carries spacecraft {list(ids)}"
                               f"{' with' if msg.q_lvlh_body else ' without'} attitude, earlier "
                               f"truth {list(self._ids)}"
                               f"{' with' if self._attitude else ' without'}")
        parts = [msg.r_lvlh_m, msg.v_lvlh_mps]
        if self._attitude:
            parts += [msg.q_lvlh_body, msg.w_body_radps, [[d] for d in msg.dv_mps]]
        self._t.append(msg.t_sim)
        self._rows.append(np.hstack(parts).ravel())

    def finish(self) -> TruthTable:
        ids, n = self._ids or (), len(self._rows)
        flat = np.array(self._rows, dtype=float).reshape(n, len(ids), 14 if self._attitude else 6)
        if self._attitude:
            q, w, dv = flat[:, :, 6:10], flat[:, :, 10:13], flat[:, :, 13]
        else:
            q, w, dv = np.zeros((n, 0, 4)), np.zeros((n, 0, 3)), np.zeros((n, 0))
        return TruthTable(t_s=np.array(self._t, dtype=float), spacecraft=ids,
                          r_m=flat[:, :, 0:3], v_mps=flat[:, :, 3:6],
                          q_lvlh_body=q, w_body_radps=w, dv_mps=dv)
