"""Message bytes (interfaces/runtime/encoding.py) in a real (in-process) run: every message type
a run publishes, and those it does not, encoded as pydantic does, and the Bus's own bytes."""

from __future__ import annotations

from deploy.inproc import run_inproc
from interfaces.contracts.messages import (
    AssignmentDecision,
    FaultReport,
    Message,
    NeighbourDeclaration,
    NeighbourRuling,
    OnboardCommand,
    OnboardFdirEvent,
    ScanStatus,
    registry,
)
from interfaces.runtime.encoding import encode
from interfaces.runtime.transport import Sample
from tests.conftest import small_scenario
from tests.interfaces.runtime.test_encoding import _pydantic


def test_every_message_type_of_a_run_is_encoded_as_pydantic_does() -> None:
    """A short run with faults, FDIR windows and the neighbours' FDIR (its judgements, and the
    pose with every observation): every message it publishes, then the types it does not (a
    fault report, an assignment decision, the onboard FDIR's command and event, a neighbours'
    declaration, the ground's ruling and the sequential test's statistics)."""
    scenario = small_scenario(
        "enc", duration_s=100.0, rates={"fdi_period_s": 10.0}, neighbours={"enabled": True},
        faults=[{"spacecraft": 1, "kind": "pointing_actuator", "start_s": 5.0, "magnitude": 20.0},
                {"spacecraft": 2, "kind": "thruster_bias", "start_s": 5.0, "magnitude": 0.5}],
        phases=[{"name": "p", "start_s": 1.0, "transfer_s": 30.0}])
    samples: list[Sample] = []
    run_inproc(scenario, sample_tap=samples.append)
    extra: list[Message] = [
        FaultReport(sender="ground", t_sim=40.0, spacecraft=2, fault_class="actuator",
                    direction="degraded", metric=0.3, threshold=0.01, window_end_s=40.0,
                    evidence={"dv_rate": 1.5e-5, "beta": 0.98}),
        AssignmentDecision(sender="ground", t_sim=900.0, phase="inspection", reason="saturated",
                           library_indices=[3, -1, 17], expected_gain=0.25, upper_bound=0.5,
                           ratio_bound=0.5, current_gain=None, measured_gains=[0.1, 2e-9],
                           switched=True),
        OnboardCommand(sender="sc2", t_sim=40.1, spacecraft=2, command="safe_hold",
                       sequence="safe_hold", assignment_id=3),
        OnboardFdirEvent(sender="sc2", t_sim=40.1, spacecraft=2, event="trip",
                         name="pointing_deg", value=2.25, limit=1.0, fault_class="actuator",
                         detail="action request_plan"),
        NeighbourDeclaration(sender="sc1", t_sim=64.0, spacecraft=1, subject=2, t_start_s=30.0,
                             t_end_s=60.0, judges=[1, 3], decided=[1, 3, 4]),
        NeighbourRuling(sender="ground", t_sim=90.0, subject=2, window_end_s=60.0,
                        verdict="upheld"),
        ScanStatus(sender="ground", t_sim=41.0, spacecraft=2, image_z=3.2, image_threshold=5.3,
                   nis_z=None, nis_threshold=5.17),
    ]
    messages = [s.message for s in samples if s.message is not None] + extra
    assert {type(m).__name__ for m in messages} == set(registry())  # every type is here
    for msg in messages:
        assert encode(msg) == _pydantic(msg), type(msg).__name__
    assert all(s.payload == _pydantic(s.message) for s in samples[:2000])  # the Bus's bytes
