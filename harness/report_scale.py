"""How a run report scales with the observers: the plots and per-observer tables show the
observers with a fault or a declaration first, at most ``SHOWN_MOST`` in all; the others are
summed up in one line (their figures stay in summary.json)."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence

import numpy as np

from harness.summary import RunSummary

SHOWN_MOST = 8
"""Observers plotted, and listed one per row, at most."""

ROWS_MOST = 24
"""Rows of a table of links or nodes at most; the rest are summed up in one line."""


def shown_observers(ids: Iterable[int], summary: RunSummary) -> list[int]:
    """Of the observers ``ids``, those the report shows one by one: each with an injected
    fault or a declaration first, then the others in order, ``SHOWN_MOST`` at most."""
    ids = sorted(set(ids))
    marked = {f.spacecraft for f in summary.injected_faults} | {
        d.spacecraft for d in summary.detections or []}
    first = [sc for sc in ids if sc in marked]
    return sorted((first + [sc for sc in ids if sc not in marked])[:SHOWN_MOST])


def others_line(what: str, shown: Sequence[int], figures: dict[int, float], unit: str
                ) -> list[str]:
    """One line for the observers not shown: the median and the largest of ``figures`` (by
    observer) over them, named ``what`` in ``unit``; nothing when every observer is shown."""
    rest = {sc: v for sc, v in figures.items() if sc not in shown}
    if not rest:
        return []
    worst = max(rest, key=lambda sc: rest[sc])
    return [f"The other {len(rest)} observers (no fault, no declaration): {what} median "
            f"{np.median(list(rest.values())):.3g} {unit}, largest {rest[worst]:.3g} {unit} "
            f"(sc{worst}).", ""]


def capped_rows(rows: Sequence[str], rank: Callable[[int], float], what: str) -> list[str]:
    """At most ``ROWS_MOST`` of a table's ``rows``, those ranked highest (``rank``: of a row's
    index) in their order, then a line counting those left out ("``what``")."""
    if len(rows) <= ROWS_MOST:
        return list(rows)
    keep = sorted(sorted(range(len(rows)), key=lambda i: -rank(i))[:ROWS_MOST])
    return [*(rows[i] for i in keep), "",
            f"{len(rows) - ROWS_MOST} more {what} with less to show are in summary.json."]


def figure_height_in(panels: int, per_panel_in: float = 1.8, extra_in: float = 1.0) -> float:
    """A stacked figure's height (in) for ``panels`` panels, at most ``SHOWN_MOST`` of them."""
    return per_panel_in * min(panels, SHOWN_MOST) + extra_in
