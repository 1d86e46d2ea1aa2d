"""The neighbours' declarations in summary.json (harness/summary/neighbours.py): one detection
per subject and window, at the window's end (the ground's rulings are keyed by it), declared
when first sent: mid-window where the judges' scans declared it."""

from __future__ import annotations

from harness.summary.neighbours import declarations
from interfaces.contracts.messages import NeighbourDeclaration


def _declared(by: int, t: float, crossed_s: float | None = None) -> NeighbourDeclaration:
    return NeighbourDeclaration(sender=f"sc{by}", t_sim=t, spacecraft=by, subject=2,
                                t_start_s=30.0, t_end_s=60.0, judges=[1, 3], decided=[1, 3],
                                crossed_s=crossed_s)


def test_a_mid_window_declaration_is_declared_when_first_sent() -> None:
    (found,) = declarations([_declared(3, 36.0, 33.0), _declared(1, 35.0, 33.0)])
    assert (found.spacecraft, found.time_s, found.declared_s) == (2, 60.0, 35.0)
    assert found.judges == [1, 3]
    (at_end,) = declarations([_declared(1, 63.0)])
    assert (at_end.time_s, at_end.declared_s) == (60.0, 63.0)
