"""The ground's rulings on the neighbours' declarations (ground/fdir/neighbour_rulings.py): ruled
once per subject and window, on the first window of the subject the ground decided, at or after
the declared one; upheld when the ground's window failed, overruled when it passed, and then no
observer excludes the subject any more."""

from __future__ import annotations

import logging

from ground.fdir.neighbour_rulings import NeighbourRulings
from interfaces.contracts.messages import NeighbourDeclaration


def _declaration(by: int, subject: int, t_end: float) -> NeighbourDeclaration:
    return NeighbourDeclaration(sender=f"sc{by}", seq=1, t_sim=t_end + 4.0, spacecraft=by,
                                subject=subject, t_start_s=t_end - 30.0, t_end_s=t_end,
                                judges=[by], decided=[by])


def test_a_declaration_is_ruled_once_on_the_first_decided_window() -> None:
    r = NeighbourRulings("ground", logging.getLogger("t"))
    for by in (1, 3, 2):  # every observer that applied the rule sends it; the subject too
        r.declaration(_declaration(by, 2, 60.0))
    assert r.excludes(1) and r.excludes(3) and not r.excludes(2)
    assert r.rule(30.0, {2: True}) == []          # an earlier window
    assert r.rule(60.0, {2: None, 1: False}) == []  # the ground did not decide on it
    (ruling,) = r.rule(90.0, {2: True})
    assert (ruling.subject, ruling.window_end_s, ruling.verdict) == (2, 60.0, "upheld")
    assert r.rule(120.0, {2: True}) == []
    r.declaration(_declaration(1, 2, 60.0))       # a late copy: ruled already
    assert r.rule(150.0, {2: False}) == [] and r.excludes(1)


def test_an_overruled_subject_is_fused_again_by_everyone() -> None:
    r = NeighbourRulings("ground", logging.getLogger("t"))
    r.declaration(_declaration(1, 3, 90.0))
    r.declaration(_declaration(2, 3, 90.0))
    (ruling,) = r.rule(90.0, {3: False})
    assert ruling.verdict == "overruled"
    assert not r.excludes(1) and not r.excludes(2)


def test_a_subject_the_ground_holds_declared_is_upheld_though_its_window_passed() -> None:
    """The ground's scan declared the subject inside the window (a pointing fault begun late
    in it), whose median test passed: the ground's own declaration upholds the neighbours'
    (passes campaign, pointing-neighbours-0000: overruled before, and the subject fused
    again)."""
    r = NeighbourRulings("ground", logging.getLogger("t"))
    r.declaration(_declaration(1, 2, 540.0))
    (ruling,) = r.rule(540.0, {2: False}, declared={2})
    assert ruling.verdict == "upheld" and r.excludes(1)
    r.declaration(_declaration(1, 3, 540.0))
    assert r.rule(540.0, {3: None}, declared={3}) == []  # undecided: no ruling yet
