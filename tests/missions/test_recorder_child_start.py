"""The recorder child of a one-process run starts without running the launcher's script again
(issue 61, item 4: start-up): a spawned interpreter imports the parent's main module unless
told otherwise, a second of CPU taken from the run."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def test_the_recorder_child_does_not_run_the_parents_script_again(tmp_path: Path) -> None:
    marker, archive = tmp_path / "ran.txt", tmp_path / "run.mcap"
    script = tmp_path / "launcher.py"
    script.write_text(
        "import sys\n"
        f"sys.path.insert(0, {str(REPO)!r})\n"
        f"with open({str(marker)!r}, 'a') as f:\n"
        "    f.write('ran\\n')\n"
        "from ground.archive.recorder_process import RecorderProcess\n"
        "if __name__ == '__main__':\n"
        f"    with RecorderProcess({str(archive)!r}):\n"
        "        pass\n"
        "    assert sys.modules['__main__'].__file__ == __file__  # given back\n")
    subprocess.run([sys.executable, str(script)], check=True, timeout=120)
    assert marker.read_text() == "ran\n"  # the parent's run only
    assert archive.stat().st_size > 0  # the child wrote the (empty) archive
