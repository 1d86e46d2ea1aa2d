"""The neighbours' FDIR onboard (``[neighbours]``; ``fsw/apps/neighbours.py``, docs/fdir.md
"Neighbours judge each other"): between ground passes each observer judges every neighbour it
hears, and a fault is declared aboard by their agreement.

    [neighbours]
    enabled = true
    agree = 2          # judges that must find a window failed (one, when only one judged it)
    action = "none"    # what the declared observer's own FDIR starts when told
    clear_windows = 3  # windows in a row found passing that clear a declaration aboard

Off by default, so that a scenario without it flies as before.
"""

from __future__ import annotations

from pydantic import Field

from interfaces.contracts.scenario.base import Section
from interfaces.contracts.scenario.onboard import SequenceName


class Neighbours(Section):
    """The neighbours' FDIR: the agreement rule and the declared observer's action."""

    enabled: bool = False
    agree: int = Field(
        default=2, ge=1, le=64,
        description="a neighbour's window is declared failed when at least this many of the "
                    "neighbours that judged it found it failed and they are more than half of "
                    "them; when only one neighbour judged it, that one suffices")
    action: SequenceName = Field(
        default="none", description="the stored sequence the declared observer's onboard FDIR "
                                    "starts when its neighbours declare it (with "
                                    "[onboard_fdir] on; none: an event only)")
    clear_windows: int = Field(
        default=3, ge=1, le=1000,
        description="a declared neighbour is still judged; this many of its windows in a row "
                    "found passing by the same agreement clear the declaration aboard (it is "
                    "fused again), so a later fault is declared anew")
