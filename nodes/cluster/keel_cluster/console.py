"""The ground's view of a cluster: a page in the browser that follows a run directory.

    keel-cluster console RUN_DIR [--port PORT] [--mission FILE]
    keel-cluster run MISSION --console [PORT] ...

The console serves one page on 127.0.0.1 (no other address) and feeds it from the run
directory's files, so it shows a live run and a finished one alike:

- `NAME.trace.ndjson`, each node's protocol trace (spec/NAMES.md), tailed: files may appear
  late, grow, or be replaced (another inode: read again from the start), and only whole
  lines are read (a line being written is read once its newline is there). A node killed
  mid-write leaves half a line, and its restarted process appends to it: the half line is
  counted as malformed and the line after it read; once the run is finished, a last line
  without its newline is counted as malformed;
- `*.image.json`, the mission image the nodes fly: nodes, configurations, the graph; after a
  mission update the launcher logs, the update's image (`update-N/*.image.json`, or the
  image the update was given);
- `events.jsonl`, what the launcher did and when (kill, restart, partition, phase, update,
  ...), appended as it happens; for a run directory without it, `report.json`'s events. A
  simulator trace's `env` lines (Crash, Partition, RequestPhase) stand in for them;
- `report.json`: the run is finished once it is newer than the run's last launcher `start`
  (and than the console, for `run --console`): a run directory used again is not taken for
  finished by an earlier run's report.

How it works, in the order data flows:

1. `Tail` reads what the files gained since the last pass, whole lines only, about
   PASS_BYTES_MAX a pass in all.
2. `Fold` turns each trace line into at most a few compact *events*, `{"i", "t", "n", "f",
   "a", "k", "d", "p"}`: index, time, node, fsm, action, kind (the timeline's lane and
   marker), a sentence for the timeline (or none) and a *patch*, a JSON merge patch (RFC
   7386) of the console's state. An event's time is its line's `t_ns`, or its file's
   previous line's when that is later (a clock that stepped back). Heartbeat sends and
   receipts never leave the fold (hundreds a second); a monitor's Tick leaves only when its
   `missed` counts, its declarations or its `late` change. A line's fields are kept only in
   the type their producer writes (FIELD_TYPES). A patch changes only the state of the
   line's own node (a launcher's event: its `down` and `paused`, which no line sets), or
   adds an entry to a log keyed by its own id (the Master's path through the graph, the
   measures, the launcher's faults), so applying events in time order or in arrival order
   gives the same state: a replay seeks by applying the events up to the time it shows.
3. `Measures` times each fault as `analysis.fault_metrics` does (detection, decision,
   switch, restore; the same function, each fault over its lines up to the next fault,
   over the lines seen so far) and adds a `measure` event each time a figure changes, never
   before the fault's previous one.
4. `Feed` runs passes 1-3 on a thread every `poll_s` and keeps the events. Past
   EVENT_LIMIT (or EVENT_BYTES_LIMIT), checkpoints and liveness marks are not kept: their
   patches ride on the node's next event, or on one mark per node per SEEN_EVERY_NS; past
   EVENT_LIMIT_HARD (or EVENT_BYTES_LIMIT_HARD) nothing more is read. No patch is lost: the
   events always add up to the server's state. A pass that fails is counted and said in
   the status; the next pass goes on.
5. `ConsoleServer` (http.server) serves the page (`console/`: index.html, console.js,
   console.css; nothing from the network) and `/api/stream`, Server-Sent Events: the events
   from the one the client has, in batches, as they come. `/api/events?since=N`,
   `/api/state`, `/api/mission` and `/api/status` answer once, as JSON. It answers only
   requests addressed to 127.0.0.1 or localhost that no page of another origin makes, and
   forbids framing and foreign content (SECURITY_HEADERS).

The page applies the patches (its one fold: `apply` in console.js) and derives what it
shows from the state: the acting Master and the cluster's configuration, silent nodes,
the link matrix. It keeps every event, so it plays a run back (play, pause, seek) without the
server.

Threading: the feed's thread is the only writer of its events, state and counters, and
of what the status says of the files (`trace_names`, `malformed`), all under `Feed.lock`;
HTTP handler threads read them under it (a condition variable that wakes the streams).
The tails (`Tail.files`) are the feed's thread's alone.
"""

from __future__ import annotations

import copy
import json
import math
import os
import re
import secrets
import subprocess
import sys
import threading
import time
from bisect import bisect_left
from dataclasses import dataclass
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from stat import S_ISREG
from typing import Any
from urllib.parse import parse_qs, urlsplit

import yaml

from keel_cluster import analysis
from keel_cluster.common import image_as_mission
from keel_cluster.launcher import EVENTS_FILE, is_image

TRACE_GLOB = "*.trace.ndjson"
REPORT_FILE = "report.json"
# What keel-observe saw on the cluster's DDS domain (`console --dds`): recorded in the
# console's folder, so that the same folder plays back later.
OBSERVED_FILE = "observed.jsonl"
# Each node's status lines as keel-cluster received them (`run --console` asks for one a
# second): their task counts make the task data rates.
STATUS_GLOB = "*.status.jsonl"
RATE_MIN_NS = 900_000_000  # a rate is counted over at least this long

POLL_S = 0.05  # the feed's pass; the page's delay is about half of it on average
READ_BYTES_MAX = 8 << 20  # read per file per pass: a long finished trace takes several passes
PASS_BYTES_MAX = 16 << 20  # read per pass, all files together
LINE_BYTES_MAX = 1 << 20  # a longer line is skipped, counted as malformed
FILES_MAX = 1024
# Past either soft limit (events, or their bytes as JSON), checkpoints and liveness marks
# are not kept as events of their own: their changes ride on the node's next event (or
# one mark per node per SEEN_EVERY_NS). Past either hard limit nothing more is read, and
# the page says so.
EVENT_LIMIT = 500_000
EVENT_LIMIT_HARD = 2 * EVENT_LIMIT
EVENT_BYTES_LIMIT = 128 << 20
EVENT_BYTES_LIMIT_HARD = 2 * EVENT_BYTES_LIMIT
STREAM_BATCH_MAX = 5_000  # events per Server-Sent Event
STREAMS_MAX = 16
# A command the page sends (POST /api/command): one line, as on `run --ground`'s stdin.
COMMAND_BYTES_MAX = 1024
KEEPALIVE_S = 15.0
SEEN_EVERY_NS = 500_000_000  # a node's liveness mark, when nothing else shows it: at most two a second
DRAIN_S = 30.0  # run --console: how long the console may take to send a finished run's last lines

STATIC_FILES = {
    "/": ("index.html", "text/html; charset=utf-8"),
    "/index.html": ("index.html", "text/html; charset=utf-8"),
    "/console.js": ("console.js", "text/javascript; charset=utf-8"),
    "/console.css": ("console.css", "text/css; charset=utf-8"),
}
STATIC_DIR = Path(__file__).resolve().parent / "console"


class ConsoleError(Exception):
    """Bad input: a run directory that is not one, a mission that cannot be read."""


# --- 1. Tailing -----------------------------------------------------------------------------


@dataclass
class _Tailed:
    offset: int = 0
    inode: int = -1
    skipping: bool = False  # inside a line longer than LINE_BYTES_MAX: drop up to its end
    partial: bool = False  # the file ends in a line without its newline (yet)


class Tail:
    """Whole lines appended to one kind of file in a folder since the last `poll`. A file
    that shrinks or is replaced (another inode) is read again from its start."""

    def __init__(self, folder: Path, pattern: str):
        self.folder = folder
        self.pattern = pattern
        self.files: dict[Path, _Tailed] = {}  # the feed's thread only (Feed.trace_names for others)
        self.oversized = 0
        self.replaced: set[str] = set()  # names read again from their start since the caller last cleared it

    def partial_lines(self) -> int:
        """Files whose last line has no newline: in a finished run, lines their writer never
        finished (a node killed mid-write)."""
        return sum(1 for tailed in self.files.values() if tailed.partial or tailed.skipping)

    def poll(self, budget: int | None = None) -> tuple[list[tuple[str, bytes]], bool]:
        """(file name, line) pairs in file order, and whether any file has more to read. About
        `budget` bytes (PASS_BYTES_MAX) are read in all, a line longer than what is left
        included: a file whose turn does not come is read in the next pass."""
        budget = PASS_BYTES_MAX if budget is None else budget
        found: list[tuple[str, bytes]] = []
        more = False
        try:
            paths = sorted(self.folder.glob(self.pattern))[:FILES_MAX]
        except OSError:
            return found, False
        for path in paths:
            tailed = self.files.setdefault(path, _Tailed())
            try:
                with open(path, "rb") as handle:
                    stat = os.fstat(handle.fileno())
                    size = stat.st_size
                    if stat.st_ino != tailed.inode or size < tailed.offset:
                        if tailed.inode != -1:
                            self.replaced.add(path.name)
                        tailed.offset, tailed.skipping, tailed.inode = 0, False, stat.st_ino
                    if size == tailed.offset:
                        tailed.partial = False
                        continue
                    if budget <= 0:
                        more = True
                        continue
                    handle.seek(tailed.offset)
                    chunk = handle.read(min(READ_BYTES_MAX, max(budget, LINE_BYTES_MAX + 1)))
            except OSError:
                continue
            budget -= len(chunk)
            at_end = tailed.offset + len(chunk) >= size
            end = chunk.rfind(b"\n") + 1
            tailed.partial = at_end and end < len(chunk)
            if end == 0:
                # No whole line yet: wait for one, unless it is already too long.
                if len(chunk) >= LINE_BYTES_MAX:
                    tailed.offset += len(chunk)
                    tailed.skipping = True
                    tailed.partial = False
                    more |= tailed.offset < size
                continue
            more |= not at_end
            tailed.offset += end
            for raw in chunk[:end].split(b"\n")[:-1]:
                if tailed.skipping or len(raw) > LINE_BYTES_MAX:
                    tailed.skipping = False
                    self.oversized += 1
                    continue
                if raw.strip():
                    found.append((path.name, raw))
        return found, more


# --- The mission ----------------------------------------------------------------------------


def _newest_image(folder: Path) -> Path | None:
    """The newest `*.image.json` of a folder (None: none, or the folder cannot be read)."""
    found: list[tuple[int, Path]] = []
    try:
        for path in folder.glob("*.image.json"):
            try:
                stat = path.stat()
            except OSError:
                continue  # gone since the listing
            if S_ISREG(stat.st_mode):
                found.append((stat.st_mtime_ns, path))
    except OSError:
        return None
    return max(found, default=(0, None))[1]


def _is_image_file(name: str) -> bool:
    """Whether a launcher event's argument names a mission image (False for anything else,
    a name no file can have included)."""
    try:
        return Path(name).is_file() and is_image(Path(name))
    except (OSError, ValueError):
        return False


def find_image(run_dir: Path, updates: int = 0) -> Path | None:
    """The mission image a run directory's nodes fly after `updates` mission updates: the
    newest `*.image.json` of `update-N/` (where the launcher compiles update N) for the
    highest N <= updates that has one, else the newest `*.image.json` of the run
    directory. None when there is none (or the folder cannot be read)."""
    for n in range(updates, 0, -1):
        image = _newest_image(run_dir / f"update-{n}")
        if image is not None:
            return image
    return _newest_image(run_dir)


def image_names(path: Path) -> ImageNames | None:
    """The ids of a mission image (None for a YAML mission, or a file that is no image)."""
    if not _is_image_file(str(path)):
        return None
    try:
        return ImageNames(json.loads(path.read_text(encoding="utf-8"))["content"])
    except (OSError, ValueError, KeyError, TypeError, AttributeError, RecursionError):
        return None


def read_mission(path: Path) -> dict[str, Any]:
    """What the page needs of a mission (an image or a YAML): nodes, tasks, the heartbeat,
    and the graph as configurations and edges. Raises ConsoleError."""
    try:
        if is_image(path):
            raw = image_as_mission(json.loads(path.read_text(encoding="utf-8"))["content"])
        else:
            raw = yaml.safe_load(path.read_text(encoding="utf-8"))
        return mission_summary(raw)
    except (OSError, ValueError, KeyError, TypeError, AttributeError, RecursionError,
            yaml.YAMLError) as error:
        raise ConsoleError(f"{path}: not a mission the console can read ({error})") from None


def mission_summary(raw: dict[str, Any]) -> dict[str, Any]:
    """A mission in the YAML's shape (common.read_mission) as the page draws it."""
    phases = []
    edges = []
    for phase_name, phase in raw["phases"].items():
        configurations = []
        for name, config in (phase.get("configurations") or {}).items():
            configurations.append({
                "name": str(name), "master": str(config["master"]),
                "observers": [str(n) for n in config.get("observers") or []],
                "tasks": {str(t): str(n) for t, n in (config.get("tasks") or {}).items()},
            })
        phases.append({"name": str(phase_name), "initial": str(phase["initial"]),
                       "configurations": configurations})
        for source, targets in (phase.get("on_failure") or {}).items():
            for node, target in (targets or {}).items():
                edges.append({"from": str(source), "to": str(target), "kind": "failure", "label": str(node)})
        for source, targets in (phase.get("on_recovery") or {}).items():
            for node, target in (targets or {}).items():
                edges.append({"from": str(source), "to": str(target), "kind": "recovery", "label": str(node)})
        for target_phase, moves in (phase.get("on_phase") or {}).items():
            for source, target in (moves or {}).items():
                edges.append({"from": str(source), "to": str(target), "kind": "phase",
                              "label": str(target_phase)})
    heartbeat = raw.get("heartbeat") or {}
    return {
        "name": str(raw.get("mission", "")),
        "period_ms": int(heartbeat.get("period_ms", 0) or 0),
        "miss_limit": int(heartbeat.get("miss_limit", 0) or 0),
        "nodes": [{"name": str(n), "kind": str((node or {}).get("kind", "")),
                   "role": (node or {}).get("role")} for n, node in raw["nodes"].items()],
        "tasks": [{"name": str(t), "checkpoint": bool((task or {}).get("checkpoint")),
                   "essential": bool((task or {}).get("essential"))}
                  for t, task in (raw.get("tasks") or {}).items()],
        "phases": phases,
        "edges": edges,
    }


# --- 2. The fold ----------------------------------------------------------------------------

# Per-node fields a switch or election line's vars set (their names in the state).
SWITCH_VARS = {"role": "role", "epoch": "epoch", "config": "config", "stage": "stage",
               "active": "active", "masterConfig": "masterConfig", "failed": "view"}
ELECTION_VARS = {"role": "role", "epoch": "epoch", "leader": "leader", "suspects": "suspects"}

# Timeline kinds (the page's markers) of the lines that get a sentence.
KIND = {
    ("heartbeat", "DeclareFailed"): "declare", ("heartbeat", "Readmit"): "readmit",
    ("heartbeat", "Rejoin"): "readmit",
    ("election", "Suspect"): "suspect", ("election", "BecomeMaster"): "master",
    ("election", "WarmBoot"): "master", ("switch", "GroundDesignate"): "ground",
    ("switch", "Exclude"): "exclude", ("switch", "BecomeMaster"): "master",
    ("switch", "BootSwitch"): "switch", ("switch", "BroadcastCommand"): "switch",
    ("switch", "RequestPhase"): "switch", ("switch", "CompleteSwitch"): "switch",
    ("switch", "GroundRecovery"): "ground", ("switch", "GroundExclude"): "ground",
    ("switch", "GroundReadmit"): "ground", ("switch", "RefuseGroundCommand"): "ground",
    ("switch", "GroundPause"): "ground", ("switch", "GroundResume"): "ground",
    ("switch", "Readmit"): "readmit",
    ("switch", "HandOver"): "master",
    ("switch", "Activate"): "activate", ("switch", "Deactivate"): "deactivate",
    ("switch", "FlushCheckpoint"): "checkpoint", ("switch", "StoreCheckpoint"): "checkpoint",
    ("switch", "StateOutOfReach"): "problem", ("switch", "Hold"): "lease",
    ("switch", "Release"): "lease", ("switch", "LeaseLapsed"): "lease",
    ("switch", "Resign"): "problem", ("switch", "Resigned"): "problem",
    ("switch", "AskExclusion"): "problem", ("health", "TaskUnhealthy"): "problem",
}
# Heartbeats sent and received: hundreds a second, and the monitors' Ticks say what they
# add up to. The fold reads only their time and node (a liveness mark).
_HEARTBEAT_ACTIONS = {("heartbeat", "SendHeartbeat"), ("heartbeat", "ReceiveHeartbeat")}
_HEARTBEAT_TRAFFIC = (b'"action":"SendHeartbeat"', b'"action":"ReceiveHeartbeat"')
# The lines analysis.fault_metrics reads; at most RELEVANT_MAX are kept.
MEASURED = {("heartbeat", "DeclareFailed"), ("switch", "Exclude"), ("switch", "BecomeMaster"),
            ("switch", "CompleteSwitch"), ("switch", "Activate"), ("switch", "RequestPhase"),
            ("switch", "AskExclusion"), ("switch", "Resign")}
RELEVANT_MAX = 100_000
_HEAD = re.compile(rb'^\{"t_ns":(\d+),"node":"([^"\\]*)"')

# Launcher actions (Cluster._record) and what they do to the node they name.
LAUNCHER_NODE_PATCH = {"kill": {"down": True, "paused": False}, "start": {"down": False},
                       "restart": {"down": False}, "pause": {"paused": True},
                       "resume": {"paused": False}}


def _names(value: object) -> list[str]:
    return [str(v) for v in value] if isinstance(value, list) else []


def _version(args: dict[str, Any]) -> str:
    version = args.get("version")
    lineage = args.get("lineage")
    if isinstance(lineage, list) and len(lineage) == 2 and lineage != [0, 0]:
        return f"{version} (lineage {lineage[0]}.{lineage[1]})"
    return str(version)


def describe(node: str | None, fsm: str, action: str, args: dict[str, Any]) -> str:
    """The timeline's sentence for a trace line."""
    a = args
    if fsm == "heartbeat" and action == "DeclareFailed":
        return f"{a.get('m', node)} declares {a.get('n')} failed ({a.get('reason', 'missed')})"
    if fsm == "heartbeat" and action == "Readmit":
        return f"{a.get('m', node)} hears {a.get('n')} again (epoch {a.get('epoch')})"
    if fsm == "heartbeat" and action == "Rejoin":
        return f"{node} rejoins at epoch {a.get('epoch')}"
    if fsm == "election" and action == "Suspect":
        return f"{a.get('n', node)} suspects {a.get('m')}"
    if fsm == "election" and action == "BecomeMaster":
        above = f", above {a['above']}" if "above" in a else ""
        return f"{a.get('n', node)} becomes Master, epoch {a.get('epoch', a.get('e'))}{above}"
    if fsm == "election" and action == "WarmBoot":
        return f"{node} warm-boots the cluster: epoch {a.get('epoch')}, above {a.get('above')}"
    if fsm == "switch" and action == "GroundDesignate":
        return (f"{a.get('n', node)} takes the ground's designate {a.get('d')} (wait {a.get('wait')}, "
                f"span {a.get('span')}, echo {a.get('echo')})")
    if fsm == "switch":
        return _describe_switch(node, action, a)
    if fsm == "health" and action == "TaskUnhealthy":
        return f"{a.get('t')} unhealthy on {a.get('n', node)} ({a.get('kind')})"
    if fsm == "env":
        shown = " ".join(f"{k}={','.join(_names(v)) if isinstance(v, list) else v}" for k, v in a.items())
        return f"{action} {shown}".strip()
    return f"{node} {fsm}.{action}"


_SAYS = {"Resign": "resigns", "Resigned": "has resigned", "AskExclusion": "asks to be excluded"}


def _describe_switch(node: str | None, action: str, a: dict[str, Any]) -> str:
    who = a.get("m", a.get("n", node))
    if action == "Exclude":
        why = " (the ground's)" if a.get("ground") else ""
        return f"{who} excludes {a.get('f')}{why} -> {a.get('c')}"
    if action == "BecomeMaster":
        was = f", excluding {','.join(_names(a.get('was')))}" if _names(a.get("was")) else ""
        warm = " (warm boot)" if a.get("warm") else ""
        return f"{who} takes over in {a.get('c')}{was}{warm}"
    if action == "BootSwitch":
        return f"{who} boots the cluster into {a.get('c')}"
    if action == "BroadcastCommand":
        return f"{who} commands {a.get('c')} (epoch {a.get('epoch')}, seq {a.get('seq')})"
    if action == "RequestPhase":
        return f"{who} enters phase {a.get('phase')} -> {a.get('c')}"
    if action == "CompleteSwitch":
        return f"switch to {a.get('c')} complete ({who})"
    if action == "Activate":
        start = (f"from checkpoint {_version(a)}" if a.get("restored")
                 else "from its initial state")
        return f"{a.get('t')} starts on {who} {start}"
    if action == "Deactivate":
        return f"{a.get('t')} stops on {who}"
    if action == "FlushCheckpoint":
        final = " (final)" if a.get("final") else ""
        return f"{who} checkpoints {a.get('t')} v{_version(a)}{final}"
    if action == "StoreCheckpoint":
        return f"{node} stores {a.get('t')} v{_version(a)} from {a.get('from')}"
    if action == "StateOutOfReach":
        return f"{who}: {a.get('t')}'s newest state is out of reach"
    if action == "Hold":
        return f"{who} holds its tasks (no lease)"
    if action == "Release":
        return f"{who} releases its tasks"
    if action == "LeaseLapsed":
        return f"{who}'s lease lapsed: it steps down"
    if action in _SAYS:
        return f"{who} {_SAYS[action]}"
    if action in ("GroundExclude", "GroundReadmit"):
        verb = "exclude" if action == "GroundExclude" else "readmit"
        return f"{node} takes the ground's {verb} {a.get('f')}"
    if action in ("GroundPause", "GroundResume"):
        verb = "pause-task" if action == "GroundPause" else "resume-task"
        return f"{node} takes the ground's {verb} {a.get('t')}"
    if action == "GroundRecovery":
        return f"{who} leaves safe mode for {a.get('c')} (the ground's)"
    if action == "RefuseGroundCommand":
        return f"{who} refuses the ground's recover {a.get('c')}: {a.get('why')}"
    if action == "Readmit":
        return f"{who} readmits {a.get('r')} -> {a.get('c')}"
    if action == "HandOver":
        return (f"{who} hands the mastership to {a.get('to')} (epoch {a.get('epoch')}), "
                f"readmitting {a.get('r')} -> {a.get('c')}")
    return f"{node} switch.{action}"


def describe_launcher(action: str, argument: str) -> str:
    return f"{action} {argument}".strip()


T_NS_MAX = 1 << 63  # a t_ns at or past it (or below 0) does not read


def read_time(value: object) -> int:
    """A line's t_ns as an int; ValueError when it is not a time (a bool, not finite, out
    of range)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"t_ns {value!r} is not a number")
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"t_ns {value!r} is not finite")
    t_ns = int(value)
    if not 0 <= t_ns < T_NS_MAX:
        raise ValueError(f"t_ns {value!r} is out of range")
    return t_ns


def _digits_time(digits: bytes) -> int | None:
    """A t_ns read from the digits of a line's head (None: too long to be one)."""
    if len(digits) > 19:
        return None
    t_ns = int(digits)
    return t_ns if t_ns < T_NS_MAX else None


# What the console keeps of a trace line's fields, by the type its producer writes; a value
# of another type is dropped (the page draws these, and a string where a list belongs would
# stop its rendering).
def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and -T_NS_MAX <= value < T_NS_MAX


def _is_name(value: object) -> bool:
    return value is None or isinstance(value, str)


def _is_names(value: object) -> bool:
    return isinstance(value, list) and all(isinstance(v, str) for v in value)


def _is_counts(value: object) -> bool:
    return isinstance(value, dict) and all(_is_int(v) for v in value.values())


FIELD_TYPES = {
    "role": _is_name, "config": _is_name, "stage": _is_name, "masterConfig": _is_name,
    "leader": _is_name, "epoch": _is_int, "active": _is_names, "view": _is_names,
    "suspects": _is_names, "declared": _is_names, "missed": _is_counts, "stored": _is_counts,
    "late": lambda v: isinstance(v, bool),
}


# keel-observe's roles (KeelNodeState, keel.idl) as the traces name them.
OBSERVED_ROLES = {"master": "Master", "observer": "Observer", "worker": "Worker", "storage": "Worker",
                  "interface": "Worker"}
_NO_ID = 65535  # "none" (a node), SAFE (a configuration)
_NO_CONFIG = 65534  # a node that holds no view yet


class ImageNames:
    """Ids to names, as keel-node numbers them from the image (core/fsm/topology.cpp; as
    core/net/dds/tools/keel-dds-names): nodes and tasks by their `id`, configurations in
    the order of the phases and of the configurations within each."""

    def __init__(self, content: dict[str, Any]) -> None:
        self.nodes = {int(n["id"]): str(n["name"]) for n in content["nodes"]}
        self.tasks = {int(t["id"]): str(t["name"]) for t in content.get("tasks") or []}
        configs = [str(c["name"]) for phase in content["phases"] for c in phase["configurations"]]
        self.configs = dict(enumerate(configs))

    def node(self, value: object) -> str | None:
        return self.nodes.get(value) if _is_int(value) else None  # type: ignore[arg-type]

    def config(self, value: object) -> str | None:
        if value == _NO_ID:
            return "SAFE"
        if value == _NO_CONFIG:
            return None
        return self.configs.get(value) if _is_int(value) else None  # type: ignore[arg-type]


def status_line(raw: bytes) -> tuple[int, str | None, str, str, dict[str, Any], dict[str, Any]] | None:
    """One status line of a node (`NAME.status.jsonl`) as the fold reads it: (t_ns, node,
    "status", "counts", its task counts, {}), or None when it does not read."""
    try:
        line = json.loads(raw)
        t_ns, node, counts = read_time(line["t_ns"]), line["node"], line.get("task_counts") or {}
    except (ValueError, KeyError, TypeError, AttributeError, RecursionError, OverflowError):
        return None
    if not isinstance(node, str) or not isinstance(counts, dict):
        return None
    return t_ns, node, "status", "counts", counts, {}


def observed_line(raw: bytes, names: ImageNames | None
                  ) -> tuple[int, str | None, str, str, dict[str, Any], dict[str, Any]] | None:
    """One line of keel-observe's output (nodes/observe/src/main.cpp) as the fold reads a
    trace line: (t_ns, node, "dds", what was observed, its fields by name, {}), or None when
    it does not read or names what the image does not have (counted as malformed). Without
    the image nothing is named: every line is None."""
    try:
        line = json.loads(raw)
        t_ns, observed = read_time(line["t_ns"]), str(line["observed"])
    except (ValueError, KeyError, TypeError, AttributeError, RecursionError, OverflowError):
        return None
    if names is None:
        return None
    if observed == "joined":
        return t_ns, None, "dds", observed, {}, {}
    node = names.node(line.get("node" if observed == "state" else "from"))
    if node is None:
        return None
    args: dict[str, Any] = {}
    if observed == "state":
        config = names.config(line.get("configuration_id"))
        if not (isinstance(line.get("role"), str) and _is_int(line.get("epoch"))
                and isinstance(line.get("phase"), str)):
            return None
        args = {"role": line["role"], "epoch": line["epoch"], "config": config, "phase": line["phase"]}
    elif observed == "command":
        config = names.config(line.get("config"))
        failed = line.get("failed")
        if config is None or not isinstance(failed, list) or not all(_is_int(f) for f in failed):
            return None
        out = [names.node(f) for f in failed]
        if None in out or not (_is_int(line.get("epoch")) and _is_int(line.get("seq"))):
            return None
        args = {"config": config, "failed": out, "epoch": line["epoch"], "seq": line["seq"]}
    elif observed == "activate":
        if not (_is_int(line.get("epoch")) and _is_int(line.get("seq"))):
            return None
        args = {"epoch": line["epoch"], "seq": line["seq"]}
    elif observed == "declare":
        failed = names.node(line.get("failed"))
        if failed is None:
            return None
        args = {"failed": failed}
    elif observed == "checkpoint":
        task = names.tasks.get(line.get("task")) if _is_int(line.get("task")) else None
        if task is None or not (_is_int(line.get("lineage")) and _is_int(line.get("count"))):
            return None
        args = {"task": task, "version": f"{line['lineage']}.{line['count']}"}
    elif observed not in ("heartbeat", "ack"):
        return None
    return t_ns, node, "dds", observed, args, {}


class Fold:
    """Trace lines in, events out. `state` is what the events' patches add up to (the
    page rebuilds it the same way), and `faults` what the launcher (or a simulator's env
    lines) did, for `Measures`.

    The state: `nodes` (per node: what its own lines say, `seen` the time of its last
    event, `down` and `paused` what the launcher did to it), `path` (the configurations
    the Masters completed switches to, in order), `faults` and `measures`.

    A line is read (`read`: parsed, or for a heartbeat only its head) apart from being
    folded (`take`), so that the feed can order a pass's lines by time first; an event's
    time is the one the feed gives (its line's t_ns, never before the previous line of its
    file), the measures use the lines' own t_ns, as analysis does."""

    def __init__(self) -> None:
        self.state: dict[str, Any] = {"nodes": {}, "path": {}, "measures": {}, "faults": {}}
        self.events: list[dict[str, Any]] = []
        self.faults: list[dict[str, Any]] = []  # {"t_ns", "action", "argument"}, as analysis takes them
        self.relevant: list[analysis.TraceLine] = []  # what fault_metrics reads
        self.malformed = 0
        self.lines = 0
        self._marked: dict[str, int] = {}  # node -> time of its last event
        self._counts: dict[str, tuple[int, dict[str, Any]]] = {}  # node -> its last task counts, their time
        self._path_last: str | None = None

    def _emit(self, t_ns: int, node: str | None, fsm: str, action: str, kind: str,
              text: str | None, patch: dict[str, Any] | None) -> None:
        event: dict[str, Any] = {"i": len(self.events), "t": t_ns, "n": node, "f": fsm, "a": action, "k": kind}
        if text is not None:
            event["d"] = text
        if node is not None and kind not in ("fault", "measure"):
            # Every event of a node marks it alive at its time (the page tells a silent
            # node by the age of its mark).
            patch = patch or {}
            patch.setdefault("nodes", {}).setdefault(node, {})["seen"] = t_ns
            self._marked[node] = max(self._marked.get(node, t_ns), t_ns)
        if patch:
            event["p"] = patch
            merge_patch(self.state, patch)
        self.events.append(event)

    def _node_patch(self, node: str, changes: dict[str, Any]) -> dict[str, Any] | None:
        """The patch that brings the node's state to `changes` (None: nothing changes)."""
        known = self.state["nodes"].get(node, {})
        changed = diff_patch({k: known.get(k) for k in changes}, changes)
        return {"nodes": {node: changed}} if changed else None

    # -- trace lines --------------------------------------------------------------------

    def read(self, raw: bytes) -> tuple[int, str | None, str, str, dict[str, Any], dict[str, Any]] | None:
        """One line of a trace file, as read: (t_ns, node, fsm, action, args, vars), or None
        when it does not parse (counted). A heartbeat sent or received is read no further
        than its head (args and vars empty).

        A node killed mid-write leaves half a line, and its restarted process appends: its
        first line follows the half line on the same line. Such a line is read from its
        last `{"t_ns":`, the half line before it counted as malformed."""
        self.lines += 1
        line = self._read(raw)
        if line is None:
            self.malformed += 1
            start = raw.rfind(b'{"t_ns":')
            if start > 0:
                line = self._read(raw[start:])
        return line

    @staticmethod
    def _read(raw: bytes) -> tuple[int, str | None, str, str, dict[str, Any], dict[str, Any]] | None:
        if any(needle in raw for needle in _HEARTBEAT_TRAFFIC) and raw.find(b'{"t_ns":', 1) < 0:
            head = _HEAD.match(raw)
            if head:
                t_ns = _digits_time(head.group(1))
                if t_ns is not None:
                    action = "SendHeartbeat" if _HEARTBEAT_TRAFFIC[0] in raw else "ReceiveHeartbeat"
                    return t_ns, head.group(2).decode("utf-8", "replace"), "heartbeat", action, {}, {}
        try:
            line = json.loads(raw)
            t_ns, node = read_time(line["t_ns"]), line.get("node")
            fsm = str(line["fsm"])
            action = analysis.legacy_action(fsm, str(line["action"]))
            args, variables = line.get("args") or {}, line.get("vars") or {}
            if not isinstance(args, dict) or not isinstance(variables, dict):
                raise TypeError("args and vars must be objects")
        except (ValueError, KeyError, TypeError, AttributeError, RecursionError, OverflowError):
            return None
        return t_ns, None if node is None else str(node), fsm, action, args, variables

    def raw_line(self, raw: bytes) -> None:
        """One line of a trace file, read and folded at its own time."""
        line = self.read(raw)
        if line is not None:
            self.take(line[0], line)

    def take(self, t_ns: int, line: tuple[int, str | None, str, str, dict[str, Any], dict[str, Any]]) -> None:
        """A line `read` gave, folded at time `t_ns`."""
        own_t, node, fsm, action, args, variables = line
        if fsm == "env":
            self._env(t_ns, own_t, action, args)
            return
        if fsm == "dds":
            self._observed(t_ns, node, action, args)
            return
        if fsm == "status" and node is not None:
            self.status(t_ns, node, args)
            return
        if node is None:
            return
        if (fsm, action) in _HEARTBEAT_ACTIONS:
            self._liveness(t_ns, node)
            return
        if (fsm, action) in MEASURED:
            self.relevant.append(analysis.TraceLine(own_t, node, fsm, action, args, variables))
            if len(self.relevant) > RELEVANT_MAX:
                del self.relevant[: len(self.relevant) - RELEVANT_MAX]
        patch = self._node_patch(node, self._changes(fsm, action, args, variables))
        if (fsm, action) == ("switch", "CompleteSwitch"):
            patch = self._path(t_ns, node, args, variables, patch)
        kind = KIND.get((fsm, action))
        if kind is not None:
            self._emit(t_ns, node, fsm, action, kind, describe(node, fsm, action, args), patch)
        elif patch:
            self._emit(t_ns, node, fsm, action, "link" if fsm == "heartbeat" else "state", None, patch)
        else:
            self._liveness(t_ns, node)

    def line(self, t_ns: int, node: str | None, fsm: str, action: str,
             args: dict[str, Any], variables: dict[str, Any]) -> None:
        """A line given by its fields, folded at its own time."""
        self.take(t_ns, (t_ns, node, fsm, action, args, variables))

    def _changes(self, fsm: str, action: str, args: dict[str, Any],
                 variables: dict[str, Any]) -> dict[str, Any]:
        """The node's fields a line states, those of the type their producer writes."""
        changes: dict[str, Any] = {}
        if fsm == "heartbeat":
            if "missed" in variables:
                changes["missed"] = variables["missed"]
            if "failed" in variables:
                changes["declared"] = variables["failed"]
            # Every Tick says whether its period ran late (core/fsm/heartbeat_monitor.cpp:
            # `late` on counting and self-suspecting Ticks alike).
            if action == "Tick" and "late" in args:
                changes["late"] = args["late"]
        elif fsm == "switch":
            changes.update({name: variables[key] for key, name in SWITCH_VARS.items() if key in variables})
            if "stored" in variables:
                changes["stored"] = variables["stored"]
            if action in ("Hold", "Release", "LeaseLapsed"):
                changes["held"] = action == "Hold"
            if action in ("Resign", "Resigned", "LeaseLapsed"):
                changes["resigned"] = True
            elif action == "ReceiveCommand" and args.get("n") not in _names(args.get("out")):
                changes["resigned"] = False  # in the view again
        elif fsm == "election":
            changes.update({name: variables[key] for key, name in ELECTION_VARS.items() if key in variables})
        valid = {k: v for k, v in changes.items() if k not in FIELD_TYPES or FIELD_TYPES[k](v)}
        if "missed" in valid:
            valid["missed"] = {str(k): v for k, v in valid["missed"].items()}
        if "stored" in valid:
            valid["stored"] = {str(k): v for k, v in valid["stored"].items()}
        return valid

    def _path(self, t_ns: int, node: str, args: dict[str, Any], variables: dict[str, Any],
              patch: dict[str, Any] | None) -> dict[str, Any] | None:
        """A switch the Master completed: the next step of the path through the graph."""
        config = args.get("c") or variables.get("masterConfig")
        if not isinstance(config, str) or config == self._path_last:
            return patch
        self._path_last = config
        epoch = variables.get("epoch")
        step = {"t": t_ns, "c": config, "m": node, "epoch": epoch if _is_int(epoch) else None}
        patch = patch or {}
        patch["path"] = {str(len(self.state["path"])): step}
        return patch

    def _liveness(self, t_ns: int, node: str) -> None:
        """A line that changes nothing shown: an event only when the node's last one is
        SEEN_EVERY_NS old, to keep its mark fresh."""
        last = self._marked.get(node)
        if last is not None and t_ns - last < SEEN_EVERY_NS:
            return
        self._emit(t_ns, node, "", "", "seen", None, None)

    def _observed(self, t_ns: int, node: str | None, action: str, args: dict[str, Any]) -> None:
        """What keel-observe saw on the DDS domain (`observed_line` names it): the nodes'
        own state, their heartbeats (liveness), the Master's commands and the monitors'
        declarations. No task, checkpoint version or trace variable travels there."""
        if node is None:
            return
        if action == "state":
            changes: dict[str, Any] = {"epoch": args["epoch"], "config": args["config"], "phase": args["phase"]}
            if args["role"] == "resigned":
                changes["resigned"] = True
            elif args["role"] in OBSERVED_ROLES:
                changes["role"] = OBSERVED_ROLES[args["role"]]
                changes["resigned"] = False
            patch = self._node_patch(node, changes)
            if changes.get("role") == "Master":
                patch = self._path(t_ns, node, {"c": args["config"]}, {"epoch": args["epoch"]}, patch)
            if patch:
                self._emit(t_ns, node, "dds", "state", "state", None, patch)
            else:
                self._liveness(t_ns, node)
        elif action == "command":
            out = _names(args.get("failed"))
            text = f"{node} commands {args['config']} (epoch {args['epoch']}, seq {args['seq']}" + (
                f"; out: {', '.join(out)})" if out else ")")
            patch = self._node_patch(node, {"masterConfig": args["config"], "view": out})
            self._emit(t_ns, node, "dds", "command", "switch", text, patch)
        elif action == "activate":
            self._emit(t_ns, node, "dds", "activate", "switch",
                       f"{node} activates its switch (epoch {args['epoch']}, seq {args['seq']})", None)
        elif action == "declare":
            failed = args["failed"]
            text = f"{node} asks to be excluded" if failed == node else f"{node} declares {failed} failed"
            self._emit(t_ns, node, "dds", "declare", "declare", text, None)
        elif action == "checkpoint":
            self._emit(t_ns, node, "dds", "checkpoint", "checkpoint",
                       f"{node} holds {args['task']} at version {args['version']}", None)
        else:  # heartbeat, ack: the node is alive
            self._liveness(t_ns, node)

    def status(self, t_ns: int, node: str, counts: dict[str, Any]) -> None:
        """A node's status line's task counts (executions, samples in and out since its
        process started): each task's rates per second over the time since the last counts
        at least RATE_MIN_NS before, set on the node (`rates`). A count that went back (a
        new process) starts again."""
        base = self._counts.get(node)
        if base is None or any(not isinstance(c, dict) for c in counts.values()):
            self._counts[node] = (t_ns, counts)
            return
        then, before = base
        if t_ns - then < RATE_MIN_NS:
            return
        rates: dict[str, dict[str, float]] = {}
        for task, now in counts.items():
            old = before.get(task)
            if not isinstance(old, dict):
                continue
            rate = {}
            for key, short in (("executions", "exec"), ("inputs", "in"), ("outputs", "out")):
                a, b = old.get(key), now.get(key)
                if _is_int(a) and _is_int(b) and b >= a:
                    rate[short] = round((b - a) * 1e9 / (t_ns - then), 1)
            if len(rate) == 3:
                rates[task] = rate
        self._counts[node] = (t_ns, counts)
        patch = self._node_patch(node, {"rates": rates})
        if patch:
            self._emit(t_ns, node, "status", "rates", "state", None, patch)
        else:
            self._liveness(t_ns, node)

    def _env(self, t_ns: int, own_t: int, action: str, args: dict[str, Any]) -> None:
        """A simulator's environment line: the faults it injected."""
        node = str(args["n"]) if "n" in args else None
        fault: tuple[str, str] | None = None
        patch: dict[str, Any] = {}
        if action == "Crash" and node:
            fault, patch = ("kill", node), {"nodes": {node: {"down": True}}}
        elif action == "Restart" and node:
            fault, patch = ("restart", node), {"nodes": {node: {"down": False}}}
        elif action == "Pause" and node:
            fault = ("pause", node)
        elif action == "Partition":
            alone = [side[0] for side in (_names(args.get("a")), _names(args.get("b"))) if len(side) == 1]
            if alone:
                fault = ("partition", alone[0])
        elif action == "RequestPhase" and "phase" in args:
            fault = ("phase", str(args["phase"]))
        if fault is not None:
            self._fault(own_t, fault[0], fault[1], patch)
        self._emit(t_ns, node, "env", action, "fault", describe(node, "env", action, args), patch or None)

    def _fault(self, t_ns: int, action: str, argument: str, patch: dict[str, Any]) -> None:
        key = str(len(self.faults))
        self.faults.append({"t_ns": t_ns, "action": action, "argument": argument})
        patch["faults"] = {key: {"t": t_ns, "action": action, "argument": argument}}

    # -- the launcher's events ----------------------------------------------------------

    @staticmethod
    def read_launcher(raw: bytes) -> tuple[int, str, str] | None:
        """One line of the launcher's log (Cluster._record): (t_ns, action, argument), or
        None when it does not read."""
        try:
            event = json.loads(raw)
            return read_time(event["t_ns"]), str(event["action"]), str(event["argument"])
        except (KeyError, TypeError, ValueError, AttributeError, RecursionError, OverflowError):
            return None

    def launcher(self, event: tuple[int, str, str], t_ns: int | None = None) -> None:
        """One event of the launcher's log, as `read_launcher` gives it, folded at `t_ns`
        (its own time when not given)."""
        own_t, action, argument = event
        if action == "refused":
            # A node's refusal of a ground command at admission (the launcher reads it from
            # the node's status line): no fault, a ground event of that node.
            node, _, kind = argument.partition(" ")
            self._emit(own_t if t_ns is None else t_ns, node or None, "launcher", action, "ground",
                       f"{node} refused a ground command at admission ({kind or 'no reason given'})", None)
            return
        patch: dict[str, Any] = {}
        node_changes = LAUNCHER_NODE_PATCH.get(action)
        if node_changes:
            patch["nodes"] = {argument: dict(node_changes)}
        self._fault(own_t, action, argument, patch)
        self._emit(own_t if t_ns is None else t_ns, argument if node_changes else None, "launcher", action,
                   "fault", None if action == "start" else describe_launcher(action, argument), patch)

    def measure(self, key: str, t_ns: int, figures: dict[str, Any], text: str | None) -> None:
        self._emit(t_ns, None, "", "", "measure", text, {"measures": {key: figures}})


def diff_patch(old: Any, new: Any) -> Any:
    """The merge patch (RFC 7386) that turns `old` into `new`; None when they are equal.
    Objects are compared key by key, anything else is replaced whole."""
    if not isinstance(old, dict) or not isinstance(new, dict):
        return None if old == new else new
    patch: dict[str, Any] = {}
    for key, value in new.items():
        before = old.get(key)
        if before is None or value is None:
            if before != value:
                patch[key] = value
            continue
        inner = diff_patch(before, value)
        if inner is not None:
            patch[key] = inner
    for key, before in old.items():
        if key not in new and before is not None:
            patch[key] = None
    return patch or None


def merge_patch(target: dict[str, Any], patch: dict[str, Any]) -> dict[str, Any]:
    """RFC 7386: objects merge key by key, null removes a key, anything else replaces."""
    for key, value in patch.items():
        if value is None:
            target.pop(key, None)
        elif isinstance(value, dict):
            inner = target.get(key)
            if not isinstance(inner, dict):
                inner = target[key] = {}
            merge_patch(inner, value)
        else:
            target[key] = value
    return target


# --- 3. Measures ----------------------------------------------------------------------------

FIGURES = ("detection_ms", "decision_ms", "switch_ms", "restore_ms", "total_ms")
TIMED = ("kill", "partition", "phase", "exclude")  # the faults analysis.fault_metrics times


class Measures:
    """The paper's figures per fault, by `analysis.fault_metrics` over the lines seen so
    far. Each pass that brought lines times every fault from the oldest not yet settled
    (a finished run's whole history arrives in the first passes: every fault is timed);
    after a pass, the faults before the last two are settled (a fault's window ends where
    the next one starts; lines of other nodes may still arrive late for the last two), and
    the lines before the oldest fault not settled are dropped. A fault's measure event
    never goes back in time: a revision comes at the time of the one before it, or later."""

    def __init__(self, fold: Fold):
        self.fold = fold
        self.oldest = 0  # index among timed faults of the oldest not settled
        self.shown: dict[int, dict[str, Any]] = {}  # index among timed faults -> figures sent
        self.shown_t: dict[int, int] = {}  # index among timed faults -> time of its last measure

    def update(self) -> None:
        timed = [f for f in self.fold.faults if f["action"] in TIMED]
        if self.oldest >= len(timed):
            return
        since = timed[self.oldest]["t_ns"]
        lines = self.fold.relevant
        # Lines before the oldest fault not settled are never needed again.
        keep = next((k for k, x in enumerate(lines) if x.t_ns >= since), len(lines))
        if keep > 0:
            del lines[:keep]
        window = sorted(lines, key=lambda x: x.t_ns)
        times = [x.t_ns for x in window]
        for index in range(self.oldest, len(timed)):
            # fault_metrics's own window: from the fault to the next timed one.
            first = bisect_left(times, timed[index]["t_ns"])
            last = bisect_left(times, timed[index + 1]["t_ns"]) if index + 1 < len(timed) else len(window)
            [metrics] = analysis.fault_metrics(window[first:max(first, last)], timed[index:index + 1])
            figures = {key: _plain(value) for key, value in metrics.as_dict().items()}
            if self.shown.get(index) == figures:
                continue
            self.shown[index] = figures
            known = [figures[k] for k in FIGURES if figures[k] is not None]
            t_ns = max(metrics.t_ns + int(max(known, default=0) * 1e6), self.shown_t.get(index, 0))
            self.shown_t[index] = t_ns
            text = None
            if figures["total_ms"] is not None:
                text = _measure_text(figures)
            self.fold.measure(str(index), t_ns, figures, text)
        self.oldest = max(self.oldest, len(timed) - 2)


def _plain(value: object) -> object:
    """A figure as JSON carries it to the page: a finite number, a string or None (a
    configuration named by anything else in a trace line, as text)."""
    if value is None or isinstance(value, (str, bool, int)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return str(value)


def _measure_text(f: dict[str, Any]) -> str:
    def ms(key: str) -> str:
        return "-" if f[key] is None else f"{f[key]:.0f} ms"

    head = f"{f['kind']} {f['target']}: "
    parts = [] if f["kind"] == "phase" else [f"detected {ms('detection_ms')}", f"decided {ms('decision_ms')}"]
    parts += [f"switched {ms('switch_ms')}", f"restored {ms('restore_ms')}", f"total {ms('total_ms')}"]
    return head + ", ".join(parts) + f" -> {f.get('config') or '-'} (Master {f.get('new_master') or '-'})"


# --- 4. The feed ----------------------------------------------------------------------------


class Feed:
    """A run directory followed: its traces, the launcher's events and its image, folded
    into events. `start()` runs `poll_once` on a thread of its own every `poll_s`.

    `not_before_ns` (`run --console`: the console's start) tells a finished run from the
    report.json of an earlier run in the same directory: only a report written since, and
    since the run's last launcher `start`, says the run finished."""

    def __init__(self, run_dir: Path, mission_path: Path | None = None, poll_s: float = POLL_S,
                 not_before_ns: int = 0):
        self.run_dir = run_dir
        self.mission_path = mission_path
        self.poll_s = poll_s
        self.not_before_ns = not_before_ns
        self.lock = threading.Condition()
        self.fold = Fold()
        self.measures = Measures(self.fold)
        self.traces = Tail(run_dir, TRACE_GLOB)
        self.launcher = Tail(run_dir, EVENTS_FILE)
        self.observed = Tail(run_dir, OBSERVED_FILE)
        self.status_lines = Tail(run_dir, STATUS_GLOB)
        self.names: ImageNames | None = None  # the image's ids, for what keel-observe saw
        # What HTTP handlers read, under self.lock (the feed's thread writes it under it too).
        self.trace_names: tuple[str, ...] = ()
        self.malformed = 0
        self.mission: dict[str, Any] | None = None
        self.mission_version = 0  # a new mission (a mission update) is sent to the pages again
        self.mission_error: str | None = None
        self.mission_source: Path | None = None
        self.dropped = 0  # checkpoints and liveness marks past the soft limit, not kept as events
        self.event_bytes = 0  # the kept events, as JSON
        self.truncated = False  # a hard limit reached: nothing more is read
        self.finished = False
        self.quiet = False  # the last pass read nothing and found nothing more to read
        self.error: str | None = None  # the last pass that failed, and why
        self.errors = 0
        self.closing = False
        self.passes = 0
        # Tells a page that reconnects whether it talks to the console it knew.
        self.instance = secrets.token_hex(8)
        self._from_report = False
        self._run_start_ns = 0  # the newest launcher `start`
        self._clock: dict[tuple[bool, str], int] = {}  # per file: its last line's time (events never go back)
        self._mission_tried: tuple[Path, int] | None = None
        self._mission_for = -1  # the updates the mission read accounts for
        # Past the soft limit: per node, the changes of the events not kept, until they ride on
        # one (None: past the hard limit, the changes of other events).
        self._pending: dict[str | None, dict[str, Any]] = {}
        self._pending_t: dict[str | None, int] = {}
        self._pending_since: dict[str | None, float] = {}
        self._kept_mark: dict[str, int] = {}  # node -> time of its last kept event
        self._thread: threading.Thread | None = None

    # -- the thread ---------------------------------------------------------------------

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="console-feed", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        with self.lock:
            self.closing = True
            self.lock.notify_all()
        if self._thread is not None:
            self._thread.join(timeout=5)

    def _run(self) -> None:
        while not self.closing:
            try:
                more = self.poll_once()
            except Exception as error:  # noqa: BLE001 - a pass that fails is said; the feed goes on
                more = False
                with self.lock:
                    self.errors += 1
                    self.error = f"{type(error).__name__}: {error}"[:300]
                    self.lock.notify_all()
            if not more:
                time.sleep(self.poll_s)

    def drain(self, timeout_s: float = DRAIN_S) -> bool:
        """Waits until a whole pass that began after the call found nothing more to read
        (the run's last lines folded); False when timeout_s passed first."""
        with self.lock:
            start = self.passes
            return self.lock.wait_for(lambda: self.closing or (self.passes >= start + 2 and self.quiet),
                                      timeout_s)

    def poll_once(self) -> bool:
        """One pass over the run directory; True when a file has more to read at once."""
        self._read_mission()
        lines, more_traces = self.traces.poll()
        launched, more_events = self.launcher.poll()
        statuses, more_statuses = self.status_lines.poll()
        more_traces = more_traces or more_statuses
        observed: list[tuple[str, bytes]] = []
        more_observed = False
        if self.names is not None:  # read once the image names its ids
            observed, more_observed = self.observed.poll()
            more_traces = more_traces or more_observed
        if not launched and not self._from_report and not self.launcher.files and self._report_is_fresh():
            launched = self._report_events()
        with self.lock:
            for tail, is_trace in ((self.traces, True), (self.launcher, False), (self.observed, True),
                                   (self.status_lines, True)):
                for name in tail.replaced:  # a file read again from its start: its clock too
                    self._clock.pop((is_trace, name), None)
                tail.replaced.clear()
            before = len(self.fold.events)
            if not self.truncated:
                for t_ns, is_trace, item in self._in_time_order(launched, lines, observed, statuses):
                    if is_trace:
                        self.fold.take(t_ns, item)
                    else:
                        self.fold.launcher(item, t_ns)
                if lines or launched:
                    self.measures.update()
            self.quiet = not (lines or launched or observed or statuses or more_traces or more_events)
            self._limit(before, flush=self.quiet)
            self.finished = self._report_is_fresh()
            self.trace_names = tuple(sorted(p.name for p in [*self.traces.files, *self.observed.files]))
            self.malformed = (self.fold.malformed + self.traces.oversized + self.launcher.oversized
                              + self.observed.oversized
                              + (self.traces.partial_lines() + self.observed.partial_lines() if self.finished else 0))
            self.passes += 1
            self.lock.notify_all()
        return more_traces or more_events

    def _in_time_order(self, launched: list[tuple[str, bytes]], lines: list[tuple[str, bytes]],
                       observed: list[tuple[str, bytes]] = (),  # type: ignore[assignment]
                       statuses: list[tuple[str, bytes]] = ()) -> list[tuple[int, bool, Any]]:  # type: ignore[assignment]
        """A pass's launcher events and trace lines, read, as (t_ns, is a trace line, what
        was read), merged by time. An event's time is its line's t_ns, or its file's
        previous line's if that is later (a clock that stepped back): a file's lines keep
        their order, and the page, which orders events by time, applies them in the order
        the feed folds them."""
        merged: list[tuple[int, bool, Any]] = []
        for name, raw in launched:
            event = self.fold.read_launcher(raw)
            if event is None:
                self.fold.malformed += 1
                continue
            if event[1] == "start":
                self._run_start_ns = max(self._run_start_ns, event[0])
            merged.append((self._clamp(False, name, event[0]), False, event))
        for name, raw in lines:
            line = self.fold.read(raw)
            if line is not None:
                merged.append((self._clamp(True, name, line[0]), True, line))
        for name, raw in statuses:
            line = status_line(raw)
            if line is None:
                self.fold.malformed += 1
                continue
            merged.append((self._clamp(True, name, line[0]), True, line))
        for name, raw in observed:
            self.fold.lines += 1
            line = observed_line(raw, self.names)
            if line is None:
                self.fold.malformed += 1
                continue
            merged.append((self._clamp(True, name, line[0]), True, line))
        merged.sort(key=lambda item: item[0])  # stable
        return merged

    def _clamp(self, is_trace: bool, name: str, t_ns: int) -> int:
        key = (is_trace, name)
        t_ns = max(t_ns, self._clock.get(key, 0))
        self._clock[key] = t_ns
        return t_ns

    def _report_is_fresh(self) -> bool:
        """report.json is there and is this run's: written since the console started
        (`not_before_ns`) and since the run's last launcher `start`."""
        try:
            written = (self.run_dir / REPORT_FILE).stat().st_mtime_ns
        except OSError:
            return False
        return written >= max(self.not_before_ns, self._run_start_ns)

    # -- the limits ---------------------------------------------------------------------

    def _over(self) -> tuple[bool, bool]:
        """Whether the kept events are past the soft limit, and past the hard one."""
        count = len(self.fold.events)
        return (count >= EVENT_LIMIT or self.event_bytes >= EVENT_BYTES_LIMIT,
                count >= EVENT_LIMIT_HARD or self.event_bytes >= EVENT_BYTES_LIMIT_HARD)

    def _limit(self, before: int, flush: bool) -> None:
        """This pass's events, kept within the limits. No change is lost: past the soft
        limit a checkpoint's or liveness mark's patch rides on its node's next event kept
        (or on one mark of the node per SEEN_EVERY_NS); past the hard limit the pass's
        patches are kept merged, one event per node, and nothing more is read. The page's
        state is the server's once those marks are sent (at the latest when a pass finds
        nothing new, `flush`)."""
        events = self.fold.events
        new = events[before:]
        del events[before:]
        for event in new:
            self._keep(event)
        now = time.monotonic()
        for node in list(self._pending):
            if (flush or self.truncated or node is None
                    or self._pending_t[node] - self._kept_mark.get(node, -SEEN_EVERY_NS) >= SEEN_EVERY_NS
                    or now - self._pending_since[node] >= SEEN_EVERY_NS / 1e9):
                self._flush(node)

    def _keep(self, event: dict[str, Any]) -> None:
        node = event["n"]
        soft, hard = self._over()
        if hard or self.truncated:
            self.truncated = True
            self._carry(node, event)
            return
        if soft and node is not None and event["k"] in ("checkpoint", "seen"):
            self.dropped += 1
            self._carry(node, event)
            return
        if node in self._pending and event["t"] >= self._pending_t[node]:
            carried = self._pending[node]
            if compose_patch(carried, event.get("p") or {}):
                self._drop_pending(node)
                event["p"] = carried
            else:
                self._flush(node)
        self._append(event)

    def _carry(self, node: str | None, event: dict[str, Any]) -> None:
        patch = event.get("p") or {}
        if node in self._pending and not compose_patch(self._pending[node], patch):
            self._flush(node)
        if node in self._pending:
            self._pending_t[node] = max(self._pending_t[node], event["t"])
        else:
            self._pending[node] = copy.deepcopy(patch)
            self._pending_t[node] = event["t"]
            self._pending_since[node] = time.monotonic()

    def _drop_pending(self, node: str | None) -> tuple[dict[str, Any], int]:
        self._pending_since.pop(node)
        return self._pending.pop(node), self._pending_t.pop(node)

    def _flush(self, node: str | None) -> None:
        """A node's carried changes as an event of their own: a liveness mark."""
        patch, t_ns = self._drop_pending(node)
        if patch:
            self._append({"i": 0, "t": t_ns, "n": node, "f": "", "a": "",
                          "k": "state" if node is None else "seen", "p": patch})

    def _append(self, event: dict[str, Any]) -> None:
        events = self.fold.events
        event["i"] = len(events)
        self.event_bytes += len(_json_bytes(event))
        if event["n"] is not None and event["k"] not in ("fault", "measure"):
            self._kept_mark[event["n"]] = max(self._kept_mark.get(event["n"], event["t"]), event["t"])
        events.append(event)

    # -- the run directory's other files -----------------------------------------------

    def _report_events(self) -> list[tuple[str, bytes]]:
        """A run directory without the launcher's event log (an older run): its report's
        events, once the report is there."""
        report = self.run_dir / REPORT_FILE
        if not report.is_file():
            return []
        self._from_report = True
        try:
            events = json.loads(report.read_text(encoding="utf-8")).get("events") or []
        except (OSError, ValueError, AttributeError, RecursionError):
            return []
        if not isinstance(events, list):
            return []
        return [(REPORT_FILE, json.dumps(e).encode()) for e in events if isinstance(e, dict)]

    def _mission_path(self) -> tuple[Path | None, int]:
        """The mission image the nodes fly after the updates the launcher logged, and how
        many updates it accounts for: update N's image is in `update-N/` (or, when the update
        was an image, that file itself: the launcher flies it without a copy)."""
        updates = [f["argument"] for f in self.fold.faults if f["action"] == "update"]
        for n in range(len(updates), 0, -1):
            image = _newest_image(self.run_dir / f"update-{n}")
            if image is None and _is_image_file(updates[n - 1]):
                image = Path(updates[n - 1])
            if image is not None:
                return image, n
        return self.mission_path or _newest_image(self.run_dir), 0

    def _read_mission(self) -> None:
        """The mission, once its file is there and reads (an image being written is read
        again when it changes), and again after each mission update the launcher logs."""
        updates = sum(1 for f in self.fold.faults if f["action"] == "update")
        if self.mission is not None and self._mission_for == updates:
            return
        path, covers = self._mission_path()
        if path is None:
            return
        try:
            stamp = (path, path.stat().st_mtime_ns)
        except OSError:
            return
        if stamp == self._mission_tried:
            return
        self._mission_tried = stamp
        try:
            mission = read_mission(path)
        except ConsoleError as error:
            with self.lock:
                self.mission_error = str(error)
            return
        self._mission_for = covers
        names = image_names(path)
        with self.lock:
            if names is not None:
                self.names = names
            if mission != self.mission:
                self.mission_version += 1
            self.mission, self.mission_source, self.mission_error = mission, path, None

    # -- what handlers read (under self.lock) --------------------------------------------

    def status(self) -> dict[str, Any]:
        return {
            "run_dir": str(self.run_dir),
            "exists": self.run_dir.is_dir(),
            "trace_files": list(self.trace_names),
            "waiting": not self.trace_names,
            "lines": self.fold.lines,
            "malformed": self.malformed,
            "events": len(self.fold.events),
            "event_bytes": self.event_bytes,
            "dropped": self.dropped,
            "truncated": self.truncated,
            "finished": self.finished,
            "mission": str(self.mission_source) if self.mission_source else None,
            "mission_error": self.mission_error,
            "error": self.error,
            "errors": self.errors,
            "passes": self.passes,
            "instance": self.instance,
        }

    def signature(self) -> tuple[Any, ...]:
        """What of the status a page shows, apart from the events: a change is sent."""
        return (len(self.trace_names), self.finished, self.truncated, self.mission_error,
                self.mission_version, self.errors, self.dropped > 0)

    def events_since(self, since: int, limit: int = STREAM_BATCH_MAX) -> list[dict[str, Any]]:
        return self.fold.events[max(0, since):max(0, since) + limit]


def compose_patch(first: dict[str, Any], then: dict[str, Any]) -> bool:
    """Makes `first` the merge patch (RFC 7386) that does `first`, then `then`; False, and
    `first` unchanged, when no one patch does (`then` merges an object where `first` sets
    something else: the target's own object would be merged, not replaced)."""

    def possible(a: dict[str, Any], b: dict[str, Any]) -> bool:
        for key, value in b.items():
            if isinstance(value, dict) and key in a:
                if not isinstance(a[key], dict) or not possible(a[key], value):
                    return False
        return True

    def merge(a: dict[str, Any], b: dict[str, Any]) -> None:
        for key, value in b.items():
            if isinstance(value, dict):
                if key in a:
                    merge(a[key], value)
                else:
                    a[key] = copy.deepcopy(value)
            else:
                a[key] = value

    if not possible(first, then):
        return False
    merge(first, then)
    return True


# --- 5. The HTTP server ---------------------------------------------------------------------


@dataclass
class Applied:
    """A command the run applied, with a note for the page (for a ground command: the
    proven graph's target from the cluster's configuration, or why the nodes will refuse it)."""

    note: str


@dataclass
class Commands:
    """What the page may command: `take(line)` returns why the line was not taken, None
    (or an Applied, with its note) when it was (the run applies it at once); `examples`
    are shown on the page."""

    take: Any  # Callable[[str], str | None]
    examples: list[str]


class ConsoleServer(ThreadingHTTPServer):
    """The console's HTTP server on 127.0.0.1. `port` 0 takes any free port (`url`)."""

    daemon_threads = True
    allow_reuse_address = True

    def __init__(self, feed: Feed, port: int = 0, static_dir: Path = STATIC_DIR,
                 commands: Commands | None = None):
        self.feed = feed
        self.static_dir = static_dir
        # The run's ground console (`run --console`): takes one command line, says why it
        # was not taken (None: it was). None: a replay, nothing to command.
        self.commands = commands
        # Sent with every command: the page reads it from the address the run printed
        # (command_url); the console serves it to no one (any local process may ask).
        self.token = secrets.token_urlsafe(24)
        self.streams = 0
        self.streams_lock = threading.Lock()
        # Per open stream (under feed.lock): the next event it sends and the status it sent.
        self.sent: dict[int, tuple[int, tuple[Any, ...]]] = {}
        super().__init__(("127.0.0.1", port), ConsoleHandler)

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.server_address[1]}/"

    @property
    def command_url(self) -> str:
        """The address to give the user: with commands, it carries the token (#k=), which
        the page reads and the console serves to no one."""
        return self.url if self.commands is None else f"{self.url}#k={self.token}"

    def start(self) -> threading.Thread:
        """The feed's thread and the server's, both daemons; `close()` ends them."""
        self.feed.start()
        thread = threading.Thread(target=self.serve_forever, kwargs={"poll_interval": 0.2},
                                  name="console-http", daemon=True)
        thread.start()
        return thread

    def drain(self, timeout_s: float = DRAIN_S) -> bool:
        """Waits until the feed has folded all the run wrote (Feed.drain) and every open
        page's stream has sent every event and the last status; False when timeout_s
        passed first (a page that does not read)."""
        deadline = time.monotonic() + timeout_s
        if not self.feed.drain(timeout_s):
            return False
        feed = self.feed
        with feed.lock:
            return feed.lock.wait_for(
                lambda: feed.closing or all(at >= len(feed.fold.events) and shown == feed.signature()
                                            for at, shown in self.sent.values()),
                max(0.0, deadline - time.monotonic()))

    def close(self) -> None:
        self.feed.stop()
        self.shutdown()
        self.server_close()

    def handle_error(self, request: Any, client_address: Any) -> None:
        """A request that failed: a page that went away says nothing; anything else one line."""
        error = sys.exc_info()[1]
        if isinstance(error, (ConnectionError, TimeoutError)):
            return
        print(f"keel-cluster console: a request from {client_address[0]}:{client_address[1]} failed: "
              f"{type(error).__name__}: {error}", file=sys.stderr)


def _json_bytes(value: Any) -> bytes:
    return json.dumps(value, separators=(",", ":")).encode()


# Sent with every answer: the page loads nothing but its own files, no page may frame it,
# and a browser takes each file as the type it is served as.
SECURITY_HEADERS = (
    ("Content-Security-Policy", "default-src 'self'; frame-ancestors 'none'"),
    ("X-Content-Type-Options", "nosniff"),
    ("Referrer-Policy", "no-referrer"),
)


class ConsoleHandler(BaseHTTPRequestHandler):
    server: ConsoleServer
    protocol_version = "HTTP/1.1"
    server_version = "keel-console"

    def log_message(self, format: str, *args: Any) -> None:
        pass  # the console prints its URL and nothing per request

    def end_headers(self) -> None:
        for name, value in SECURITY_HEADERS:
            self.send_header(name, value)
        super().end_headers()

    def do_HEAD(self) -> None:
        self.do_GET()

    def refused(self) -> str | None:
        """Why a request is not answered, or None. Only requests addressed to 127.0.0.1 or
        localhost (a web page elsewhere cannot reach the console through a name it points
        at this address: DNS rebinding), and none a page of another origin makes: the
        browser says so in Sec-Fetch-Site, or in Origin."""
        host = (self.headers.get("Host") or "").rsplit(":", 1)[0]
        if host not in ("127.0.0.1", "localhost"):
            return "the console answers to 127.0.0.1 only"
        if (self.headers.get("Sec-Fetch-Site") or "").lower() in ("cross-site", "same-site"):
            return "the console answers to its own page only"
        origin = self.headers.get("Origin")
        port = self.server.server_address[1]
        if origin is not None and origin not in (f"http://127.0.0.1:{port}", f"http://localhost:{port}"):
            return "the console answers to its own page only"
        return None

    def do_GET(self) -> None:
        refusal = self.refused()
        if refusal is not None:
            self._send(HTTPStatus.FORBIDDEN, f"{refusal}\n".encode(), "text/plain")
            return
        parts = urlsplit(self.path)
        query = parse_qs(parts.query)
        feed = self.server.feed
        if parts.path in STATIC_FILES:
            name, content_type = STATIC_FILES[parts.path]
            try:
                body = (self.server.static_dir / name).read_bytes()
            except OSError as error:
                self._send(HTTPStatus.INTERNAL_SERVER_ERROR,
                           f"cannot read the page's {name}: {error.strerror}\n".encode(), "text/plain")
                return
            self._send(HTTPStatus.OK, body, content_type)
        elif parts.path == "/favicon.ico":
            self._send(HTTPStatus.NO_CONTENT, b"", "image/x-icon")
        elif parts.path == "/api/stream":
            self._stream(self._since(query))
        elif parts.path == "/api/events":
            since = self._since(query)
            with feed.lock:
                events = feed.events_since(since)
                body = _json_bytes({"events": events, "next": since + len(events),
                                    "status": feed.status()})
            self._json(body)
        elif parts.path == "/api/state":
            with feed.lock:
                body = _json_bytes(feed.fold.state)
            self._json(body)
        elif parts.path == "/api/mission":
            with feed.lock:
                body = _json_bytes({"mission": feed.mission, "error": feed.mission_error})
            self._json(body)
        elif parts.path == "/api/status":
            with feed.lock:
                body = _json_bytes(feed.status())
            self._json(body)
        elif parts.path == "/api/command":
            commands = self.server.commands
            self._json(_json_bytes({"enabled": False} if commands is None else
                                   {"enabled": True, "examples": commands.examples}))
        else:
            self._send(HTTPStatus.NOT_FOUND, b"no such page\n", "text/plain")

    def do_POST(self) -> None:
        """POST /api/command {"line": "..."} with the header X-Keel-Token: a command of the
        run's ground console, as on `run --ground`'s stdin. Only from the console's own page
        (refused(), and Origin required), with the token the page read."""
        refusal = self.refused()
        if refusal is None and self.headers.get("Origin") is None:
            refusal = "the console takes commands from its own page only"
        length_text = (self.headers.get("Content-Length") or "").strip()
        length = (int(length_text) if length_text.isascii() and length_text.isdigit() and len(length_text) <= 9
                  else -1)
        if self.headers.get("Transfer-Encoding"):
            length = -1
        if refusal is not None:
            self.close_connection = True
            self._send(HTTPStatus.FORBIDDEN, f"{refusal}\n".encode(), "text/plain")
            return
        if urlsplit(self.path).path != "/api/command":
            self.close_connection = True
            self._send(HTTPStatus.NOT_FOUND, b"no such page\n", "text/plain")
            return
        if length < 0 or length > COMMAND_BYTES_MAX:
            self.close_connection = True
            self._answer(HTTPStatus.REQUEST_ENTITY_TOO_LARGE if length > COMMAND_BYTES_MAX
                         else HTTPStatus.LENGTH_REQUIRED,
                         f"a command is one line of at most {COMMAND_BYTES_MAX} bytes")
            return
        body = self.rfile.read(length)
        commands = self.server.commands
        if commands is None:
            self._answer(HTTPStatus.CONFLICT, "this console replays a run: there is no cluster to command")
            return
        if not secrets.compare_digest((self.headers.get("X-Keel-Token") or "").encode(),
                                      self.server.token.encode()):
            self._answer(HTTPStatus.FORBIDDEN, "the command does not carry this console's key "
                                               "(open the address the run printed, with its #k=)")
            return
        try:
            line = json.loads(body)["line"]
        except (ValueError, KeyError, TypeError, RecursionError):
            line = None
        if not isinstance(line, str) or not line.strip() or "\n" in line or "\r" in line:
            self._answer(HTTPStatus.BAD_REQUEST, 'a command is {"line": "..."}, one line')
            return
        why = commands.take(line.strip())
        if isinstance(why, str):
            self._answer(HTTPStatus.BAD_REQUEST, why)
            return
        taken: dict[str, Any] = {"ok": True, "line": line.strip()}
        if isinstance(why, Applied):
            taken["note"] = why.note
        self._json(_json_bytes(taken))

    def _answer(self, status: HTTPStatus, error: str) -> None:
        self._send(status, _json_bytes({"ok": False, "error": error}), "application/json")

    def _since(self, query: dict[str, list[str]]) -> int:
        text = (query.get("since") or [self.headers.get("Last-Event-ID") or "0"])[0]
        try:
            return max(0, int(text))
        except ValueError:
            return 0

    def _send(self, status: HTTPStatus, body: bytes, content_type: str) -> None:
        self.send_response(status)
        if self.close_connection:
            self.send_header("Connection", "close")
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        if self.command != "HEAD" and body:
            self.wfile.write(body)

    def _json(self, body: bytes) -> None:
        self._send(HTTPStatus.OK, body, "application/json")

    def _stream(self, since: int) -> None:
        """Server-Sent Events: `{"events", "status", "mission"?}` per message, its id the
        index of the next event, so a reconnecting EventSource resumes where it was."""
        server = self.server
        with server.streams_lock:
            if server.streams >= STREAMS_MAX:
                self._send(HTTPStatus.SERVICE_UNAVAILABLE, b"too many pages open\n", "text/plain")
                return
            server.streams += 1
        try:
            self.send_response(HTTPStatus.OK)
            self.send_header("Content-Type", "text/event-stream")
            self.send_header("Cache-Control", "no-store")
            self.end_headers()
            if self.command != "HEAD":
                self._pump(since)
        finally:
            with server.feed.lock:
                server.sent.pop(id(self), None)
                server.feed.lock.notify_all()
            with server.streams_lock:
                server.streams -= 1

    def _pump(self, since: int) -> None:
        feed = self.server.feed
        sent = self.server.sent
        mission_sent = 0  # the mission_version sent
        shown: tuple[Any, ...] = ()
        with feed.lock:
            sent[id(self)] = (since, shown)
        while True:
            with feed.lock:
                def fresh(since: int = since, mission_sent: int = mission_sent,
                          shown: tuple[Any, ...] = shown) -> bool:
                    return (feed.closing or len(feed.fold.events) > since
                            or (feed.mission is not None and feed.mission_version != mission_sent)
                            or feed.signature() != shown)

                if not feed.lock.wait_for(fresh, timeout=KEEPALIVE_S):
                    body = b": keepalive\n\n"
                elif feed.closing:
                    return
                else:
                    events = feed.events_since(since)
                    message: dict[str, Any] = {"events": events, "status": feed.status()}
                    if feed.mission is not None and feed.mission_version != mission_sent:
                        message["mission"] = feed.mission
                        mission_sent = feed.mission_version
                    shown = feed.signature()
                    since += len(events)
                    data = json.dumps(message, separators=(",", ":"))
                    body = f"id: {since}\ndata: {data}\n\n".encode()
            self.wfile.write(body)
            self.wfile.flush()
            with feed.lock:
                sent[id(self)] = (since, shown)
                feed.lock.notify_all()


def serve(run_dir: Path, port: int = 0, mission_path: Path | None = None,
          not_before_ns: int = 0, commands: Commands | None = None) -> ConsoleServer:
    """A started console of `run_dir` (the feed's and the server's threads running).
    Raises OSError when the port cannot be bound. `not_before_ns`: Feed's. `commands`:
    the run's ground console, which the page may send lines to (ConsoleServer)."""
    server = ConsoleServer(Feed(run_dir, mission_path, not_before_ns=not_before_ns), port,
                           commands=commands)
    server.start()
    return server


OBSERVE_JOIN_S = 20.0  # how long keel-observe may take to create its participant (DDS Security's set-up)


class Observer:
    """keel-observe (nodes/observe) joined to a cluster's protocol domain, read only, its
    lines appended to DIR/observed.jsonl, which the console's feed follows like a trace."""

    def __init__(self, folder: Path, domain: int, security: Path | None, interface: str = "lo",
                 peers: list[str] | None = None):
        from keel_cluster.common import find_executable

        binary = find_executable("keel-observe", ["nodes/observe/keel-observe"])
        if binary is None:
            raise ConsoleError("keel-observe is not built (./keel setup builds it)")
        command = [str(binary), "--domain", str(domain), "--interface", interface]
        for peer in peers or []:
            command += ["--peer", peer]
        if security is not None:
            command += ["--security", str(security)]
        self.path = folder / OBSERVED_FILE
        self._out = open(self.path, "ab")  # noqa: SIM115 - the process writes it until stop()
        self.process = subprocess.Popen(command, stdout=self._out, stderr=subprocess.PIPE,
                                        stdin=subprocess.DEVNULL)

    def joined(self, timeout_s: float = OBSERVE_JOIN_S) -> str | None:
        """None once its participant exists (its first line is written), else why not."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                return self.failure()
            try:
                if self.path.stat().st_size > 0:
                    return None
            except OSError:
                pass
            time.sleep(0.05)
        return f"keel-observe did not join within {timeout_s:g} s"

    def failure(self) -> str:
        """Why it ended (its own words on stderr, and its exit status)."""
        assert self.process.stderr is not None
        said = self.process.stderr.read().decode("utf-8", "replace").strip()
        return (said or "keel-observe ended") + f" (exit {self.process.returncode})"

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._out.close()


def _dds_folder(args: Any, mission_path: Path) -> Path:
    """The folder `console --dds` records in: RUN_DIR (created) or a new temporary one,
    with the mission image beside the observation so the folder plays back alone."""
    import shutil
    import tempfile

    if args.run_dir:
        folder = Path(args.run_dir)
        folder.mkdir(parents=True, exist_ok=True)
        if (folder / OBSERVED_FILE).exists():
            raise ConsoleError(f"{folder}: already holds an observation ({OBSERVED_FILE}); name another folder")
    else:
        folder = Path(tempfile.mkdtemp(prefix=f"keel-console-{args.dds}-"))
    if _newest_image(folder) is None:
        shutil.copy2(mission_path, folder / (mission_path.name if mission_path.name.endswith(".image.json")
                                             else "mission.image.json"))
    return folder


def main_console(args: Any) -> int:
    """`keel-cluster console RUN_DIR`, or `console --dds DOMAIN`: serves until Ctrl-C.
    Exit codes: 0 stopped by Ctrl-C (or SIGTERM); 2 bad input (no such run directory, a
    mission that cannot be read, --dds without the mission's image, a credentials folder
    without the monitor's identity); 3 the server could not start (the port is taken);
    4 (--dds) keel-observe could not join the domain or stopped (its reason printed)."""
    import signal
    import sys

    mission_path = Path(args.mission) if args.mission else None
    if mission_path is not None:
        try:
            read_mission(mission_path)
        except ConsoleError as error:
            print(f"keel-cluster console: {error}", file=sys.stderr)
            return 2
    observer: Observer | None = None
    if getattr(args, "dds", None) is not None:
        if not 0 <= args.dds <= 230:
            print(f"keel-cluster console: --dds {args.dds}: a domain is 0..230", file=sys.stderr)
            return 2
        if mission_path is None or image_names(mission_path) is None:
            print("keel-cluster console: --dds needs --mission IMAGE, the image the nodes fly (RUN_DIR/*.image.json, "
                  "or keel-mission compile's): the wire carries the image's ids, not names", file=sys.stderr)
            return 2
        security = Path(args.security) if args.security else None
        if security is not None and not (security / "tools" / "monitor" / "cert.pem").is_file():
            print(f"keel-cluster console: --security {security}: no monitor identity (tools/monitor/cert.pem); "
                  "give the mission's credentials folder", file=sys.stderr)
            return 2
        try:
            run_dir = _dds_folder(args, mission_path)
            observer = Observer(run_dir, args.dds, security, args.interface, getattr(args, "peer", None))
        except (ConsoleError, OSError) as error:
            print(f"keel-cluster console: {error}", file=sys.stderr)
            return 2
        problem = observer.joined()
        if problem is not None:
            observer.stop()
            print(f"keel-cluster console: --dds {args.dds}: {problem}", file=sys.stderr)
            return 4
        mission_path = None  # the folder holds its copy
    else:
        if not args.run_dir:
            print("keel-cluster console: give a RUN_DIR, or --dds DOMAIN", file=sys.stderr)
            return 2
        run_dir = Path(args.run_dir)
        if not run_dir.is_dir():
            print(f"keel-cluster console: {run_dir}: no such run directory", file=sys.stderr)
            return 2
    try:
        server = serve(run_dir, args.port, mission_path)
    except OSError as error:
        if observer is not None:
            observer.stop()
        print(f"keel-cluster console: cannot listen on 127.0.0.1:{args.port}: {error.strerror}",
              file=sys.stderr)
        return 3
    if observer is not None:
        print(f"keel-cluster: console of DDS domain {args.dds} ({'as keel-monitor' if args.security else 'insecure'}; "
              f"recorded in {run_dir}) at {server.url} (Ctrl-C ends it)", file=sys.stderr, flush=True)
    else:
        print(f"keel-cluster: console of {run_dir} at {server.url} (Ctrl-C ends it)", file=sys.stderr, flush=True)
    stop = threading.Event()
    previous = signal.signal(signal.SIGTERM, lambda *_: stop.set())
    status = 0
    try:
        while not stop.wait(0.5):
            if observer is not None and observer.process.poll() is not None:
                print(f"keel-cluster console: --dds {args.dds}: {observer.failure()}", file=sys.stderr)
                status = 4
                break
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGTERM, previous)
        server.close()
        if observer is not None:
            observer.stop()
            print(f"keel-cluster: console closed; replay the observation with: keel-cluster console {run_dir}",
                  file=sys.stderr)
    return status
