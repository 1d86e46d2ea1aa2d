"""The recorder of a one-process run, in a process of its own: the MCAP writing and its
compression leave the simulation loop for the other core.

The run's process prepares each sample (key, type, the JSON bytes it already has, sim time and
sequence from the message: :func:`ground.archive.recorder.prepare_sample`) and sends them in batches
over a pipe; the child hands them to an :class:`ground.archive.recorder.McapRecorder`.  The pipe is
the back-pressure: a writer that falls behind blocks the run, nothing is dropped.

Failure: if the run's process dies, the child reads the end of the pipe, writes what it
received and closes the file (a complete archive up to the last batch sent).  If the child
dies, the next send raises :class:`RecorderDied` with its exit code; the file stays readable
up to its last complete chunk (``harness.archive.reader.load_run``).
"""

from __future__ import annotations

import multiprocessing
import pickle
import signal
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


class RecorderDied(RuntimeError):
    """The recorder process ended before the run closed it."""


def _serve(conn: Connection, path: str, metadata: dict[str, dict[str, str]] | None,
           chunk_size: int) -> None:
    """The child: write every batch until the end-of-run sentinel or the end of the pipe.  It
    ignores SIGINT (Ctrl-C reaches the whole process group): the run decides when it ends."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with McapRecorder(path, metadata, chunk_size=chunk_size) as rec:
        while True:
            try:
                data = conn.recv_bytes()
            except EOFError:  # the run's process is gone: keep what arrived
                break
            if not data:
                break
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
        self._proc.start()
        child_conn.close()
        _widen(self._conn.fileno())
        self._batch: list[Pending] = []
        self._closed = False

    def record_sample(self, sample: Sample) -> None:
        """Queue one bus sample for the archive."""
        self.take(prepared(sample))

    def take(self, pending: Pending) -> None:
        """Queue one sample already prepared (:func:`prepare_sample`)."""
        self._batch.append(pending)
        if len(self._batch) >= BATCH:
            self._send()

    def _send(self) -> None:
        data, self._batch = pickle.dumps(self._batch, protocol=pickle.HIGHEST_PROTOCOL), []
        try:
            self._conn.send_bytes(data)
        except OSError as exc:
            self._proc.join(timeout=5.0)
            raise RecorderDied(f"recorder process ended (exit code {self._proc.exitcode}); "
                               f"the archive holds what it wrote before") from exc

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
        finally:
            self._conn.close()
            self._proc.join()
        if self._proc.exitcode != 0:
            raise RecorderDied(f"recorder process failed (exit code {self._proc.exitcode})")

    def __enter__(self) -> RecorderProcess:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()
