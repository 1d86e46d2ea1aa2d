"""A campaign's Dask cluster (``--cluster tcp://HOST:PORT``): the client connected within a
stated time, or a :class:`ClusterError` that says so (issue 40: not a traceback after 30 s)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

CONNECT_TIMEOUT_S = 30.0
"""How long a scheduler has to answer, s."""


class ClusterError(RuntimeError):
    """No Dask scheduler answered; the message names the address and the time waited."""


@contextmanager
def dask_client(address: str, timeout_s: float | None = None) -> Iterator[Any]:
    """A ``distributed.Client`` of the scheduler at ``address`` (answering within
    ``timeout_s``, default ``CONNECT_TIMEOUT_S``), closed on leaving."""
    from distributed import Client

    timeout_s = CONNECT_TIMEOUT_S if timeout_s is None else timeout_s
    try:
        client = Client(address, timeout=f"{timeout_s}s")
    except (OSError, TimeoutError, ValueError) as e:
        raise ClusterError(f"--cluster {address}: no Dask scheduler answered within "
                           f"{timeout_s:g} s ({type(e).__name__}: {e})") from None
    with client:
        yield client
