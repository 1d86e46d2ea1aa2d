"""Fault injection in a real (in-process) run: the truth of every fault is archived, and the
hardware, link and software faults act where they should."""

from __future__ import annotations

from deploy.inproc import run_inproc
from interfaces.contracts.messages import FaultEvent, InfoCostTelemetry, LinkStats, TruthState
from tests.conftest import collector, small_scenario


def test_faults_act_and_their_truth_is_published() -> None:
    sc = small_scenario("flt", duration_s=200.0, target={"pois": 500},
                        rates={"fdi_period_s": 20.0},
                        faults=[{"spacecraft": 1, "kind": "thruster_bias", "start_s": 50.0,
                                 "magnitude": 0.2},
                                {"spacecraft": 2, "kind": "faulty_data", "start_s": 0.0,
                                 "magnitude": 2.0},
                                {"spacecraft": 3, "kind": "link_loss", "start_s": 100.0,
                                 "end_s": 150.0}])
    tap, got = collector(FaultEvent, InfoCostTelemetry, TruthState, LinkStats,
                         key_prefix={"LinkStats": "insp/flt/ground/"})
    run_inproc(sc, tap=tap)
    events, telemetry = got["FaultEvent"], got["InfoCostTelemetry"]
    truth, ground_links = got["TruthState"], got["LinkStats"]
    assert [(e.spacecraft, e.kind, e.active, e.t_sim) for e in events] == [
        (2, "faulty_data", True, 0.0), (1, "thruster_bias", True, 50.0),
        (3, "link_loss", True, 100.0), (3, "link_loss", False, 150.0)]
    # faulty data: the reported H_i is twice what the same message's own fused view gives
    mine = [m for m in telemetry if m.spacecraft == 2 and m.h_i > 0.0]
    assert mine and all(abs(m.h_i - 2.0 * m.contributions["2"]) <= 1e-12 * m.h_i for m in mine)
    others = [m for m in telemetry if m.spacecraft == 1 and m.h_i > 0.0]
    assert others and all(m.h_i == m.contributions["1"] for m in others)
    # thruster bias: a continuous force, so the truth Δv of sc1 grows at least at its rate
    force = events[1].detail["force_body_n"]
    assert isinstance(force, list)
    by_t = {round(m.t_sim, 6): m for m in truth}
    spent = by_t[200.0].dv_mps[0] - by_t[50.0].dv_mps[0]
    assert spent >= sum(abs(f) for f in force) * 150.0 / sc.observers.mass_kg * (1 - 1e-9)
    # link loss: sc3's traffic to the ground was cut during the fault, and only then
    cut = next(c for c in ground_links[-1].links if c.src == "sc3")
    assert cut.dropped_cut > 0
    assert all(c.dropped_cut == 0 for c in ground_links[-1].links if c.src != "sc3")
    before = next(m for m in ground_links if m.t_sim >= 99.0)
    assert next(c for c in before.links if c.src == "sc3").dropped_cut == 0
