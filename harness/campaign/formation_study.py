"""The formation study: the chapter's higher-dimensional example (Sec. III.G, Figs. 10-21) flown
as a campaign (``deploy/campaigns/formations.toml``): formations of 1, 2 and 4 observers, one of
them faulty (an actuator fault, ``state_disturbance``; a sensor fault, ``camera_misalignment``),
each faulty run beside its nominal twin (same formation and seed, no fault).

For every run the global cost H (Eq. 7) and every observer's H_i (Eq. 8, the centralized
decomposition) are computed from every camera image the sim produced, fused in time order
(``harness.summary.coverage``), sampled every ``SAMPLE_S``.  The study writes
``<out>/study.md`` with, per case (formation size x fault kind):

* a figure of H and every H_i over time, faulty run against twin, and each agent's
  contributions (the change of each H_i, and the drop of H, per sample interval), as
  Figs. 10-21 do;
* a table, one row per faulty run: detected, latency and identified class (the ground FDIR's,
  from summary.json), and how far the faulty agent's H_i and the global H moved, each
  relative to its twin (:func:`relative_move`);

and checks the chapter's two claims against the measured figures (:func:`claims`).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from harness.archive.reader import Record, load_run  # noqa: E402
from harness.archive.run_scenario import archived_scenario  # noqa: E402
from harness.summary import FaultScore, RunSummary  # noqa: E402
from harness.summary.coverage import CoverageFuser  # noqa: E402
from interfaces.contracts import catalogue as cat  # noqa: E402
from interfaces.contracts.scenario import Fault  # noqa: E402

OTHERS = ("C0", "C1", "C2", "C4", "C5", "C6", "C7", "C8", "C9")
"""Colours of the agents that are not faulty (red is the faulty one's)."""
SAMPLE_S = 10.0
"""Sampling interval of H and H_i, s."""
UNREAD = (cat.TRUTH, cat.ATTITUDE_SENSORS, cat.RELNAV, cat.NAV_ESTIMATE, cat.ATTITUDE_ESTIMATE,
          cat.OBSERVATIONS)
"""Topics the study does not read (streamed past at load, not held)."""


@dataclass(frozen=True)
class Curves:
    """H and every H_i of one run over time (all the sim's images fused)."""

    t_s: np.ndarray
    """sample times, s"""
    h: np.ndarray
    """global cost H (Eq. 7), dimensionless"""
    h_i: np.ndarray
    """(samples, observers): each observer's H_i (Eq. 8) on the same fused map"""


@dataclass(frozen=True)
class StudyRun:
    """One finished run of the study: its formation size, seed, fault (None: a twin), the
    ground FDIR's score of the fault, and its curves."""

    id: str
    observers: int
    seed: int
    fault: Fault | None
    score: FaultScore | None
    curves: Curves

    @property
    def case(self) -> tuple[int, str]:
        """(formation size, fault kind): the study's cases."""
        return self.observers, self.fault.kind if self.fault else "nominal"


@dataclass(frozen=True)
class Moves:
    """How far a faulty run moved from its twin (:func:`relative_move`): the faulty agent's
    H_i, the global H, and the largest difference before the onset (0 when the twin is one)."""

    h_i: float
    h: float
    before_onset: float


def _drop(_rec: Record) -> None:
    """Sink of the records the study does not read."""


def curves_of(path: Path) -> tuple[int, Curves]:
    """The formation size and the curves of the run archived at ``path`` (``run.mcap`` and its
    segments)."""
    scenario = archived_scenario(path)
    fuser = CoverageFuser(scenario, sample_every_s=SAMPLE_S)
    stream = {cat.CAMERA_IMAGE.any_mission(): fuser.add_record,
              **{t.any_mission(): _drop for t in UNREAD}}
    archive = load_run(path, stream=stream)
    cov = fuser.finish(archive, archive.mission())
    return scenario.observers.count, Curves(np.array(cov.t_s), np.array(cov.h),
                                            np.array(cov.h_j))


def relative_move(t_s: np.ndarray, x: np.ndarray, twin_t_s: np.ndarray, twin: np.ndarray,
                  onset_s: float) -> tuple[float, float]:
    """How far the curve ``x`` moved from its twin's after ``onset_s``: the mean of
    |x - x_twin| over the samples at or after the onset, over the mean of |x_twin| there
    (the twin interpolated to the samples of ``x``); and the largest |x - x_twin| before the
    onset (0 for a true twin: the runs are the same until the fault)."""
    ref = np.interp(t_s, twin_t_s, twin)
    after = t_s >= onset_s
    if not after.any():
        raise ValueError(f"no sample at or after the onset {onset_s:g} s")
    move = float(np.mean(np.abs(x[after] - ref[after])) / max(np.mean(np.abs(ref[after])),
                                                               1e-300))
    before = float(np.max(np.abs(x[~after] - ref[~after]), initial=0.0))
    return move, before


def moves(run: StudyRun, twin: StudyRun) -> Moves:
    """The faulty agent's H_i and the global H of ``run`` against ``twin``."""
    assert run.fault is not None
    c, w, k, onset = run.curves, twin.curves, run.fault.spacecraft - 1, run.fault.start_s
    hi, before_i = relative_move(c.t_s, c.h_i[:, k], w.t_s, w.h_i[:, k], onset)
    h, before = relative_move(c.t_s, c.h, w.t_s, w.h, onset)
    return Moves(hi, h, max(before_i, before))


def load_study(out: Path, ids: Sequence[str]) -> list[StudyRun]:
    """The finished runs among ``ids`` under ``<out>/runs/`` (those with an archive)."""
    runs = []
    for rid in ids:
        d = out / "runs" / rid
        if not (d / "summary.json").exists() or not (d / "run.mcap").exists():
            continue
        summary = RunSummary.read(d / "summary.json")
        observers, curves = curves_of(d / "run.mcap")
        fault = summary.injected_faults[0] if summary.injected_faults else None
        score = summary.scores.per_fault[0] if fault and summary.scores else None
        runs.append(StudyRun(rid, observers, summary.seed, fault, score, curves))
    return runs


def twins(runs: Sequence[StudyRun]) -> list[tuple[StudyRun, StudyRun]]:
    """Every faulty run with its twin: the nominal run of the same formation and seed (a
    faulty run without one is left out)."""
    nominal = {(r.observers, r.seed): r for r in runs if r.fault is None}
    return [(r, nominal[(r.observers, r.seed)]) for r in runs
            if r.fault is not None and (r.observers, r.seed) in nominal]


def claims(pairs: Sequence[tuple[StudyRun, Moves]]) -> list[str]:
    """The chapter's two claims, checked against the measured moves (markdown lines)."""
    lines = ["## The chapter's claims", ""]
    stable = [m.h < m.h_i for _, m in pairs]
    lines += [f"**\"The global cost H remains relatively stable even after fault injection\"** "
              f"(Sec. III.G, Fig. 10): the global H moved less than the faulty agent's H_i in "
              f"{sum(stable)} of {len(stable)} faulty runs; median move of H "
              f"{_pct(np.median([m.h for _, m in pairs]))} against "
              f"{_pct(np.median([m.h_i for _, m in pairs]))} for H_i.", ""]
    lines += ["**\"The fault's effect is more pronounced in H_i as the number of agents "
              "increases\"** (Figs. 12, 14): median moves by formation size, per fault kind:", "",
              "| fault | observers | runs | H_i moved | H moved | H_i / H |",
              "|---|---|---|---|---|---|"]
    verdicts = []
    for kind in sorted({r.fault.kind for r, _ in pairs if r.fault}):
        medians = []
        for n in sorted({r.observers for r, _ in pairs}):
            ms = [m for r, m in pairs if r.fault and r.fault.kind == kind and r.observers == n]
            if not ms:
                continue
            hi, h = float(np.median([m.h_i for m in ms])), float(np.median([m.h for m in ms]))
            ratio = float(np.median([m.h_i / max(m.h, 1e-300) for m in ms]))
            medians.append((n, hi, ratio))
            lines.append(f"| {kind} | {n} | {len(ms)} | {_pct(hi)} | {_pct(h)} | {ratio:.1f} |")
        verdicts.append(_trend(kind, medians))
    return lines + [""] + verdicts + [""]


def _trend(kind: str, medians: list[tuple[int, float, float]]) -> str:
    """Whether the faulty agent's H_i move, relative to H's, grows with the formation size."""
    ratios = [r for _, _, r in medians]
    grows = all(b > a for a, b in pairwise(ratios))
    sizes = ", ".join(f"{n}: {r:.1f}" for n, _, r in medians)
    verdict = ("holds" if grows else "does not hold here") if len(ratios) > 1 else \
        "cannot be judged (one formation size)"
    return (f"- {kind}: the H_i move over the H move, by formation size ({sizes}): the claim "
            f"{verdict}.")


def _pct(x: float) -> str:
    return f"{100.0 * x:.2f}%"


def _fmt(v: float | None, f: str = ".0f") -> str:
    return "-" if v is None else format(v, f)


def _case_figure(path: Path, run: StudyRun, twin: StudyRun) -> None:
    """H and every H_i against the twin's, and each agent's contributions per interval."""
    assert run.fault is not None
    c, w, k = run.curves, twin.curves, run.fault.spacecraft - 1
    fig, ax = plt.subplots(1, 3, figsize=(15, 4))
    ax[0].plot(w.t_s, w.h, "k--", lw=1, label="H, nominal twin")
    ax[0].plot(c.t_s, c.h, "r-", lw=1.2, label="H, faulty run")
    ax[0].set_ylabel("global cost H (Eq. 7)")
    for j in range(c.h_i.shape[1]):
        style = {"color": "r" if j == k else OTHERS[j % len(OTHERS)], "lw": 1.4 if j == k else 0.8}
        ax[1].plot(c.t_s, c.h_i[:, j], "-", label=f"H_{j + 1}", **style)
        ax[1].plot(w.t_s, w.h_i[:, j], ":", **style)
        ax[2].plot(c.t_s[1:], np.diff(c.h_i[:, j]), "-", label=f"ΔH_{j + 1}", **style)
    ax[1].set_ylabel("H_i (Eq. 8); dotted: twin")
    ax[2].plot(c.t_s[1:], -np.diff(c.h), "k-", lw=1, label="-ΔH (global)")
    ax[2].set_ylabel(f"contribution per {SAMPLE_S:g} s")
    for a in ax:
        a.axvline(run.fault.start_s, color="grey", ls="--", lw=0.8)
        a.set_xlabel("sim time (s)")
        a.grid(True, alpha=0.3)
        a.legend(fontsize=7)
    fig.suptitle(f"{run.observers} observer(s), {run.fault.kind} on sc{run.fault.spacecraft} "
                 f"at {run.fault.start_s:.0f} s (run {run.id})")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _case_lines(out: Path, case: tuple[int, str],
                pairs: list[tuple[StudyRun, StudyRun, Moves]]) -> list[str]:
    n, kind = case
    name = f"n{n}-{kind}"
    _case_figure(out / "study" / f"{name}.png", pairs[0][0], pairs[0][1])
    lines = [f"### {n} observer(s), {kind}", "", f"![{name}](study/{name}.png)", "",
             "| run | seed | fault | onset (s) | detected | latency (s) | class | H_i moved | "
             "H moved | H_i / H | before onset |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for run, _, m in pairs:
        f, s = run.fault, run.score
        assert f is not None
        what = f"{f.magnitude:g}" + (f" m, {f.velocity_mps or 0:g} m/s {f.disturbance or 'bias'}"
                                     if f.kind == "state_disturbance" else "°")
        lines.append(f"| {run.id} | {run.seed} | {what} | {f.start_s:.0f} | "
                     f"{'yes' if s and s.isolated else 'no'} | {_fmt(s.latency_s if s else None)}"
                     f" | {s.identified_class if s else '-'} | {_pct(m.h_i)} | {_pct(m.h)} | "
                     f"{m.h_i / max(m.h, 1e-300):.1f} | {m.before_onset:.1e} |")
    return lines + [""]


def write_formation_study(out: Path, ids: Sequence[str]) -> Path:
    """Write ``<out>/study.md`` and its figures (``<out>/study/``) from the finished runs."""
    runs = load_study(out, ids)
    (out / "study").mkdir(exist_ok=True)
    paired = [(r, w, moves(r, w)) for r, w in twins(runs)]
    lines = ["# Formation study (Sec. III.G, Figs. 10-21)", "",
             f"{len(runs)} runs read, {len(paired)} faulty runs with their nominal twin.  H is "
             "the global cost of every image fused (Eq. 7), H_i the centralized decomposition "
             "(Eq. 8) on the same map, both sampled every "
             f"{SAMPLE_S:g} s.  *Moved*: the mean of |x - x_twin| after the onset over the "
             "mean of |x_twin| there; *before onset*: the largest |x - x_twin| before it (0: "
             "the twin is the same run until the fault).  Detection, latency and class: the "
             "ground FDIR's (summary.json).", ""]
    lines += claims([(r, m) for r, _, m in paired])
    lines += ["## Cases", ""]
    cases = sorted({r.case for r, _, _ in paired})
    for case in cases:
        lines += _case_lines(out, case, [p for p in paired if p[0].case == case])
    path = out / "study.md"
    path.write_text("\n".join(lines) + "\n")
    (out / "study.json").write_text(json.dumps(
        [{"run": r.id, "twin": w.id, "observers": r.observers, "kind": r.case[1],
          "h_i_moved": m.h_i, "h_moved": m.h, "before_onset": m.before_onset,
          "detected": bool(r.score and r.score.isolated),
          "latency_s": r.score.latency_s if r.score else None,
          "identified_class": r.score.identified_class if r.score else None}
         for r, w, m in paired], indent=1) + "\n")
    return path
