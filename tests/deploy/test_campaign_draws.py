"""Campaigns that draw the set-up itself (deploy/draws.py, deploy/onsets.py,
deploy/campaign_file.py, deploy/campaign.py): the same file gives the same draws, draws stay
in their bounds, a subset's elements are distinct and in list order, the existing campaigns
expand to exactly the runs they did before, bad drawn values are refused at load naming
them, faults follow the drawn set-up (any observer, an onset in a phase it has, a magnitude per
kind), every run records what it drew, and deploy/campaigns/space.toml expands into valid runs
over every bin of every dimension."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from deploy.campaign import CampaignError, RunSpec, fingerprint, finished, load_campaign
from deploy.campaign_file import FaultSpec
from deploy.draws import Choice, Record, Uniform, draw_tree, parse_tree, rng_for
from deploy.onsets import WINDOWS_AFTER, heard_by_s, phase_spans
from deploy.run_campaign import main as run_campaign
from gnc.passes import scenario_pass_table
from harness.campaign.dimensions import Binning, campaign_domains
from harness.campaign.rescore import CampaignRun
from harness.summary import RunSummary
from interfaces.contracts.scenario import load_scenario
from tests.deploy.test_campaign import BASE

CAMPAIGNS = Path(__file__).resolve().parents[2] / "deploy" / "campaigns"
SCENARIOS = Path(__file__).resolve().parents[2] / "deploy" / "scenarios"

DRAWN = """name = "dc"
base = "base.toml"
seeds = {{ first = 1, count = 12 }}
duration_s = 200.0
[overrides]
observers = {{ count = {{ min = 2, max = 6 }} }}
camera = {{ half_angle_deg = {{ min = 10.0, max = 25.0 }} }}
neighbours = {{ enabled = {{ choose = [true, false] }} }}
[overrides.ground]
contact = "passes"
[overrides.ground.stations]
count = {{ min = 1, max = 3 }}
choose = [
  {{ name = "Svalbard", latitude_deg = 78.23, longitude_deg = 15.39 }},
  {{ name = "Kiruna", latitude_deg = 67.86, longitude_deg = 20.96 }},
  {{ name = "Weilheim", latitude_deg = 47.88, longitude_deg = 11.08 }},
  {{ name = "Perth", latitude_deg = -31.80, longitude_deg = 115.89 }},
]
[[groups]]
name = "f"
[[groups.faults]]
spacecraft = {spacecraft}
kind = {{ choose = ["thruster_bias", "link_loss", "camera_degradation"] }}
start_s = {{ during = ["inspection"] }}
[groups.faults.magnitude.per_kind]
thruster_bias = {{ min = 0.1, max = 0.7 }}
camera_degradation = 0.5
[[groups]]
name = "n"
nominal = true
"""


def _write(tmp: Path, text: str) -> Path:
    (tmp / "base.toml").write_text(BASE)
    path = tmp / "c.toml"
    path.write_text(text)
    return path


def _drawn_campaign(tmp: Path, spacecraft: str = '"any"') -> Path:
    return _write(tmp, DRAWN.format(spacecraft=spacecraft))


def test_the_same_file_draws_the_same_runs(tmp_path: Path) -> None:
    path = _drawn_campaign(tmp_path)
    _, runs = load_campaign(path)
    _, again = load_campaign(path)
    assert [(r.id, r.scenario, r.drawn, r.domains) for r in runs] == \
        [(r.id, r.scenario, r.drawn, r.domains) for r in again]
    assert len({r.drawn["camera.half_angle_deg"] for r in runs}) == len(runs)  # per run


def test_draws_stay_in_their_bounds(tmp_path: Path) -> None:
    _, runs = load_campaign(_drawn_campaign(tmp_path))
    names = ["Svalbard", "Kiruna", "Weilheim", "Perth"]
    for r in runs:
        s, d = r.scenario, r.drawn
        assert isinstance(d["observers.count"], int) and 2 <= s.observers.count <= 6
        assert d["observers.count"] == s.observers.count
        assert 10.0 <= s.camera.half_angle_deg <= 25.0
        assert s.neighbours.enabled is d["neighbours.enabled"]
        stations = [st.name for st in s.ground.stations]
        assert stations == d["ground.stations.names"] and len(stations) == d["ground.stations"]
        assert 1 <= len(stations) <= 3 and len(set(stations)) == len(stations)
        assert stations == sorted(stations, key=names.index)  # in list order
    assert {r.drawn["observers.count"] for r in runs} >= {2, 6}  # both ends reachable
    assert {r.drawn["neighbours.enabled"] for r in runs} == {True, False}


def test_draw_primitives() -> None:
    rng = np.random.default_rng(0)
    assert all(isinstance(v, int) and 2 <= v <= 4
               for v in (Uniform(2, 4, True).draw(rng) for _ in range(50)))
    subset = Choice(tuple("abcde"), Uniform(2, 4, True))
    for _ in range(50):
        picked = subset.draw(rng)
        assert 2 <= len(picked) <= 4 and picked == sorted(set(picked))
    assert Choice((1, 2, 3), 3).draw(rng) == [1, 2, 3]
    assert rng_for("a", "b", 3).random() == rng_for("a/b/3").random()


def test_each_setting_draws_from_its_own_stream() -> None:
    """A setting's draw does not depend on which other settings are drawn."""
    def stream(path: str) -> np.random.Generator:
        return rng_for("c", "g", 0, "setup", path)

    one, two = Record(), Record()
    a = draw_tree(parse_tree({"camera": {"half_angle_deg": {"min": 10.0, "max": 20.0}}}, "o"),
                  stream, one)
    b = draw_tree(parse_tree({"target": {"pois": {"min": 1, "max": 9}},
                              "camera": {"half_angle_deg": {"min": 10.0, "max": 20.0}}}, "o"),
                  stream, two)
    assert a["camera"] == b["camera"] and one.values["camera.half_angle_deg"] == \
        two.values["camera.half_angle_deg"]


def test_set_up_draws_leave_the_fault_draws_alone(tmp_path: Path) -> None:
    """Adding drawn settings to a group changes none of its fault draws."""
    text = DRAWN.format(spacecraft="2")
    _, drawn = load_campaign(_write(tmp_path, text))
    plain = tmp_path / "plain.toml"
    plain.write_text(text[:text.index("[overrides]")] + text[text.index("[[groups]]"):])
    _, fixed = load_campaign(plain)
    assert all(r.drawn == {} for r in fixed if r.group == "n")
    assert [r.scenario.faults for r in drawn] == [r.scenario.faults for r in fixed]


EXPANDED = {"beyond": "13a24b202d18d1e1", "formations": "111c873b91c1bbd7",
            "hard": "3c6f330d195433a1", "identify": "e0f0b8b56893939f",
            "paper": "30a429f35ba4ea2a", "passes": "1039ca13c7f999d3"}
"""A digest of each shipped campaign's runs (ids, groups, the settings each scenario states)
as they expanded before set-ups could be drawn.  A campaign file or a scenario file edited on
purpose changes its digest: recompute it with :func:`_expanded` then."""


def _expanded(runs: list[RunSpec]) -> str:
    h = hashlib.sha256()
    for r in runs:
        h.update(json.dumps([r.id, r.group, r.scenario.model_dump(mode="json",
                                                                  exclude_defaults=True)],
                            sort_keys=True).encode())
    return h.hexdigest()[:16]


@pytest.mark.parametrize("name", sorted(EXPANDED))
def test_the_existing_campaigns_expand_as_before(name: str) -> None:
    _, runs = load_campaign(CAMPAIGNS / f"{name}.toml")
    assert _expanded(runs) == EXPANDED[name]
    assert all(r.drawn == {} for r in runs)


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace("min = 2, max = 6", "min = 6, max = 2"),
     r"^overrides.observers.count: range min 6 exceeds max 2"),
    (lambda t: t.replace("choose = [true, false]", "choose = []"),
     r"overrides.neighbours.enabled.choose: must be a non-empty list"),
    (lambda t: t.replace("count = { min = 1, max = 3 }", "count = 5"),
     r"overrides.ground.stations.count: 5 of a list of 4"),
    (lambda t: t.replace("count = { min = 1, max = 3 }", "count = { min = 0, max = 2 }"),
     r"overrides.ground.stations.count: 0 to 2 of a list of 4"),
    (lambda t: t.replace('name = "f"\n', 'name = "f"\noverrides = { orbit = { raan_degs = '
                         '{ min = 0.0, max = 360.0 } } }\n'),
     r"group f: groups\[0\].overrides.orbit.raan_degs: the scenario has no such setting"),
    (lambda t: t.replace('{ name = "Perth"', '{ nam = "Perth"'),
     r"overrides.ground.stations.choose\[#4\].nam: the scenario has no such setting; did "
     r"you mean 'name'\?"),
    (lambda t: t.replace("camera_degradation = 0.5\n", ""),
     r"magnitude.per_kind has no entry for kind camera_degradation"),
    (lambda t: t.replace('during = ["inspection"]', 'during = ["deployment", "transfer"]'),
     r"run f-0000: no onset phase in this set-up: deployment: the observers start on their "
     r"PROs .*transfer: the scenario has no \[\[phases\]\]"),
    (lambda t: t.replace('base = "base.toml"', 'base = { choose = [] }'),
     r"base.choose: List should have at least 1 item"),
])
def test_bad_draws_are_refused_at_load_naming_them(tmp_path: Path, edit: Any,
                                                   message: str) -> None:
    path = _write(tmp_path, edit(DRAWN.format(spacecraft='"any"')))
    with pytest.raises(CampaignError, match=message):
        load_campaign(path)
    assert run_campaign(["--campaign", str(path), "--out", str(tmp_path / "out")]) == 2
    assert not (tmp_path / "out" / "runs").exists()  # nothing ran


def test_a_spacecraft_above_a_drawn_count_is_refused(tmp_path: Path) -> None:
    with pytest.raises(CampaignError, match=r"groups\[0\].faults\[0\].spacecraft: 4 but "
                                            r"observers.count is drawn from 2"):
        load_campaign(_drawn_campaign(tmp_path, "[1, 4]"))
    _, runs = load_campaign(_drawn_campaign(tmp_path, "2"))
    assert {r.scenario.faults[0].spacecraft for r in runs if r.group == "f"} == {2}


def test_a_run_that_does_not_validate_says_what_it_drew(tmp_path: Path) -> None:
    """Settings each within its own limits, which only some runs' draws make inconsistent: a
    camera's field of view against its pointing margin... here the star tracker's rate, drawn,
    that must divide the high rate."""
    text = DRAWN.format(spacecraft='"any"').replace(
        "[overrides.ground]", "sensors = { star_tracker_hz = { choose = [1.0, 3.0] } }\n"
        "[overrides.ground]")
    with pytest.raises(CampaignError, match=r"run f-\d{4}: invalid scenario: .*"
                                            r"star_tracker_hz = 3.0 must divide .* \(drawn: "
                                            r"observers.count = \d, camera.half_angle_deg = "):
        load_campaign(_write(tmp_path, text))


def test_faults_follow_the_drawn_set_up(tmp_path: Path) -> None:
    _, runs = load_campaign(_drawn_campaign(tmp_path))
    faulty = [r for r in runs if r.group == "f"]
    for r in faulty:
        (f,) = r.scenario.faults
        assert 1 <= f.spacecraft <= r.scenario.observers.count
        assert r.drawn["fault.spacecraft"] == f.spacecraft and r.drawn["fault.kind"] == f.kind
        assert r.drawn["fault.phase"] == "inspection"
        assert any(a <= f.start_s <= b for a, b in phase_spans(r.scenario, "inspection"))
        assert {"thruster_bias": f.magnitude is not None and 0.1 <= f.magnitude <= 0.7,
                "camera_degradation": f.magnitude == 0.5,
                "link_loss": f.magnitude is None}[f.kind]
    assert {r.drawn["fault.kind"] for r in faulty} == {"thruster_bias", "link_loss",
                                                         "camera_degradation"}
    assert all("fault.kind" not in r.drawn and r.scenario.faults == [] for r in runs
               if r.group == "n")


def test_onset_phases_of_the_shipped_scenarios() -> None:
    """Deployment, transfers, holds and the minute after a pass, each ending three FDI
    windows (90 s) before the run's end."""
    default = load_scenario(SCENARIOS / "default.toml")
    assert phase_spans(default, "deployment") == [(0.0, 150.0)]
    assert phase_spans(default, "transfer") == [(150.0, 750.0), (900.0, 1500.0)]
    assert phase_spans(default, "inspection") == [(750.0, 900.0), (1500.0, 2310.0)]
    assert phase_spans(default, "after_pass") == []  # continuous contact
    nominal = load_scenario(SCENARIOS / "nominal.toml")
    assert phase_spans(nominal, "inspection") == [(0.0, 1110.0)]
    assert phase_spans(nominal, "deployment") == phase_spans(nominal, "transfer") == []
    ((a, b),) = phase_spans(load_scenario(SCENARIOS / "passes.toml"), "after_pass")
    assert a == pytest.approx(498.0, abs=1.0) and b == pytest.approx(a + 60.0)


def test_a_passes_run_lasts_until_the_ground_hears_its_fault() -> None:
    """passes.toml's passes: 29-498 s and 5,963-6,367 s.  An onset in the first pass is heard
    in it, until its loss of signal plus three FDI windows (90 s); one after that needs the
    second pass, unless that lengthens the run by more than allowed (then that onset alone is
    left out)."""
    passes = load_scenario(SCENARIOS / "passes.toml")
    short = passes.model_copy(update={"duration_s": 1200.0})
    assert heard_by_s(short, [300.0], 6000.0) == 1200.0
    assert heard_by_s(short, [450.0], 6000.0) == pytest.approx(6367.09 + 90.0, abs=0.5)
    assert heard_by_s(short, [300.0, 600.0], 6000.0) == pytest.approx(6457.1, abs=0.5)
    assert heard_by_s(short, [600.0], 5000.0) == 1200.0  # beyond the allowance
    shorter = passes.model_copy(update={"duration_s": 450.0})  # ends in the first pass
    assert heard_by_s(shorter, [300.0], 6000.0) == pytest.approx(497.99 + 90.0, abs=0.5)
    assert heard_by_s(shorter, [300.0, 600.0], 5000.0) == pytest.approx(588.0, abs=0.5)
    continuous = short.model_copy(update={"ground": short.ground.model_copy(
        update={"contact": "continuous"})})
    assert heard_by_s(continuous, [600.0], 6000.0) == 1200.0


def a_period(runs: list[RunSpec]) -> float:
    """The FDI period the runs share, s."""
    (period,) = {r.scenario.rates.fdi_period_s for r in runs}
    return period


def test_a_campaign_lengthens_its_passes_runs(tmp_path: Path) -> None:
    """``extend_to_pass_s``: a fault run is lengthened as heard_by_s says, recorded as
    ``run.lengthened_s``; nominal runs and runs that need nothing keep their length."""
    text = DRAWN.format(spacecraft='"any"').replace("duration_s = 200.0",
                                                   "duration_s = 200.0\nextend_to_pass_s = 9000.0")
    _, plain = load_campaign(_drawn_campaign(tmp_path))
    _, runs = load_campaign(_write(tmp_path, text))
    margin = WINDOWS_AFTER * a_period(plain)
    for a, b in zip(plain, runs, strict=True):
        need = heard_by_s(a.scenario, [f.start_s for f in a.scenario.faults], 9000.0)
        assert b.scenario.duration_s == pytest.approx(need)
        if need > 200.0:  # on the lengthened run's own pass table: it ends just after the
            # loss of signal of the first pass lasting past the onset, with the dump's margin
            onset = b.scenario.faults[0].start_s
            los = [w.los_s for w in scenario_pass_table(b.scenario) if w.los_s > onset + margin]
            assert los and los[0] + margin == pytest.approx(b.scenario.duration_s, abs=1.0)
        assert b.drawn.get("run.lengthened_s") == (None if need == 200.0
                                                   else pytest.approx(need - 200.0, abs=1e-3))
        assert b.scenario.faults == a.scenario.faults
    assert any("run.lengthened_s" in r.drawn for r in runs)
    assert all(r.scenario.duration_s == 200.0 for r in runs if r.group == "n")


def test_the_fault_spec_accepts_every_drawn_form() -> None:
    spec = FaultSpec.model_validate({
        "spacecraft": "any", "kind": {"choose": ["link_loss", "faulty_data"]},
        "start_s": {"during": ["after_pass"]}, "magnitude": {"per_kind": {"faulty_data": 2.0}}})
    assert spec.needs_setup() and spec.kinds() == ["link_loss", "faulty_data"]
    assert spec.fixed_spacecraft() == []


def test_every_run_records_what_it_drew(tmp_path: Path) -> None:
    """drawn.json beside summary.json; the fingerprint covers it, so a run recorded without it
    (or with another draw) is not taken for finished."""
    from deploy.campaign import record_failure

    _, runs = load_campaign(_drawn_campaign(tmp_path))
    spec, out = runs[0], tmp_path / "out"
    record_failure(spec, str(out), "not flown")
    d = out / "runs" / spec.id
    assert json.loads((d / "drawn.json").read_text()) == {"drawn": spec.drawn,
                                                          "domains": spec.domains}
    assert finished(spec, out) and RunSummary.read(d / "summary.json").status == "failed"
    assert fingerprint(spec) != fingerprint(RunSpec(spec.id, spec.group, spec.scenario))


def test_a_drawn_setting_cannot_be_set_for_every_run(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _drawn_campaign(tmp_path)
    args = ["--campaign", str(path), "--out", str(tmp_path / "o"), "--report-only"]
    assert run_campaign([*args, "--set", "neighbours.enabled=true"]) == 2
    assert "--set neighbours.enabled: the campaign draws this setting" in capsys.readouterr().err
    assert run_campaign([*args, "--set", "fdir.floor=0.05"]) == 0


def test_variants_fly_the_same_drawn_set_up(tmp_path: Path) -> None:
    text = DRAWN.format(spacecraft='"any"') + (
        '[[variants]]\nname = "a"\noverrides = { fdir = { floor = 0.05 } }\n'
        '[[variants]]\nname = "b"\noverrides = { fdir = { floor = 0.06 } }\n')
    _, runs = load_campaign(_write(tmp_path, text))
    by = {r.id: r for r in runs}
    pairs = [(by[r.id], by[r.id.replace("-a-", "-b-")]) for r in runs if "-a-" in r.id]
    assert pairs and all(a.drawn == b.drawn and a.scenario.faults == b.scenario.faults
                         for a, b in pairs)


def test_space_campaign_covers_every_bin_of_every_dimension() -> None:
    """deploy/campaigns/space.toml: at least 300 valid runs (load_campaign validates each),
    faulty and nominal, with a run in every bin of every drawn dimension."""
    campaign, runs = load_campaign(CAMPAIGNS / "space.toml")
    assert campaign.name == "space" and len(runs) >= 300
    assert sum(not r.scenario.faults for r in runs) >= 50
    fake = [CampaignRun(r.id, r.group, "-", RunSummary(scenario=r.id, seed=r.seed,
                                                       status="completed", error=None,
                                                       injected_faults=[]),
                        r.drawn, r.domains) for r in runs]
    domains = campaign_domains(fake)
    assert {"mission", "observers.count", "camera.half_angle_deg", "target.pois",
            "comms.packet_loss", "orbit.raan_deg", "orbit.arg_latitude_deg",
            "neighbours.enabled", "onboard_fdir.enabled", "ground.contact", "ground.stations",
            "fault.kind", "fault.phase"} <= set(domains)
    assert len(domains["fault.kind"]["choose"]) == 8
    for name, domain in domains.items():
        binning = Binning(domain)
        hit = {binning.index(r.drawn[name]) for r in runs if name in r.drawn}
        assert hit == set(range(len(binning.labels()))), name
