"""The heap a run starts with, out of the cyclic collector's reach while the run flies.

A process that starts a run holds some 160,000 objects the collector tracks (modules, pydantic
models, apps, their state) that live to its end.  Every full collection walks them all: on
the default mission in one process a full collection took 91 ms, inside a tick (a cycle slip
that is none of the flight software's doing), and the collector's time was 3 % of the run.
Frozen (``gc.freeze``) as the run starts, they are no longer walked; what the run makes is
collected as before.  Unfrozen at the end, so a process that flies several runs (a campaign's
worker) collects what a finished run left.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def frozen_heap() -> Iterator[None]:
    """While inside, the objects that existed on entry are not walked by the cyclic
    collector (they are still freed by reference counting); on exit they are again."""
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()
