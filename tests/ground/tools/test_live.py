"""The live view speaks the Foxglove WebSocket protocol on loopback: a client sees a channel
per bus key (JSON, with the message's JSON schema) and the truth poses, and receives the
forwarded payloads byte for byte; junk is counted and dropped, never raised."""

from __future__ import annotations

import asyncio
import json
import socket
import struct

from tornado.websocket import websocket_connect

from ground.tools.live import POSES_TOPIC, LiveView
from interfaces.contracts.messages import FaultReport, TruthState


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


async def _session(live: LiveView, report: bytes, truth: bytes) -> tuple[dict, list[bytes]]:
    conn = await websocket_connect(f"ws://127.0.0.1:{live.port}/",
                                   subprotocols=["foxglove.sdk.v1"])
    live.forward("insp/m/ground/fdir/report", "FaultReport", report)
    live.forward("insp/m/sim/truth/state", "TruthState", truth)
    live.forward("insp/m/x/y", "NoSuchType", b"{}")
    channels: dict[str, dict] = {}
    while len(channels) < 3:
        msg = await asyncio.wait_for(conn.read_message(), 10)
        data = json.loads(msg)
        if data.get("op") == "advertise":
            channels.update({c["topic"]: c for c in data["channels"]})
    ch = channels["insp/m/ground/fdir/report"]
    conn.write_message(json.dumps({"op": "subscribe",
                                   "subscriptions": [{"id": 7, "channelId": ch["id"]}]}))
    await asyncio.sleep(0.3)
    live.forward("insp/m/ground/fdir/report", "FaultReport", report)
    frames = []
    while not frames:
        msg = await asyncio.wait_for(conn.read_message(), 10)
        if isinstance(msg, bytes):
            frames.append(msg)
    conn.close()
    return channels, frames


def test_live_view_streams_bus_messages_to_a_foxglove_client() -> None:
    live = LiveView(_free_port())
    try:
        report = FaultReport(sender="ground", t_sim=300.0, spacecraft=2, fault_class="camera",
                             window_end_s=300.0).model_dump_json().encode()
        truth = TruthState(sender="sim", t_sim=1.5, spacecraft=[1, 2],
                           r_lvlh_m=[[10.0, 0.0, 0.0], [0.0, 20.0, 0.0]],
                           v_lvlh_mps=[[0.0] * 3] * 2).model_dump_json().encode()
        channels, frames = asyncio.run(_session(live, report, truth))
    finally:
        live.close()
    ch = channels["insp/m/ground/fdir/report"]
    assert ch["encoding"] == "json" and ch["schemaName"] == "FaultReport"
    assert "fault_class" in json.loads(ch["schema"])["properties"]
    assert "insp/m/sim/truth/state" in channels and POSES_TOPIC in channels
    assert "insp/m/x/y" not in channels and live.dropped == 1
    opcode, sub_id, _log_time = struct.unpack_from("<BIQ", frames[0])
    assert (opcode, sub_id) == (1, 7)
    assert frames[0][13:] == report
