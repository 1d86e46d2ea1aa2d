"""The ground's rulings on the faults its observers' neighbours declared aboard (docs/fdir.md,
"Neighbours judge each other"): the ground's decision stands over the neighbours'.

A declaration (``NeighbourDeclaration``; every observer that applied the agreement rule sends
one, the same subject and window) is ruled on the first window of its subject, ending at or
after the declared window's end, on which the ground's own information test decided:
``upheld`` if that window failed or the ground's own declaration of the subject stands at its
end (the sequential test declares between windows: a pointing fault that began late in a
window is declared by the ground's scan while that window, a median, passes), ``overruled``
if it passed (the observers then fuse the subject again).  Each (subject, window) is ruled
once.
"""

from __future__ import annotations

import logging
from collections.abc import Collection

from interfaces.contracts.messages import NeighbourDeclaration, NeighbourRuling
from interfaces.contracts.timing import TIME_TOL_S


class NeighbourRulings:
    """The declarations awaiting a ruling, and who excludes whom meanwhile."""

    def __init__(self, node: str, log: logging.Logger) -> None:
        self.node = node
        self.log = log
        self.pending: dict[tuple[int, float], NeighbourDeclaration] = {}
        self.ruled: set[tuple[int, float]] = set()
        self.excluding: dict[int, set[int]] = {}
        """observer -> the subjects it leaves out of its fusion (its H_i is not the ground's)"""

    def declaration(self, msg: NeighbourDeclaration) -> None:
        key = (msg.subject, msg.t_end_s)
        if msg.spacecraft != msg.subject:
            self.excluding.setdefault(msg.spacecraft, set()).add(msg.subject)
        if key not in self.ruled:
            self.pending.setdefault(key, msg)

    def excludes(self, observer: int) -> bool:
        """Whether ``observer`` leaves a declared neighbour out of its fusion."""
        return bool(self.excluding.get(observer))

    def rule(self, b: float, exceeded: dict[int, bool | None], declared: Collection[int] = ()
             ) -> list[NeighbourRuling]:
        """Rulings on the declarations whose subject the ground judged in the window ending at
        ``b`` (s): ``exceeded`` by observer, None where it did not decide; ``declared``: the
        observers whose fault the ground itself holds declared at ``b``."""
        out = []
        for key in sorted(self.pending):
            subject, t_end = key
            verdict = exceeded.get(subject)
            if verdict is not None and subject in declared:
                verdict = True
            if t_end > b + TIME_TOL_S or verdict is None:
                continue
            del self.pending[key]
            self.ruled.add(key)
            ruling = "upheld" if verdict else "overruled"
            if ruling == "overruled":
                for subjects in self.excluding.values():
                    subjects.discard(subject)
            self.log.warning("FDIR: the neighbours' declaration on sc%d (window to %.0f s) %s "
                             "on the window to %.0f s", subject, t_end, ruling, b)
            out.append(NeighbourRuling(sender=self.node, t_sim=b, subject=subject,
                                       window_end_s=t_end, verdict=ruling))
        return out
