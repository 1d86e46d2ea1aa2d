"""The boresight an image shows (ground/fdir/boresight.py), on constructed images of a
spherical target: the misalignment is recovered to the grid's resolution, in any direction; a
camera that sees the whole target shows no offset (unobservable); an empty image gives none."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gnc.infocost import Camera, visibility
from gnc.poi import sphere_pois
from ground.fdir.boresight import STEP_DEG, boresight_offset, candidate_boresights

POS, NORMAL = sphere_pois(2000, 5.0)
CAMERA_AT = np.array([0.0, -25.0, 4.0])


def _tilted(bore: np.ndarray, angle_deg: float, toward: np.ndarray) -> np.ndarray:
    """``bore`` rotated by ``angle_deg`` toward the direction ``toward`` (perpendicularised)."""
    t = toward - (toward @ bore) * bore
    t /= np.linalg.norm(t)
    a = math.radians(angle_deg)
    return math.cos(a) * bore + math.sin(a) * t


def _offset(camera: Camera, misalignment_deg: float, toward: np.ndarray) -> float | None:
    reported = -CAMERA_AT / np.linalg.norm(CAMERA_AT)  # the attitude says: on the centre
    true = _tilted(reported, misalignment_deg, toward)
    seen = np.flatnonzero(visibility(CAMERA_AT[None], true[None], POS, NORMAL, camera)[0])
    return boresight_offset(CAMERA_AT, reported, seen, POS, NORMAL, camera)


@pytest.mark.parametrize("misalignment_deg", [0.0, 3.0, 5.0, 8.0])
@pytest.mark.parametrize("toward", [np.array([1.0, 0.0, 0.0]), np.array([0.3, 0.0, 1.0])])
def test_a_narrow_cameras_misalignment_is_recovered(misalignment_deg: float,
                                                    toward: np.ndarray) -> None:
    got = _offset(Camera(math.radians(8.0), 200.0, 1.0), misalignment_deg, toward)
    assert got is not None
    assert math.degrees(got) == pytest.approx(misalignment_deg, abs=STEP_DEG)


def test_a_camera_seeing_the_whole_target_shows_no_offset() -> None:
    """The target (5 m at 25 m: 11.5° half-width) wholly inside a 30° cone at 5° off: every
    candidate within the scan sees the same POIs."""
    assert _offset(Camera(math.radians(30.0), 200.0, 1.0), 5.0, np.array([1.0, 0.0, 0.0])) == 0.0


def test_nothing_seen_gives_no_offset_and_the_grid_starts_at_the_reported_boresight() -> None:
    cam = Camera(math.radians(8.0), 200.0, 1.0)
    assert boresight_offset(CAMERA_AT, np.array([0.0, 1.0, 0.0]), [], POS, NORMAL, cam) is None
    bores = candidate_boresights(np.array([0.0, 0.0, 2.0]), 4.0, 2.0)
    assert len(bores) == 25 and np.allclose(np.linalg.norm(bores, axis=1), 1.0)
    assert np.allclose(bores[12], [0.0, 0.0, 1.0])  # the grid's centre: no tilt
    assert math.degrees(max(np.arccos(np.clip(bores[:, 2], -1, 1)))) == pytest.approx(
        math.degrees(math.atan(math.hypot(math.tan(math.radians(4.0)),
                                          math.tan(math.radians(4.0))))))
