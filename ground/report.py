"""report.md of a run, with PNG plots beside it (matplotlib, no display needed)."""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ground.evaluation import NavErrors, nav_errors  # noqa: E402
from ground.reader import ArchiveError, RunArchive, load_run  # noqa: E402
from interfaces import topics  # noqa: E402
from interfaces.messages import TruthState  # noqa: E402
from interfaces.scenario import Scenario  # noqa: E402


def write_report(out: Path, scenario: Scenario, mission: str | None = None) -> Path:
    """Write ``<out>/report.md`` (and its plots) from ``run.mcap`` and ``summary.json``."""
    mission = mission or scenario.name
    summary = json.loads((out / "summary.json").read_text())
    lines = [f"# Run report: {scenario.name}", "",
             f"Status **{summary['status']}**, seed {scenario.seed}, transport "
             f"{summary['transport']}, {summary.get('t_sim_final_s', 0):.0f} s simulated in "
             f"{summary['wall_s']:.1f} s wall"
             + (f" ({summary['real_time_factor']:.0f}× real time)." if summary.get("real_time_factor") else "."),
             ""]
    if summary.get("error"):
        lines += ["```", summary["error"], "```", ""]
    try:
        archive = load_run(out / "run.mcap")
    except (ArchiveError, OSError) as e:
        lines.append(f"The archive could not be read: {e}")
        return _write(out, lines)
    lines += _trajectory_section(out, archive, mission)
    lines += _nav_section(out, nav_errors(archive, mission), summary)
    lines += _links_section(summary) + _exec_section(summary)
    return _write(out, lines)


def _write(out: Path, lines: list[str]) -> Path:
    path = out / "report.md"
    path.write_text("\n".join(lines) + "\n")
    return path


def _trajectory_section(out: Path, archive: RunArchive, mission: str) -> list[str]:
    truth = archive.messages(topics.truth(mission), TruthState)
    if not truth:
        return ["No truth recorded.", ""]
    r = np.array([t.r_lvlh_m for t in truth])  # (K, N, 3)
    fig, axes = plt.subplots(1, 2, figsize=(11, 5))
    for i, sc in enumerate(truth[0].spacecraft):
        axes[0].plot(r[:, i, 1], r[:, i, 0], label=f"sc{sc}")
        axes[1].plot(r[:, i, 1], r[:, i, 2], label=f"sc{sc}")
    for ax, (yl, title) in zip(axes, (("radial x (m)", "in-plane"), ("cross-track z (m)", "along-track / cross-track"))):
        ax.plot(0, 0, "k*", ms=12, label="target")
        ax.set_xlabel("along-track y (m)")
        ax.set_ylabel(yl)
        ax.set_title(title)
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="best", fontsize=8)
    fig.suptitle("True relative trajectories (LVLH of the target)")
    fig.tight_layout()
    fig.savefig(out / "trajectories.png", dpi=110)
    plt.close(fig)
    return ["## Relative trajectories", "", "![trajectories](trajectories.png)", ""]


def _nav_section(out: Path, errs: dict[int, NavErrors], summary: dict) -> list[str]:
    if not errs:
        return ["No navigation estimates recorded.", ""]
    fig, axes = plt.subplots(len(errs), 1, figsize=(10, 2.2 * len(errs)), sharex=True, squeeze=False)
    for ax, (sc, e) in zip(axes[:, 0], errs.items()):
        pos = np.linalg.norm(e.error[:, :3], axis=1)
        bound = 3 * np.sqrt(np.sum(e.sigma[:, :3] ** 2, axis=1))
        ax.semilogy(e.t_s, pos, lw=0.8, label="|position error|")
        ax.semilogy(e.t_s, bound, "r--", lw=0.8, label="3σ (trace)")
        ax.set_ylabel(f"sc{sc} (m)")
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(loc="upper right", fontsize=8)
    axes[-1, 0].set_xlabel("sim time (s)")
    fig.suptitle("Navigation position error against truth")
    fig.tight_layout()
    fig.savefig(out / "nav_error.png", dpi=110)
    plt.close(fig)
    rows = ["| sc | pos RMS (m) | pos max (m) | vel RMS (m/s) | mean NEES (6 dof) | NEES in 95% | mean NIS |",
            "|---|---|---|---|---|---|---|"]
    for sc, st in summary.get("nav", {}).items():
        if st:
            rows.append(f"| {sc} | {st['pos_rms_m']:.3f} | {st['pos_max_m']:.3f} | "
                        f"{st['vel_rms_mps']:.4f} | {st['nees_mean']:.2f} | "
                        f"{100 * st['nees_in_95_bounds']:.0f}% | {st['nis_mean'] or float('nan'):.2f} |")
    return ["## Navigation", "", "![nav error](nav_error.png)", "", *rows, ""]


def _links_section(summary: dict) -> list[str]:
    rows = ["## Links", "", "| link | sent | delivered | dropped (range) | dropped (loss) | dropped (cut) |",
            "|---|---|---|---|---|---|"]
    for c in summary.get("links", []):
        rows.append(f"| {c['src']} → {c['dst']} | {c['sent']} | {c['delivered']} | "
                    f"{c['dropped_range']} | {c['dropped_loss']} | {c['dropped_cut']} |")
    return rows + [""]


def _exec_section(summary: dict) -> list[str]:
    rows = ["## Executives", "", "| node | cycle slips (high/mid/low) | max exec ms (high/mid/low) | app errors | invalid msgs | barrier timeouts |",
            "|---|---|---|---|---|---|"]
    for node, e in summary.get("exec", {}).items():
        slips = "/".join(str(e["cycle_slips"].get(g, 0)) for g in ("high", "mid", "low"))
        ms = "/".join(f"{e['max_exec_ms'].get(g, 0):.2f}" for g in ("high", "mid", "low"))
        rows.append(f"| {node} | {slips} | {ms} | {e['app_errors']} | {e['invalid_dropped']} | "
                    f"{e['barrier_timeouts']} |")
    return rows + [""]
