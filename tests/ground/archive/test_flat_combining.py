"""Tests of ground.archive.flat_combining: every item done once, in the order handed in, by
one thread at a time; items handed in during an exclusive block done after it."""

from __future__ import annotations

import threading
from collections import deque

from ground.archive.flat_combining import FlatCombiner


def test_items_from_many_threads_are_all_done_in_order_one_thread_at_a_time() -> None:
    done: list[tuple[int, int]] = []
    inside = threading.Lock()

    def work(pending: deque[tuple[int, int]]) -> None:
        assert inside.acquire(blocking=False), "two threads working at once"
        try:
            while pending:
                done.append(pending.popleft())
        finally:
            inside.release()

    combiner: FlatCombiner[tuple[int, int]] = FlatCombiner(work, max_pending=50)

    def produce(t: int) -> None:
        for i in range(2000):
            combiner.put((t, i))

    threads = [threading.Thread(target=produce, args=(t,)) for t in range(4)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    combiner.drain()
    assert len(done) == 8000
    for t in range(4):
        assert [i for s, i in done if s == t] == list(range(2000))


def test_items_handed_in_during_an_exclusive_block_are_done_after_it() -> None:
    done: list[str] = []

    def work(pending: deque[str]) -> None:
        while pending:
            done.append(pending.popleft())

    combiner: FlatCombiner[str] = FlatCombiner(work, max_pending=10)
    with combiner.exclusive():
        worker = threading.Thread(target=combiner.put_all, args=(["a", "b"],))
        worker.start()
        worker.join()  # the lock was held: left pending
        assert done == [] and list(combiner.pending) == ["a", "b"]
        done.append("block")
    assert done == ["block", "a", "b"]
