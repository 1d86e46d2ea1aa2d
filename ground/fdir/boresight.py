"""Where the camera really looked, from the POIs an image saw (issue 15: a misaligned camera).

A camera rotated in its mount by δ looks δ away from where the attitude estimate says, and
nothing onboard knows it: the reported pointing error stays at the loop's jitter, the camera's
position and health located from the images are right, and only the set of POIs seen betrays
it.  With a wide camera (20°) on a small target a few degrees move only the POIs near the edge
of the field of view (the Jaccard overlap of the seen and expected sets stayed at 0.94-0.99 for
a 5° misalignment in the hard campaign), which a bound on the overlap cannot tell from
noise; the edge itself can.  Given the camera's position (located from the image) the POIs in
range and facing it are known, and of them the camera sees exactly those within its half angle
α of the boresight b: seen ⇔ b·u ≥ cos α, u the unit vector to the POI.  Scanning b over a
grid of small rotations of the reported boresight and keeping the one whose predicted set
matches the seen set best (Jaccard; near-ties, within ``TIE_POIS``, to the smallest rotation)
gives the boresight the image shows, and its angle to the reported one the misalignment.  A
target wholly inside the field of view at every candidate leaves every candidate tied: the
offset is then 0 (unobservable, and harmless to the information).

Pure functions; ``ground/fdir/identify.py`` calls them on exceeded windows.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from gnc.infocost import Camera

FloatArray = npt.NDArray[np.float64]

SCAN_DEG = 12.0
"""Largest rotation of the reported boresight scanned, deg."""
STEP_DEG = 0.5
"""Grid step of the scan, deg.  The Jaccard landscape is flat but for a narrow peak when the
cone barely clips the target (a 5° misalignment of a 12° camera 40 m from a 5 m target: found
at 0.5°, missed at 1°), so the scan is a full fine grid, not a coarse one refined; it runs only
on windows that must name a class."""
TIE_POIS = 2
"""Candidates within this many POIs' worth of Jaccard of the best are tied (a POI at the very
edge of the cone, or a camera fix a few tenths of a metre off, moves one or two)."""


def candidate_boresights(bore: FloatArray, scan_deg: float = SCAN_DEG,
                         step_deg: float = STEP_DEG) -> FloatArray:
    """Unit boresights (G, 3) on a square grid of tilts of ``bore`` (3,) up to ``scan_deg``
    about two axes perpendicular to it, ``step_deg`` apart (the untilted one among them)."""
    b = bore / np.linalg.norm(bore)
    e1 = np.cross(b, [1.0, 0.0, 0.0] if abs(b[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(b, e1)
    steps = np.tan(np.radians(np.arange(-scan_deg, scan_deg + step_deg / 2, step_deg)))
    t1, t2 = (g.ravel() for g in np.meshgrid(steps, steps))
    c = b + t1[:, None] * e1 + t2[:, None] * e2
    return c / np.linalg.norm(c, axis=1, keepdims=True)


def boresight_offset(camera_pos: FloatArray, bore: FloatArray, seen: npt.ArrayLike,
                     poi_pos: FloatArray, poi_normal: FloatArray, camera: Camera) -> float | None:
    """Angle (rad) between the reported boresight ``bore`` and the one whose field of view best
    explains the POIs ``seen`` (indices) from ``camera_pos`` (module docstring); None when the
    image saw nothing."""
    seen_idx = np.asarray(seen, dtype=int)
    if seen_idx.size == 0:
        return None
    d = poi_pos - camera_pos
    dist = np.linalg.norm(d, axis=1)
    facing = (np.einsum("ij,ij->i", poi_normal, -d) > 0.0) & (dist > 0.0) & \
        (dist <= camera.max_range_m)
    cand = np.flatnonzero(facing)
    u = d[cand] / dist[cand, None]
    was_seen = np.isin(cand, seen_idx).astype(float)  # seen yet not facing: in every union
    b = bore / np.linalg.norm(bore)
    boresights = candidate_boresights(b)
    predicted = (boresights @ u.T >= math.cos(camera.half_angle_rad)).astype(float)
    inter = predicted @ was_seen
    union = predicted.sum(axis=1) + seen_idx.size - inter
    jaccard = inter / np.maximum(union, 1.0)
    tied = jaccard >= jaccard.max() - TIE_POIS / max(float(union.max()), 1.0)
    nearest = float(np.max(boresights[tied] @ b))  # the smallest rotation among the near-ties
    return math.acos(min(nearest, 1.0))
