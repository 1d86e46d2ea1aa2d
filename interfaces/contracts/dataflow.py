"""The constellation's dataflow (docs/architecture.md, "Dataflow"): every catalogued topic with
who publishes it and who reads it, each reader and writer with its rate group, and the picture
of it (Mermaid) that the architecture document carries.

Where the logic lives, and why.  What an app reads and publishes is declared on its class
(``INPUTS``, ``OUTPUTS``, ``RATE``: ``interfaces/runtime/app.py``), in flight and ground code
that the contracts may not import.  So the graph is built here from plain declarations
(``Declared``), which know only the catalogue's topics, and the declarations are gathered by
``interfaces.runtime.assembly:declarations``, the one place that already loads the apps the
topology names, by name, at run time.  ``python -m interfaces.contracts.topology --graph``
loads that function by name as the topology names its apps, so no contract imports the runtime,
and the graph itself can be tested on made-up declarations.

Who publishes what, when it is no app, is read from the catalogue's publisher field
(``Topic.space``): the sim every topic of its key spaces (``sim``, ``sim hardware``), every
lockstep node's executive every ``every node`` topic.  What the sim reads is its own
declaration's (``SIM``: ``SUBSCRIBES``).  The recorder reads everything (``insp/<m>/**``): the
graph says so once and draws no edge to it.

Keys are collapsed over spacecraft: ``sc/{i}/nav/estimate`` is spacecraft i's; a reader on
``sc{i}`` hears its own spacecraft's key, one on ``sc{*}`` every spacecraft's (each spacecraft
does), the ground every spacecraft's.  Apps that a scenario section turns on are marked
``if <section>`` (``[onboard_fdir]``, ``[neighbours]``).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, NamedTuple

from interfaces.contracts import catalogue as cat
from interfaces.contracts.apps import (
    GROUND_APPS,
    NEIGHBOUR_APPS,
    ONBOARD_FDIR_APPS,
    SPACECRAFT_APPS,
)
from interfaces.contracts.catalogue import Space, Topic

Place = Literal["sc", "ground", "sim", "node"]
"""Where a reader or writer runs: on each spacecraft, on the ground, in the sim, or on every
lockstep node (the executive, the bus's channel model)."""

SIM = "sim.node:SimNode"
"""The sim's side of the bus, whose ``SUBSCRIBES`` lists what the sim reads."""

BEGIN = "<!-- dataflow:begin (generated: python -m interfaces.contracts.topology --write-doc) -->"
END = "<!-- dataflow:end -->"
"""The markers around the picture's block in docs/architecture.md."""

RECORDER = "the recorder (ground.archive.record) reads every topic, insp/<m>/**: no edge drawn"


class AppSlot(NamedTuple):
    """An app the topology can run: its ``"module:Class"`` name, where, and the scenario section
    that turns it on (None: always)."""

    name: str
    place: Place
    when: str | None = None


def roster() -> tuple[AppSlot, ...]:
    """Every app the topology can run, optional ones included, in the topology's order."""
    return (*(AppSlot(a, "sc") for a in SPACECRAFT_APPS),
            *(AppSlot(a, "sc", "onboard_fdir") for a in ONBOARD_FDIR_APPS),
            *(AppSlot(a, "sc", "neighbours") for a in NEIGHBOUR_APPS),
            *(AppSlot(a, "ground") for a in GROUND_APPS))


@dataclass(frozen=True)
class Read:
    """A subscription to ``topic``: from every publisher (``every_spacecraft``) or only the key
    that concerns the reader's own node (as ``interfaces.runtime.app.Input``)."""

    topic: Topic
    every_spacecraft: bool = False


@dataclass(frozen=True)
class Declared:
    """One reader and writer of the bus as declared: ``who`` (an app's NAME, or the sim, an
    executive, a channel model), where it runs, its rate group (``""``: no app, it runs every
    tick or on arrival), what it reads and writes, and the scenario section that turns it on."""

    who: str
    place: Place
    rate: str = ""
    reads: tuple[Read, ...] = ()
    writes: tuple[Topic, ...] = ()
    when: str | None = None


def written_by(*spaces: Space) -> tuple[Topic, ...]:
    """The catalogued topics of ``spaces`` (their publisher, by the catalogue)."""
    return tuple(t for t in cat.ALL if t.space in spaces)


def sim(reads: Iterable[Topic]) -> Declared:
    """The sim: it reads ``reads`` from every node and publishes its key spaces' topics."""
    return Declared("sim", "sim", reads=tuple(Read(t, True) for t in reads),
                    writes=written_by(Space.SIM, Space.SIM_HARDWARE))


def executive(reads: Iterable[Topic]) -> Declared:
    """Every lockstep node's executive: it reads ``reads`` (the lockstep's) and publishes the
    topics every node publishes."""
    return Declared("executive", "node", reads=tuple(Read(t) for t in reads),
                    writes=written_by(Space.EVERY_NODE))


@dataclass(frozen=True)
class End:
    """One end of an edge: a declaration where it runs, ``every``: a reader hearing every
    publisher of the topic (not only its own node's key), ``note``: whose key it hears when
    that is not plain from where it runs."""

    place: Place
    who: str
    rate: str = ""
    when: str | None = None
    every: bool = False
    note: str = ""

    @property
    def node(self) -> str:
        """``sc{i}``, ``sc{*}`` (each spacecraft, hearing every spacecraft), ``ground``,
        ``sim`` or ``{node}`` (every lockstep node)."""
        if self.place == "sc":
            return "sc{*}" if self.every else "sc{i}"
        return "{node}" if self.place == "node" else self.place

    @property
    def box(self) -> str:
        """Its box in the picture (one per declaration, wherever it reads from)."""
        return "sim" if self.place == "sim" else f"{self.place}_{self.who}"

    @property
    def tags(self) -> tuple[str, ...]:
        """Its rate group and the section that turns it on, those it has."""
        return tuple(x for x in (self.rate, f"if {self.when}" if self.when else "") if x)

    def __str__(self) -> str:
        tags = ", ".join(self.tags)
        name = self.who if self.who == self.node else f"{self.node}.{self.who}"
        return name + (f" [{tags}]" if tags else "") + (f" ({self.note})" if self.note else "")


def pattern(topic: Topic) -> str:
    """The topic's key below ``insp/<m>/``, collapsed over spacecraft and nodes."""
    where = {Space.SPACECRAFT: "sc/{i}", Space.EVERY_NODE: "{node}"}.get(topic.space)
    if topic.space is Space.SIM_HARDWARE:
        return f"sim/{topic.app}/sc{{i}}/{topic.name}"
    return f"{where or topic.space.value}/{topic.app}/{topic.name}"


@dataclass(frozen=True)
class Flow:
    """A topic's edges: its publishers, each to each of its readers."""

    topic: Topic
    producers: tuple[End, ...]
    consumers: tuple[End, ...]

    def __str__(self) -> str:
        writers = ", ".join(map(str, self.producers)) or "(no publisher)"
        readers = ", ".join(map(str, self.consumers)) or "(the recorder only)"
        return f"{pattern(self.topic)}: {writers} → {readers}"


def _producer(d: Declared) -> End:
    return End(d.place, d.who, d.rate, d.when)


def _consumer(d: Declared, r: Read) -> End:
    note = ""
    if r.topic.space is Space.EVERY_NODE and d.place in ("sc", "ground"):
        note = "from sc{*}" if r.every_spacecraft else f"{_producer(d).node}'s own"
    return End(d.place, d.who, d.rate, d.when, r.every_spacecraft, note)


def graph(declared: Iterable[Declared]) -> tuple[Flow, ...]:
    """Every catalogued topic, in the catalogue's order, with the declarations that publish and
    read it (topics outside the catalogue are the catalogue test's business)."""
    ds = tuple(declared)
    return tuple(Flow(t, tuple(_producer(d) for d in ds if t in d.writes),
                      tuple(_consumer(d, r) for d in ds for r in d.reads if r.topic == t))
                 for t in cat.ALL)


def edges(flows: Iterable[Flow]) -> str:
    """The graph as text: a legend, then each topic's ``key: publishers → readers``."""
    legend = [
        "# key (below insp/<m>/): publishers → readers [rate group, if <scenario section>]",
        "# sc{i}: spacecraft i (its own key); sc{*}: each spacecraft, hearing every spacecraft;"
        " {node}: every lockstep node",
        f"# {RECORDER}",
    ]
    return "\n".join([*legend, *map(str, flows)])


# --- the picture -----------------------------------------------------------------------------

GROUPS: tuple[tuple[Place, str], ...] = (
    ("sc", "sc{i}: each observer's flight software"),
    ("ground", "ground"),
    ("node", "{node}: every lockstep node"),
)
"""The picture's frames, one per place (the sim is a box of its own)."""


def _box_label(end: End) -> str:
    if end.place == "sim":
        return "sim<br/>clock, truth, sensors, actuators"
    tags = " · ".join(end.tags)
    return end.who + (f"<br/>{tags}" if tags else "")


def _edge_label(topic: Topic, reader: End) -> str:
    note = reader.note or ("from every sc" if reader.every and reader.place == "sc" else "")
    return f"{topic.app}/{topic.name}" + (f" ({note})" if note else "")


def _boxes(flows: tuple[Flow, ...]) -> list[End]:
    """Each declaration's box once, in the order first seen."""
    seen: dict[str, End] = {}
    for end in (e for f in flows for e in (*f.producers, *f.consumers)):
        seen.setdefault(end.box, End(end.place, end.who, end.rate, end.when))
    return list(seen.values())


def _arrows(flows: tuple[Flow, ...]) -> list[str]:
    """One arrow per (publisher, reader, optional) with its topics; dashed when either end
    is an optional app."""
    labels: dict[tuple[str, str, bool], list[str]] = {}
    for f in flows:
        for p in f.producers:
            for c in f.consumers:
                key = (p.box, c.box, bool(p.when or c.when))
                labels.setdefault(key, []).append(_edge_label(f.topic, c))
    return [f'    {a} {"-.->" if dashed else "-->"}|"{"<br/>".join(ls)}"| {b}'
            for (a, b, dashed), ls in labels.items()]


def mermaid(flows: Iterable[Flow]) -> str:
    """The graph as a Mermaid flowchart: a frame per place, a box per declaration (its rate
    group; ``if <section>`` for an optional app), an arrow per publisher and reader labelled
    with their topics (dashed to or from an optional app), the recorder said once."""
    fs = tuple(flows)
    boxes = _boxes(fs)
    lines = ["flowchart LR", f'    sim["{_box_label(End("sim", "sim"))}"]']
    for place, title in GROUPS:
        lines.append(f'    subgraph {place}_frame["{title}"]')
        lines += [f'        {e.box}["{_box_label(e)}"]' for e in boxes if e.place == place]
        lines.append("    end")
    lines.append('    recorder["recorder<br/>reads every topic: no edge drawn"]')
    return "\n".join(lines + _arrows(fs)) + "\n"


def doc_block(flows: Iterable[Flow]) -> str:
    """What stands between the markers in docs/architecture.md."""
    return f"\n```mermaid\n{mermaid(flows)}```\n"


def _bounds(doc: str) -> tuple[int, int]:
    if doc.count(BEGIN) != 1 or doc.count(END) != 1 or doc.index(BEGIN) > doc.index(END):
        raise ValueError(f"the document needs one {BEGIN!r} and, after it, one {END!r}")
    return doc.index(BEGIN) + len(BEGIN), doc.index(END)


def block_of(doc: str) -> str:
    """The block between the markers of ``doc``."""
    start, stop = _bounds(doc)
    return doc[start:stop]


def spliced(doc: str, block: str) -> str:
    """``doc`` with ``block`` between its markers."""
    start, stop = _bounds(doc)
    return doc[:start] + block + doc[stop:]


def write_doc(path: Path, flows: Iterable[Flow]) -> bool:
    """Rewrite the block in the document at ``path``; whether it changed."""
    doc = path.read_text()
    new = spliced(doc, doc_block(flows))
    if new != doc:
        path.write_text(new)
    return new != doc
