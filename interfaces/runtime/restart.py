"""A node process's restart: restored from its critical-data store when it can be, started cold
(and the reason recorded) when not, and the store kept from then on (docs/architecture.md,
"Restarts").

The store holds the node's state at its last ω_mid boundary, tick m.  A restored node first
runs again, before it announces itself, every tick the sim sent since, up to the one the sim
holds open for it: the ticks and everything they announce come from what the sim and the
other nodes keep of their last ticks (``interfaces.runtime.recent``).  What it sends again is
dropped by its receivers as duplicates.  Then it is where it was when it stopped, and the sim's
tick sent again on its return is the next it runs.  If the ticks since are no longer kept (or
the sim's cannot be read), it goes on with the state of tick m, numbering its messages afresh,
and its start record says why: the mission goes on, no longer as if nothing happened.
"""

from __future__ import annotations

import dataclasses
import logging
import pickle
import time

from pydantic import ValidationError

from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.messages import Tick
from interfaces.runtime.cds import CriticalDataStore, StartRecord, StoreRefused
from interfaces.runtime.checkpoint import capture, restore
from interfaces.runtime.executive import TickClient
from interfaces.runtime.recent import fetch_recent


def resume(client: TickClient, store: CriticalDataStore, others: list[str],
           log: logging.Logger) -> StartRecord:
    """Restore the node of ``client`` from ``store`` if this process is a restart and run
    again the ticks since (from the sim and the ``others`` nodes), or start cold (logged with
    the reason); record how it started; write the store at every ω_mid boundary from now on.
    Call before the node announces itself, its recent ticks served (``Bus.serve_recent``)."""
    return resume_together([(client, store)], others, log)[0]


def resume_together(members: list[tuple[TickClient, CriticalDataStore]], nodes: list[str],
                    log: logging.Logger) -> list[StartRecord]:
    """:func:`resume` for the nodes one process hosts (``members``, each with its store), which
    stopped and start again together.  Each is restored first, with what it sent in its last
    ticks (served to the others restarted with it); each then takes in what the sim and the
    other ``nodes`` sent lately; and the ticks since are run again tick by tick across the
    members, so that what one sends again in a tick reaches the others before their next, as
    in flight."""
    records = [_start(client, store, log) for client, store in members]
    for client, store in members:
        _keep(client, store, log)
    runs = [_recent_ticks(client, [n for n in nodes if n != client.executive.bus.node],
                          record, log) if record.outcome == "restored" else ({}, record)
            for (client, _), record in zip(members, records, strict=True)]
    for k in sorted({k for ticks, _ in runs for k in ticks}):
        for (client, _), (ticks, _) in zip(members, runs, strict=True):
            if k in ticks:
                client.catch_up(ticks[k])
    out = []
    for (client, store), (ticks, record) in zip(members, runs, strict=True):
        if record.outcome == "restored":
            record = _ran_again(client, ticks, record, log)
        store.record_start(record)
        out.append(record)
    return out


def _keep(client: TickClient, store: CriticalDataStore, log: logging.Logger) -> None:
    """Write ``store`` at every ω_mid boundary of ``client``'s node from now on."""
    ex = client.executive
    every = ex.period["mid"]
    failed: list[int] = [0]

    def save() -> None:
        done = ex.last_done
        if done is None or done.k % every:
            return
        try:
            store.save(capture(ex), done.k, done.t_sim)
        except (OSError, pickle.PicklingError, TypeError) as e:  # the node flies on
            failed[0] += 1
            if failed[0] == 1 or failed[0] % 100 == 0:
                log.error("%s: critical-data store not written at tick %d (%s; failure #%d): "
                          "a restart would restore an older one", store.identity.node, done.k,
                          e, failed[0])

    ex.at_tick_end = save


def _start(client: TickClient, store: CriticalDataStore, log: logging.Logger) -> StartRecord:
    node = store.identity.node
    if not store.restarted():
        log.info("%s: first start; critical-data store %s", node, store.path)
        return StartRecord("fresh", wall_time=time.time())
    try:
        state, header = store.load()
        restore(client, state)
    except (StoreRefused, ValueError) as e:
        log.error("%s: restarted cold (%s)", node, e)
        return StartRecord("cold", reason=str(e), wall_time=time.time())
    tick, t_sim = int(header["tick"]), float(header["t_sim"])  # type: ignore[arg-type]
    log.warning("%s: restored from %s after tick %d (t=%.1f s)", node, store.path, tick, t_sim)
    return StartRecord("restored", tick=tick, t_sim=t_sim, wall_time=time.time())


def _recent_ticks(client: TickClient, others: list[str], record: StartRecord,
                  log: logging.Logger) -> tuple[dict[int, Tick], StartRecord]:
    """Take in what the sim and ``others`` sent lately; the sim's ticks after the restored one
    to run again, in order (none when some are no longer kept: the node then goes on from
    where it is, numbering afresh), and the record saying why not, if so."""
    bus = client.executive.bus
    tick_key = cat.TICK.key(bus.mission)
    ticks: dict[int, Tick] = {}
    heard_sim = False
    for owner in others:
        samples = fetch_recent(bus, owner)
        heard_sim = heard_sim or (owner == topics.SIM and bool(samples))
        for sample in samples:
            if sample.key != tick_key:
                bus.take_in(sample)
                continue
            try:
                tick = Tick.model_validate_json(sample.payload)
            except ValidationError:
                continue
            if tick.k > record.tick:
                ticks.setdefault(tick.k, tick)
    run = sorted(ticks)
    gap = ("the sim's last ticks could not be read" if not heard_sim else
           f"the sim's ticks {record.tick + 1}-{run[0] - 1} are no longer kept"
           if run and run[0] != record.tick + 1 else "")
    if gap:  # go on from where it is, numbering afresh: its receivers saw higher numbers
        log.error("%s: %s; rejoining with the state of tick %d", bus.node, gap, record.tick)
        bus.number_afresh()
        return {}, dataclasses.replace(record, reason=gap)
    return {k: ticks[k] for k in run}, record


def _ran_again(client: TickClient, ticks: dict[int, Tick], record: StartRecord,
               log: logging.Logger) -> StartRecord:
    """The record of a restored node that ran ``ticks`` again since its store."""
    run = sorted(ticks)
    log.warning("%s: ran again ticks %s since the store", client.executive.bus.node,
                f"{run[0]}-{run[-1]}" if run else "(none)")
    return StartRecord("restored", reason=record.reason, tick=run[-1] if run else record.tick,
                       t_sim=ticks[run[-1]].t_sim if run else record.t_sim,
                       wall_time=record.wall_time)
