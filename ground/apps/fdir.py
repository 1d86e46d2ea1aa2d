"""Ground FDIR: detect, isolate and identify faulty observers from their information gain
(paper Sec. III.B-E; docs/fdir.md).  The app is the bus adapter of the FDIR pipeline
(``ground/fdir/pipeline.py``, which holds the stages and says what each judges).

Rate group mid. Inputs, each handed to the pipeline: every observer's POI observations (the
images that reached the ground), its transfer plans, its nav, attitude, guidance and H_i
telemetry, its onboard FDIR's events (a camera turned off onboard is expected to send no image),
the ground's own PRO assignments, its own link counters (with ground passes, what each
observer's onboard store lost to overflow, and sent again after a loss), and the faults the
observers' neighbours declared aboard, which it rules on (``NeighbourRuling`` on
``ground/fdir/ruling``). Outputs: one ``FdirWindow`` per observer and FDI window on
``ground/fdir/window``, one ``ConstellationWindow`` per FDI window on
``ground/fdir/constellation``, a ``FaultReport``
on ``ground/fdir/report`` for each fault declared or identified, and with the sequential
test each observer's newest scan statistics as they are scored (``ScanStatus`` on
``ground/fdir/scan``). Each window is judged
``fdir.latency_s`` after it closes."""

from __future__ import annotations

from ground.fdir.pipeline import FdirPipeline
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    ConstellationWindow,
    FaultReport,
    FdirWindow,
    Message,
    NeighbourRuling,
    ScanStatus,
)
from interfaces.runtime.app import App, AppContext, Input, Output


class FdirApp(App):
    NAME = "fdir"
    RATE = "mid"
    INPUTS = (
        Input(cat.OBSERVATIONS, "pipeline.observations", every_spacecraft=True),
        Input(cat.TRANSFER_PLAN, "pipeline.transfer", every_spacecraft=True),
        Input(cat.ASSIGNMENTS, "pipeline.assignments"),
        Input(cat.ATTITUDE_ESTIMATE, "pipeline.attitude", every_spacecraft=True),
        Input(cat.INFO_COST, "pipeline.telemetry", every_spacecraft=True),
        Input(cat.NAV_ESTIMATE, "pipeline.nav", every_spacecraft=True),
        Input(cat.GUIDANCE_STATUS, "pipeline.guidance", every_spacecraft=True),
        Input(cat.FDIR_EVENT, "pipeline.onboard", every_spacecraft=True),
        Input(cat.LINK_STATS, "pipeline.link_stats"),
        Input(cat.NEIGHBOUR_DECLARATION, "pipeline.neighbours", every_spacecraft=True),
    )
    OUTPUTS = (Output("window", cat.FDIR_WINDOW), Output("report", cat.FAULT_REPORT),
               Output("constellation", cat.CONSTELLATION_WINDOW),
               Output("ruling", cat.NEIGHBOUR_RULING), Output("scan", cat.SCAN_STATUS))
    CRITICAL = ("pipeline",)
    PORTS: dict[type[Message], str] = {FdirWindow: "window", FaultReport: "report",
                                        ConstellationWindow: "constellation",
                                        NeighbourRuling: "ruling", ScanStatus: "scan"}
    """the output each of the pipeline's messages goes out on"""

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        self.pipeline = FdirPipeline(ctx.scenario, ctx.constants, ctx.node, self.log)

    def step(self, t: float) -> None:
        for msg in self.pipeline.due(t):
            self.publish(self.PORTS[type(msg)], msg)
