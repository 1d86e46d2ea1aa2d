"""Supervision of the constellation's OS processes: start, watch, stop, report deaths."""

from __future__ import annotations

import ctypes
import os
import re
import signal
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from deploy.rehearsal.netns import Entry, libc

_PR_SET_PDEATHSIG = 1
ANSI_ESCAPE = re.compile(r"\x1b\[[0-9;?]*[ -/]*[@-~]")
"""A terminal control sequence (colours, styles)."""


def die_with_parent(library: ctypes.CDLL | None = None) -> None:
    """In the child before exec (Linux): get SIGTERM when the launcher dies, however it dies
    (even SIGKILL), so no orphan keeps a port or a key space busy.  ``library``: the C library
    loaded in the parent (else loaded here)."""
    (library or libc()).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)


@dataclass
class Child:
    """One supervised process, its output going to ``log_path``."""

    name: str
    argv: list[str]
    log_path: Path
    netns: str | None = None
    """the network namespace it runs in (a rehearsed host's: ``deploy/rehearsal``), or None"""
    proc: subprocess.Popen[bytes] | None = None
    _log: IO[bytes] | None = None

    def start(self, cwd: Path) -> None:
        self.log_path.parent.mkdir(parents=True, exist_ok=True)
        self._log = self.log_path.open("wb")
        library = libc()
        entry = Entry.open(self.netns, library) if self.netns is not None else None

        def prepare() -> None:
            """In the child before exec: die with the launcher, enter its host's network."""
            die_with_parent(library)
            if entry is not None:
                entry.enter()

        try:
            self.proc = subprocess.Popen(
                [sys.executable, *self.argv], cwd=cwd, stdout=self._log,
                stderr=subprocess.STDOUT,
                start_new_session=True,  # a Ctrl-C at the launcher does not hit children
                preexec_fn=prepare if sys.platform.startswith("linux") else None,
            )
        finally:
            if entry is not None:
                entry.close()

    @property
    def returncode(self) -> int | None:
        return None if self.proc is None else self.proc.poll()

    def signal(self, sig: int) -> None:
        if self.proc is not None and self.proc.poll() is None:
            try:
                self.proc.send_signal(sig)
            except ProcessLookupError:
                pass

    def wait(self, timeout_s: float) -> int | None:
        if self.proc is None:
            return None
        try:
            return self.proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            return None

    def stop(self, timeout_s: float = 5.0) -> int | None:
        """SIGINT, then SIGTERM, then SIGKILL, each given ``timeout_s`` to work."""
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL):
            if self.returncode is not None:
                break
            self.signal(sig)
            self.wait(timeout_s)
        self.close_log()
        return self.returncode

    def close_log(self) -> None:
        if self._log is not None:
            self._log.close()
            self._log = None

    def describe_exit(self) -> str:
        code = self.returncode
        if code is None:
            return "still running"
        if code < 0:
            try:
                return f"killed by {signal.Signals(-code).name}"
            except ValueError:
                return f"killed by signal {-code}"
        return f"exited with code {code}"

    def log_tail(self, lines: int = 15) -> str:
        """The last ``lines`` of its log, without terminal colour codes (Zenoh's logger
        colours its lines), for errors, summaries and reports."""
        try:
            text = self.log_path.read_text(errors="replace").splitlines()
        except OSError:
            return ""
        return ANSI_ESCAPE.sub("", "\n".join(text[-lines:]))


@dataclass
class Incident:
    """A process that stopped before the end of the run: which, how, when (sim time, s), and
    whether it was started again."""

    node: str
    what: str
    t_sim: float
    restarted: bool
    came_back: str = ""
    """How the restarted process came back (``StartRecord.describe``), once known."""

    def __str__(self) -> str:
        return (f"{self.node} {self.what} at t≈{self.t_sim:.1f} s"
                + (f" (restarted: {self.came_back})" if self.came_back else
                   " (restarted)" if self.restarted else ""))


@dataclass
class Supervisor:
    """Starts, restarts and stops children."""

    cwd: Path
    children: list[Child] = field(default_factory=list)

    def start(self, child: Child) -> Child:
        child.start(self.cwd)
        self.children.append(child)
        return child

    def restart(self, child: Child, attempt: int) -> Child:
        """Start ``child``'s command again (its log continues in ``<name>.restart<N>.log``)."""
        child.close_log()
        again = Child(child.name, child.argv,
                      child.log_path.with_name(f"{child.name}.restart{attempt}.log"), child.netns)
        self.children[self.children.index(child)] = again
        again.start(self.cwd)
        return again

    def named(self, name: str) -> Child:
        return next(c for c in self.children if c.name == name)

    def find(self, name: str) -> Child | None:
        """The child called ``name``, or None when none was started."""
        return next((c for c in self.children if c.name == name), None)

    def stop_all(self, order: list[str] | None = None, exclude: set[str] | None = None,
                 timeout_s: float = 5.0) -> None:
        """Stop children (those named in ``order`` first, in that order), except ``exclude``."""
        rank = {n: i for i, n in enumerate(order or [])}
        for c in sorted(self.children, key=lambda c: rank.get(c.name, len(rank))):
            if c.name not in (exclude or set()):
                c.stop(timeout_s)


def host_cores() -> int:
    """The cores this process may run on (its CPU affinity; the machine's count elsewhere)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1
