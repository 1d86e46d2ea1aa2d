"""Live view: the running constellation streamed to Foxglove over the Foxglove WebSocket
protocol (foxglove-sdk's server, subprotocol ``foxglove.sdk.v1``), bound to loopback.

Every bus message is forwarded raw on a channel named by its key expression, JSON-encoded
with the JSON schema of its type (so Foxglove's Plot and Raw Messages panels can show H, H_i,
the FDIR metric and threshold, fault events and reports, ...), and the truth poses are
re-published as ``foxglove.PosesInFrame`` on ``/insp/truth/poses`` (frame ``lvlh``, the
target at the origin) for the 3D panel.  Off by default; ``run_constellation.py --live PORT``
turns it on.  Connect Foxglove to ``ws://127.0.0.1:PORT``.
"""

from __future__ import annotations

import json
import logging
import threading
from typing import Any

import foxglove
from foxglove.channels import PosesInFrameChannel
from foxglove.messages import Pose, PosesInFrame, Quaternion, Timestamp, Vector3

from interfaces.contracts.messages import json_schema, registry

log = logging.getLogger("insp.live")

POSES_TOPIC = "/insp/truth/poses"


class LiveView:
    """A Foxglove WebSocket server fed by :meth:`forward` (a raw bus tap:
    key, type name, JSON payload)."""

    def __init__(self, port: int, host: str = "127.0.0.1") -> None:
        self.context = foxglove.Context()
        self.server = foxglove.start_server(name="insp-fdir", host=host, port=port,
                                            context=self.context)
        self.port = self.server.port
        self._channels: dict[str, foxglove.Channel] = {}
        self._poses = PosesInFrameChannel(POSES_TOPIC, context=self.context)
        self._lock = threading.Lock()
        self.dropped = 0
        log.info("live view on ws://%s:%d (Foxglove: open connection)", host, self.port)

    def forward(self, key: str, type_name: str, payload: bytes) -> None:
        """Forward one bus message; an unknown type or a bad payload is counted and dropped."""
        try:
            with self._lock:
                channel = self._channels.get(key)
                if channel is None:
                    model = registry().get(type_name)
                    if model is None:
                        self.dropped += 1
                        return
                    schema = foxglove.Schema(name=type_name, encoding="jsonschema",
                                             data=json.dumps(json_schema(model)).encode())
                    channel = foxglove.Channel(key, schema=schema, message_encoding="json",
                                               context=self.context)
                    self._channels[key] = channel
            channel.log(payload)
            if type_name == "TruthState":
                self._log_poses(json.loads(payload))
        except Exception:  # noqa: BLE001 - a live view never stops the run
            self.dropped += 1
            log.debug("live view: dropped a %s on %s", type_name, key, exc_info=True)

    def _log_poses(self, truth: dict[str, Any]) -> None:
        t = float(truth["t_sim"])
        quats = truth.get("q_lvlh_body") or []
        poses = []
        for i, r in enumerate(truth["r_lvlh_m"]):
            q = quats[i] if i < len(quats) else (0.0, 0.0, 0.0, 1.0)  # scalar last
            poses.append(Pose(position=Vector3(x=r[0], y=r[1], z=r[2]),
                              orientation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3])))
        sec = int(t)
        self._poses.log(PosesInFrame(timestamp=Timestamp(sec, int((t - sec) * 1e9)),
                                     frame_id="lvlh", poses=poses))

    def close(self) -> None:
        self.server.stop()
