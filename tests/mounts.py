"""Small filesystems for the tests of a full disk and a read-only destination: a tmpfs of a
given size mounted on a folder of the test's, unmounted (lazily, so nothing left open keeps it)
at the end.  A test is skipped, with the reason, where mounts cannot be made (no
CAP_SYS_ADMIN)."""

from __future__ import annotations

import subprocess
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest


@contextmanager
def tmpfs(where: Path, size_mb: float, read_only: bool = False) -> Iterator[Path]:
    """``where`` (made) holding a tmpfs of ``size_mb`` megabytes (10^6 bytes), read-only if
    asked; skips the test if it cannot be mounted."""
    where.mkdir(parents=True, exist_ok=True)
    options = f"size={int(size_mb * 1e6)}" + (",ro" if read_only else "")
    made = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(where)],
                          capture_output=True, text=True, check=False)
    if made.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {made.stderr.strip() or made.returncode}")
    try:
        yield where
    finally:
        subprocess.run(["umount", "-l", str(where)], capture_output=True, check=False)


@contextmanager
def read_only(folder: Path) -> Iterator[Path]:
    """``folder`` (which exists, with what it holds) seen read-only for the block: bound onto
    itself, then remounted read-only; skips the test if it cannot be."""
    bound = subprocess.run(["mount", "--bind", str(folder), str(folder)], capture_output=True,
                           text=True, check=False)
    if bound.returncode != 0:
        pytest.skip(f"cannot bind-mount here: {bound.stderr.strip() or bound.returncode}")
    try:
        ro = subprocess.run(["mount", "-o", "remount,bind,ro", str(folder)],
                            capture_output=True, text=True, check=False)
        if ro.returncode != 0:
            pytest.skip(f"cannot remount read-only here: {ro.stderr.strip()}")
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], capture_output=True, check=False)
