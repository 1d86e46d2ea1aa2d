"""The infocost app (fsw/apps/infocost.py) against what the observers share: observations fused
into its map by spacecraft, one telemetry report per FDI window boundary with its H_i as the
map's decomposition gives it (Eq. 8), and observations naming a spacecraft outside the
constellation dropped and counted, not raised."""

from __future__ import annotations

import numpy as np
import pytest

from fsw.apps.infocost import InfoCostApp
from interfaces.contracts.messages import InfoCostTelemetry, Message, PoiObservations
from tests.conftest import app_alone, small_scenario


def _app() -> tuple[InfoCostApp, list[Message]]:
    sc = small_scenario("ic", observers={"count": 2}, rates={"fdi_period_s": 10.0})
    return app_alone(InfoCostApp, sc)


def _obs(sc: int, poi: list[int]) -> PoiObservations:
    return PoiObservations(sender=f"sc{sc}", t_sim=1.0, seq=1, spacecraft=sc, image_t_s=1.0,
                           poi=poi, precision=[0.5] * len(poi))


def test_reports_its_contribution_once_per_window_boundary() -> None:
    app, sent = _app()
    app.on_observations(_obs(1, [1, 2, 3]))
    app.on_observations(_obs(2, [3, 4]))
    for t in (5.0, 10.0, 10.0, 15.0):
        app.step(t)
    reports = [m for m in sent if isinstance(m, InfoCostTelemetry)]
    assert [r.t_sim for r in reports] == [10.0]  # boundary 1 only, once
    h = app.map.contributions()
    assert reports[0].h_i == pytest.approx(float(h[0]))
    assert reports[0].images == 1 and reports[0].shared_received == 1
    assert reports[0].h_local == pytest.approx(reports[0].prior_term + float(h.sum()))


def test_observations_of_a_spacecraft_outside_the_constellation_are_dropped() -> None:
    app, _ = _app()
    before = app.map.F.copy()
    app.on_observations(_obs(5819873, [1]))
    assert app.rejected == 1 and np.array_equal(app.map.F, before)
