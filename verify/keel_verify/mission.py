"""The mission model and its loader — the reader of the mission-file contract.

The rules are those of ``config/schema/README.md`` and ``mission.schema.json``. This is
the only reader of mission YAML: a node reads the image ``keel-verify compile`` writes
(``core/mission/image.cpp``), and ``tests/missions/`` runs every fixture through this
reader. ``load_mission(path)`` returns a :class:`Mission` or raises :class:`MissionError`
carrying every error of the first stage that found any, each with its file, line, column
and rule.
"""

from __future__ import annotations

import difflib
import json
import math
import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import jsonschema
import jsonschema_rs
import yaml

from keel_verify.resources import schema_path

# The mission file's JSON Schema, config/schema/mission.schema.json (keel_verify.resources).
SCHEMA_NAME = "mission.schema.json"
SAFE = "SAFE"

# Rules of stage 1 are reported by the verifier as kind "schema" (exit 2); the others keep
# their own kind (exit 1). See config/schema/README.md.
SHAPE_RULES = frozenset(
    {
        "unreadable",
        "yaml-syntax",
        "duplicate-key",
        "unknown-key",
        "missing-key",
        "wrong-type",
        "out-of-range",
        "bad-value",
        "bad-name",
        "empty",
        "duplicate-name",
    }
)

# Limits: a document larger than MAX_FILE_BYTES, nested deeper than MAX_YAML_DEPTH (also
# through aliases), or whose aliases add more than MAX_YAML_NODES nodes to those written
# (alias bombs) is refused. What is written is bounded by the file's size alone.
MAX_YAML_NODES = 1_000_000
MAX_YAML_DEPTH = 100
MAX_FILE_BYTES = 16 * 1024 * 1024
INT64_MIN = -(2**63)
INT64_MAX = 2**63 - 1

Path_ = tuple[Any, ...]

# Control characters and line breaks in messages (a quoted name may hold any) are escaped,
# so that every error prints as one line.
_ONE_LINE = {
    code: {0x09: "\\t", 0x0A: "\\n", 0x0D: "\\r"}.get(code, f"\\x{code:02x}")
    for code in [*range(0x20), *range(0x7F, 0xA0)]
} | {0x2028: "\\u2028", 0x2029: "\\u2029"}


@dataclass(frozen=True, order=True)
class LoadError:
    line: int
    col: int
    rule: str
    message: str
    file: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "message", self.message.translate(_ONE_LINE))

    @property
    def kind(self) -> str:
        return "schema" if self.rule in SHAPE_RULES else self.rule

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}: {self.rule}: {self.message}"


class MissionError(Exception):
    """A mission file that cannot be loaded; ``errors`` is sorted by position."""

    def __init__(self, errors: list[LoadError]):
        self.errors = sorted(set(errors))
        super().__init__("\n".join(str(e) for e in self.errors))

    @property
    def is_input_error(self) -> bool:
        return any(e.rule in SHAPE_RULES for e in self.errors)


# --------------------------------------------------------------------------------------
# The model


@dataclass(frozen=True)
class Resources:
    cpu: int | None
    mem_mb: int | None


@dataclass(frozen=True)
class Node:
    name: str
    kind: str  # "processing" | "interface"
    role: str | None  # None for processing nodes; "storage" | "interface"
    capabilities: tuple[str, ...]
    capacity: Resources  # None = unbounded
    line: int = 0

    @property
    def is_processing(self) -> bool:
        return self.kind == "processing"

    @property
    def is_storage(self) -> bool:
        return self.role == "storage"


@dataclass(frozen=True)
class Health:
    min: float | None
    max: float | None
    deadline_ms: int | None


@dataclass(frozen=True)
class Task:
    name: str
    port: int
    component: str
    requires: tuple[str, ...]
    load: Resources  # never None: missing = 0
    essential: bool
    checkpoint: bool
    inputs: tuple[str, ...]
    period_ms: int | None
    health: Health | None
    params: dict[str, Any]
    max_sample_bytes: int | None = None  # the largest sample it outputs; None: not stated
    max_state_bytes: int | None = None  # the largest checkpoint state; None: not stated
    priority: int | None = None  # the online placer sheds the lowest first; None: not stated (0)
    group: str | None = None  # tasks of one group are spread over nodes; None: in none
    line: int = 0


@dataclass(frozen=True)
class Configuration:
    name: str
    phase: str
    master: str
    observers: tuple[str, ...]
    placement: dict[str, str]  # task -> node, in file order
    line: int = 0


@dataclass(frozen=True)
class Phase:
    name: str
    tasks: tuple[str, ...]
    initial: str
    configurations: dict[str, Configuration]
    on_failure: dict[str, dict[str, str]]  # config -> failed node -> next config | SAFE
    on_phase: dict[str, dict[str, str]]  # target phase -> (config -> target config)
    params: dict[str, dict[str, Any]]
    line: int = 0
    # Line of each on_failure edge (config, node) and each on_phase entry (phase, config).
    on_failure_lines: dict[tuple[str, str], int] = field(default_factory=dict)
    # Line of each configuration's on_failure block (config -> line; "" -> the phase's
    # `on_failure:` key): where an edge that is missing is written.
    on_failure_block_lines: dict[str, int] = field(default_factory=dict)
    on_phase_lines: dict[tuple[str, str], int] = field(default_factory=dict)
    # config -> readmitted node -> next config (never SAFE); no edge: the configuration of
    # the smaller failed set (docs/fault-model.md, "Reintegration").
    on_recovery: dict[str, dict[str, str]] = field(default_factory=dict)
    on_recovery_lines: dict[tuple[str, str], int] = field(default_factory=dict)
    # Where the configurations come from (docs/missions.md, "Placement modes"): "graph",
    # "online" (the placer for every failure; the initial configuration only) or
    # "graph+online" (the placer where the graph says SAFE or has no edge).
    placement: str = "graph"


# heartbeat.startup_grace_ms when the mission does not set it (mission.schema.json).
DEFAULT_STARTUP_GRACE_MS = 2000


@dataclass(frozen=True)
class Heartbeat:
    period_ms: int
    miss_limit: int
    startup_grace_ms: int = DEFAULT_STARTUP_GRACE_MS
    # Periods a node runs in a tie on the ground's standing acknowledgement
    # (spec/Designate.tla, TieGrace); 0: the ground is no voter (mission.schema.json).
    tie_grace: int = 0

    @property
    def startup_grace_periods(self) -> int:
        """Periods a never-heard node is given: max(miss_limit, ceil(grace / period))."""
        return max(self.miss_limit, -(-self.startup_grace_ms // self.period_ms))


@dataclass(frozen=True)
class Tolerance:
    node_failures: int
    nodes: tuple[str, ...]


@dataclass(frozen=True)
class Mission:
    name: str
    path: str
    heartbeat: Heartbeat
    tolerance: Tolerance
    nodes: dict[str, Node]
    tasks: dict[str, Task]
    phases: dict[str, Phase]
    # The mission's revision (a number that only grows from one image to the next), or
    # None when the file states none (read as 0).
    revision: int | None = None

    def configuration(self, name: str) -> Configuration:
        for phase in self.phases.values():
            if name in phase.configurations:
                return phase.configurations[name]
        raise KeyError(name)

    @property
    def processing_nodes(self) -> list[str]:
        return [n for n, node in self.nodes.items() if node.is_processing]

    @property
    def storage_nodes(self) -> list[str]:
        return [n for n, node in self.nodes.items() if node.is_storage]

    def to_json(self) -> dict[str, Any]:
        """The normalised form ``keel-verify load --json`` prints (config/schema/README.md)."""

        def resources(r: Resources) -> dict[str, Any]:
            return {"cpu": r.cpu, "mem_mb": r.mem_mb}

        return {
            "mission": self.name,
            "schema": 1,
            # Absent when not stated: an image without it reads as before.
            **({"revision": self.revision} if self.revision is not None else {}),
            "heartbeat": {
                "period_ms": self.heartbeat.period_ms,
                "miss_limit": self.heartbeat.miss_limit,
                "startup_grace_ms": self.heartbeat.startup_grace_ms,
                # Absent when 0, so that images of missions that leave it at 0 keep their
                # bytes and hash.
                **({"tie_grace": self.heartbeat.tie_grace} if self.heartbeat.tie_grace else {}),
            },
            "tolerance": {
                "node_failures": self.tolerance.node_failures,
                "nodes": list(self.tolerance.nodes),
            },
            "nodes": [
                {
                    "name": n.name,
                    "kind": n.kind,
                    "role": n.role,
                    "capabilities": list(n.capabilities),
                    "capacity": resources(n.capacity),
                }
                for n in self.nodes.values()
            ],
            "tasks": [
                {
                    "name": t.name,
                    "port": t.port,
                    "component": t.component,
                    "requires": list(t.requires),
                    "load": resources(t.load),
                    "essential": t.essential,
                    "checkpoint": t.checkpoint,
                    "inputs": list(t.inputs),
                    "period_ms": t.period_ms,
                    "health": None
                    if t.health is None
                    else {
                        "min": t.health.min,
                        "max": t.health.max,
                        "deadline_ms": t.health.deadline_ms,
                    },
                    "params": dict(t.params),
                    # Absent when not stated: an image without it reads as before.
                    **(
                        {"max_sample_bytes": t.max_sample_bytes}
                        if t.max_sample_bytes is not None
                        else {}
                    ),
                    **(
                        {"max_state_bytes": t.max_state_bytes}
                        if t.max_state_bytes is not None
                        else {}
                    ),
                    **({"priority": t.priority} if t.priority is not None else {}),
                    **({"group": t.group} if t.group is not None else {}),
                }
                for t in self.tasks.values()
            ],
            "phases": [_phase_json(p) for p in self.phases.values()],
        }


def _phase_json(p: Phase) -> dict[str, Any]:
    out: dict[str, Any] = {
        "name": p.name,
        "tasks": list(p.tasks),
        "initial": p.initial,
        "configurations": [
            {
                "name": c.name,
                "master": c.master,
                "observers": list(c.observers),
                "tasks": [[t, n] for t, n in c.placement.items()],
            }
            for c in p.configurations.values()
        ],
        "on_failure": [
            {"config": c, "node": n, "next": nxt}
            for c, edges in p.on_failure.items()
            for n, nxt in edges.items()
        ],
        "on_phase": [
            {"phase": target, "from": c, "to": to}
            for target, mapping in p.on_phase.items()
            for c, to in mapping.items()
        ],
        "params": {t: dict(v) for t, v in p.params.items()},
    }
    # Absent for the graph: a graph image reads, and hashes, as before.
    if p.placement != "graph":
        out["placement"] = p.placement
    # Absent when the phase has none: an image without recovery edges reads as before.
    if p.on_recovery:
        out["on_recovery"] = [
            {"config": c, "node": n, "next": nxt}
            for c, edges in p.on_recovery.items()
            for n, nxt in edges.items()
        ]
    return out


# --------------------------------------------------------------------------------------
# Stage 0: YAML to plain data, with positions, YAML 1.2 core scalars and duplicate keys

_INT = re.compile(r"^[-+]?[0-9]+$")
_FLOAT = re.compile(r"^[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?$")
_INF = re.compile(r"^[-+]?\.(inf|Inf|INF)$")
_NAN = re.compile(r"^\.(nan|NaN|NAN)$")


def _scalar(node: yaml.ScalarNode) -> Any:
    if node.style is not None:  # quoted or block scalars are strings
        return node.value
    return _plain_scalar(node.value)


def _plain_scalar(text: str) -> Any:
    """A plain scalar's value under YAML 1.2's core schema."""
    if text[:1] not in _NUMBER_START:
        return _WORDS.get(text, text)
    if _INT.match(text):
        return int(text)
    if _FLOAT.match(text):
        return float(text)
    if _INF.match(text):
        return -math.inf if text.startswith("-") else math.inf
    if _NAN.match(text):
        return math.nan
    return text


# Every number, infinity and NaN starts with one of these; no word below does.
_NUMBER_START = frozenset("+-.0123456789")
_WORDS: dict[str, Any] = {
    "": None,
    "~": None,
    "null": None,
    "Null": None,
    "NULL": None,
    "true": True,
    "True": True,
    "TRUE": True,
    "false": False,
    "False": False,
    "FALSE": False,
}


_SURROGATE = re.compile("[\ud800-\udfff]")


class _Checks:
    """PyYAML's safe composer, refusing tags and documents nested too deeply.

    Tags are refused because YAML readers disagree on how to type tagged scalars (the
    mission schema never needs one). The depth limit keeps the recursive composer far
    from Python's recursion limit.
    """

    _depth = 0
    buffer: str

    def compose_node(self, parent: yaml.Node | None, index: Any) -> yaml.Node:
        event = self.peek_event()
        self._depth += 1
        try:
            if self._depth > MAX_YAML_DEPTH:
                raise yaml.composer.ComposerError(
                    None, None, f"nested deeper than {MAX_YAML_DEPTH} levels", event.start_mark
                )
            anchor = getattr(event, "anchor", None)
            start = event.start_mark.index
            if anchor is not None and self.buffer[start : start + 1] in ("&", "*"):
                # YAML 1.2 lets an anchor name go on with ':' (`&a: x` is an anchor "a:");
                # PyYAML stops the name there. Refuse what YAML readers read apart.
                after = self.buffer[start + 1 + len(anchor) : start + 2 + len(anchor)]
                if after in (":", "?", "%", "@", "`"):
                    raise yaml.composer.ComposerError(
                        None,
                        None,
                        f"an anchor name is letters, digits, '-' and '_' (found '{anchor}{after}')",
                        event.start_mark,
                    )
            is_key = isinstance(parent, yaml.MappingNode) and index is None
            if is_key and isinstance(event, yaml.ScalarEvent) and event.value == "":
                if event.implicit[0] and event.anchor is None:
                    # `? ` with nothing after it: YAML readers build different
                    # mappings from it, and a mission has no use for an empty key.
                    raise yaml.composer.ComposerError(
                        None, None, "a mapping key is empty", event.start_mark
                    )
            if isinstance(event, yaml.ScalarEvent) and _SURROGATE.search(event.value):
                # "\ud83d" escapes a lone surrogate: not a character, and not UTF-8.
                raise yaml.composer.ComposerError(
                    None, None, "a \\u escape names a surrogate, not a character", event.start_mark
                )
            tag = getattr(event, "tag", None)
            if tag is not None and not isinstance(event, yaml.AliasEvent):
                raise yaml.composer.ComposerError(
                    None,
                    None,
                    f"tags are not supported in a mission file (found '{tag}')",
                    event.start_mark,
                )
            return super().compose_node(parent, index)  # type: ignore[misc]
        finally:
            self._depth -= 1


class _Loader(_Checks, yaml.SafeLoader):
    """The pure-Python reader: its error messages and positions are the reference."""


try:
    from yaml._yaml import CParser as _CParser
except ImportError:  # pragma: no cover - PyYAML built without libyaml
    _CParser = None

if _CParser is not None:

    class _FastLoader(
        _Checks,
        yaml.composer.Composer,
        _CParser,
        yaml.constructor.SafeConstructor,
        yaml.resolver.Resolver,
    ):
        """libyaml's parser under the same Python composer and checks: several times faster
        on large missions. Used first; a document it refuses is read again by _Loader so
        that syntax errors are reported exactly as the reference reader reports them."""

        def __init__(self, stream: str):
            _CParser.__init__(self, stream)
            yaml.composer.Composer.__init__(self)
            yaml.constructor.SafeConstructor.__init__(self)
            yaml.resolver.Resolver.__init__(self)
            self.buffer = stream

        def compose_scalar_node(self, anchor: Any) -> yaml.ScalarNode:
            node = super().compose_scalar_node(anchor)
            if node.style == "":  # libyaml says '' where PyYAML says None: a plain scalar
                node.style = None
            return node

else:  # pragma: no cover - PyYAML built without libyaml
    _FastLoader = _Loader  # type: ignore[misc,assignment]


class _Unusual(Exception):
    """Raised by _read_plain on anything outside the common shape of a mission file."""


def _read_plain(text: str, file: str) -> tuple[Any, _Document]:
    """Plain data and positions straight from libyaml's events, with no node tree.

    Covers the files missions are: one document of mappings, sequences and untagged
    scalars without anchors or aliases, nested at most MAX_YAML_DEPTH deep, with unique
    non-empty scalar keys and integers that fit in 64 bits. Anything else raises _Unusual
    and the file is read by the composers above, which know how to say what is wrong; the
    result of both routes is the same (tests/missions/test_loaders.py compares them).
    """
    if _CParser is None:  # pragma: no cover - PyYAML built without libyaml
        raise _Unusual()
    try:
        return _read_events(text, file)
    except yaml.YAMLError:
        raise _Unusual() from None  # not YAML: the reference reader says where and why


def _read_events(text: str, file: str) -> tuple[Any, _Document]:
    doc = _Document(file)
    value_pos = doc.value_pos
    key_pos = doc.key_pos
    get = _CParser(text).get_event
    scalar_event = yaml.ScalarEvent
    mapping_start, sequence_start = yaml.MappingStartEvent, yaml.SequenceStartEvent
    if type(get()) is not yaml.StreamStartEvent or type(get()) is not yaml.DocumentStartEvent:
        raise _Unusual()
    root: Any = None
    integral_float = False
    # One frame per open collection: [the collection, its path, the key awaiting a value].
    stack: list[list[Any]] = []
    container: Any = None
    path: Path_ = ()
    key: Any = None
    while True:
        event = get()
        kind = type(event)
        if kind is scalar_event or kind is mapping_start or kind is sequence_start:
            if event.anchor is not None or event.tag is not None:
                raise _Unusual()
            if len(stack) >= MAX_YAML_DEPTH:
                raise _Unusual()
            mark = event.start_mark
            pos = (mark.line + 1, mark.column + 1)
            if kind is scalar_event:
                text_value = event.value
                # Only a double-quoted scalar's \u escape can name a surrogate.
                if event.style == '"' and _SURROGATE.search(text_value):
                    raise _Unusual()
                if type(container) is dict and key is None:  # a mapping key
                    if text_value == "" and event.implicit[0]:
                        raise _Unusual()
                    if text_value in container:
                        raise _Unusual()
                    key = text_value
                    key_pos[path + (key,)] = pos
                    continue
                if event.style:  # quoted or block scalars are strings
                    value: Any = text_value
                else:
                    value = _plain_scalar(text_value)
                    if type(value) is int and not INT64_MIN <= value <= INT64_MAX:
                        raise _Unusual()
                    if type(value) is float and not (math.isfinite(value) and value % 1):
                        integral_float = True
            else:
                if type(container) is dict and key is None:  # a collection as a key
                    raise _Unusual()
                value = {} if kind is mapping_start else []
            if container is None:
                if stack or root is not None:
                    raise _Unusual()
                root = value
                here: Path_ = ()
            elif type(container) is dict:
                here = path + (key,)
                container[key] = value
                key = None
            else:
                here = path + (len(container),)
                container.append(value)
            value_pos[here] = pos
            if kind is not scalar_event:
                stack.append([container, path, key])
                container, path, key = value, here, None
        elif kind is yaml.MappingEndEvent or kind is yaml.SequenceEndEvent:
            container, path, key = stack.pop()
        elif kind is yaml.DocumentEndEvent:
            break
        else:  # an alias, or anything libyaml adds
            raise _Unusual()
    if root is None or type(get()) is not yaml.StreamEndEvent:
        raise _Unusual()
    doc.fast_shape = not integral_float
    return root, doc


def _position(text: str, index: int) -> tuple[int, int]:
    """PyYAML's 1-based line and column of a character index (a BOM takes no column)."""
    line, col = 1, 1
    i = 0
    while i < index:
        ch = text[i]
        if ch == "\n" or (ch == "\r" and (i + 1 >= len(text) or text[i + 1] != "\n")):
            line, col = line + 1, 1
        elif ch != "\ufeff":
            col += 1
        i += 1
    return line, col


_LINE_BREAKS = re.compile("[\x85\u2028\u2029]")
_NON_PRINTABLE = re.compile(
    "[^\x09\x0a\x0d\x20-\x7e\x85\xa0-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]"
)


def _check_characters(text: str, file: str) -> None:
    """Refuse what one of the two YAML parsers would read differently or not at all."""
    match = _LINE_BREAKS.search(text)
    if match:
        line, col = _position(text, match.start())
        name = f"U+{ord(match.group()):04X}"
        raise MissionError(
            [
                LoadError(
                    line,
                    col,
                    "yaml-syntax",
                    f"line break character {name} is not supported (use LF or CRLF)",
                    file,
                )
            ]
        )
    match = _NON_PRINTABLE.search(text)
    if match:
        line, col = _position(text, match.start())
        message = (
            f"unacceptable character #x{ord(match.group()):04x}: special characters are not allowed"
        )
        raise MissionError([LoadError(line, col, "yaml-syntax", message, file)])


class _Document:
    """Plain data plus the position of every value and every mapping key."""

    def __init__(self, file: str):
        self.file = file
        self.value_pos: dict[Path_, tuple[int, int]] = {}
        self.key_pos: dict[Path_, tuple[int, int]] = {}
        self.errors: list[LoadError] = []
        self._count = 0
        self._limit = MAX_YAML_NODES
        # Set by _read_plain when every number is one jsonschema_rs types as Python's
        # jsonschema does (no integral float, infinity or NaN): shape is then checked by
        # jsonschema_rs first, and by jsonschema only to name what is wrong.
        self.fast_shape = False

    def error(self, pos: tuple[int, int], rule: str, message: str) -> None:
        self.errors.append(LoadError(pos[0], pos[1], rule, message, self.file))

    def convert(self, node: yaml.Node, path: Path_, active: set[int]) -> Any:
        self._count += 1
        if self._count > self._limit:
            raise _TooLarge()
        pos = (node.start_mark.line + 1, node.start_mark.column + 1)
        self.value_pos[path] = pos
        if id(node) in active:
            raise _Cyclic(pos)
        if len(path) + 1 > MAX_YAML_DEPTH:  # aliases can nest deeper than the text does
            raise _TooDeep(pos)
        if isinstance(node, yaml.ScalarNode):
            value = _scalar(node)
            if type(value) is int and not INT64_MIN <= value <= INT64_MAX:
                self.error(pos, "out-of-range", f"the integer {value} does not fit in 64 bits")
            return value
        active.add(id(node))
        try:
            if isinstance(node, yaml.SequenceNode):
                return [
                    self.convert(item, path + (i,), active) for i, item in enumerate(node.value)
                ]
            result: dict[str, Any] = {}
            for key_node, value_node in node.value:
                key_pos = (key_node.start_mark.line + 1, key_node.start_mark.column + 1)
                if not isinstance(key_node, yaml.ScalarNode):
                    self.error(key_pos, "wrong-type", "a mapping key must be a scalar")
                    continue
                key = str(key_node.value)  # names are compared as written
                if key in result:
                    self.error(key_pos, "duplicate-key", f"duplicate key '{key}'")
                    continue
                self.key_pos[path + (key,)] = key_pos
                result[key] = self.convert(value_node, path + (key,), active)
            return result
        finally:
            active.discard(id(node))


def _expanded_size(
    node: yaml.Node, depth: int, sizes: dict[int, int], active: set[int], limit: int
) -> int:
    """How many nodes `node` stands for once its aliases are expanded (memoized per node,
    so shared subtrees cost once); deeper than MAX_YAML_DEPTH or cyclic is refused. Counting
    stops past `limit`."""
    known = sizes.get(id(node))
    if known is not None:
        return known
    pos = (node.start_mark.line + 1, node.start_mark.column + 1)
    if id(node) in active:
        raise _Cyclic(pos)
    if depth > MAX_YAML_DEPTH:
        raise _TooDeep(pos)
    total = 1
    if isinstance(node, (yaml.SequenceNode, yaml.MappingNode)):
        active.add(id(node))
        children = node.value if isinstance(node, yaml.SequenceNode) else [
            child for pair in node.value for child in pair]
        for child in children:
            total += _expanded_size(child, depth + 1, sizes, active, limit)
            if total > limit:
                break  # refused anyway; no need to count on
        active.discard(id(node))
    sizes[id(node)] = total
    return total


def _count_nodes(root: yaml.Node) -> int:
    """How many distinct nodes the document writes (an alias's target counts once)."""
    seen: set[int] = set()
    todo = [root]
    while todo:
        node = todo.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        if isinstance(node, yaml.SequenceNode):
            todo.extend(node.value)
        elif isinstance(node, yaml.MappingNode):
            for pair in node.value:
                todo.extend(pair)
    return len(seen)


class _Cyclic(Exception):
    def __init__(self, pos: tuple[int, int]):
        self.pos = pos


class _TooDeep(Exception):
    def __init__(self, pos: tuple[int, int]):
        self.pos = pos


class _TooLarge(Exception):
    pass


def _parse(text: str, file: str, loader: type = _Loader) -> tuple[Any, _Document]:
    doc = _Document(file)
    if len(text.encode("utf-8", "surrogatepass")) > MAX_FILE_BYTES:
        message = f"the mission file is larger than {MAX_FILE_BYTES // (1024 * 1024)} MiB"
        raise MissionError([LoadError(1, 1, "yaml-syntax", message, file)])
    _check_characters(text, file)
    if loader is _read_plain:
        return _read_plain(text, file)
    try:
        root = yaml.compose(text, Loader=loader)
    except yaml.MarkedYAMLError as error:
        mark = error.problem_mark or error.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (1, 1)
        problem = error.problem or "not valid YAML"
        raise MissionError([LoadError(line, col, "yaml-syntax", problem, file)]) from None
    except yaml.YAMLError as error:
        raise MissionError([LoadError(1, 1, "yaml-syntax", str(error), file)]) from None
    if root is None:
        raise MissionError([LoadError(1, 1, "yaml-syntax", "the mission file is empty", file)])
    try:
        # The size aliases expand to, counted once per distinct node, before any expansion:
        # a 1 KB alias bomb is refused at once, not after walking a million nodes. What is
        # written is bounded by MAX_FILE_BYTES; aliases may add at most MAX_YAML_NODES.
        sizes: dict[int, int] = {}
        written = _count_nodes(root)
        doc._limit = written + MAX_YAML_NODES
        if _expanded_size(root, 1, sizes, set(), doc._limit) > doc._limit:
            raise _TooLarge()
        data = doc.convert(root, (), set())
    except _Cyclic as cyclic:
        raise MissionError(
            [LoadError(cyclic.pos[0], cyclic.pos[1], "yaml-syntax", "cyclic alias", file)]
        ) from None
    except _TooDeep as deep:
        message = f"nested deeper than {MAX_YAML_DEPTH} levels"
        raise MissionError(
            [LoadError(deep.pos[0], deep.pos[1], "yaml-syntax", message, file)]
        ) from None
    except _TooLarge:
        raise MissionError(
            [
                LoadError(
                    1,
                    1,
                    "yaml-syntax",
                    f"aliases expand the document by more than {MAX_YAML_NODES} YAML nodes",
                    file,
                )
            ]
        ) from None
    return data, doc


# --------------------------------------------------------------------------------------
# Stage 1: shape (JSON Schema), errors mapped to rules and positions


def _is_integer(checker: Any, instance: Any) -> bool:
    # An integer is an integer scalar: the schema's "integer" does not take 1.0, as
    # jsonschema's default would (config/schema/README.md).
    return isinstance(instance, int) and not isinstance(instance, bool)


def _pattern(validator: Any, pattern: str, instance: Any, schema: Any) -> Any:
    # ECMA-262 semantics, as JSON Schema means them: '$' matches only at the very end
    # (Python's re.search would also let a name end in a line break).
    if validator.is_type(instance, "string") and not re.search(
        pattern.replace("$", r"\Z"), instance
    ):
        yield jsonschema.ValidationError(f"{instance!r} does not match {pattern!r}")


def _inline_refs(node: Any, definitions: dict[str, Any]) -> Any:
    """The schema with every local `$ref` replaced by what it names (the schema is not
    recursive). Resolving tens of thousands of references dominated validation time."""
    if isinstance(node, dict):
        ref = node.get("$ref")
        if isinstance(ref, str) and ref.startswith("#/$defs/"):
            target = _inline_refs(definitions[ref[len("#/$defs/") :]], definitions)
            rest = {k: _inline_refs(v, definitions) for k, v in node.items() if k != "$ref"}
            return {**target, **rest}
        return {k: _inline_refs(v, definitions) for k, v in node.items() if k != "$defs"}
    if isinstance(node, list):
        return [_inline_refs(item, definitions) for item in node]
    return node


@lru_cache(maxsize=1)
def _validator() -> Any:
    schema = json.loads(schema_path(SCHEMA_NAME).read_text(encoding="utf-8"))
    schema = _inline_refs(schema, schema.get("$defs", {}))
    base = jsonschema.Draft202012Validator
    validator = jsonschema.validators.extend(
        base,
        validators={"pattern": _pattern},
        type_checker=base.TYPE_CHECKER.redefine("integer", _is_integer),
    )
    return validator(schema)


_TYPE_WORDS = {
    "string": "a string",
    "integer": "an integer",
    "number": "a number",
    "boolean": "a boolean (true or false)",
    "array": "a list",
    "object": "a mapping",
}


def _describe(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, int):
        return f"the integer {value}"
    if isinstance(value, float):
        return f"the number {value}"
    if isinstance(value, str):
        return f"the string '{value}'"
    if isinstance(value, list):
        return "a list"
    return "a mapping"


def _did_you_mean(name: str, defined: Any) -> str:
    """" (did you mean 'PN3'?)" when a defined name is close to `name` (a typo), else "";
    the names are listed when there are a few and none is close."""
    names = sorted(str(d) for d in defined)
    # Only a name that is closer than every other: PN9 is as close to PN1 as to PN3.
    scored = sorted(((difflib.SequenceMatcher(None, name, other).ratio(), other)
                     for other in names), reverse=True)
    if scored and scored[0][0] >= 0.6 and (len(scored) == 1 or scored[0][0] > scored[1][0]):
        return f" (did you mean '{scored[0][1]}'?)"
    if 0 < len(names) <= 8:
        return f" (defined: {', '.join(names)})"
    return ""


def _where(path: Path_) -> str:
    return ".".join(str(p) for p in path) or "the file"


@lru_cache(maxsize=1)
def _fast_validator() -> Any:
    schema = json.loads(schema_path(SCHEMA_NAME).read_text(encoding="utf-8"))
    return jsonschema_rs.Draft202012Validator(schema)


def _shape_errors(data: Any, doc: _Document) -> None:
    # Every value the event route lets through (64-bit integers, finite non-integral floats,
    # strings, booleans, null) is one jsonschema_rs takes as jsonschema does.
    if doc.fast_shape and _fast_validator().is_valid(data):
        return
    for error in _validator().iter_errors(data):
        path: Path_ = tuple(error.absolute_path)
        value_pos = doc.value_pos.get(path, (1, 1))
        in_names = "propertyNames" in error.absolute_schema_path
        if in_names:
            key = error.instance
            pos = doc.key_pos.get(path + (key,), value_pos)
            doc.error(pos, "bad-name", f"'{key}' is not a valid name in {_where(path)}")
            continue
        kind = error.validator
        if kind == "additionalProperties" and isinstance(error.instance, dict):
            allowed = set(error.schema.get("properties", {}))
            for key in error.instance:
                if key not in allowed:
                    pos = doc.key_pos.get(path + (key,), value_pos)
                    known = ", ".join(sorted(allowed))
                    doc.error(
                        pos,
                        "unknown-key",
                        f"unknown key '{key}' in {_where(path)} (known: {known})",
                    )
        elif kind == "required" and isinstance(error.instance, dict):
            for key in error.validator_value:
                if key not in error.instance:
                    doc.error(
                        value_pos, "missing-key", f"{_where(path)} lacks required key '{key}'"
                    )
        elif kind == "type":
            wanted = error.validator_value
            wanted_list = wanted if isinstance(wanted, list) else [wanted]
            words = " or ".join(_TYPE_WORDS.get(w, w) for w in wanted_list)
            doc.error(
                value_pos,
                "wrong-type",
                f"{_where(path)} must be {words}, not {_describe(error.instance)}",
            )
        elif kind in ("enum", "const"):
            allowed_values = error.validator_value if kind == "enum" else [error.validator_value]
            shown = ", ".join(str(v) for v in allowed_values)
            doc.error(
                value_pos,
                "bad-value",
                f"{_where(path)} is {_describe(error.instance)}; allowed: {shown}",
            )
        elif kind in ("minimum", "maximum", "minLength"):
            doc.error(value_pos, "out-of-range", f"{_where(path)}: {error.message}")
        elif kind == "minProperties":
            doc.error(value_pos, "empty", f"{_where(path)} must not be empty")
        elif kind == "pattern":
            doc.error(
                value_pos, "bad-name", f"'{error.instance}' is not a valid name ({_where(path)})"
            )
        else:  # pragma: no cover - every keyword of the schema is mapped above
            doc.error(value_pos, "wrong-type", f"{_where(path)}: {error.message}")


def _rule_errors(data: dict[str, Any], doc: _Document) -> None:
    """Shape rules a JSON Schema cannot say: reserved names, role, health, config ids."""

    def reserved(path: Path_, name: str, what: str) -> None:
        if name == SAFE:
            doc.error(
                doc.key_pos[path], "bad-name", f"'{SAFE}' is reserved and cannot name a {what}"
            )

    for name in data["nodes"]:
        reserved(("nodes", name), name, "node")
    for name in data["tasks"]:
        reserved(("tasks", name), name, "task")
    for name in data["phases"]:
        reserved(("phases", name), name, "phase")
    for name, node in data["nodes"].items():
        if node["kind"] == "processing" and "role" in node:
            doc.error(
                doc.value_pos[("nodes", name, "role")],
                "bad-value",
                f"node {name}: role is only for interface nodes",
            )
    for name, task in data["tasks"].items():
        if "max_state_bytes" in task and not task.get("checkpoint", False):
            doc.error(
                doc.value_pos[("tasks", name, "max_state_bytes")],
                "bad-value",
                f"task {name}: max_state_bytes is for a checkpointed task (checkpoint: true)",
            )
        health = task.get("health") or {}
        # Compared as doubles, the type the Mission (and a node) keeps them in.
        if "min" in health and "max" in health and float(health["min"]) > float(health["max"]):
            doc.error(
                doc.value_pos[("tasks", name, "health", "max")],
                "bad-value",
                f"task {name}: health.max {health['max']} is below health.min {health['min']}",
            )
    seen: dict[str, str] = {}
    for phase_name, phase in data["phases"].items():
        for config_name in phase["configurations"]:
            path = ("phases", phase_name, "configurations", config_name)
            reserved(path, config_name, "configuration")
            if config_name in seen:
                doc.error(
                    doc.key_pos[path],
                    "duplicate-name",
                    f"configuration {config_name} is already defined in phase {seen[config_name]}",
                )
            else:
                seen[config_name] = phase_name


# --------------------------------------------------------------------------------------
# Stage 2: references and ports


def _reference_errors(data: dict[str, Any], doc: _Document) -> None:
    nodes = data["nodes"]
    tasks = data["tasks"]
    phases = data["phases"]
    capabilities = {c for n in nodes.values() for c in n.get("capabilities", [])}

    def unknown(pos: tuple[int, int], message: str) -> None:
        doc.error(pos, "unknown-reference", message)

    def check_value(path: Path_, name: str, defined: Any, what: str) -> None:
        if name not in defined:
            unknown(doc.value_pos[path],
                    f"{_where(path)}: {what} '{name}' is not defined{_did_you_mean(name, defined)}")

    def check_key(path: Path_, name: str, defined: Any, what: str) -> None:
        if name not in defined:
            unknown(doc.key_pos[path],
                    f"{_where(path[:-1])}: {what} '{name}' is not defined"
                    f"{_did_you_mean(name, defined)}")

    for i, name in enumerate(data["tolerance"].get("nodes", [])):
        check_value(("tolerance", "nodes", i), name, nodes, "node")
    for task_name, task in tasks.items():
        for i, cap in enumerate(task.get("requires", [])):
            path = ("tasks", task_name, "requires", i)
            if cap not in capabilities:
                unknown(doc.value_pos[path], f"{_where(path)}: no node offers capability '{cap}'"
                                             f"{_did_you_mean(cap, capabilities)}")
        for i, name in enumerate(task.get("inputs", [])):
            check_value(("tasks", task_name, "inputs", i), name, tasks, "task")
    for phase_name, phase in phases.items():
        base: Path_ = ("phases", phase_name)
        configs = phase["configurations"]
        for i, name in enumerate(phase.get("tasks", [])):
            check_value(base + ("tasks", i), name, tasks, "task")
        check_value(
            base + ("initial",), phase["initial"], configs, f"configuration of phase {phase_name}"
        )
        for config_name, config in configs.items():
            cpath = base + ("configurations", config_name)
            check_value(cpath + ("master",), config["master"], nodes, "node")
            for i, name in enumerate(config.get("observers", [])):
                check_value(cpath + ("observers", i), name, nodes, "node")
            for task_name, node_name in config["tasks"].items():
                check_key(cpath + ("tasks", task_name), task_name, tasks, "task")
                check_value(cpath + ("tasks", task_name), node_name, nodes, "node")
        for config_name, edges in phase.get("on_failure", {}).items():
            fpath = base + ("on_failure", config_name)
            check_key(fpath, config_name, configs, f"configuration of phase {phase_name}")
            for node_name, target in edges.items():
                check_key(fpath + (node_name,), node_name, nodes, "node")
                if target != SAFE:
                    check_value(
                        fpath + (node_name,),
                        target,
                        [*configs, SAFE],
                        f"configuration of phase {phase_name} (or {SAFE})",
                    )
        for config_name, edges in phase.get("on_recovery", {}).items():
            rpath = base + ("on_recovery", config_name)
            check_key(rpath, config_name, configs, f"configuration of phase {phase_name}")
            for node_name, target in edges.items():
                check_key(rpath + (node_name,), node_name, nodes, "node")
                check_value(
                    rpath + (node_name,), target, configs, f"configuration of phase {phase_name}"
                )
        for target_phase, mapping in phase.get("on_phase", {}).items():
            ppath = base + ("on_phase", target_phase)
            check_key(ppath, target_phase, phases, "phase")
            target_configs = phases.get(target_phase, {}).get("configurations", {})
            for config_name, to in mapping.items():
                check_key(
                    ppath + (config_name,),
                    config_name,
                    configs,
                    f"configuration of phase {phase_name}",
                )
                if target_phase in phases:
                    check_value(
                        ppath + (config_name,),
                        to,
                        target_configs,
                        f"configuration of phase {target_phase}",
                    )
        for task_name in phase.get("params", {}):
            check_key(base + ("params", task_name), task_name, tasks, "task")
        if phase.get("placement") == "online":
            # The placer decides every switch of an online phase: it has its initial
            # configuration and no graph edges (the image loader's rule).
            extra = [c for c in configs if c != phase["initial"]]
            if extra:
                doc.error(doc.key_pos[base + ("configurations", extra[0])], "bad-value",
                          f"phase {phase_name}: an online phase has only its initial configuration "
                          f"({phase['initial']}); the placer computes the others, not {extra[0]}")
            for key in ("on_failure", "on_recovery"):
                if phase.get(key):
                    doc.error(doc.key_pos[base + (key,)], "bad-value",
                              f"phase {phase_name}: an online phase has no {key} edges "
                              f"(the placer decides every switch)")

    ports: dict[int, str] = {}
    for task_name, task in tasks.items():
        port = task["port"]
        if port in ports:
            doc.error(
                doc.value_pos[("tasks", task_name, "port")],
                "port-conflict",
                f"task {task_name} uses port {port}, already used by task {ports[port]}",
            )
        else:
            ports[port] = task_name


# --------------------------------------------------------------------------------------
# Building the model


def _resources(raw: dict[str, Any] | None, default: int | None) -> Resources:
    raw = raw or {}
    return Resources(cpu=raw.get("cpu", default), mem_mb=raw.get("mem_mb", default))


def _float(value: int | float | None) -> float | None:
    return None if value is None else float(value)


def _build(data: dict[str, Any], doc: _Document, path: str) -> Mission:
    key_line = lambda *p: doc.key_pos.get(tuple(p), (0, 0))[0]  # noqa: E731
    nodes = {
        name: Node(
            name=name,
            kind=raw["kind"],
            role=raw.get("role", "interface") if raw["kind"] == "interface" else None,
            capabilities=tuple(raw.get("capabilities", [])),
            capacity=_resources(raw.get("capacity"), None),
            line=key_line("nodes", name),
        )
        for name, raw in data["nodes"].items()
    }
    tasks = {}
    for name, raw in data["tasks"].items():
        health = raw.get("health")
        tasks[name] = Task(
            name=name,
            port=raw["port"],
            component=raw.get("component", name),
            requires=tuple(raw.get("requires", [])),
            load=_resources(raw.get("load"), 0),
            essential=raw.get("essential", False),
            checkpoint=raw.get("checkpoint", False),
            inputs=tuple(raw.get("inputs", [])),
            period_ms=raw.get("period_ms"),
            health=None
            if health is None
            else Health(
                _float(health.get("min")), _float(health.get("max")), health.get("deadline_ms")
            ),
            params=dict(raw.get("params", {})),
            max_sample_bytes=raw.get("max_sample_bytes"),
            max_state_bytes=raw.get("max_state_bytes"),
            priority=raw.get("priority"),
            group=raw.get("group"),
            line=key_line("tasks", name),
        )
    phases = {}
    for phase_name, raw in data["phases"].items():
        base = ("phases", phase_name)
        configurations = {
            config_name: Configuration(
                name=config_name,
                phase=phase_name,
                master=c["master"],
                observers=tuple(c.get("observers", [])),
                placement=dict(c["tasks"]),
                line=key_line(*base, "configurations", config_name),
            )
            for config_name, c in raw["configurations"].items()
        }
        on_failure = {c: dict(edges) for c, edges in raw.get("on_failure", {}).items()}
        on_phase = {p: dict(m) for p, m in raw.get("on_phase", {}).items()}
        on_recovery = {c: dict(edges) for c, edges in raw.get("on_recovery", {}).items()}
        phases[phase_name] = Phase(
            name=phase_name,
            tasks=tuple(raw.get("tasks", list(tasks))),
            initial=raw["initial"],
            configurations=configurations,
            on_failure=on_failure,
            on_phase=on_phase,
            params={t: dict(v) for t, v in raw.get("params", {}).items()},
            line=key_line("phases", phase_name),
            placement=str(raw.get("placement", "graph")),
            on_failure_lines={
                (c, n): key_line(*base, "on_failure", c, n)
                for c, edges in on_failure.items()
                for n in edges
            },
            on_failure_block_lines={
                "": key_line(*base, "on_failure"),
                **{c: key_line(*base, "on_failure", c) for c in on_failure},
            },
            on_phase_lines={
                (p, c): key_line(*base, "on_phase", p, c) for p, m in on_phase.items() for c in m
            },
            on_recovery=on_recovery,
            on_recovery_lines={
                (c, n): key_line(*base, "on_recovery", c, n)
                for c, edges in on_recovery.items()
                for n in edges
            },
        )
    tolerance = data["tolerance"]
    return Mission(
        name=data["mission"],
        path=path,
        heartbeat=Heartbeat(
            data["heartbeat"]["period_ms"],
            data["heartbeat"]["miss_limit"],
            data["heartbeat"].get("startup_grace_ms", DEFAULT_STARTUP_GRACE_MS),
            data["heartbeat"].get("tie_grace", 0),
        ),
        tolerance=Tolerance(
            node_failures=tolerance["node_failures"],
            nodes=tuple(tolerance.get("nodes", list(nodes))),
        ),
        nodes=nodes,
        tasks=tasks,
        phases=phases,
        revision=data.get("revision"),
    )


def loads_mission(text: str, path: str = "<string>") -> Mission:
    """Load a mission from YAML text; ``path`` is used in error messages.

    A file is first read straight from libyaml's events into plain data (no node tree), and
    its shape checked by jsonschema_rs: the route of a mission without anchors or tags,
    about ten times faster than composing. A file that route does not cover goes to
    libyaml's parser under PyYAML's composer. If either finds any problem, or the text has
    a tab (libyaml accepts tabs where the reference reader does not) or a byte-order mark
    past its start (libyaml skips it there, the reference reader does not), the file is
    read again with the pure-Python reader, whose verdict and positions are the contract.
    """
    if _FastLoader is not _Loader and "\t" not in text and "\ufeff" not in text[1:]:
        for loader in (_read_plain, _FastLoader):
            try:
                return _load(text, path, loader)
            except _Unusual:
                continue  # anchors, tags, or something wrong: the composers read it
            except MissionError:
                break
    return _load(text, path, _Loader)


def _load(text: str, path: str, loader: Any) -> Mission:
    data, doc = _parse(text, path, loader)
    if doc.errors:
        raise MissionError(doc.errors)
    _shape_errors(data, doc)
    if doc.errors:
        raise MissionError(doc.errors)
    _rule_errors(data, doc)
    if doc.errors:
        raise MissionError(doc.errors)
    _reference_errors(data, doc)
    if doc.errors:
        raise MissionError(doc.errors)
    return _build(data, doc, path)


def load_mission(path: str | Path) -> Mission:
    """Load a mission file. Raises :class:`MissionError` (never anything else for bad input)."""
    name = str(path)
    try:
        with open(path, "rb") as stream:
            raw = stream.read(MAX_FILE_BYTES + 1)
    except OSError as error:
        raise MissionError(
            [LoadError(1, 1, "unreadable", f"cannot read: {error.strerror}", name)]
        ) from None
    if len(raw) > MAX_FILE_BYTES:
        message = f"the mission file is larger than {MAX_FILE_BYTES // (1024 * 1024)} MiB"
        raise MissionError([LoadError(1, 1, "yaml-syntax", message, name)])
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as error:
        raise MissionError(
            [LoadError(1, 1, "yaml-syntax", f"not UTF-8 text (byte {error.start})", name)]
        ) from None
    return loads_mission(text, name)
