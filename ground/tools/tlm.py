"""Live telemetry: ``python -m ground.tools.tlm --zenoh-config <run>/access/tlm.json5
[--filter 'insp/**/nav/**'] [--stream]``.

Joins the run's Zenoh network as a client with the run's read-only telemetry account
(``<out>/access/tlm.json5``, written by deploy/run_constellation.py: endpoint, user, password
and, over TLS, the certificate authority) and shows the latest message of every key matching the
filter as a table refreshed once per second (one row per observer where the observers share a
key, as the ground's FDIR windows do), or, with ``--stream``, one line per message.
Without ``--zenoh-config`` it connects to ``--connect`` with no credentials (a network without
access control).  Ctrl-C quits.
"""

from __future__ import annotations

import argparse
import json
import sys
import threading
import time
from dataclasses import dataclass

from interfaces.runtime.arguments import command_help, endpoint, prog_name
from interfaces.runtime.zenoh_transport import DEFAULT_ENDPOINT, ZenohSettings, ZenohTransport

SKIP_FIELDS = {"sender", "seq", "t_sim", "t_wall"}


@dataclass
class _Row:
    type_name: str
    seq: int
    t_sim: float
    count: int
    summary: str


def summarize(payload: bytes, width: int = 90) -> tuple[int, float, str]:
    """(seq, t_sim, short 'field=value' text) of a JSON message; never raises."""
    try:
        d = json.loads(payload)
        if not isinstance(d, dict):
            raise ValueError
    except ValueError:
        return 0, float("nan"), f"<not JSON: {payload[:40]!r}>"
    parts = []
    for k, v in d.items():
        if k in SKIP_FIELDS:
            continue
        parts.append(f"{k}={_short(v)}")
    text = " ".join(parts)
    seq = d.get("seq", 0)
    t = d.get("t_sim", float("nan"))
    return (seq if isinstance(seq, int) else 0, t if isinstance(t, (int, float)) else float("nan"),
            text if len(text) <= width else text[: width - 1] + "…")


def row_key(key: str, payload: bytes) -> str:
    """The table row of a message on ``key``: the key, and where its observers share it (the
    ground's FDIR windows, fault reports...), the observer the message is about, so each
    observer keeps its own row ("``key`` [sc2]")."""
    try:
        d = json.loads(payload)
    except ValueError:
        return key
    sc = d.get("spacecraft") if isinstance(d, dict) else None
    if not isinstance(sc, int) or isinstance(sc, bool) or f"/sc/{sc}/" in f"{key}/":
        return key
    return f"{key} [sc{sc}]"


def _short(v: object) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, list):
        if v and all(isinstance(x, (int, float)) for x in v):
            return "[" + ",".join(f"{x:.3g}" for x in v) + "]"
        return f"[{len(v)} items]"
    if isinstance(v, dict):
        return "{" + f"{len(v)} keys" + "}"
    return str(v)


def table(rows: dict[str, _Row]) -> str:
    """The latest message per key, as an aligned text table."""
    if not rows:
        return "(no messages yet)"
    kw = max(len(k) for k in rows)
    head = f"{'key':<{kw}}  {'type':<17} {'seq':>7} {'t_sim (s)':>10} {'count':>7}  fields"
    lines = [head, "-" * len(head)]
    for k in sorted(rows):
        r = rows[k]
        lines.append(f"{k:<{kw}}  {r.type_name:<17} {r.seq:>7} {r.t_sim:>10.1f} {r.count:>7}  "
                     f"{r.summary}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog=prog_name("python -m ground.tools.tlm"),
                                description=command_help(__doc__, "docs/bus-and-security.md",
                                                         2),
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--filter", default="insp/**", help="Zenoh key expression (default insp/**)")
    p.add_argument("--connect", default=DEFAULT_ENDPOINT, type=endpoint,
                   help="Zenoh endpoint of the constellation (default %(default)s)")
    p.add_argument("--zenoh-config", help="client configuration with credentials (the run's "
                   "access/tlm.json5)")
    p.add_argument("--stream", action="store_true", help="print every message instead of a table")
    p.add_argument("--duration", type=float, help="quit after this many seconds")
    args = p.parse_args(argv)
    rows: dict[str, _Row] = {}
    lock = threading.Lock()

    def on_raw(key: str, type_name: str, payload: bytes) -> None:
        seq, t, text = summarize(payload)
        if args.stream:
            print(f"{t:10.1f}  {key}  {type_name}#{seq}  {text}", flush=True)
            return
        row = row_key(key, payload)
        with lock:
            prev = rows.get(row)
            rows[row] = _Row(type_name, seq, t, (prev.count if prev else 0) + 1, text)

    try:
        transport = ZenohTransport(ZenohSettings(connect=(args.connect,), mode="client",
                                                 config_file=args.zenoh_config))
    except Exception as e:  # noqa: BLE001 - zenoh raises ZError
        print(f"error: cannot join {args.zenoh_config or args.connect}: {e}\n(a run's network "
              "needs its read-only account: --zenoh-config <run>/access/tlm.json5)",
              file=sys.stderr)
        return 2
    transport.subscribe(args.filter, on_raw)
    deadline = time.monotonic() + args.duration if args.duration else float("inf")
    try:
        while time.monotonic() < deadline:
            time.sleep(min(1.0, max(0.0, deadline - time.monotonic())))
            if not args.stream:
                with lock:
                    text = table(rows)
                sys.stdout.write("\x1b[2J\x1b[H" if sys.stdout.isatty() else "\n")
                print(f"{args.filter} @ {args.connect}  ({time.strftime('%H:%M:%S')})\n{text}",
                      flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        transport.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
