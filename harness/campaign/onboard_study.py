"""The onboard FDIR judged on a campaign (issue 28): a campaign flown with it on
(``run_campaign.py --set onboard_fdir.enabled=true``) beside the same campaign with it off.

    python -m harness.campaign.onboard_study runs/paper-onboard runs/paper [--out FILE]

Reads every run's summary.json from both folders, pairs the runs by id, and writes a markdown
report (``<on>/onboard.md`` by default) with:

* the watchpoint trips and sequences in the nominal runs (the target is 0 of each);
* per fault, whether its declaration was followed by its class's sequence within one tick
  of the report's arrival onboard, and whether a watchpoint tripped before the ground's
  declaration;
* the ground's detection, isolation and identification with the onboard FDIR on and off;
* the recovery's effect: the final H (every image fused) with the onboard actions and
  without, per fault class and kind.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.summary import RunSummary


@dataclass(frozen=True)
class Pair:
    """One run of the campaign, flown with the onboard FDIR (``on``) and without (``off``)."""

    id: str
    on: RunSummary
    off: RunSummary | None


def load_pairs(on_dir: Path, off_dir: Path) -> list[Pair]:
    """The finished runs of ``on_dir`` with their twin in ``off_dir`` (None when missing)."""
    pairs = []
    for path in sorted((on_dir / "runs").glob("*/summary.json")):
        twin = off_dir / "runs" / path.parent.name / "summary.json"
        pairs.append(Pair(path.parent.name, RunSummary.read(path),
                          RunSummary.read(twin) if twin.exists() else None))
    return pairs


def _h_final(s: RunSummary) -> float | None:
    return s.coverage.H_final if s.coverage else None


def nominal_lines(pairs: Sequence[Pair]) -> list[str]:
    """Trips and sequences in the runs without a fault."""
    nominal = [p.on for p in pairs if not p.on.injected_faults]
    trips = sum(s.onboard_fdir.trips for s in nominal if s.onboard_fdir)
    actions = sum(s.onboard_fdir.actions for s in nominal if s.onboard_fdir)
    missing = sum(s.onboard_fdir is None for s in nominal)
    return ["## Nominal runs", "",
            f"{len(nominal)} nominal runs: **{trips} watchpoint trips, {actions} sequences "
            "started**" + (f" ({missing} summaries without an onboard section)" if missing
                           else "") + ".", ""]


def fault_rows(pairs: Sequence[Pair], dt_s: float) -> list[dict[str, object]]:
    """One row per injected fault of the runs with the onboard FDIR on."""
    rows: list[dict[str, object]] = []
    for p in pairs:
        ob = p.on.onboard_fdir
        for k, f in enumerate(ob.per_fault if ob else []):
            off = p.off.scores.per_fault[k] if p.off and p.off.scores else None
            on = p.on.scores.per_fault[k] if p.on.scores else None
            prompt = (f.action_s is not None and f.report_received_s is not None
                      and f.action_s - f.report_received_s <= dt_s + 1e-9)
            rows.append({
                "id": p.id, "kind": f.kind, "class": on.expected_class if on else None,
                "declared": f.report_received_s is not None, "acted": f.action is not None,
                "prompt": prompt,
                "trip_first": f.trip_s is not None and (f.detected_s is None
                                                        or f.trip_s < f.detected_s),
                "isolated_on": bool(on and on.isolated), "isolated_off": bool(off and off.isolated),
                "identified_on": bool(on and on.identified_correctly),
                "identified_off": bool(off and off.identified_correctly),
                "h_on": _h_final(p.on), "h_off": _h_final(p.off) if p.off else None})
    return rows


def _n(rows: Sequence[dict[str, object]], key: str) -> int:
    return sum(bool(r[key]) for r in rows)


def fault_lines(rows: Sequence[dict[str, object]]) -> list[str]:
    """The onboard story and the ground's figures, on and off, per fault kind."""
    lines = ["## Faults", "",
             "| kind | faults | declared (classed) | its sequence within a tick | a trip before "
             "the ground | isolated on / off | identified on / off |",
             "|---|---|---|---|---|---|---|"]
    for kind in sorted({str(r["kind"]) for r in rows}):
        rs = [r for r in rows if r["kind"] == kind]
        lines.append(f"| {kind} | {len(rs)} | {_n(rs, 'declared')} | "
                     f"{_n(rs, 'prompt')} of {_n(rs, 'acted')} acted on | {_n(rs, 'trip_first')}"
                     f" | {_n(rs, 'isolated_on')} / {_n(rs, 'isolated_off')} | "
                     f"{_n(rs, 'identified_on')} / {_n(rs, 'identified_off')} |")
    return lines + [""]


def effect_lines(rows: Sequence[dict[str, object]]) -> list[str]:
    """Final H with the onboard actions and without, per expected class and kind."""
    lines = ["## The recovery's effect", "",
             "Final H (every image fused, Eq. 7; lower is better) of the same run and seed with "
             "the onboard FDIR on and off.", "",
             "| class | kind | runs | H final, on (mean) | off (mean) | on - off, mean "
             "(min / max) |",
             "|---|---|---|---|---|---|"]
    both = [r for r in rows if r["h_on"] is not None and r["h_off"] is not None]
    for cls, kind in sorted({(str(r["class"]), str(r["kind"])) for r in both}):
        rs = [r for r in both if r["class"] == cls and r["kind"] == kind]
        on = np.array([float(r["h_on"]) for r in rs])  # type: ignore[arg-type]
        off = np.array([float(r["h_off"]) for r in rs])  # type: ignore[arg-type]
        d = on - off
        lines.append(f"| {cls} | {kind} | {len(rs)} | {on.mean():.4f} | {off.mean():.4f} | "
                     f"{d.mean():+.4f} ({d.min():+.4f} / {d.max():+.4f}) |")
    return lines + [""]


def write_onboard_report(on_dir: Path, off_dir: Path, out: Path | None = None,
                         dt_s: float = 0.1) -> Path:
    """Write the report (module docstring); ``dt_s``: one tick, s."""
    pairs = load_pairs(on_dir, off_dir)
    rows = fault_rows(pairs, dt_s)
    lines = [f"# The onboard FDIR on a campaign: {on_dir} against {off_dir}", "",
             f"{len(pairs)} runs with it on, {sum(p.off is not None for p in pairs)} with their "
             "twin flown without it.", ""]
    lines += nominal_lines(pairs) + fault_lines(rows) + effect_lines(rows)
    path = out or on_dir / "onboard.md"
    path.write_text("\n".join(lines) + "\n")
    (path.with_suffix(".json")).write_text(json.dumps(rows, indent=1) + "\n")
    return path


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m harness.campaign.onboard_study",
                                description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("on", type=Path, help="campaign folder flown with the onboard FDIR on")
    p.add_argument("off", type=Path, help="the same campaign flown with it off")
    p.add_argument("--out", type=Path, help="report path (default <on>/onboard.md)")
    args = p.parse_args(argv)
    print(write_onboard_report(args.on, args.off, args.out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
