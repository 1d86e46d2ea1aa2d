"""The heap a run starts with, frozen while it flies (interfaces/runtime/heap.py): not walked
by the cyclic collector inside, collected again after; what the run makes is collected as
usual."""

from __future__ import annotations

import gc
import weakref

from interfaces.runtime.heap import frozen_heap


class _Cycle:
    def __init__(self) -> None:
        self.me = self


def test_the_start_is_frozen_the_run_is_collected_and_all_is_again_after() -> None:
    before = _Cycle()
    was = weakref.ref(before)
    del before  # garbage, held by its own cycle: only the collector frees it
    with frozen_heap():
        assert gc.get_freeze_count() > 0
        made = _Cycle()
        made_ref = weakref.ref(made)
        del made
        gc.collect()
        assert made_ref() is None  # made during the run: collected as usual
        assert was() is not None  # frozen at the start: not walked
    assert gc.get_freeze_count() == 0
    gc.collect()
    assert was() is None
