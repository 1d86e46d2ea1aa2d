"""A run's output folder (``--out``): never silently reused (issue 40).

A folder that holds anything is refused unless the user says ``--overwrite``, which removes it
wholly first, so two runs never mix in one folder; and ``--overwrite`` removes only a run's
folder (one holding a run's files), never another folder given by mistake.  The default name,
``runs/<scenario>-<time>``, is made unique with a counter.  Errors name the folder and what is
in it (``OutFolderError``), for the command to print with exit 2; so does a folder that cannot
be written (a read-only disk), before any work.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from harness.destination import DestinationError, check_folder

RUN_FILES = ("run.mcap", "summary.json", "run.log", "report.md", "run.foxglove.json")
"""Files only a run writes: a folder holding one of them is a run's."""


class OutFolderError(ValueError):
    """An output folder that cannot be used; the message says why and what to do."""


def _contents(folder: Path, inputs: tuple[Path, ...] = ()) -> list[str]:
    """The names in ``folder``, but the run's own ``inputs``."""
    own = {i.resolve() for i in inputs}
    return sorted(p.name for p in folder.iterdir() if p.resolve() not in own)


def prepare(out: Path | None, default: Path, overwrite: bool,
            inputs: tuple[Path, ...] = ()) -> Path:
    """The run's folder, made and empty but for the run's own ``inputs`` (its scenario file,
    which a campaign writes there): ``out`` (refused when it holds anything else, unless
    ``overwrite`` and it is a run's folder, which is then removed first), or ``default``
    (with ``-2``, ``-3``... when taken).  Raises OutFolderError."""
    if out is None:
        out, k = default, 1
        while out.exists():
            k += 1
            out = default.with_name(f"{default.name}-{k}")
    elif out.exists() and not out.is_dir():
        raise OutFolderError(f"--out {out}: a file, not a folder")
    elif out.exists() and _contents(out, inputs):
        held = _contents(out, inputs)
        listed = ", ".join(held[:6]) + (" ..." if len(held) > 6 else "")
        if not overwrite:
            raise OutFolderError(f"--out {out} already holds {listed}: give another --out, or "
                                 "--overwrite to remove that run wholly first")
        if not any(name.startswith(RUN_FILES) for name in held):
            raise OutFolderError(f"--out {out} holds {listed}, not a run's files: "
                                 "--overwrite removes only a run's folder")
        shutil.rmtree(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise OutFolderError(f"--out {out}: cannot make the folder: {e.strerror or e}") from None
    try:
        check_folder(out, "another --out")
    except DestinationError as e:
        raise OutFolderError(str(e)) from None
    return out


def written(out: Path, layout: Path, report: bool) -> list[Path]:
    """The run's files in ``out`` the console names at the end (the archive, the Foxglove
    ``layout``, the summary and, with ``report``, the report): those that exist (a run that
    failed before its recorder started has no archive)."""
    paths = [out / "run.mcap", layout, out / "summary.json"] + ([out / "report.md"] * report)
    return [p for p in paths if p.exists()]
