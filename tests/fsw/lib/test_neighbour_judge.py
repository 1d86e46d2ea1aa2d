"""The neighbours' judge (fsw/lib/neighbour_judge.py): a neighbour's window imaged as its plan
says, with the camera noise of the hardware model, passes (50 draws: none exceeds); the same
window with its camera's information scaled by β = 0.3 fails with H_m = 0.7 (Eq. 9's
|1 - β|); a window without a plan, or whose images carry no pose or were taken before the
attitude settled, does not decide.  The agreement rule's table, and the exclusions held for the
ground's ruling."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsw.lib.neighbour_judge import Exclusions, agreed, judge
from gnc.infocost import Camera
from gnc.poi import sphere_pois
from gnc.pro import Pro
from gnc.twin import TwinModel, centre_boresights
from gnc.window_test import WindowTestSettings
from interfaces.contracts.messages import (
    NeighbourDeclaration,
    NeighbourRuling,
    PoiObservations,
    ReportedPose,
)
from tests.conftest import small_scenario

N = 0.0011  # rad/s, 500 km
PRO = Pro(10.0, 0.3, 0.0, 15.0, 1.1)
CFG = WindowTestSettings.of(small_scenario())
TWIN = TwinModel(*sphere_pois(2000, 5.0), Camera(math.radians(12.0), 200.0, 1.0), 5.0, 0.1)


def _images(beta: float, rng: np.random.Generator, tracking_s: float = 100.0,
            posed: bool = True, nav_off_m: float = 0.0, pointing_rad: float = 2e-4
            ) -> list[PoiObservations]:
    """30 images at 1 Hz from the PRO, aimed at the target centre, each precision the nominal
    camera's times β and the hardware model's noise max(0, 1 + ν ε); the reported nav
    ``nav_off_m`` off the plan (radially) and the reported pointing error ``pointing_rad``."""
    times = np.arange(300.0, 330.0)
    pos = PRO.states(N, times)[:, :3]
    prec = TWIN.precision(pos, centre_boresights(pos))
    out = []
    for t, p, row in zip(times, pos, prec, strict=True):
        seen = np.flatnonzero(row > 0.0)
        noisy = beta * row[seen] * np.maximum(0.0, 1.0 + TWIN.noise_frac
                                              * rng.standard_normal(seen.size))
        pose = ReportedPose(nav_m=list(p + [nav_off_m, 0.0, 0.0]), nav_sigma_m=0.05,
                            aim_m=[0.0, 0.0, 0.0], knowledge_rad=1e-4,
                            tracking_rad=pointing_rad, tracking_s=tracking_s)
        out.append(PoiObservations(sender="sc2", seq=1, t_sim=float(t), spacecraft=2,
                                   image_t_s=float(t), poi=seen.tolist(),
                                   precision=noisy.tolist(), pose=pose if posed else None))
    return out


def _map() -> tuple[np.ndarray, np.ndarray]:
    psi = np.random.default_rng(3).uniform(0.05, 1.0, len(TWIN.poi_pos)) ** 2
    return psi, np.ones(len(TWIN.poi_pos))


def test_a_nominal_neighbour_passes_and_a_degraded_camera_fails() -> None:
    psi, phi = _map()
    nominal = [judge(2, _images(1.0, np.random.default_rng(s)), PRO, psi, phi, TWIN, N, CFG,
                     np.random.default_rng([s, 1])) for s in range(50)]
    assert all(v.exceeded is False for v in nominal)
    assert max(v.metric for v in nominal if v.metric is not None) < 0.05
    v = judge(2, _images(0.3, np.random.default_rng(9)), PRO, psi, phi, TWIN, N, CFG,
              np.random.default_rng(1))
    assert v.exceeded is True and v.direction == "degraded" and v.images == 30
    assert v.failed == ["information"]
    assert v.metric == pytest.approx(0.7, abs=0.03)
    assert v.threshold is not None and CFG.floor <= v.threshold < 0.2


def test_the_pose_tests_read_the_reported_nav_and_pointing() -> None:
    """A nav 1 m off the plan fails ``plan`` (tolerance 0.5 m), a reported pointing error of
    2° fails ``pointing`` (1°), each while the information still matches the plan; with the
    ground's guidance tests off (``fdir.fuse_guidance = false``) neither is judged."""
    psi, phi = _map()
    rng = np.random.default_rng(4)
    for kwargs, failed in (({"nav_off_m": 1.0}, ["plan"]),
                           ({"pointing_rad": math.radians(2.0)}, ["pointing"]),
                           ({"nav_off_m": 0.3, "pointing_rad": math.radians(0.8)}, [])):
        v = judge(2, _images(1.0, rng, **kwargs), PRO, psi, phi, TWIN, N, CFG, rng)
        assert v.failed == failed and v.exceeded is bool(failed), kwargs
    off = WindowTestSettings.of(small_scenario(fdir={"fuse_guidance": False}))
    v = judge(2, _images(1.0, rng, nav_off_m=1.0), PRO, psi, phi, TWIN, N, off, rng)
    assert v.failed == [] and v.exceeded is False


def test_a_window_without_plan_pose_or_settled_attitude_does_not_decide() -> None:
    psi, phi = _map()
    rng = np.random.default_rng(0)
    for images, pro in ((_images(0.3, rng), None), (_images(0.3, rng, posed=False), PRO),
                        (_images(0.3, rng, tracking_s=CFG.settle_s / 2), PRO)):
        v = judge(2, images, pro, psi, phi, TWIN, N, CFG, rng)
        assert v.exceeded is None and v.metric is None


@pytest.mark.parametrize(("verdicts", "agree", "expected"), [
    ({1: True}, 2, [1]),                          # the only one that decided suffices
    ({1: True, 3: None}, 2, [1]),                 # an undecided judge does not count
    ({1: True, 3: False}, 2, None),               # one of two is no agreement
    ({1: True, 3: True}, 2, [1, 3]),
    ({1: True, 3: True, 4: False}, 2, [1, 3]),
    ({1: True, 3: True, 4: False, 5: False}, 2, None),  # half is not more than half
    ({1: True, 3: True, 4: True, 5: False}, 2, [1, 3, 4]),
    ({1: True, 3: True, 4: False}, 3, None),      # a stricter quorum
    ({1: False, 3: None}, 2, None),
])
def test_the_agreement_rule(verdicts: dict[int, bool | None], agree: int,
                            expected: list[int] | None) -> None:
    assert agreed(verdicts, agree) == expected


def test_an_excluded_observer_is_held_and_fused_again_when_overruled() -> None:
    ex = Exclusions()
    msgs = _images(1.0, np.random.default_rng(0))
    decl = NeighbourDeclaration(sender="sc1", seq=1, t_sim=315.0, spacecraft=1, subject=2,
                                t_start_s=280.0, t_end_s=310.0, judges=[1], decided=[1])
    ex.declared(decl, own=1)
    ex.declared(decl.model_copy(update={"subject": 1}), own=1)  # never itself
    admitted = [m for m in msgs if ex.admits(m)]
    assert [m.image_t_s for m in admitted] == [float(t) for t in range(300, 310)]
    assert ex.ruled(NeighbourRuling(sender="ground", seq=1, t_sim=400.0, subject=2,
                                    window_end_s=310.0, verdict="upheld")) == []
    back = ex.ruled(NeighbourRuling(sender="ground", seq=2, t_sim=400.0, subject=2,
                                    window_end_s=310.0, verdict="overruled"))
    assert back == msgs[10:] and all(ex.admits(m) for m in msgs)
