"""The nominal twin of one observer (the ground's FDIR and the neighbours' judge fly it): where the
plan puts it, where its camera points, and the information its images should bring
(docs/fdir.md: H_i^pred over [t − Δt, t] from the plan and the fused state at t − Δt).

Information change with ψ held at the window start.  With F the fused precision and
ψ = H_POI(t − Δt)² (Eq. 8) frozen over the window, agent i's contribution changes by::

    ΔH_i = Σ_s φ(s) ψ(s) ΔF_i(s),

linear in its own new precision ΔF_i — the linearisation under which the paper's ratios are
exact (r_i = β for a camera fault, Eq. 21) and faults isolate to one agent (Sec. III.F: with ψ
recomputed, one agent's loss also rescales the others' contributions).  The twin compares
like with like: the prediction covers exactly the images whose observations reached the ground,
so a lost packet removes an image from both sides and never reads as zero information gain.

Pure functions and frozen dataclasses; the FDIR app holds the state.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from gnc.hcw import zoh_matrices
from gnc.infocost import Camera, PoiSet
from gnc.infocost_kernels import precision_on
from gnc.pro import Pro
from interfaces.contracts.messages import ProAssignment

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]


@dataclass(frozen=True)
class Transfer:
    """A planned transfer as published by the spacecraft (``TransferPlanMsg``): node times
    (s, mission time), node states (N+1, 6) and ZOH accelerations (N, 3), LVLH."""

    t_s: FloatArray
    x: FloatArray
    u: FloatArray


@dataclass(frozen=True)
class FlightPlan:
    """What an observer is expected to fly from ``t_from_s``: the PRO ``pro`` (from the ground's
    assignment), preceded by ``transfer`` where one is planned."""

    t_from_s: float
    pro: Pro
    transfer: Transfer | None = None
    t_arrive_s: float | None = None
    """end of the transfer the assignment asks for (None: no transfer)"""

    @classmethod
    def of(cls, assignment: ProAssignment, from_s: float | None = None,
           transfer: Transfer | None = None) -> FlightPlan:
        """The plan of an uplinked ``assignment``, in force from ``from_s`` (s; default its
        departure), with the ``transfer`` published for it if any."""
        a = assignment
        return cls(a.t_depart_s if from_s is None else from_s, Pro.of(a.pro), transfer,
                   a.t_arrive_s if a.t_arrive_s > a.t_depart_s else None)

    @property
    def starts_s(self) -> float:
        """When the observer leaves its previous plan for this one: the first node of the
        transfer it published (it may start later than asked, e.g. after an outage), else
        ``t_from_s``."""
        return float(self.transfer.t_s[0]) if self.transfer is not None else self.t_from_s

    @property
    def holds_from_s(self) -> float:
        """When the observer is on its PRO: the end of the transfer it published, else the
        arrival the assignment asks for, else ``t_from_s``."""
        if self.transfer is not None:
            return float(self.transfer.t_s[-1])
        return self.t_arrive_s if self.t_arrive_s is not None else self.t_from_s

    def known(self, t: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        """Whether the plan says where the observer is at each time ``t``: not between the
        departure and the arrival of a transfer whose plan has not been received (a lost
        ``TransferPlanMsg``: the path is the spacecraft's own choice)."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        if self.transfer is not None or self.t_arrive_s is None:
            return np.ones(tt.shape, dtype=bool)
        return ~((tt >= self.t_from_s) & (tt < self.t_arrive_s))

    def on_transfer(self, t: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        """Whether each absolute time ``t`` (s) falls on the planned transfer."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        if self.transfer is None:
            return np.zeros(tt.shape, dtype=bool)
        return (tt >= self.transfer.t_s[0]) & (tt < self.transfer.t_s[-1])

    def positions(self, n: float, t: npt.ArrayLike) -> FloatArray:
        """Planned LVLH positions (K, 3), m, at absolute times ``t`` (K,): on the transfer
        between its first and last node (exact ZOH propagation from the preceding node), on the
        PRO otherwise."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        out = self.pro.states(n, tt)[:, :3]
        tr = self.transfer
        if tr is None:
            return out
        inside = self.on_transfer(tt)
        if inside.any():
            k = np.minimum(np.maximum(np.searchsorted(tr.t_s, tt[inside], side="right") - 1, 0),
                           len(tr.u) - 1)
            phi, gam = zoh_matrices(n, tt[inside] - tr.t_s[k])
            x = np.einsum("tij,tj->ti", phi, tr.x[k]) + np.einsum("tij,tj->ti", gam, tr.u[k])
            out[inside] = x[:, :3]
        return out


def plans_in_force(plans: Iterable[FlightPlan], times: npt.ArrayLike
                   ) -> tuple[list[FlightPlan], IntArray]:
    """The plan in force at each of ``times`` (s): ``plans`` in the order they take over
    (``FlightPlan.starts_s``; of two starting together, the later given takes over), and at
    each time the index of the last to have started by it (−1 before the first)."""
    ordered = sorted(plans, key=lambda p: p.starts_s)
    starts = np.array([p.starts_s for p in ordered])
    return ordered, np.searchsorted(starts, times, side="right") - 1


def held_over(plans: Iterable[FlightPlan], a: float, b: float) -> FlightPlan | None:
    """The plan whose PRO the observer holds over all of [a, b) (s): the one in force at a
    (:func:`plans_in_force`), none taking over within the window, its transfer over by a.
    None without a plan in force, or when a transfer or a change of plan falls in [a, b)."""
    ordered, which = plans_in_force(plans, np.array([a]))
    if which[0] < 0 or any(a < p.starts_s < b for p in ordered):
        return None
    plan = ordered[int(which[0])]
    return plan if plan.holds_from_s <= a else None


def centre_boresights(positions: npt.ArrayLike) -> FloatArray:
    """Unit boresights (K, 3) from each position to the target centre (the default pointing)."""
    p = np.asarray(positions, dtype=float)
    norm = np.linalg.norm(p, axis=1, keepdims=True)
    if np.any(norm <= 0.0):
        raise ValueError("a planned position is at the target centre: no boresight")
    return -p / norm


def delta_h(psi: npt.ArrayLike, phi: npt.ArrayLike, new_precision: npt.ArrayLike) -> float:
    """ΔH_i = Σ_s φ ψ ΔF_i with ψ held at the window start; ``new_precision`` (K, M) or (M,):
    the precision of the window's images (summed over images)."""
    p = np.asarray(new_precision, dtype=float)
    total = p.sum(axis=0) if p.ndim == 2 else p
    return float(total @ (np.asarray(phi, dtype=float) * np.asarray(psi, dtype=float)))


def predicted_delta_h(positions: npt.ArrayLike, boresights: npt.ArrayLike,
                      poi_pos: npt.ArrayLike, poi_normal: npt.ArrayLike | None, camera: Camera,
                      psi: npt.ArrayLike, phi: npt.ArrayLike) -> float:
    """ΔH_i^pred of images taken at ``positions`` (K, 3) along ``boresights`` (K, 3) with the
    nominal camera (β = 1, no noise)."""
    return predicted_on(positions, boresights, PoiSet(poi_pos, poi_normal),  # type: ignore[arg-type]
                        camera, psi, phi)


def predicted_on(positions: npt.ArrayLike, boresights: npt.ArrayLike, pois: PoiSet,
                 camera: Camera, psi: npt.ArrayLike, phi: npt.ArrayLike) -> float:
    """:func:`predicted_delta_h` of POIs validated once (``pois``)."""
    if np.shape(positions)[0] == 0:
        return 0.0
    return delta_h(psi, phi, precision_on(positions, boresights, pois, camera))


def perturbed_boresights(boresight: npt.ArrayLike, eps_rad: float, count: int,
                         rng: np.random.Generator, draws: int = 1) -> FloatArray:
    """Unit directions drawn uniformly (in solid angle) within ``eps_rad`` of a boresight: the
    ε-neighbourhood pointings of the adaptive threshold (Eq. 11).  ``boresight`` (3,) gives
    ``count`` draws about it; (K, 3) gives one draw about each row (``count`` must be K).
    ``draws`` > 1 repeats that ``draws`` times, stacked (draws·count, 3): the same directions,
    bit for bit, as that many calls one after the other on ``rng``."""
    b = np.atleast_2d(np.asarray(boresight, dtype=float))
    b = b / np.linalg.norm(b, axis=1, keepdims=True)
    if b.shape[0] == 1:
        b = np.repeat(b, count, axis=0)
    elif b.shape[0] != count:
        raise ValueError(f"{b.shape[0]} boresights for {count} draws")
    if not (math.isfinite(eps_rad) and 0.0 < eps_rad < math.pi / 2):
        raise ValueError(f"eps_rad must be in (0, pi/2), got {eps_rad!r}")
    if draws < 1:
        raise ValueError(f"draws must be at least 1, got {draws!r}")
    uniform = [(rng.random(count), rng.random(count)) for _ in range(draws)]  # a call's order
    cos_t = 1.0 - np.concatenate([u for u, _ in uniform]) * (1.0 - math.cos(eps_rad))
    sin_t = np.sqrt(1.0 - cos_t**2)
    az = np.concatenate([v for _, v in uniform]) * 2.0 * math.pi
    helper = np.where((np.abs(b[:, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    e1 = np.cross(b, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(b, e1)
    b, e1, e2 = (np.tile(v, (draws, 1)) for v in (b, e1, e2))
    return (cos_t[:, None] * b + sin_t[:, None] * (np.cos(az)[:, None] * e1
                                                  + np.sin(az)[:, None] * e2))


@dataclass(frozen=True)
class TwinModel:
    """What the twin knows of the target and the cameras: the POIs (positions and outward
    normals, LVLH, m), the target radius (m), the nominal camera model and the 1σ
    multiplicative noise ν of a measured precision (``[camera] noise_frac``)."""

    poi_pos: FloatArray
    poi_normal: FloatArray
    camera: Camera
    radius_m: float
    noise_frac: float = 0.0
    pois: PoiSet = field(init=False, repr=False, compare=False)
    """the POIs validated once (the twin images them thousands of times a window)"""

    def __post_init__(self) -> None:
        object.__setattr__(self, "pois", PoiSet(self.poi_pos, self.poi_normal))

    def precision(self, positions: npt.ArrayLike, boresights: npt.ArrayLike) -> FloatArray:
        """σ⁻¹ (K, M) of nominal images taken from ``positions`` along ``boresights``."""
        return precision_on(positions, boresights, self.pois, self.camera)

    def predicted(self, positions: npt.ArrayLike, boresights: npt.ArrayLike,
                  psi: npt.ArrayLike, phi: npt.ArrayLike) -> float:
        """ΔH_i^pred of images taken from ``positions`` along ``boresights``
        (:func:`predicted_delta_h`)."""
        return predicted_on(positions, boresights, self.pois, self.camera, psi, phi)

    def predicted_each(self, positions: npt.ArrayLike, boresights: Sequence[FloatArray],
                       psi: npt.ArrayLike, phi: npt.ArrayLike) -> list[float]:
        """:meth:`predicted` of the images taken from ``positions`` (K, 3) along each set of
        ``boresights`` (each (K, 3)), imaged together: as many sets a call as
        ``IMAGED_BYTES`` of precisions hold."""
        pos = np.asarray(positions, dtype=float)
        if pos.shape[0] == 0:
            return [0.0] * len(boresights)
        step = max(1, IMAGED_BYTES // (8 * pos.shape[0] * len(self.pois.pos)))
        out: list[float] = []
        for i in range(0, len(boresights), step):
            part = boresights[i:i + step]
            prec = self.precision(np.tile(pos, (len(part), 1)), np.concatenate(part))
            out += [delta_h(psi, phi, block) for block in np.split(prec, len(part))]
        return out


IMAGED_BYTES = 16 * 2**20
"""The most precisions (bytes) :meth:`TwinModel.predicted_each` makes at once: the default
threshold's 10 draws of 20 images of 5,000 POIs (8 MB) in one call, 1,000 draws of 200,000
POIs not all at once."""


SAMPLED_IMAGES = 20
"""The costlier twin runs (threshold samples, seen-set overlap) use at most this many of a
window's images, evenly spread."""


def sample_stride(images: int, at_most: int = SAMPLED_IMAGES) -> int:
    """Every k-th image, so that at most ``at_most`` of them are used."""
    return max(1, math.ceil(images / at_most))


def planned_boresights(attitude: FloatArray | None, positions: FloatArray) -> FloatArray:
    """The twin's pointing: from each planned position to the aim point the observer reports
    (``attitude`` rows: reported boresight (3), pointing error, aim point (3) LVLH m; its camera
    policy's choice: the target centre by default, the max-variance POI with
    ``[camera] pointing = "max_variance"``), or to the target centre when the attitude reports
    are missing.  A pointing or camera fault leaves the aim as intended, so it still shows
    against this prediction."""
    if attitude is None:
        return centre_boresights(positions)
    return aimed_boresights(attitude[:, 4:7], positions)


def aimed_boresights(aims: FloatArray, positions: FloatArray) -> FloatArray:
    """Unit boresights from each position (K, 3) to its aim point (K, 3), LVLH m; to the
    target centre where an aim point coincides with its position."""
    los = aims - positions
    norm = np.linalg.norm(los, axis=1, keepdims=True)
    if np.any(norm <= 0.0):
        return centre_boresights(positions)
    return los / norm
