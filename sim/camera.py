"""The observers' inspection cameras in the sim (the hardware stand-in): which POIs each image
sees and with what precision, from the TRUE pose and the camera's faults.

An image of observer i sees the POIs visible from its true position along its true boresight
(``gnc.infocost.visibility``: inside the field-of-view cone, within range, front-facing on
the convex target) and measures each with precision σ⁻¹ = 1/(k d²) (Eq. 5), scaled by the
camera's health β and perturbed by multiplicative noise: σ⁻¹_meas = β σ⁻¹ max(0, 1 + ν ε),
ε ~ N(0, 1) from the observer's own generator, and quantised to the significant digits the
message carries (``interfaces.contracts.messages.poi_packing.quantise``).  Fault hooks
(issue 5): ``beta`` (camera degradation, information scaled by β ∈ (0, 1]) and
``misalignment`` (a rotation of the boresight in body axes: other POIs, or none, are seen).

The precision of every camera-POI pair is computed by the compiled kernel
(``gnc.infocost_kernels.precision_on``, ``compiled=True``, the default) or by the numpy
reference (``gnc.infocost.precision``).  They agree to rounding; after quantisation the
images are the same unless a pair lies within rounding of the cone, range or horizon boundary
or a value within rounding of a quantisation step (``tests/sim/test_truth_camera.py``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from gnc import infocost, infocost_kernels, quat
from gnc.checks import finite_array
from gnc.infocost import Camera, PoiSet
from interfaces.contracts.messages.poi_packing import quantise

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

@dataclass(frozen=True)
class Image:
    """One image: indices of the POIs seen (ascending) and their measured precision σ⁻¹."""

    poi: IntArray
    precision: FloatArray


@dataclass(eq=False)
class TruthCameras:
    """The cameras of N observers.

    Attributes:
        poi_pos: POI positions in the target frame (LVLH, origin at the target centre), (M, 3) m.
        poi_normal: outward surface normals, (M, 3).
        camera: field of view, range and variance coefficient k.
        boresight_body: camera boresight in body axes (unit).
        noise_frac: 1σ multiplicative noise ν of each measured precision.
        rngs: one generator per observer.
        beta: camera health per observer (fault hook), 1 = nominal.
        misalignment: boresight rotation per observer in body axes, quaternions (N, 4) scalar
            last (fault hook), identity = nominal.
        compiled: the precision by the compiled kernel (True) or the numpy reference.
    """

    poi_pos: FloatArray
    poi_normal: FloatArray
    camera: Camera
    boresight_body: FloatArray
    noise_frac: float
    rngs: Sequence[np.random.Generator]
    compiled: bool = True
    beta: FloatArray = field(init=False)
    misalignment: FloatArray = field(init=False)
    pois: PoiSet = field(init=False, repr=False, compare=False)
    """the POIs validated once, for the compiled kernel"""

    def __post_init__(self) -> None:
        m = len(self.poi_pos)
        self.poi_pos = finite_array("poi_pos", self.poi_pos, (m, 3))
        self.poi_normal = finite_array("poi_normal", self.poi_normal, (m, 3))
        self.pois = PoiSet(self.poi_pos, self.poi_normal)
        b = finite_array("boresight_body", self.boresight_body, (3,))
        if not np.linalg.norm(b) > 0.0 or not self.noise_frac >= 0.0:
            raise ValueError("need a non-zero boresight and a non-negative noise fraction")
        self.boresight_body = b / np.linalg.norm(b)
        n = len(self.rngs)
        self.beta = np.ones(n)
        self.misalignment = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))

    def boresights_lvlh(self, q_lvlh_body: npt.ArrayLike) -> FloatArray:
        """True boresight directions in LVLH (N, 3) for true attitudes body -> LVLH (N, 4)."""
        q = finite_array("q_lvlh_body", q_lvlh_body, (len(self.rngs), 4))
        cam = quat.mul(q, self.misalignment)
        out: FloatArray = quat.rotate(cam, np.broadcast_to(self.boresight_body, (len(q), 3)))
        return out

    def images(self, r_lvlh_m: npt.ArrayLike, q_lvlh_body: npt.ArrayLike) -> list[Image]:
        """One image per observer at true positions (N, 3) m and attitudes (N, 4)."""
        n = len(self.rngs)
        r = finite_array("r_lvlh_m", r_lvlh_m, (n, 3))
        bore = self.boresights_lvlh(q_lvlh_body)
        prec = (infocost_kernels.precision_on(r, bore, self.pois, self.camera) if self.compiled
                else infocost.precision(r, bore, self.poi_pos, self.poi_normal, self.camera))
        out = []
        for i in range(n):
            seen = np.flatnonzero(prec[i]).astype(np.int64)
            noise = np.maximum(0.0, 1.0 + self.noise_frac * self.rngs[i].standard_normal(len(seen)))
            out.append(Image(seen, quantise(self.beta[i] * prec[i, seen] * noise)))
        return out
