"""What a node holds between two ticks, taken whole and put back: the state its critical-data
store keeps (``interfaces.runtime.cds``), so that a restarted process goes on as if it had not
stopped (docs/architecture.md, "Restarts").

A node's state is
* each app's declared ``CRITICAL`` attributes and its random stream (``App.checkpoint``);
* the executive's counters and its last answer to the sim (sent again if the sim asks);
* the lockstep client's last tick;
* the Bus's (``Bus.checkpoint``): sequence counts, admission, the messages waiting in its inbox,
  and its channel stage.

Everything else is rebuilt identically from the scenario when the process starts.  The values
are the node's own objects, not copies: pickle them at once (the store does).
"""

from __future__ import annotations

from typing import Any

from interfaces.runtime.app import App
from interfaces.runtime.executive import Executive, TickClient

NodeState = dict[str, Any]
"""A node's state, as ``capture`` takes it (a tree of dicts, lists, numbers, arrays, messages)."""


def capture(ex: Executive) -> NodeState:
    """The state of the node ``ex`` runs, after its last tick (the one it last answered: its
    lockstep client may hold the next ones queued)."""
    return {
        "tick": -1 if ex.last_done is None else ex.last_done.k,
        "apps": {app.NAME: app.checkpoint() for app in ex.apps},
        "executive": ex.checkpoint(),
        "bus": ex.bus.checkpoint(),
    }


def restore(client: TickClient, state: NodeState) -> None:
    """Put ``state`` (``capture``) back into the freshly built node of ``client``; ValueError,
    before anything is changed, if it is not a state of this node's make."""
    ex = client.executive
    apps = {app.NAME: app for app in ex.apps}
    _check(apps, state)
    for name, saved in state["apps"].items():
        apps[name].restore(saved)
    ex.restore(state["executive"])
    ex.bus.restore(state["bus"])
    client.resume_after(state["tick"])


def _check(apps: dict[str, App], state: NodeState) -> None:
    """ValueError unless ``state`` has this node's parts and each app's declared state."""
    if not isinstance(state, dict) or set(state) != {"tick", "apps", "executive", "bus"}:
        raise ValueError("not a node's state")
    if set(apps) != set(state["apps"]):
        raise ValueError(f"the store holds apps {sorted(state['apps'])}, the node runs "
                         f"{sorted(apps)}")
    for name, app in apps.items():
        held = set(state["apps"][name].get("state", {}))
        if held != set(app.CRITICAL):
            raise ValueError(f"the store holds {sorted(held)} of app {name}, which declares "
                             f"{sorted(app.CRITICAL)}")
