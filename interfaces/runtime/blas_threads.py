"""One BLAS thread per process: what every run sets before it flies (issue 42;
docs/architecture.md, "Runtime model").

numpy's and scipy's OpenBLAS start as many threads as the machine has cores, and split a
product such as the hardware threshold's (96 × 5,000) @ (5,000,) between them.  The runtime's
products are small and come between other work, so the helper threads have gone to sleep each
time and must be woken: on a 2-core machine shared with the run's other processes, that matrix-
vector product took 3.6 ms where one thread takes 0.1 ms (``benchmarks/tick_budget.py``
names the FDIR's share).  The runtime's parallelism is its processes (the nodes, the
campaign's workers), not threads within one.

With one thread, a product's rounding also no longer depends on how many cores the machine
has: the same scenario and seed give the same bits on a laptop and on a 64-core host.
"""

from __future__ import annotations

import numpy  # noqa: F401 - loads numpy's BLAS, to be limited
import scipy.linalg  # noqa: F401 - loads scipy's own BLAS, likewise
from threadpoolctl import threadpool_limits


def one_blas_thread() -> None:
    """Limit the BLAS libraries of this process (numpy's and scipy's, loaded by this module's
    imports) to one thread each, for the rest of the process's life."""
    threadpool_limits(limits=1, user_api="blas")
