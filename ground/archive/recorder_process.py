"""The recorder of a one-process run, in a process of its own: the MCAP writing and its
compression leave the simulation loop for the other core.

The run's process prepares each sample (key, type, the JSON bytes it already has, sim time and
sequence from the message: :func:`ground.archive.recorder.prepare_sample`) and sends them in batches
over a pipe; the child hands them to an :class:`ground.archive.recorder.McapRecorder`.  The pipe is
the back-pressure: a writer that falls behind blocks the run, nothing is dropped.

Signals: the child is shielded from the signals that stop a run (SIGINT, SIGTERM, SIGHUP), and
sits in a session of its own, so a signal to the run's whole process group (Ctrl-C, ``timeout``,
Slurm's ``scancel``, systemd) reaches the run alone: the run decides when the archive ends,
and closes it with its footer.  The signals are blocked while the child starts, so not even its
first instant is exposed.

Failure: if the run's process dies, the child reads the end of the pipe, writes what it
received and closes the file (a complete archive up to the last batch sent).  If the child
dies, the next send raises :class:`RecorderDied` with the cause; the file stays readable up to
its last complete chunk (``harness.archive.reader.load_run``).  A full disk ends the child with
:data:`DISK_FULL_EXIT` (the cause then says "disk full" and the sim time of the last sample
handed over, :attr:`RecorderProcess.t_last_s`); any other failure to write, with 1 and one
line on stderr.
"""

from __future__ import annotations

import errno
import multiprocessing
import os
import pickle
import signal
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from multiprocessing.connection import Connection
from pathlib import Path
from types import TracebackType

from ground.archive.recorder import McapRecorder, Pending, prepared
from interfaces.runtime.transport import Sample

BATCH = 1024
"""Samples per message on the pipe (about 0.3 MB of JSON at the default scenario's mix)."""
PIPE_BYTES = 1 << 20
"""Capacity asked for the pipe (Linux ``F_SETPIPE_SZ``; 1 MiB is the default ceiling): a whole
batch fits, so sending it is a copy, not a wait for the child to read (64 KiB by default)."""
_F_SETPIPE_SZ = 1031


SHIELDED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
"""The signals that stop a run: the run's, never the recorder's (module docstring)."""
DISK_FULL_EXIT = 28
"""The child's exit code when the disk is full (ENOSPC's number)."""


class RecorderDied(RuntimeError):
    """The recorder process ended before the run closed it; ``disk_full`` when it ran out of
    disk space, ``t_sim_s`` the sim time (s) of the last sample handed to it (None: none)."""

    def __init__(self, message: str, disk_full: bool = False,
                 t_sim_s: float | None = None) -> None:
        super().__init__(message)
        self.disk_full, self.t_sim_s = disk_full, t_sim_s


@contextmanager
def _blocked(signals: tuple[signal.Signals, ...]) -> Iterator[None]:
    """``signals`` blocked in this thread for the block: a child started meanwhile inherits
    the mask, and a signal that comes is delivered here at the end, not lost."""
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, signals)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


@contextmanager
def _main_left_behind() -> Iterator[None]:
    """A child spawned in the block does not import the parent's main module: a fresh
    interpreter runs the parent's script again up to its ``__main__`` guard (the launcher's
    imports, about a second of CPU the run needs), where the recorder needs this module
    alone.  ``multiprocessing``'s spawn reads the main module's ``__spec__`` and ``__file__``
    when the child starts; they are hidden for that instant."""
    main = sys.modules["__main__"]
    saved = {a: main.__dict__[a] for a in ("__spec__", "__file__") if a in main.__dict__}
    main.__dict__.pop("__file__", None)
    main.__spec__ = None
    try:
        yield
    finally:
        main.__dict__.update(saved)
        if "__spec__" not in saved:
            del main.__spec__


def _shield() -> None:
    """In the child, first: a session of its own, the run's signals ignored, then unblocked
    (what came while blocked is discarded)."""
    os.setsid()
    for s in SHIELDED:
        signal.signal(s, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, SHIELDED)


def _serve(conn: Connection, path: str, metadata: dict[str, dict[str, str]] | None,
           chunk_size: int) -> None:
    """The child: write every batch until the end-of-run sentinel or the end of the pipe,
    shielded from the run's signals (module docstring).  A write that fails ends it with one
    line on stderr and :data:`DISK_FULL_EXIT` (a full disk) or 1."""
    _shield()
    try:
        with McapRecorder(path, metadata, chunk_size=chunk_size) as rec:
            _record_all(conn, rec)
    except OSError as e:
        print(f"recorder: cannot write {path}: {e.strerror or e}", file=sys.stderr)
        sys.exit(DISK_FULL_EXIT if e.errno == errno.ENOSPC else 1)


def _record_all(conn: Connection, rec: McapRecorder) -> None:
    """Every batch from ``conn`` into ``rec``, until the sentinel or the end of the pipe."""
    while True:
        try:
            data = conn.recv_bytes()
        except EOFError:  # the run's process is gone: keep what arrived
            return
        if not data:
            return
        rec.record_prepared(pickle.loads(data))


def _widen(fd: int) -> None:
    """Ask for a pipe of ``PIPE_BYTES`` (Linux; elsewhere, or when refused, it stays as it is)."""
    try:
        import fcntl

        fcntl.fcntl(fd, _F_SETPIPE_SZ, PIPE_BYTES)
    except (ImportError, OSError):
        pass


class RecorderProcess:
    """An :class:`~ground.archive.recorder.McapRecorder` in a child process (see the module
    docstring); use as a context manager or call :meth:`close`."""

    def __init__(self, path: str | Path, metadata: dict[str, dict[str, str]] | None = None,
                 chunk_size: int = 4 * 1024 * 1024) -> None:
        ctx = multiprocessing.get_context("spawn")  # a fresh interpreter: no inherited state
        self._conn, child_conn = ctx.Pipe(duplex=False)[::-1]
        self._proc = ctx.Process(target=_serve, args=(child_conn, str(path), metadata, chunk_size),
                                 name="recorder", daemon=True)
        with _blocked(SHIELDED), _main_left_behind():
            self._proc.start()
        child_conn.close()
        _widen(self._conn.fileno())
        self._batch: list[Pending] = []
        self._closed = False
        self.t_last_s: float | None = None
        """Sim time (s) of the last sample sent to the child with a sim time (None: none
        yet): where a child that died stopped, within a batch."""

    def record_sample(self, sample: Sample) -> None:
        """Queue one bus sample for the archive."""
        self.take(prepared(sample))

    def take(self, pending: Pending) -> None:
        """Queue one sample already prepared (:func:`prepare_sample`)."""
        self._batch.append(pending)
        if len(self._batch) >= BATCH:
            self._send()

    def _send(self) -> None:
        self.t_last_s = next((p[5] * 1e-9 for p in reversed(self._batch) if p[5] is not None),
                             self.t_last_s)  # once a batch, not once a sample
        data, self._batch = pickle.dumps(self._batch, protocol=pickle.HIGHEST_PROTOCOL), []
        try:
            self._conn.send_bytes(data)
        except OSError as exc:
            self._proc.join(timeout=5.0)
            raise self._died("ended") from exc

    def _died(self, how: str) -> RecorderDied:
        """The error of a child that ended before the run closed it, naming the cause."""
        code, t = self._proc.exitcode, self.t_last_s
        when = f"t = {t:.1f} s" if t is not None else "the start"
        if code == DISK_FULL_EXIT:
            return RecorderDied(f"disk full at {when}: the archive holds what was written before",
                                disk_full=True, t_sim_s=t)
        cause = (f"killed by {signal.Signals(-code).name}" if code is not None and code < 0
                 else f"exit code {code}")
        return RecorderDied(f"the recorder process {how} at {when} ({cause}); the archive holds "
                            "what it wrote before", t_sim_s=t)

    def close(self) -> None:
        """Send what is queued, let the child finish the file, and wait for it (idempotent);
        :class:`RecorderDied` if it failed."""
        if self._closed:
            return
        self._closed = True
        try:
            if self._batch:
                self._send()
            self._conn.send_bytes(b"")
        except (OSError, RecorderDied):
            pass  # the child is gone: its exit code, below, says why
        finally:
            self._conn.close()
            self._proc.join()
        if self._proc.exitcode != 0:
            raise self._died("failed")

    def __enter__(self) -> RecorderProcess:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()
