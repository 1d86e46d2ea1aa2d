"""The truth poses of a run in Foxglove's 3D panel, from the archive as it is.

The 3D panel draws only Foxglove's own schemas (``foxglove.SceneUpdate``, ``PosesInFrame``,
``FrameTransform``, ...), and the archive holds none: every channel is one of the project's
messages (``ground/archive/mcap_file.py``).  So the layout carries a *user script* (TypeScript,
run by Foxglove inside the layout, no extension to install) that reads the archive's sim truth
(``insp/<mission>/sim/truth/state``: positions in the target's LVLH frame, m, attitudes body to
LVLH, scalar last) and publishes, on a topic of the layout's own (``SCENE_TOPIC``, under the
``/studio_script/`` prefix Foxglove requires), a ``foxglove.SceneUpdate`` in frame ``lvlh``:
the target as a sphere at the origin, each observer as a sphere with its label and an arrow
along its camera boresight.  The archive itself is not changed.

The script was type-checked against ``@foxglove/schemas`` under the user-script compiler
options (strict, ES2022); where a Foxglove build cannot run user scripts the 3D panel stays
empty and every other panel still works.
"""

from __future__ import annotations

import json
import math
from string import Template
from typing import Any, Final

import numpy as np

from gnc import quat
from interfaces.contracts import catalogue as cat
from interfaces.contracts.scenario import Scenario

FRAME: Final = "lvlh"
"""The frame the scene is drawn in: the target's LVLH frame (x radial, y along-track, z along
the orbit normal), the target at the origin."""

SCENE_TOPIC: Final = "/studio_script/insp/lvlh_scene"
"""The user script's output: a topic of the layout, not of the archive."""

SCRIPT_ID: Final = "insp-lvlh-scene"
"""Key of the user script in the layout's ``userNodes``."""

OBSERVER_COLOURS: Final = ("#4e98e2", "#f5774d", "#5cd65c", "#b57edc", "#f2c12e", "#3fc1c9",
                           "#e8577e", "#a0a0a0")
"""Observer i takes colour (i - 1) modulo their number, in the plots and in the scene."""

_SCRIPT: Final = Template("""\
// Truth poses in the target's LVLH frame for the 3D panel: the target at the origin, each
// observer with its label and an arrow along its camera boresight.  Read from the archive's
// sim truth ($input_json: r_lvlh_m in m, q_lvlh_body body to LVLH, scalar last); written by the
// run (harness/foxglove_scene.py).
import { SceneEntity, SceneUpdate, Time } from "@foxglove/schemas";

type Truth = { spacecraft: number[]; r_lvlh_m: number[][]; q_lvlh_body: number[][] };
type Event = { receiveTime: Time; message: Truth };

export const inputs = [$input_json];
export const output = $output_json;

const FRAME = $frame_json;
const TARGET_RADIUS_M = $target_radius_m;
const OBSERVER_SIZE_M = $observer_size_m;
const ARROW_M = $arrow_m;
const X_TO_BORESIGHT: number[] = $x_to_boresight;  // body +x onto the camera boresight
const COLOURS: string[] = $colours_json;

function mul(p: number[], q: number[]): number[] {
  const [px, py, pz, pw] = [p[0] ?? 0, p[1] ?? 0, p[2] ?? 0, p[3] ?? 1];
  const [qx, qy, qz, qw] = [q[0] ?? 0, q[1] ?? 0, q[2] ?? 0, q[3] ?? 1];
  return [
    pw * qx + px * qw + py * qz - pz * qy,
    pw * qy - px * qz + py * qw + pz * qx,
    pw * qz + px * qy - py * qx + pz * qw,
    pw * qw - px * qx - py * qy - pz * qz,
  ];
}

function rgba(hex: string, a: number) {
  const n = parseInt(hex.slice(1), 16);
  return { r: ((n >> 16) & 255) / 255, g: ((n >> 8) & 255) / 255, b: (n & 255) / 255, a };
}

function pose(r: number[], q: number[]) {
  return {
    position: { x: r[0] ?? 0, y: r[1] ?? 0, z: r[2] ?? 0 },
    orientation: { x: q[0] ?? 0, y: q[1] ?? 0, z: q[2] ?? 0, w: q[3] ?? 1 },
  };
}

function entity(id: string, stamp: Time): SceneEntity {
  return {
    timestamp: stamp, frame_id: FRAME, id, lifetime: { sec: 0, nsec: 0 }, frame_locked: true,
    metadata: [], arrows: [], cubes: [], spheres: [], cylinders: [], lines: [], triangles: [],
    texts: [], models: [],
  };
}

function observer(sc: number, r: number[], q: number[], stamp: Time): SceneEntity {
  const colour = COLOURS[(sc - 1) % COLOURS.length] ?? "#ffffff";
  const e = entity(`sc$${sc}`, stamp);
  const size = { x: OBSERVER_SIZE_M, y: OBSERVER_SIZE_M, z: OBSERVER_SIZE_M };
  e.spheres.push({ pose: pose(r, [0, 0, 0, 1]), size, color: rgba(colour, 1) });
  e.arrows.push({
    pose: pose(r, mul(q, X_TO_BORESIGHT)), shaft_length: 0.8 * ARROW_M,
    shaft_diameter: 0.1 * OBSERVER_SIZE_M, head_length: 0.2 * ARROW_M,
    head_diameter: 0.3 * OBSERVER_SIZE_M, color: rgba(colour, 0.8),
  });
  e.texts.push({
    pose: pose([(r[0] ?? 0), (r[1] ?? 0), (r[2] ?? 0) + OBSERVER_SIZE_M], [0, 0, 0, 1]),
    billboard: true, font_size: 14, scale_invariant: true, color: rgba(colour, 1),
    text: `sc$${sc}`,
  });
  return e;
}

export default function script(event: Event): SceneUpdate {
  const stamp = event.receiveTime;
  const target = entity("target", stamp);
  const d = 2 * TARGET_RADIUS_M;
  target.spheres.push({
    pose: pose([0, 0, 0], [0, 0, 0, 1]), size: { x: d, y: d, z: d },
    color: rgba("#c8c8c8", 0.6),
  });
  const truth = event.message;
  const entities = [target];
  truth.spacecraft.forEach((sc, i) => {
    entities.push(observer(sc, truth.r_lvlh_m[i] ?? [0, 0, 0],
                           truth.q_lvlh_body[i] ?? [0, 0, 0, 1], stamp));
  });
  return { deletions: [], entities };
}
""")


def user_script(scenario: Scenario, mission: str) -> dict[str, str]:
    """The layout's user script (``userNodes`` entry: name, TypeScript source) that turns the
    archive's truth into the LVLH scene on ``SCENE_TOPIC``."""
    size_m = observer_size_m(scenario)
    source = _SCRIPT.substitute(
        input_json=json.dumps(cat.TRUTH.key(mission)), output_json=json.dumps(SCENE_TOPIC),
        frame_json=json.dumps(FRAME), target_radius_m=repr(float(scenario.target.radius_m)),
        observer_size_m=repr(size_m), arrow_m=repr(4.0 * size_m),
        x_to_boresight=json.dumps([round(float(c), 12) for c in
                                   x_to_boresight(scenario.attitude.boresight_body)]),
        colours_json=json.dumps(list(OBSERVER_COLOURS)))
    return {"name": "LVLH truth scene", "sourceCode": source}


def x_to_boresight(boresight_body: tuple[float, float, float]) -> np.ndarray:
    """The quaternion (scalar last) turning body +x onto the camera boresight (the shortest
    rotation; about body z when they are opposite): an arrow, drawn along +x of its pose,
    then points where the camera looks."""
    b = np.asarray(boresight_body, dtype=float)
    b = b / np.linalg.norm(b)
    x = np.array([1.0, 0.0, 0.0])
    axis = np.cross(x, b)
    s, c = float(np.linalg.norm(axis)), float(np.dot(x, b))
    if s < 1e-12:
        return np.array([0.0, 0.0, 0.0, 1.0]) if c > 0 else np.array([0.0, 0.0, 1.0, 0.0])
    return quat.exp(axis / s * math.atan2(s, c))


def observer_size_m(scenario: Scenario) -> float:
    """How big an observer is drawn, m: a tenth of its PRO's radial amplitude, at least 0.5 m,
    so that the observers stay visible beside the target."""
    return max(0.5, 0.1 * scenario.observers.rho_x_m)


def panel(scenario: Scenario) -> dict[str, Any]:
    """The 3D panel's configuration: the scene topic in frame ``lvlh`` over a grid in its x-y
    (radial, along-track) plane, the camera back far enough to see the PROs."""
    reach_m = max(2.0 * scenario.observers.rho_x_m, scenario.observers.rho_z_m,
                  2.0 * scenario.target.radius_m)
    return {
        "foxglovePanelTitle": "Truth poses in LVLH (target at the origin)",
        "followTf": FRAME, "followMode": "follow-pose",
        "cameraState": {"distance": 4.0 * reach_m, "perspective": True, "phi": 60.0,
                        "thetaOffset": 45.0, "target": [0.0, 0.0, 0.0],
                        "targetOffset": [0.0, 0.0, 0.0], "targetOrientation": [0.0, 0.0, 0.0, 1.0],
                        "fovy": 45.0, "near": 0.5, "far": 5000.0},
        "scene": {}, "transforms": {},
        "topics": {SCENE_TOPIC: {"visible": True}},
        "layers": {"lvlh-grid": {"layerId": "foxglove.Grid", "instanceId": "lvlh-grid",
                                 "label": "LVLH x-y plane (radial, along-track)",
                                 "visible": True, "frameId": FRAME, "size": 4.0 * reach_m,
                                 "divisions": 8, "lineWidth": 1.0, "color": "#248eff80",
                                 "position": [0.0, 0.0, 0.0], "rotation": [0.0, 0.0, 0.0],
                                 "order": 1}},
    }
