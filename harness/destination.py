"""Where a tool writes its result, checked before any work: the folder can be written (made if
missing), and a file already there is not replaced unless the user says so (``--overwrite``).

A read-only folder (a read-only mount, a folder without write permission) is found by
writing a probe file into it and removing it at once: permissions alone do not tell, since a
read-only mount refuses even root, and root passes every permission.  Errors are one line
naming the path and the option to change (:class:`DestinationError`), for the command to print
with exit status 2.
"""

from __future__ import annotations

import tempfile
from pathlib import Path


class DestinationError(ValueError):
    """A destination that cannot be written, or holds a file that would be replaced."""


def check_folder(folder: Path, option: str) -> None:
    """``folder`` exists (made, with its parents, if missing) and a file can be written in it;
    DestinationError naming ``option`` (the command line's way to choose another) if not."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".write-probe-"):
            pass
    except OSError as e:
        raise DestinationError(f"cannot write into {folder}: {e.strerror or e} (give "
                               f"{option})") from None


def check_file(file: Path, overwrite: bool, option: str) -> None:
    """``file`` can be written: its folder can (:func:`check_folder`), and it is not there
    already unless ``overwrite``, nor a folder; DestinationError naming what to do."""
    if file.is_dir():
        raise DestinationError(f"{file} is a folder, not a file (give {option})")
    if file.exists() and not overwrite:
        raise DestinationError(f"{file} exists: give --overwrite to replace it, or {option}")
    check_folder(file.parent, option)


def write_whole(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` whole or not at all: written beside, then renamed over it,
    so a full disk or a kill leaves the old file or none, never an empty or cut one."""
    partial = path.with_name(f".{path.name}.partial")
    try:
        partial.write_text(text, encoding="utf-8")
        partial.replace(path)
    finally:
        partial.unlink(missing_ok=True)
