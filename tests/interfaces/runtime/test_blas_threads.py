"""One BLAS thread per process (``interfaces.runtime.blas_threads``): numpy's and scipy's
libraries both limited, from any number of threads."""

from __future__ import annotations

from threadpoolctl import threadpool_info, threadpool_limits

from interfaces.runtime.blas_threads import one_blas_thread


def _blas_threads() -> list[int]:
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


def test_every_blas_library_runs_on_one_thread() -> None:
    threadpool_limits(limits=2, user_api="blas")  # as a 2-core machine starts them
    assert set(_blas_threads()) == {2}
    one_blas_thread()
    assert len(_blas_threads()) >= 2  # numpy's and scipy's own (the wheels ship one each)
    assert set(_blas_threads()) == {1}
    one_blas_thread()  # again: no change
    assert set(_blas_threads()) == {1}
