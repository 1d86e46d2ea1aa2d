"""Central orbit assignment: choose passive relative orbits (PROs) for N observers from a
candidate library by expected information gain, match them to observers, and decide when to
reassign.

Source: the hierarchical planner of the paper (/work/shared/paper.md, Sec. II.C: "the
hierarchical algorithm uses the information cost and the sensor model to select the informative
PROs"), with the information cost of Sec. II.D, Eq. 4-5 (Schwager, Julian & Rus, "information
per pixel"), evaluated by :mod:`gnc.infocost`.

Objective.  With ``w⁻¹_now(s)`` the current fused precision of POI ``s`` (prior ``w⁻¹`` plus every
observation fused so far) and ``P_c(s)`` the precision candidate PRO ``c`` is expected to add
over the planning window (:func:`expected_precision`), the gain of a set ``S`` of candidates is::

    f(S) = H(now) − H(now + Σ_{c∈S} P_c) = Σ_s φ(s) [1/w⁻¹_now(s) − 1/(w⁻¹_now(s) + A_S(s))],
    A_S = Σ_{c∈S} P_c.

Each term is ``g(A) = 1/w − 1/(w + A)`` with ``g' = 1/(w + A)² > 0`` and
``g'' = −2/(w + A)³ < 0``: since 1/x is convex and decreasing, ``g`` is concave and increasing
in ``A ≥ 0``.  A concave increasing function of a non-negative modular function (``A_S``) is
monotone and submodular, and a φ-weighted sum (φ ≥ 0) of such functions is too; ``f(∅) = 0``.
Hence greedy selection of N candidates achieves ``f(G) ≥ (1 − 1/e)·OPT`` (Nemhauser, Wolsey &
Fisher, Math. Prog. 14, 1978).  Because the a-priori factor is loose on most instances,
:func:`greedy_assignment` also returns the data-dependent online bound (Minoux 1978; Nemhauser,
Wolsey & Fisher 1978, and Krause & Golovin's survey "Submodular function maximization", 2014):
for any set G and any |S*| ≤ N, submodularity and monotonicity give::

    OPT = f(S*) ≤ f(G ∪ S*) ≤ f(G) + Σ_{e∈S*} Δ(e | G) ≤ f(G) + Σ_{top N e} Δ(e | G),

evaluated after every greedy step (every prefix G_i gives a valid bound; the smallest is kept).

Everything here is a pure function or a frozen dataclass; nothing touches a bus or a file.
Units: m, s, rad; precision in inverse variance units of :class:`gnc.infocost.Camera`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.optimize import linear_sum_assignment

from gnc.checks import finite_array
from gnc.infocost import Camera, precision
from gnc.pro import Pro, min_distance_between, min_distance_to_origin

__all__ = [
    "Assignment",
    "expected_precision",
    "gain_saturated",
    "greedy_assignment",
    "match_to_observers",
    "online_upper_bound",
    "pro_library",
    "set_gain",
]

FloatArray = npt.NDArray[np.float64]


# ----------------------------------------------------------------------------- candidates


def _finite_values(name: str, values: Sequence[float], *, non_negative: bool) -> list[float]:
    """``values`` as a non-empty list of finite floats (optionally ≥ 0)."""
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D sequence, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or infinite values")
    if non_negative and np.any(arr < 0.0):
        raise ValueError(f"{name} must be non-negative")
    return [float(v) for v in arr]


def _wrap(angle: float) -> float:
    """Wrap an angle (rad) to [-π, π)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def pro_library(
    rho_x_values_m: Sequence[float],
    rho_z_values_m: Sequence[float],
    phases_rad: Sequence[float],
    rho_y_m: float = 0.0,
    cross_phase_offsets_rad: Sequence[float] = (0.0,),
) -> list[Pro]:
    """The candidate PRO set: the Cartesian product of amplitudes, phases and phase offsets.

    Parameterisation (PRO form of REFERENCE.md / :mod:`gnc.pro`)::

        x = ρx sin(n t + αx),  y = ρy + 2 ρx cos(n t + αx),  z = ρz sin(n t + αz),
        αz = αx + offset   (wrapped to [-π, π)).

    ``αx`` (the in-plane phase at t = 0) sets where on the ellipse the observer is at a given
    time, i.e. how candidates with equal shape are spread around the target; ``offset`` sets the
    shape of the 3-D ellipse: offset 0 or π gives a planar ellipse tilted about the along-track
    axis (x and z in phase), offset ±π/2 gives parallel relative e/i vectors, whose radial-normal
    separation never vanishes (D'Amico & Montenbruck, JGCD 29(3), 2006).  The order is
    ``for ρx: for ρz: for αx: for offset`` (the last varies fastest).  Duplicate orbits (e.g.
    several offsets with ρz = 0) are not removed.

    Args:
        rho_x_values_m: radial amplitudes ρx ≥ 0, m.
        rho_z_values_m: cross-track amplitudes ρz ≥ 0, m.
        phases_rad: in-plane phases αx, rad.
        rho_y_m: along-track centre offset ρy of every candidate, m.
        cross_phase_offsets_rad: offsets αz − αx, rad.

    Raises:
        ValueError: empty, non-finite or negative-amplitude inputs.
    """
    rx = _finite_values("rho_x_values_m", rho_x_values_m, non_negative=True)
    rz = _finite_values("rho_z_values_m", rho_z_values_m, non_negative=True)
    ph = _finite_values("phases_rad", phases_rad, non_negative=False)
    off = _finite_values("cross_phase_offsets_rad", cross_phase_offsets_rad, non_negative=False)
    if not math.isfinite(rho_y_m):
        raise ValueError(f"rho_y_m must be finite, got {rho_y_m!r}")
    return [Pro(a, _wrap(p), float(rho_y_m), c, _wrap(p + o))
            for a, c, p, o in itertools.product(rx, rz, ph, off)]


# ----------------------------------------------------------------------------- precision model


def expected_precision(
    pro: Pro,
    n: float,
    t0_s: float,
    window_s: float,
    samples: int,
    poi_pos: npt.ArrayLike,
    poi_normal: npt.ArrayLike | None,
    camera: Camera,
) -> FloatArray:
    """Precision Σ σ⁻¹ (M,) an observer flying ``pro`` accumulates over [t0, t0 + window].

    Planning model: one image at each of ``samples`` times, the midpoints
    ``t_j = t0 + (j + ½)·window/samples`` (midpoint rule: a whole-orbit window has no duplicated
    phase), with the camera boresight pointed at the target centre (the LVLH origin),
    ``b = −p/|p|``.  σ⁻¹ = 1/(k d²) for visible POIs (cone, range, front-facing), else 0
    (Eq. 5, :func:`gnc.infocost.precision`).  In flight the camera app points at the
    maximum-variance visible POIs; centre pointing is the conservative nominal used to rank
    orbits, not a prediction of the exact images.  The samples are evaluated together as
    ``samples`` "observers" in one vectorised call.

    An empty window (``window_s == 0``) takes no image and returns zeros.

    Args:
        pro: the candidate orbit.
        n: chief mean motion, rad/s.
        t0_s: absolute start time of the window, s.
        window_s: window length ≥ 0, s.
        samples: number of images ≥ 1 in the window.
        poi_pos: POI positions (M, 3), m.
        poi_normal: outward POI normals (M, 3), or None (no facing test).
        camera: the camera model.

    Raises:
        ValueError: bad inputs, or an image position at the target centre (no boresight).
    """
    if not (math.isfinite(t0_s) and math.isfinite(window_s) and window_s >= 0.0):
        raise ValueError(f"need finite t0_s and window_s >= 0, got {t0_s!r}, {window_s!r}")
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 1:
        raise ValueError(f"samples must be an integer >= 1, got {samples!r}")
    m = np.shape(poi_pos)[0] if np.ndim(poi_pos) == 2 else -1
    if m < 1:
        raise ValueError(f"poi_pos must have shape (M, 3) with M >= 1, got {np.shape(poi_pos)}")
    if window_s == 0.0:
        finite_array("poi_pos", poi_pos, (m, 3))
        return np.zeros(m)
    t = t0_s + (np.arange(int(samples)) + 0.5) * (window_s / samples)
    pos = pro.states(n, t)[:, :3]
    if np.any(np.linalg.norm(pos, axis=1) <= 0.0):
        raise ValueError("the PRO passes through the target centre: no boresight to point")
    return precision(pos, -pos, poi_pos, poi_normal, camera).sum(axis=0)


# ----------------------------------------------------------------------------- gain and bounds


def _per_poi(name: str, value: npt.ArrayLike, m: int, *, positive: bool) -> FloatArray:
    """A finite scalar or (M,) array as (M,), ≥ 0 (or > 0 with ``positive``)."""
    a = np.asarray(value, dtype=float) if np.ndim(value) == 0 else finite_array(name, value, (m,))
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if np.any(a <= 0.0) if positive else np.any(a < 0.0):
        raise ValueError(f"{name} must be {'positive' if positive else 'non-negative'}")
    return np.broadcast_to(a, (m,)).astype(float)


def _precisions(value: npt.ArrayLike) -> FloatArray:
    """A finite, non-negative (K, M) precision array (K may be 0, M ≥ 1)."""
    shape = np.shape(value)
    if len(shape) != 2 or shape[1] < 1:
        raise ValueError(f"precisions must have shape (K, M) with M >= 1, got {shape}")
    a = finite_array("precisions", value, shape)
    if np.any(a < 0.0):
        raise ValueError("precisions must be non-negative")
    return a


def _gain_terms(phi: FloatArray, w: FloatArray, base: FloatArray, add: FloatArray) -> FloatArray:
    """Σ_s φ [1/(w + base) − 1/(w + base + add)] along the last axis, without cancellation.

    Uses the identity ``1/u − 1/(u + a) = a / (u (u + a))`` (u = w + base > 0, a ≥ 0).
    """
    u = w + base
    return (add / (u * (u + add))) @ phi


def set_gain(precisions: npt.ArrayLike, phi: npt.ArrayLike, w_inv_now: npt.ArrayLike) -> float:
    """Information gain ``H(now) − H(now + Σ_k precisions_k)`` of a set of K candidates.

    ``H = Σ_s φ(s)/(fused precision)`` (Eq. 4).  Monotone and submodular in the set: each term
    is a concave increasing function of the summed precision because 1/x is convex and
    decreasing (module docstring); so greedy selection is within (1 − 1/e) of the optimum
    (Nemhauser, Wolsey & Fisher 1978).

    Args:
        precisions: expected precision of each chosen candidate (K, M), ≥ 0 (K = 0 gives 0).
        phi: POI importance φ ≥ 0, scalar or (M,).
        w_inv_now: current fused precision per POI (prior w⁻¹ plus everything observed so
            far), scalar or (M,), > 0 (a POI with zero precision has infinite variance).

    Raises:
        ValueError: bad shapes, NaN/inf, negative precisions or φ, non-positive w_inv_now.
    """
    p = _precisions(precisions)
    m = p.shape[1]
    w = _per_poi("w_inv_now", w_inv_now, m, positive=True)
    return float(_gain_terms(_per_poi("phi", phi, m, positive=False), w, np.zeros(m),
                             p.sum(axis=0)))


def _marginal_gains(cand: FloatArray, acc: FloatArray, phi: FloatArray,
                    w: FloatArray) -> FloatArray:
    """Δ(c | G) (L,) of every candidate row of ``cand`` given accumulated precision ``acc``."""
    return _gain_terms(phi, w, acc[None, :], cand)


def _top_sum(values: FloatArray, count: int) -> float:
    """Sum of the ``count`` largest entries (all of them if fewer)."""
    if count >= values.size:
        return float(values.sum())
    return float(np.partition(values, values.size - count)[values.size - count:].sum())


def online_upper_bound(
    candidate_precisions: npt.ArrayLike,
    chosen: Sequence[int],
    n_observers: int,
    phi: npt.ArrayLike,
    w_inv_now: npt.ArrayLike,
) -> float:
    """Data-dependent bound ``OPT ≤ f(G) + Σ_{top N} Δ(e | G)`` for the set G = ``chosen``.

    Valid for every G and for the optimum over all sets of at most N candidates of the library
    (hence also for any constrained optimum over a sub-family of them); see the module
    docstring for the two-line proof (Minoux 1978; Nemhauser, Wolsey & Fisher 1978).

    Args:
        candidate_precisions: expected precision of every candidate (L, M).
        chosen: indices of G into the library rows.
        n_observers: N ≥ 1.
        phi, w_inv_now: as in :func:`set_gain`.
    """
    cand = _precisions(candidate_precisions)
    m = cand.shape[1]
    idx = _indices(chosen, cand.shape[0])
    if isinstance(n_observers, bool) or not isinstance(n_observers, (int, np.integer)) \
            or n_observers < 1:
        raise ValueError(f"n_observers must be an integer >= 1, got {n_observers!r}")
    w = _per_poi("w_inv_now", w_inv_now, m, positive=True)
    weights = _per_poi("phi", phi, m, positive=False)
    acc = cand[idx].sum(axis=0)
    base = float(_gain_terms(weights, w, np.zeros(m), acc))
    return base + _top_sum(_marginal_gains(cand, acc, weights, w), int(n_observers))


def _indices(chosen: Sequence[int], size: int) -> list[int]:
    """Validated distinct indices into ``range(size)``."""
    idx = [int(i) for i in chosen]
    if any(i < 0 or i >= size for i in idx) or len(set(idx)) != len(idx):
        raise ValueError(f"chosen must be distinct indices in [0, {size}), got {list(chosen)!r}")
    return idx


# ----------------------------------------------------------------------------- greedy


@dataclass(frozen=True)
class Assignment:
    """Result of :func:`greedy_assignment`.

    Attributes:
        indices: chosen library indices, in pick order.
        pros: the chosen PROs, same order.
        gain: f(chosen), information-cost units (H(now) − H(after the window)).
        marginal_gains: Δ of each pick given the earlier picks (they sum to ``gain``).
        upper_bound: online bound on the optimum over N-sets of keep-out-admissible candidates
            (min over greedy prefixes G_i of f(G_i) + Σ_{top N} Δ(e | G_i)); it also bounds the
            separation-constrained optimum.
        ratio_bound: gain / upper_bound ≤ gain / OPT (1.0 when upper_bound = 0: nothing can be
            gained, every choice is optimal).
        separation_active: True when the separation rule made some pick differ from the
            unconstrained greedy pick; when False the picks are the unconstrained greedy ones
            and ``gain ≥ (1 − 1/e)·OPT`` holds a priori.
    """

    indices: tuple[int, ...]
    pros: tuple[Pro, ...]
    gain: float
    marginal_gains: tuple[float, ...]
    upper_bound: float
    ratio_bound: float
    separation_active: bool


def greedy_assignment(
    library: Sequence[Pro],
    n_observers: int,
    n: float,
    t0_s: float,
    window_s: float,
    samples: int,
    poi_pos: npt.ArrayLike,
    poi_normal: npt.ArrayLike | None,
    phi: npt.ArrayLike,
    w_inv_now: npt.ArrayLike,
    camera: Camera,
    min_separation_m: float = 5.0,
    keep_out_m: float = 8.0,
) -> Assignment:
    """Choose N PROs from ``library`` greedily by marginal expected information gain.

    1. Candidates whose minimum distance to the target centre over an orbit
       (:func:`gnc.pro.min_distance_to_origin`) is below ``keep_out_m`` are excluded.
    2. Each admissible candidate's expected precision over [t0, t0 + window] is computed once
       (:func:`expected_precision`).
    3. N times: pick the candidate with the largest marginal gain Δ(c | G) (ties: lowest index)
       among those whose minimum distance to every PRO already chosen
       (:func:`gnc.pro.min_distance_between`, over one period) is at least
       ``min_separation_m``; candidates too close are skipped (collision safety).

    Guarantees.  Without the separation rule (or when it never changes a pick,
    ``separation_active`` False) this is the standard greedy for a monotone submodular function
    under a cardinality constraint: ``gain ≥ (1 − 1/e)·OPT`` (Nemhauser, Wolsey & Fisher 1978).
    With it the feasible sets form an independence system (subsets of a feasible set are
    feasible) rather than a matroid, and the a-priori factor degrades to 1/(1 + q) with q its
    rank quotient (Fisher, Nemhauser & Wolsey, Math. Prog. Study 8, 1978); no a-priori factor
    is claimed here.  The online bound ``upper_bound`` stays valid in both cases (it bounds the
    larger unconstrained optimum), so ``ratio_bound`` is a certified lower bound on gain/OPT.

    Args:
        library: candidate PROs.
        n_observers: N ≥ 1.
        n: chief mean motion, rad/s.
        t0_s, window_s, samples, poi_pos, poi_normal, camera: as in :func:`expected_precision`.
        phi, w_inv_now: as in :func:`set_gain`.
        min_separation_m: minimum distance between any two chosen PROs, m (≥ 0).
        keep_out_m: keep-out radius about the target centre, m (≥ 0; default as the scenario's
            guidance keep-out).

    Raises:
        ValueError: bad inputs, or fewer than N candidates satisfy keep-out and separation.
    """
    if isinstance(n_observers, bool) or not isinstance(n_observers, (int, np.integer)) \
            or n_observers < 1:
        raise ValueError(f"n_observers must be an integer >= 1, got {n_observers!r}")
    for name, v in (("min_separation_m", min_separation_m), ("keep_out_m", keep_out_m)):
        if not (math.isfinite(v) and v >= 0.0):
            raise ValueError(f"{name} must be finite and >= 0, got {v!r}")
    lib = list(library)
    if not lib or not all(isinstance(p, Pro) for p in lib):
        raise ValueError("library must be a non-empty sequence of Pro")
    admissible = [i for i, p in enumerate(lib) if min_distance_to_origin(p, n)[0] >= keep_out_m]
    if len(admissible) < n_observers:
        raise ValueError(f"only {len(admissible)} candidates clear the {keep_out_m} m keep-out; "
                         f"{n_observers} needed")
    cand = np.array([expected_precision(lib[i], n, t0_s, window_s, samples, poi_pos, poi_normal,
                                        camera) for i in admissible])
    m = cand.shape[1]
    w = _per_poi("w_inv_now", w_inv_now, m, positive=True)
    weights = _per_poi("phi", phi, m, positive=False)

    acc = np.zeros(m)
    gain = 0.0
    upper = math.inf
    picks: list[int] = []  # positions into ``admissible``
    marginals: list[float] = []
    blocked = np.zeros(len(admissible), dtype=bool)
    active = False
    for _ in range(n_observers):
        delta = _marginal_gains(cand, acc, weights, w)
        upper = min(upper, gain + _top_sum(delta, n_observers))
        free = ~blocked
        free[picks] = False
        feasible = np.flatnonzero(free)
        if feasible.size == 0:
            raise ValueError(f"only {len(picks)} candidates satisfy the {min_separation_m} m "
                             f"separation; {n_observers} needed")
        best = int(feasible[np.argmax(delta[feasible])])
        unconstrained = [j for j in range(len(admissible)) if j not in picks]
        if delta[best] < delta[unconstrained].max():
            active = True
        picks.append(best)
        marginals.append(float(delta[best]))
        acc = acc + cand[best]
        gain += float(delta[best])
        if min_separation_m > 0.0:
            for j in np.flatnonzero(free):
                if j != best and min_distance_between(lib[admissible[j]], lib[admissible[best]],
                                                      n)[0] < min_separation_m:
                    blocked[j] = True
    delta = _marginal_gains(cand, acc, weights, w)
    upper = min(upper, gain + _top_sum(delta, n_observers))
    gain = float(_gain_terms(weights, w, np.zeros(m), acc))
    upper = max(upper, gain)  # guard rounding: the bound is never below the achieved value
    chosen = tuple(admissible[j] for j in picks)
    return Assignment(
        indices=chosen,
        pros=tuple(lib[i] for i in chosen),
        gain=gain,
        marginal_gains=tuple(marginals),
        upper_bound=upper,
        ratio_bound=gain / upper if upper > 0.0 else 1.0,
        separation_active=active,
    )


# ----------------------------------------------------------------------------- matching, trigger


def match_to_observers(current_states: npt.ArrayLike, pros: Sequence[Pro], n: float,
                       t_s: float) -> list[int]:
    """Assign the chosen PROs to observers minimising the total position distance at ``t_s``.

    Cost of observer i taking PRO j: ``|r_i(t) − r_j(t)|`` (m), the distance from the
    observer's current position to where PRO j's slot is at time t.  It is a proxy for transfer
    fuel: for fixed transfer time the HCW Δv of a two-impulse transfer grows linearly with the
    position offset (velocity mismatch is ignored).  Solved exactly with the Hungarian method
    (scipy.optimize.linear_sum_assignment).

    Args:
        current_states: observers' HCW states (N, 6), m and m/s.
        pros: the chosen PROs, at least N of them (each observer gets a distinct one).
        n: chief mean motion, rad/s.
        t_s: absolute time of the states, s.

    Returns:
        ``result[i]`` = index into ``pros`` of observer i's PRO.

    Raises:
        ValueError: bad shapes/values, or fewer PROs than observers.
    """
    shape = np.shape(current_states)
    if len(shape) != 2 or shape[0] < 1 or shape[1] != 6:
        raise ValueError(f"current_states must have shape (N, 6), got {shape}")
    states = finite_array("current_states", current_states, shape)
    targets = list(pros)
    if len(targets) < shape[0]:
        raise ValueError(f"{len(targets)} PROs for {shape[0]} observers")
    if not math.isfinite(t_s):
        raise ValueError(f"t_s must be finite, got {t_s!r}")
    slots = np.array([p.states(n, t_s)[0, :3] for p in targets])
    cost = np.linalg.norm(states[:, None, :3] - slots[None, :, :], axis=2)
    rows, cols = linear_sum_assignment(cost)
    result = [0] * shape[0]
    for r, c in zip(rows, cols, strict=True):
        result[int(r)] = int(c)
    return result


def gain_saturated(recent_gains: Sequence[float], threshold_fraction: float) -> bool:
    """Reassignment trigger: has the current PRO set stopped paying?

    ``recent_gains`` holds the information gained (H decrease) in each window since the set was
    assigned, oldest first.  Rule: saturated when the last window's gain fell below
    ``threshold_fraction`` times the first window's gain, i.e. ``g[-1] < f·g[0]`` (needs at
    least two windows).  The first window of a fresh set is its best in expectation (gains of a
    fixed set diminish as its POIs' variance falls, by submodularity), so the ratio measures
    how much of the set's value is left.  A set whose first window gained nothing (g[0] ≤ 0)
    is saturated at once.  No windows yet: not saturated.

    Args:
        recent_gains: per-window gains, information-cost units, finite.
        threshold_fraction: f in (0, 1).

    Raises:
        ValueError: non-finite gains or a fraction outside (0, 1).
    """
    if not (math.isfinite(threshold_fraction) and 0.0 < threshold_fraction < 1.0):
        raise ValueError(f"threshold_fraction must be in (0, 1), got {threshold_fraction!r}")
    g = np.asarray(recent_gains, dtype=float).ravel()
    if not np.all(np.isfinite(g)):
        raise ValueError("recent_gains contains NaN or infinite values")
    if g.size == 0:
        return False
    if g[0] <= 0.0:
        return True
    return bool(g.size >= 2 and g[-1] < threshold_fraction * g[0])
