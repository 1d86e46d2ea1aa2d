"""The FDIR's knowledge of one observer between windows (docs/fdir.md "Information cost and
FDIR"): its plans, reported attitude modes, nav and attitude series, guidance reports, silence
and observation-loss counts -- the state the FDIR app keeps per observer, as plain code that
tests call directly.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np
from scipy.special import betainc

from gnc.interpolate import columns_at
from gnc.twin import FlightPlan, plans_in_force


class TimeSeries:
    """A time series of vectors reported by an observer (nav position, attitude), sampled at
    any time by linear interpolation (held at the ends for at most ``MAX_GAP_S``)."""

    MAX_GAP_S = 5.0
    """A time farther than this from every sample has no value (stale telemetry), s."""

    def __init__(self) -> None:
        self.t: list[float] = []
        self.v: list[np.ndarray] = []
        self._arrays: tuple[np.ndarray, np.ndarray, int] | None = None
        """``t`` (capacity,) and ``v`` by column (d, capacity) as arrays, of which the first
        (count) hold the samples: extended in place by a sample after the last (the usual
        case: reports come in time order), made afresh at the first read after any other
        change."""

    def add(self, t: float, value: np.ndarray) -> None:
        """A sample ``value`` (d,) at time ``t`` (s), in time order among the others."""
        i = bisect.bisect_right(self.t, t)
        self.t.insert(i, t)
        self.v.insert(i, value)
        if self._arrays is not None and i == self._arrays[2] == len(self.t) - 1:
            self._append(t, value)
        else:
            self._arrays = None

    def _append(self, t: float, value: np.ndarray) -> None:
        """Extend the arrays (made: ``_arrays``) by a last sample (their capacity doubled
        when full)."""
        if self._arrays is None:
            return
        times, columns, count = self._arrays
        if np.shape(value) != columns.shape[:1]:
            self._arrays = None
            return
        if count == len(times):
            times = np.resize(times, 2 * count + 8)
            grown = np.empty((columns.shape[0], len(times)))
            grown[:, :count] = columns[:, :count]
            columns = grown
        times[count] = t
        columns[:, count] = value
        self._arrays = times, columns, count + 1

    def _current(self) -> tuple[np.ndarray, np.ndarray]:
        """The sample times (N,) and values by column (d, N)."""
        if self._arrays is None or self._arrays[2] != len(self.t):
            self._arrays = (np.array(self.t, dtype=float), np.array(self.v, dtype=float).T.copy(),
                            len(self.t))
        times, columns, count = self._arrays
        return times[:count], columns[:, :count]

    def at(self, times: np.ndarray) -> np.ndarray | None:
        """Values (K, d) at ``times`` (K,), or None unless every time is within ``MAX_GAP_S``
        of a sample."""
        values = self.at_each(times)
        return None if values is None or np.isnan(values).any() else values

    def at_each(self, times: np.ndarray) -> np.ndarray | None:
        """Values (K, d) at ``times`` (K,), NaN at a time farther than ``MAX_GAP_S`` from
        every sample; None without any sample."""
        if not self.t:
            return None
        t, columns = self._current()
        return columns_at(np.ascontiguousarray(times, dtype=float), t, columns, self.MAX_GAP_S)

    def forget_before(self, t: float) -> None:
        """Drop samples no later window needs (keep the last one before t)."""
        i = max(bisect.bisect_left(self.t, t) - 1, 0)
        if i:
            del self.t[:i], self.v[:i]
            self._arrays = None


@dataclass
class ObserverState:
    """The FDIR's knowledge of one observer: its plans (by assignment id), the times its
    attitude mode changed (as reported), and its silence count."""

    plans: dict[int, FlightPlan] = field(default_factory=dict)
    refused: set[int] = field(default_factory=set)
    """assignments it refused (``TransferPlanMsg.refused``): it keeps the plan before"""
    modes: list[tuple[float, str]] = field(default_factory=list)
    nav: TimeSeries = field(default_factory=TimeSeries)
    """reported position (nav estimate), LVLH m"""
    nav_sigma: TimeSeries = field(default_factory=TimeSeries)
    """the nav's reported position 1σ per axis, √(tr P_rr / 3), m"""
    attitude: TimeSeries = field(default_factory=TimeSeries)
    """reported camera boresight (LVLH, 3), pointing error (rad), aim point (LVLH, 3, m) and
    attitude knowledge 1σ (rad)"""
    guidance: list[tuple[float, float, bool]] = field(default_factory=list)
    """reported (time s, Δv commanded so far m/s, holding its PRO), in time order"""
    nis: list[tuple[float, float]] = field(default_factory=list)
    """the nav's reported (time s, NIS of that step's measurement update), in arrival order"""
    _on_grid: tuple[tuple[FlightPlan, ...], np.ndarray, tuple[np.ndarray, np.ndarray,
                                                               np.ndarray] | None] | None = \
        field(default=None, repr=False, compare=False)
    """the plans, a grid of times and :meth:`planned` over it (``planned_on``)"""
    camera_off_s: float | None = None
    """when its onboard FDIR turned its camera off (s; None: on): no image is expected since"""
    silent: int = 0
    link_declared: bool = False
    last_image_s: float | None = None
    """when it sent its last image of a judged window while imaging and in reach (the
    message's time, s; None: none since it was last out of reach or off): a silence
    straddling windows is measured from it"""
    overflow: list[tuple[float, float]] = field(default_factory=list)
    """send times (first, last; s) of its FDIR reports its onboard store lost (ground passes)"""
    overflow_declared: bool = False
    overflow_observations: int = 0
    """its observations its onboard store lost to overflow (ground passes), since the start"""
    aboard_since_s: float | None = None
    """send time of its oldest report the ground FDIR judges still aboard (ground passes;
    None: none aboard), from its store's accounting as it came down with its dump"""
    aboard_pass: int = -1
    """index of the contact in which that accounting came down"""
    dumped_seen: int = 0
    """messages its store had dumped when the ground last took its accounting"""
    resync: bool = False
    """the next judged window numbers its observations afresh (the store lost some before)"""
    heard_s: float = -math.inf
    """send time of the newest nav, attitude or image report received (s): with ground
    passes, everything the FDIR judges sent before it is in (the dump keeps send order)"""
    fresh: bool = False
    """a report came in since the FDIR last looked (``FdirPipeline.due``)"""
    heard_pass: int = -1
    """index of the latest contact in which its reports came in (ground passes)"""
    last_seq: int = 0
    """last observation sequence number judged (the Bus numbers from 1)"""
    received: int = 0
    lost: int = 0
    """observations received and missing (sequence gaps) since the start"""
    dump_start: tuple[float, int, int] | None = None
    """(time s, messages dumped, sent again) of its store when the dump window being counted
    began (ground passes; None: not yet seen)"""
    dump_declared: bool = False
    """its dump's loss was declared a link fault, and no healthy dump window came since"""
    lossy: bool = False
    """its latest judged window lost more of its observations than its link's nominal loss
    explains (``link_checks.LOSSY_TAIL``), or all of them: the loss is not spread over the run"""

    def overflowed(self, a: float, b: float) -> bool:
        """Whether its store lost FDIR reports sent in the window [a, b) (s)."""
        return any(first < b and a <= last for first, last in self.overflow)

    def aboard_before(self, b: float) -> bool:
        """Whether reports it sent before ``b`` (s) are still aboard (ground passes): a window
        ending at b is then judged on part of its data.  The store's accounting comes with the
        ground's link counters, once a cycle; a report sent at or after b that came down says
        more recently that all before it did (its topics come down in send order)."""
        return (self.aboard_since_s is not None and self.aboard_since_s < b
                and self.heard_s < b)

    def heard(self, t_s: float) -> None:
        """A nav, attitude or image report sent at ``t_s`` (s) came in."""
        self.heard_s, self.fresh = max(self.heard_s, t_s), True

    def count_observations(self, seqs: list[int]) -> int:
        """Count a window's received observations (their sequence numbers, sorted) and those
        missing between them and the last judged; returns the number missing."""
        lost = max(seqs[-1] - self.last_seq - len(seqs), 0)
        self.last_seq = max(seqs[-1], self.last_seq)
        self.received += len(seqs)
        self.lost += lost
        return lost

    def lost_fraction(self) -> float:
        """Share of its observations that never reached the ground, since the start: lost on
        the link (sequence gaps) or to its store's overflow."""
        missing = self.lost + self.overflow_observations
        total = self.received + missing
        return missing / total if total else 0.0

    def camera_off_before(self, b: float) -> bool:
        """Whether its camera was turned off onboard before the window ending at b (s): such a
        window is judged neither for silence nor for information."""
        return self.camera_off_s is not None and self.camera_off_s < b

    def nis_between(self, a: float, b: float) -> list[float]:
        """The NIS of the nav updates in [a, b)."""
        return [v for t, v in self.nis if a <= t < b]

    def forget_before(self, t: float) -> None:
        """Drop every report no window from ``t`` on needs."""
        self.forget_modes_before(t)
        self.nav.forget_before(t)
        self.nav_sigma.forget_before(t)
        self.attitude.forget_before(t)
        self.forget_guidance_before(t)
        self.nis = [(s, v) for s, v in self.nis if s >= t]

    def forget_modes_before(self, t: float) -> None:
        """Drop mode changes no later window needs (keep the one in force at t)."""
        i = bisect.bisect_right(self.modes, (t, "~")) - 1
        del self.modes[:max(i, 0)]

    def tracking_at(self, t: float, settle_s: float) -> bool:
        """Whether the last reported attitude mode at or before t is ``track``, entered at
        least ``settle_s`` before t (the loop's transient after a slew is not predicted)."""
        i = bisect.bisect_right(self.modes, (t, "~")) - 1
        return i >= 0 and self.modes[i][1] == "track" and self.modes[i][0] <= t - settle_s

    def dv_rate(self, a: float, b: float) -> float | None:
        """Commanded Δv per second (m/s²) over the parts of [a, b] between two consecutive
        guidance reports that both say ``hold``; None without any."""
        rep = [g for g in self.guidance if a <= g[0] <= b]
        pairs = [(g0, g1) for g0, g1 in pairwise(rep) if g0[2] and g1[2] and g1[0] > g0[0]]
        if not pairs:
            return None
        return (sum(g1[1] - g0[1] for g0, g1 in pairs)
                / sum(g1[0] - g0[0] for g0, g1 in pairs))

    def forget_guidance_before(self, t: float) -> None:
        """Drop guidance reports no later window needs (keep the last one before t)."""
        i = bisect.bisect_left(self.guidance, (t,)) - 1
        del self.guidance[:max(i, 0)]

    def planned(self, n: float, times: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Planned positions (K, 3) at the image ``times`` (K,), whether each falls on a
        transfer, and whether the plan knows the path there (``FlightPlan.known``), every time
        under the plan in force at it (``gnc.twin.plans_in_force``: a window may straddle a
        departure); None when a time precedes every plan."""
        plans, which = plans_in_force(self.plans.values(), times)
        if not plans or np.any(which < 0):
            return None
        pos = np.empty((len(times), 3))
        moving = np.zeros(len(times), dtype=bool)
        known = np.ones(len(times), dtype=bool)
        for k in np.unique(which):
            sel = which == k
            pos[sel] = plans[k].positions(n, times[sel])
            moving[sel] = plans[k].on_transfer(times[sel])
            known[sel] = plans[k].known(times[sel])
        return pos, moving, known

    def planned_on(self, n: float, times: np.ndarray, grid: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """:meth:`planned` at ``times`` (K,), taken from the plans evaluated once over
        ``grid`` (s, ascending: a window's image times) when every time is one of the grid's,
        else evaluated at the times themselves: the same bits either way (a time's planned
        position does not depend on the times evaluated with it: ``gnc.hcw``'s one-time and
        stacked paths are one arithmetic).  The plans' evaluation is kept until the plans or
        the grid change."""
        plans = tuple(self.plans.values())
        held = self._on_grid
        if (held is None or held[1] is not grid or len(held[0]) != len(plans)
                or any(a is not b for a, b in zip(held[0], plans, strict=True))):
            held = self._on_grid = (plans, grid, self.planned(n, grid))
        full = held[2]
        at = np.searchsorted(grid, times)
        if full is None or not len(grid) or at.max(initial=0) >= len(grid) \
                or not np.array_equal(grid[at], times):
            return self.planned(n, times)
        pos, moving, known = full
        return pos[at], moving[at], known[at]

    def plan_at(self, t: float) -> FlightPlan | None:
        valid = [p for p in self.plans.values() if p.t_from_s <= t]
        return max(valid, key=lambda p: p.t_from_s) if valid else None


def loss_limit(packet_loss: float, burst_packets: float, loss_tol: float, sent: int) -> float:
    """Lost share of a window's ``sent`` observations beyond which the link is faulty: the
    nominal loss p (``comms.packet_loss``) plus ``fdir.loss_tol`` plus two standard deviations
    of the window's loss share, √(p(1−p)(2L−1)/n) for Gilbert-Elliott bursts of mean length L
    (2L − 1: the variance inflation of a two-state Markov loss process with rare bursts; L = 1
    is Bernoulli)."""
    p = packet_loss
    spread = math.sqrt(p * (1.0 - p) * (2.0 * burst_packets - 1.0) / max(sent, 1))
    return min(1.0, p + loss_tol + 2.0 * spread)


def loss_tail(lost: int, sent: int, packet_loss: float, burst_packets: float) -> float:
    """The probability that a healthy link loses ``lost`` or more of ``sent`` observations:
    the binomial tail P(X ≥ k), X ~ B(n, p), at the nominal loss p (``comms.packet_loss``),
    with k and n divided by 2L − 1 for Gilbert-Elliott bursts of mean length L (the variance
    inflation of :func:`loss_limit`: bursts make fewer independent draws), continued to
    non-integer k and n as the regularized incomplete beta I_p(k, n − k + 1)."""
    if lost <= 0:
        return 1.0
    if packet_loss <= 0.0:
        return 0.0
    inflation = max(2.0 * burst_packets - 1.0, 1.0)
    k, n = lost / inflation, sent / inflation
    return float(betainc(k, n - k + 1.0, min(packet_loss, 1.0)))


MAX_JUDGED_LOSS = 0.9
"""An observer with a larger share of its observations lost has no data-integrity verdict."""

