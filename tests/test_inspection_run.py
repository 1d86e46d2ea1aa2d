"""Inspection in a real (in-process) run: images become observations, observers share them only
within communication range, H_i telemetry decomposes H exactly, and the cost goes down."""

from __future__ import annotations

from deploy.inproc import run_inproc
from interfaces.messages import InfoCostTelemetry, LinkStats
from tests.conftest import small_scenario


def test_observations_are_shared_only_in_range_and_h_decomposes() -> None:
    # Two observers half an orbit apart in phase on 20 m / 25 m PROs: their distance swings
    # from 80 m at t = 0 down to 77 m at 400 s: with a 79 m range the link opens at ~240 s.
    sc = small_scenario("insp", duration_s=400.0, observers={"count": 2},
                        comms={"range_m": 79.0}, rates={"fdi_period_s": 100.0},
                        target={"pois": 1000})
    telemetry: list[InfoCostTelemetry] = []
    links: dict[float, LinkStats] = {}

    def tap(key: str, type_name: str, payload: bytes) -> None:
        if type_name == "InfoCostTelemetry":
            telemetry.append(InfoCostTelemetry.model_validate_json(payload))
        elif type_name == "LinkStats" and key.startswith("insp/insp/sc/1/"):
            m = LinkStats.model_validate_json(payload)
            links[m.t_sim] = m

    run_inproc(sc, tap=tap)
    mine = [m for m in telemetry if m.spacecraft == 1]
    last = mine[-1]
    counter = next(c for c in links[last.t_sim].links if c.src == "sc2")
    # every observation sc2 shared that reached sc1 was fused, and only those
    assert last.shared_received == counter.delivered
    assert counter.delivered > 0 and counter.dropped_range > 0
    for m in telemetry:  # Eq. 8: H = prior term + Σ H_j, to round-off
        assert abs(m.h_local - m.prior_term - sum(m.contributions.values())) < 1e-12
    h = [m.h_local for m in mine]
    assert abs(h[0] - 1.0) < 1e-12 and all(b <= a for a, b in zip(h, h[1:])) and h[-1] < 0.95
