"""The truth scene of the Foxglove layout (harness/foxglove_scene.py): the user script reads
the archive's truth and writes the scene topic with the scenario's numbers in it, its arrow
turns body +x onto the camera boresight, and the 3D panel shows the scene in LVLH."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from gnc import quat
from harness import foxglove_scene as scene
from interfaces.contracts import catalogue as cat
from tests.conftest import small_scenario


@pytest.mark.parametrize("boresight", [(0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (-1.0, 0.0, 0.0),
                                       (0.0, -2.0, 0.0), (1.0, 1.0, -1.0)])
def test_the_arrow_turns_body_x_onto_the_boresight(boresight: tuple[float, float, float]
                                                    ) -> None:
    q = scene.x_to_boresight(boresight)
    b = np.asarray(boresight) / np.linalg.norm(boresight)
    assert np.linalg.norm(q) == pytest.approx(1.0)
    assert np.allclose(quat.rotate(q, [1.0, 0.0, 0.0]), b, atol=1e-12)


def test_the_script_reads_the_truth_and_writes_the_scene() -> None:
    sc = small_scenario("fox", target={"radius_m": 3.0}, observers={"rho_x_m": 12.0})
    script = scene.user_script(sc, "mission-7")
    source = script["sourceCode"]
    assert f'export const inputs = ["{cat.TRUTH.key("mission-7")}"];' in source
    assert f'export const output = "{scene.SCENE_TOPIC}";' in source
    assert scene.SCENE_TOPIC.startswith("/studio_script/")  # Foxglove's prefix for scripts
    assert "const TARGET_RADIUS_M = 3.0;" in source and "const OBSERVER_SIZE_M = 1.2" in source
    assert 'import { SceneEntity, SceneUpdate, Time } from "@foxglove/schemas";' in source
    assert "export default function script(event: Event): SceneUpdate" in source
    arrow = json.loads(re.search(r"X_TO_BORESIGHT: number\[\] = (\[.*?\]);", source).group(1))
    assert np.allclose(quat.rotate(arrow, [1.0, 0.0, 0.0]), [0.0, 0.0, 1.0])
    assert "$" not in source.replace("${sc}", "")  # every placeholder filled


def test_the_3d_panel_shows_the_scene_in_lvlh() -> None:
    sc = small_scenario("fox", observers={"rho_x_m": 10.0, "rho_z_m": 15.0})
    panel = scene.panel(sc)
    assert panel["followTf"] == scene.FRAME == "lvlh"
    assert panel["topics"] == {scene.SCENE_TOPIC: {"visible": True}}
    assert panel["cameraState"]["distance"] == 80.0  # four times the in-plane reach, m
    (grid,) = panel["layers"].values()
    assert grid["layerId"] == "foxglove.Grid" and grid["frameId"] == "lvlh"
