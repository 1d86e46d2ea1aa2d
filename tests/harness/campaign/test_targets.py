"""The false-alarm target where a campaign's windows are too few to show it
(harness/campaign/targets.py): the windows needed, against the closed form for none, and the
report's wording instead of "not met"; the settings a campaign report was made with."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from harness.campaign.report import settings_lines
from harness.campaign.rescore import false_alarm_bound
from harness.campaign.targets import noted_rate, too_few, windows_needed


@pytest.mark.parametrize("target", [1e-3, 1e-2, 0.05, 2e-4])
def test_the_windows_needed_without_a_false_alarm_are_the_closed_form(target: float) -> None:
    """1 − 0.05^(1/n) ≤ p for n ≥ ln 0.05 / ln(1 − p)."""
    assert windows_needed(0, target) == math.ceil(math.log(0.05) / math.log(1.0 - target))


@pytest.mark.parametrize("false_alarms", [1, 2, 5])
def test_the_windows_needed_with_false_alarms_are_the_fewest_that_bound_them(
        false_alarms: int) -> None:
    n = windows_needed(false_alarms, 1e-3)
    assert false_alarm_bound(false_alarms, n) <= 1e-3 < false_alarm_bound(false_alarms, n - 1)


def test_too_few_windows_is_said_with_the_windows_needed_not_as_missed() -> None:
    assert too_few(0, 377) == ("too few windows to show the target: needs ≥ 2,995 windows "
                               "(has 377)")
    assert too_few(1, 1000).startswith("too few windows to show the target: needs ≥ 4,7")
    assert too_few(1, 1000).endswith(" windows with 1 false alarm (has 1,000)")
    assert too_few(2, 1000) == ""  # a rate of 2e-3: over the target, not met
    assert too_few(0, 3000) == ""  # enough: met
    assert too_few(0, 0) == ""  # nothing to judge
    assert noted_rate(0, 377).endswith("; too few windows to show the target: needs ≥ 2,995 "
                                       "windows (has 377)")


def test_a_campaign_report_prints_its_settings(tmp_path: Path) -> None:
    (tmp_path / "campaign.json").write_text(json.dumps(
        {"name": "c", "runs": [], "settings": {"fdir.persistence": "2"}}))
    assert settings_lines(tmp_path)[0] == ("Settings: fdir.persistence = 2 (--set, over each "
                                           "run's own).")
    (tmp_path / "campaign.json").write_text(json.dumps(
        {"name": "c", "runs": [], "replay_of": "/x", "settings": {}}))
    assert settings_lines(tmp_path)[0] == ("Settings: replay of /x: each run's own, nothing set "
                                           "over them (no --set).")
