"""When injected faults act (faults/schedule.py): a hardware or software fault switches on the
tick at its start and off the tick at its end, whatever the tick time's rounding; every kind
acts in exactly one place."""

from __future__ import annotations

from faults.schedule import HARDWARE_KINDS, LINK_KINDS, SOFTWARE_KINDS, switched_on
from interfaces.contracts.scenario import Fault


def test_every_fault_kind_acts_in_exactly_one_place() -> None:
    kinds = set(Fault.model_fields["kind"].annotation.__args__)  # type: ignore[union-attr]
    places = (HARDWARE_KINDS, LINK_KINDS, SOFTWARE_KINDS)
    assert set().union(*places) == kinds
    assert sum(len(p) for p in places) == len(kinds)


def test_a_switch_falls_on_the_tick_at_its_time_despite_rounding() -> None:
    f = Fault(spacecraft=1, kind="camera_degradation", start_s=0.8, end_s=1.0, magnitude=0.5)
    tick = [sum([0.1] * k) for k in range(13)]  # accumulated: 0.7999999999999999 at k = 8
    assert tick[8] < 0.8 and tick[10] < 1.0
    assert [k for k, t in enumerate(tick) if switched_on(f, t)] == [8, 9]

