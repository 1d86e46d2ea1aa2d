"""A campaign's figures by drawn dimension: for every setting a campaign draws per run
(``drawn.json`` beside each run's summary, written by ``deploy/campaign.py``: ``mission``,
``observers.count``, ``ground.contact``, ``fault.phase``...), its runs in bins and, per bin,
the figures the detection targets are stated in.  The report (``harness/campaign/report.py``)
renders them.

Bins: a choice's values, one bin each, in the order of its domain; a range's four
equal-width bins over [min, max], labelled with their edges (an integer range of at most four
values: one bin per value; a wider one: four bins of consecutive integers).  Groups that draw
one dimension over different domains share one: the union of their choices (in first-seen
order), or the range from the smallest min to the largest max.  A run goes into the bin of its
own value; a fault's phase or kind (``fault.phase``) is its run's.

Per bin, for the main detector as in the rest of the report (results.csv's rows): runs (that
completed; failed ones counted apart), faults, those no window could judge (``unjudged``:
between passes, none came down in the run), and of the others: detected and isolated,
identified (the right class), latency of the isolated faults from the first judgeable window
and from onset to the ground's declaration (median and p90, s); false alarms per nominal
observer-window and, over the runs with the neighbours' FDIR on, per nominal neighbour-window,
each with its one-sided 95% upper bound (``rescore.false_alarm_bound``).

The worst bin of a dimension (of two or more bins with runs) is the one with the largest share
of failed runs, then the smallest share of judgeable faults isolated, then identified, then the
highest false-alarm bound (the ground's, then the neighbours'), then the longest p90 latency.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from harness.campaign.rescore import (
    CampaignRun,
    detector_stats,
    false_alarm_bound,
    neighbour_false_alarms,
    values,
)


def value_label(value: Any) -> str:
    """A drawn value as a bin shows it: a string as it is, anything else as JSON."""
    return value if isinstance(value, str) else json.dumps(value)


@dataclass(frozen=True)
class Binning:
    """A dimension's bins: their labels, and the bin of a value (None: outside them all)."""

    domain: dict[str, Any]

    def labels(self) -> list[str]:
        if "choose" in self.domain:
            return list(dict.fromkeys(value_label(v) for v in self.domain["choose"]))
        lo, hi = self.domain["min"], self.domain["max"]
        if self.domain.get("integer"):
            return [_int_label(*_int_bin(lo, hi, k)) for k in range(_int_bins(lo, hi))]
        if hi == lo:
            return [f"{lo:g}"]
        w = (hi - lo) / 4.0
        return [f"{lo + k * w:.4g}–{lo + (k + 1) * w:.4g}" for k in range(4)]

    def index(self, value: Any) -> int | None:
        if "choose" in self.domain:
            labels = self.labels()
            return labels.index(value_label(value)) if value_label(value) in labels else None
        lo, hi = self.domain["min"], self.domain["max"]
        if not isinstance(value, int | float) or not lo <= value <= hi:
            return None
        if self.domain.get("integer"):
            return min(int((value - lo) / _int_width(lo, hi)), _int_bins(lo, hi) - 1)
        return 0 if hi == lo else min(int(4.0 * (value - lo) / (hi - lo)), 3)


def _int_bins(lo: int, hi: int) -> int:
    """Bins of an integer range [lo, hi]: one per value up to four values, else four."""
    return min(hi - lo + 1, 4)


def _int_width(lo: int, hi: int) -> float:
    """Values per bin of an integer range (its bins tile [lo, hi + 1))."""
    return (hi - lo + 1) / _int_bins(lo, hi)


def _int_bin(lo: int, hi: int, k: int) -> tuple[int, int]:
    """The first and last integer of bin ``k`` of [lo, hi]."""
    w = _int_width(lo, hi)
    return lo + math.ceil(k * w - 1e-9), lo + math.ceil((k + 1) * w - 1e-9) - 1


def _int_label(first: int, last: int) -> str:
    return f"{first}" if first == last else f"{first}–{last}"


def union(a: dict[str, Any], b: dict[str, Any]) -> dict[str, Any]:
    """One domain of a dimension two groups draw (module docstring); ``a`` when one is a
    choice and the other a range."""
    if "choose" in a and "choose" in b:
        seen = {value_label(v): v for v in [*a["choose"], *b["choose"]]}
        return {"choose": list(seen.values())}
    if "min" in a and "min" in b:
        return {"min": min(a["min"], b["min"]), "max": max(a["max"], b["max"]),
                "integer": bool(a.get("integer")) and bool(b.get("integer"))}
    return a


def campaign_domains(runs: Sequence[CampaignRun]) -> dict[str, dict[str, Any]]:
    """Every dimension the runs drew, with its domain, in first-seen order."""
    out: dict[str, dict[str, Any]] = {}
    for r in runs:
        for name, domain in r.domains.items():
            out[name] = union(out[name], domain) if name in out else domain
    return out


@dataclass(frozen=True)
class BinFigures:
    """One bin's figures (module docstring): ``isolated`` and ``identified`` of the
    ``faults`` less the ``unjudged``; latencies from the first judgeable window
    (``latencies_s``) and from onset to the ground's declaration (``onset_latencies_s``), s."""

    label: str
    runs: int = 0
    failed: int = 0
    faults: int = 0
    unjudged: int = 0
    isolated: int = 0
    identified: int = 0
    latencies_s: tuple[float, ...] = ()
    onset_latencies_s: tuple[float, ...] = ()
    false_alarms: int = 0
    windows: int = 0
    neighbour_false_alarms: int = 0
    neighbour_windows: int = 0
    worst: bool = False

    @property
    def latency_median_s(self) -> float | None:
        return float(np.median(self.latencies_s)) if self.latencies_s else None

    @property
    def latency_p90_s(self) -> float | None:
        return float(np.quantile(self.latencies_s, 0.9)) if self.latencies_s else None

    @property
    def judgeable(self) -> int:
        return self.faults - self.unjudged

    @property
    def onset_latency_median_s(self) -> float | None:
        return float(np.median(self.onset_latencies_s)) if self.onset_latencies_s else None

    @property
    def false_alarm_bound(self) -> float | None:
        """95% upper bound of the false alarms per observer-window (None: no window)."""
        return false_alarm_bound(self.false_alarms, self.windows) if self.windows else None

    @property
    def neighbour_false_alarm_bound(self) -> float | None:
        """95% upper bound of the neighbours' false alarms per neighbour-window."""
        return false_alarm_bound(self.neighbour_false_alarms, self.neighbour_windows) \
            if self.neighbour_windows else None

    def to_json(self) -> dict[str, Any]:
        return {"bin": self.label, "runs": self.runs, "failed": self.failed,
                "faults": self.faults, "unjudged": self.unjudged,
                "detected_isolated": self.isolated, "identified": self.identified,
                "latency_median_s": self.latency_median_s, "latency_p90_s": self.latency_p90_s,
                "onset_latency_median_s": self.onset_latency_median_s,
                "false_alarms": self.false_alarms,
                "observer_windows": self.windows, "false_alarm_bound": self.false_alarm_bound,
                "neighbour_false_alarms": self.neighbour_false_alarms,
                "neighbour_windows": self.neighbour_windows,
                "neighbour_false_alarm_bound": self.neighbour_false_alarm_bound,
                "worst": self.worst}


@dataclass(frozen=True)
class Dimension:
    """A drawn dimension: its name, domain and bins."""

    name: str
    domain: dict[str, Any]
    bins: tuple[BinFigures, ...]

    def to_json(self) -> dict[str, Any]:
        return {"domain": self.domain, "bins": [b.to_json() for b in self.bins]}


def _bin_figures(label: str, mine: Sequence[CampaignRun], failed: int,
                 rows: Sequence[dict[str, Any]]) -> BinFigures:
    """The figures of the completed runs ``mine`` (with ``failed`` others) from the main
    detector's results.csv ``rows``."""
    ids = {r.id for r in mine}
    own = [r for r in rows if r["run"] in ids and r["detector"] == "main"]
    st = detector_stats(own, 0.0)
    nfa, nwin = neighbour_false_alarms(mine)
    judged = [r for r in own if r["kind"] != "none" and not r["unjudged"]]
    return BinFigures(
        label, runs=len(mine), failed=failed, faults=st["faults"], unjudged=st["unjudged"],
        isolated=st["isolated_judgeable"], identified=st["identified_judgeable"],
        latencies_s=tuple(values(judged, "window_latency_s")),
        onset_latencies_s=tuple(values(judged, "declared_latency_s")),
        false_alarms=st["false_alarms"], windows=st["nominal_cycles"],
        neighbour_false_alarms=nfa, neighbour_windows=nwin)



def _badness(b: BinFigures) -> tuple[float, ...]:
    """Smaller is worse (module docstring)."""
    def share(n: int, d: int) -> float:
        return n / d if d else 1.0

    return (-share(b.failed, b.runs + b.failed), share(b.isolated, b.judgeable),
            share(b.identified, b.judgeable), -(b.false_alarm_bound or 0.0),
            -(b.neighbour_false_alarm_bound or 0.0), -(b.latency_p90_s or 0.0))


def _mark_worst(bins: list[BinFigures]) -> tuple[BinFigures, ...]:
    """The bins with the worst one marked, when two or more have runs."""
    flown = [k for k, b in enumerate(bins) if b.runs + b.failed > 0]
    if len(flown) < 2:
        return tuple(bins)
    k = min(flown, key=lambda k: _badness(bins[k]))
    return tuple(replace(b, worst=True) if i == k else b for i, b in enumerate(bins))


def by_dimension(loaded: Sequence[CampaignRun], rows: Sequence[dict[str, Any]]
                 ) -> list[Dimension]:
    """Every drawn dimension of the ``loaded`` runs (failed ones counted apart) with the
    figures of each bin, from the completed runs' results.csv ``rows``."""
    out = []
    for name, domain in campaign_domains(loaded).items():
        binning = Binning(domain)
        members: dict[int, list[CampaignRun]] = {}
        for r in loaded:
            k = binning.index(r.drawn.get(name)) if name in r.drawn else None
            if k is not None:
                members.setdefault(k, []).append(r)
        bins = []
        for k, label in enumerate(binning.labels()):
            mine = members.get(k, [])
            done = [r for r in mine if r.summary.status == "completed"]
            bins.append(_bin_figures(label, done, len(mine) - len(done), rows))
        out.append(Dimension(name, domain, _mark_worst(bins)))
    return out
