"""A run's disk space: checked before it starts, and a reserve that its summary is written into.

A full disk must not cost a run its results.  Before a run starts, the free space of its
``--out`` is checked against the archive the run will write (:func:`estimate_archive_bytes`,
an upper estimate from the scenario's size), and a run that cannot fit is refused with the
figures (:class:`DiskSpaceError`).  While the run goes, :class:`Reserve` holds
:data:`RESERVE_BYTES` of that disk in a file of its own, released just before the summary,
the layout and the report are written: a disk filled by the archive (or by anything else on
the machine) still takes them.  A run whose recorder meets a full disk ends ``failed`` with
"disk full at t = ... s" and an archive that replays to that point (``ground/archive``).
"""

from __future__ import annotations

import errno
import os
import shutil
from dataclasses import dataclass
from pathlib import Path

from interfaces.contracts.scenario import Scenario

RESERVE_BYTES = 8_000_000
"""Disk held back for the summary, the layout and the report (the default run's take about
1 MB: summary.json 56 kB, the plots 0.6 MB; a 64-observer report a few times that)."""
RESERVE_NAME = ".disk-reserve"
"""The reserve's file in the run's folder (removed once the run is written)."""
BYTES_PER_HIGH_TICK = 90.0
"""Archive bytes per observer per ω_high tick: attitude measurements, wheel commands, the
lockstep's answers, compressed.  This and the next two are fitted to three in-process runs
(bytes per observer per simulated second): the default mission's first 600 s (5 observers,
5,000 POIs, 10 Hz: 8,680), 3 observers with 1,000 POIs at 5 Hz (4,150) and 8 observers with
20,000 POIs at 10 Hz (23,960), each 300 s; the fit is within 1 % of each."""
BYTES_PER_MID_TICK = 2700.0
"""Archive bytes per observer per ω_mid tick apart from the images' per-POI part: navigation,
telemetry, truth, statistics, the ground's products (fitted as above)."""
BYTES_PER_POI_IMAGE = 1.0
"""Archive bytes per POI of the target per observer per ω_mid tick: the camera images and the
observations that repeat them (fitted as above)."""
MARGIN = 1.25
"""The estimate's margin over the fitted rates (other phases, other geometries): an estimate
runs about 25 % above what a run writes."""


_CHUNK = 1 << 20
"""What a reserve takes at a time when the disk has less than it asks (bytes)."""


class DiskSpaceError(OSError):
    """The run's folder has too little free space; the message gives the figures."""


def estimate_archive_bytes(scenario: Scenario) -> int:
    """An upper estimate of the archive a run of ``scenario`` writes, bytes: the observers'
    streams at their rates (:data:`BYTES_PER_HIGH_TICK`, :data:`BYTES_PER_MID_TICK`,
    :data:`BYTES_PER_POI_IMAGE`) over its duration, with :data:`MARGIN`."""
    rates = scenario.rates
    per_observer_s = (BYTES_PER_HIGH_TICK * rates.high_hz
                      + (BYTES_PER_MID_TICK + BYTES_PER_POI_IMAGE * scenario.target.pois)
                      * rates.mid_hz)
    return round(MARGIN * scenario.observers.count * per_observer_s * scenario.duration_s)


def free_bytes(folder: Path) -> int:
    """Free space on the disk of ``folder`` (or its nearest existing parent), bytes, for this
    user."""
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    return shutil.disk_usage(folder).free


def megabytes(n: float) -> str:
    """``n`` bytes as MB (10^6), for messages."""
    return f"{n / 1e6:,.0f} MB" if n >= 1e7 else f"{n / 1e6:.1f} MB"


def check_space(out: Path, scenario: Scenario, option: str = "--out") -> int:
    """Refuse a run that cannot fit in ``out`` (DiskSpaceError naming ``option``, the free
    space, the estimate and what it rests on); the estimate, bytes, when it fits."""
    need = estimate_archive_bytes(scenario) + RESERVE_BYTES
    free = free_bytes(out)
    if free < need:
        raise DiskSpaceError(
            errno.ENOSPC,
            f"{option} {out} has {megabytes(free)} free; the run needs about {megabytes(need)} "
            f"(its archive, {scenario.observers.count} observers for {scenario.duration_s:g} s, "
            f"and {megabytes(RESERVE_BYTES)} for its summary and report): free some space, "
            "shorten the run (--duration), or give another --out")
    return need


def is_disk_full(error: BaseException | None) -> bool:
    """Whether ``error`` (or what caused it) is the disk being full."""
    while error is not None:
        if isinstance(error, OSError) and error.errno in (errno.ENOSPC, errno.EDQUOT):
            return True
        error = error.__cause__ or error.__context__
    return False


def disk_full_logged(log_tail: str) -> bool:
    """Whether a process's last log lines say it met a full disk (ENOSPC, EDQUOT)."""
    return any(text in log_tail for text in ("No space left on device", "Disk quota exceeded",
                                             "[Errno 28]", "[Errno 122]"))


@dataclass
class Reserve:
    """:data:`RESERVE_BYTES` held in ``<folder>/.disk-reserve`` until :meth:`release`; a disk
    too full to hold it holds what it can (see the module docstring)."""

    folder: Path
    nbytes: int = RESERVE_BYTES

    def __post_init__(self) -> None:
        self.path = self.folder / RESERVE_NAME
        try:
            with open(self.path, "wb", buffering=0) as f:
                try:
                    os.posix_fallocate(f.fileno(), 0, self.nbytes)
                except OSError:  # all or nothing: take what the disk has, a chunk at a time
                    for _ in range(0, self.nbytes, _CHUNK):
                        f.write(bytes(_CHUNK))
        except OSError:
            pass  # the disk is full: what is held is released all the same

    def release(self) -> None:
        """Give the space back (idempotent)."""
        self.path.unlink(missing_ok=True)

    def __enter__(self) -> Reserve:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()
