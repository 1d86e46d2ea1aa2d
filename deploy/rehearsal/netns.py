"""Linux network namespaces for a rehearsal: made, entered, swept and removed with iproute2's
``ip`` (docs/hosts.md).  Each is named ``insp<pid>-<host>`` for the launcher that made it, so
the namespaces of a launcher that was killed outright are found and removed by the next."""

from __future__ import annotations

import ctypes
import ctypes.util
import ipaddress
import os
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

NETNS_DIR = Path("/run/netns")
_CLONE_NEWNET = 0x40000000
_OURS = re.compile(r"^insp(?P<pid>\d+)-[a-z0-9]+$")


class RehearsalError(RuntimeError):
    """A rehearsal that cannot be made here; the message names what is missing."""


def namespace(pid: int, host: str) -> str:
    """The namespace of ``host`` for the launcher ``pid``."""
    return f"insp{pid}-{host}"


def ip(*args: str) -> str:
    """Run ``ip args``; its output, or :class:`RehearsalError` with its message."""
    done = subprocess.run(["ip", *args], capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RehearsalError(f"ip {' '.join(args)}: {done.stderr.strip() or done.returncode}")
    return done.stdout


def require_privilege() -> None:
    """Stop at once, naming what is missing, unless namespaces and TAP links can be made
    here: Linux, iproute2's ``ip``, ``/dev/net/tun``, CAP_SYS_ADMIN and CAP_NET_ADMIN (tried:
    a namespace made and removed)."""
    if not os.uname().sysname == "Linux":
        raise RehearsalError("--rehearse needs Linux network namespaces; this is "
                             f"{os.uname().sysname}")
    if shutil.which("ip") is None:
        raise RehearsalError("--rehearse needs iproute2's `ip` command (apt install iproute2)")
    if not os.access("/dev/net/tun", os.R_OK | os.W_OK):
        raise RehearsalError("--rehearse needs /dev/net/tun (the hosts' links are TAP "
                             "devices); it is missing or not readable and writable here")
    probe = namespace(os.getpid(), "probe")
    try:
        ip("netns", "add", probe)
    except RehearsalError as e:
        raise RehearsalError("--rehearse needs CAP_SYS_ADMIN and CAP_NET_ADMIN (root, or a "
                             "container that grants them) to make network namespaces: "
                             f"{e}") from None
    ip("netns", "delete", probe)


def addresses_in(network: ipaddress.IPv4Network) -> list[str]:
    """The interfaces of this namespace with an address in ``network`` (``name address``)."""
    out = []
    for line in ip("-o", "-4", "addr", "show").splitlines():
        fields = line.split()
        if "inet" in fields:
            address = ipaddress.IPv4Interface(fields[fields.index("inet") + 1]).ip
            if address in network:
                out.append(f"{fields[1]} {address}")
    return out


def unavailable() -> str | None:
    """Why a rehearsal cannot be made here (:func:`require_privilege`'s message), or None."""
    try:
        require_privilege()
    except RehearsalError as e:
        return str(e)
    return None


def add(name: str) -> None:
    """Make namespace ``name`` with its loopback up."""
    ip("netns", "add", name)
    ip("-n", name, "link", "set", "lo", "up")


def remove(name: str) -> None:
    """Remove namespace ``name`` (its interfaces go with it); quiet when it is gone."""
    if (NETNS_DIR / name).exists():
        subprocess.run(["ip", "netns", "delete", name], capture_output=True, check=False)


def ours(pid: int) -> list[str]:
    """The namespaces launcher ``pid`` made (still there)."""
    return sorted(n for n in _listed() if (m := _OURS.match(n)) and int(m["pid"]) == pid)


def sweep() -> list[str]:
    """Remove the namespaces of launchers no longer running (killed outright, so that they
    could not clean up); the names removed."""
    gone = [n for n in _listed() if (m := _OURS.match(n)) and not _alive(int(m["pid"]))]
    for n in gone:
        remove(n)
    return gone


def _listed() -> list[str]:
    try:
        return [p.name for p in NETNS_DIR.iterdir()]
    except OSError:
        return []


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def libc() -> ctypes.CDLL:
    """The C library (to be loaded in a parent: a child forked from a process with threads
    should only make system calls before exec)."""
    return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)


@dataclass
class Entry:
    """Namespace ``name`` opened here, for a child to enter before exec (:meth:`enter`, one
    system call) and for the parent to :meth:`close` once the child is started."""

    name: str
    library: ctypes.CDLL
    fd: int

    @classmethod
    def open(cls, name: str, library: ctypes.CDLL) -> Entry:
        return cls(name, library, os.open(NETNS_DIR / name, os.O_RDONLY | os.O_CLOEXEC))

    def enter(self) -> None:
        """Move the calling thread (the child) into the namespace."""
        if self.library.setns(self.fd, _CLONE_NEWNET) != 0:
            raise OSError(ctypes.get_errno(), f"setns into {self.name}")

    def close(self) -> None:
        os.close(self.fd)
