"""The one-process run's tap into its recorder, guarded: a recorder that fails (a full disk, a
recorder process that died) stops the run at the next tick instead of raising into the app
whose message it was recording (where the executive would count it as that app's failure and
the run would fly on unrecorded).  The run then ends ``failed`` with the recorder's cause, and
its summary is read from what the archive holds."""

from __future__ import annotations

import threading
from collections.abc import Callable

from deploy.disk_space import is_disk_full
from interfaces.runtime.transport import Sample

DISK_FULL = "disk full"
"""How the cause of a run stopped by a full disk begins (the launcher's and the campaign's
test for a fault of the host, not of the run)."""


def disk_full_cause(error: str | None) -> bool:
    """Whether a run's error says its disk was full."""
    return error is not None and error.startswith(DISK_FULL)


class RecorderGuard:
    """A sample handler giving each sample to ``record`` until it first fails; then ``stop``
    is set and every later sample dropped.  ``cause`` says what failed, when (sim time)."""

    def __init__(self, record: Callable[[Sample], None], stop: threading.Event) -> None:
        self._record, self._stop = record, stop
        self.error: BaseException | None = None
        self._t_sim_s: float | None = None

    def __call__(self, sample: Sample) -> None:
        if self.error is not None:
            return
        try:
            self._record(sample)
        except Exception as e:  # noqa: BLE001 - never into the publishing app: the run stops
            self.error = e
            self._t_sim_s = sample.message.t_sim if sample.message is not None else None
            self._stop.set()

    @property
    def cause(self) -> str | None:
        """The recorder's failure in one line (None: it did not fail): "disk full at t = ..."
        for a full disk."""
        if self.error is None:
            return None
        t = getattr(self.error, "t_sim_s", None) or self._t_sim_s
        when = f" at t = {t:.1f} s" if t is not None else ""
        if is_disk_full(self.error) or getattr(self.error, "disk_full", False):
            return (f"{DISK_FULL}{when}: the recorder could not write the archive, which "
                    "holds the run up to its last complete chunk")
        return f"the recorder failed{when}: {self.error}"
