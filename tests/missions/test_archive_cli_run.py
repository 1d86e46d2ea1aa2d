"""``python -m harness.archive``: list, summary and CSV export of a real run archive, with its
scenario, seed and software version in the metadata."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest

from deploy.inproc import run_inproc
from ground.archive.metadata import run_metadata, software_version
from ground.archive.recorder import McapRecorder
from harness.archive.cli import export_csv, main
from harness.archive.reader import load_run
from tests.conftest import small_scenario


@pytest.fixture(scope="module")
def archive_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    sc = small_scenario("arch", duration_s=20.0, observers={"count": 2},
                        faults=[{"spacecraft": 2, "kind": "camera_degradation", "start_s": 5.0,
                                 "magnitude": 0.5}])
    path = tmp_path_factory.mktemp("arch") / "run.mcap"
    with McapRecorder(path, run_metadata(sc, "inproc", "# test\n")) as rec:
        run_inproc(sc, tap=rec.record)
    return path


def test_list_and_summary(archive_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["list", str(archive_path)]) == 0
    text = capsys.readouterr().out
    assert "insp/arch/sc/1/nav/estimate  StateEstimate  " in text
    assert main(["summary", str(archive_path)]) == 0
    text = capsys.readouterr().out
    assert "scenario: arch" in text and "seed: 3" in text
    assert f"software_version: {software_version()}" in text
    assert "fault camera_degradation on sc2 on at 5 s" in text


def test_export_matches_the_reader(archive_path: Path, tmp_path: Path) -> None:
    out = tmp_path / "nav.csv"
    assert main(["export", str(archive_path), "--topic", "insp/arch/sc/1/nav/estimate",
                 "--out", str(out)]) == 0
    rows = list(csv.DictReader(open(out)))
    est = load_run(archive_path).messages("insp/arch/sc/1/nav/estimate")
    assert len(rows) == len(est) > 10
    assert [float(r["x.0"]) for r in rows] == [m.x[0] for m in est]  # type: ignore[attr-defined]
    assert float(rows[-1]["P.2.2"]) == est[-1].P[2][2]  # type: ignore[attr-defined]
    buf = io.StringIO()
    assert export_csv(load_run(archive_path), "insp/arch/nothing/**", buf) == 0
