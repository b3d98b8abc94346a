"""The ground's view of a cluster: a page in the browser that follows a run directory.

    keel-cluster console RUN_DIR [--port PORT] [--mission FILE]
    keel-cluster run MISSION --console [PORT] ...

The console serves one page on 127.0.0.1 (no other address) and feeds it from the run
directory's files, so it shows a live run and a finished one alike:

- `NAME.trace.ndjson`, each node's protocol trace (spec/NAMES.md), tailed: files may appear
  late and grow, and only whole lines are read (a line being written is read once its
  newline is there; a node killed mid-write leaves a line that does not parse, counted);
- `*.image.json`, the mission image the nodes fly: nodes, configurations, the graph;
- `events.jsonl`, what the launcher did and when (kill, restart, partition, phase, ...),
  appended as it happens; for a run directory without it, `report.json`'s events. A
  simulator trace's `env` lines (Crash, Partition, RequestPhase) stand in for them.

How it works, in the order data flows:

1. `Tail` reads what the files gained since the last pass, whole lines only.
2. `Fold` turns each trace line into at most a few compact *events*, `{"i", "t", "n", "f",
   "a", "k", "d", "p"}`: index, time (the line's `t_ns`), node, fsm, action, kind (the
   timeline's lane and marker), a sentence for the timeline (or none) and a *patch*, a JSON
   merge patch (RFC 7386) of the console's state. Heartbeat sends and receipts never leave
   the fold (hundreds a second); a monitor's Tick leaves only when its `missed` counts or
   its declarations change. A patch changes only the state of the line's own node, or adds
   an entry to a log keyed by its own id (the Master's path through the graph, the
   measures, the launcher's faults), so applying events in time order or in arrival order
   gives the same state: a replay seeks by applying the events up to the time it shows.
3. `Measures` times each fault as `analysis.fault_metrics` does (detection, decision,
   switch, restore; the same function, over the lines seen so far) and adds a `measure`
   event each time a figure is known.
4. `Feed` runs passes 1-3 on a thread every `poll_s` and keeps the events (past
   `EVENT_LIMIT`, checkpoints and liveness marks are counted, not kept; past
   `EVENT_LIMIT_HARD`, nothing).
5. `ConsoleServer` (http.server) serves the page (`console/`: index.html, console.js,
   console.css; nothing from the network) and `/api/stream`, Server-Sent Events: the events
   from the one the client has, in batches, as they come. `/api/events?since=N`,
   `/api/state`, `/api/mission` and `/api/status` answer once, as JSON.

The page applies the patches (its one fold: `apply` in console.js) and derives what it
shows from the state: the acting Master and the cluster's configuration, silent nodes,
the link matrix. It keeps every event, so it plays a run back (play, pause, seek) without the
server.

Threading: the feed's thread is the only writer of its events, state and counters; HTTP
handler threads read them under `Feed.lock` (a condition variable that wakes the streams).
"""

from __future__ import annotations

import json
import re
import secrets
import threading
import time
from dataclasses import dataclass
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlsplit

import yaml

from keel_cluster import analysis
from keel_cluster.common import image_as_mission
from keel_cluster.launcher import EVENTS_FILE, is_image

TRACE_GLOB = "*.trace.ndjson"
REPORT_FILE = "report.json"

POLL_S = 0.05  # the feed's pass; the page's delay is about half of it on average
READ_BYTES_MAX = 8 << 20  # read per file per pass: a long finished trace takes several passes
LINE_BYTES_MAX = 1 << 20  # a longer line is skipped, counted as malformed
FILES_MAX = 1024
EVENT_LIMIT = 500_000  # then checkpoints and liveness marks are counted, not kept
EVENT_LIMIT_HARD = 2 * EVENT_LIMIT  # then nothing more is kept, and the page says so
STREAM_BATCH_MAX = 5_000  # events per Server-Sent Event
STREAMS_MAX = 16
KEEPALIVE_S = 15.0
SEEN_EVERY_NS = 500_000_000  # a node's liveness mark, when nothing else shows it: at most two a second

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
    skipping: bool = False  # inside a line longer than LINE_BYTES_MAX: drop up to its end


class Tail:
    """Whole lines appended to one kind of file in a folder since the last `poll`. A file
    that shrinks (replaced) is read again from its start."""

    def __init__(self, folder: Path, pattern: str):
        self.folder = folder
        self.pattern = pattern
        self.files: dict[Path, _Tailed] = {}
        self.oversized = 0

    def poll(self) -> tuple[list[tuple[str, bytes]], bool]:
        """(file name, line) pairs in file order, and whether any file has more to read."""
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
                    size = handle.seek(0, 2)
                    if size < tailed.offset:
                        tailed.offset, tailed.skipping = 0, False
                    if size == tailed.offset:
                        continue
                    handle.seek(tailed.offset)
                    chunk = handle.read(READ_BYTES_MAX)
            except OSError:
                continue
            end = chunk.rfind(b"\n") + 1
            if end == 0:
                # No whole line yet: wait for one, unless it is already too long.
                if len(chunk) >= LINE_BYTES_MAX:
                    tailed.offset += len(chunk)
                    tailed.skipping = True
                    more = tailed.offset < size
                continue
            more |= tailed.offset + len(chunk) < size
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


def find_image(run_dir: Path) -> Path | None:
    """The mission image of a run directory (the newest, if an update wrote another)."""
    try:
        images = [p for p in run_dir.glob("*.image.json") if p.is_file()]
    except OSError:
        return None
    return max(images, key=lambda p: p.stat().st_mtime, default=None)


def read_mission(path: Path) -> dict[str, Any]:
    """What the page needs of a mission (an image or a YAML): nodes, tasks, the heartbeat,
    and the graph as configurations and edges. Raises ConsoleError."""
    try:
        if is_image(path):
            raw = image_as_mission(json.loads(path.read_text(encoding="utf-8"))["content"])
        else:
            raw = yaml.safe_load(path.read_text(encoding="utf-8"))
        return mission_summary(raw)
    except (OSError, ValueError, KeyError, TypeError, AttributeError, yaml.YAMLError) as error:
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
    ("election", "WarmBoot"): "master",
    ("switch", "Exclude"): "exclude", ("switch", "BecomeMaster"): "master",
    ("switch", "BootSwitch"): "switch", ("switch", "BroadcastCommand"): "switch",
    ("switch", "RequestPhase"): "switch", ("switch", "CompleteSwitch"): "switch",
    ("switch", "GroundRecovery"): "ground", ("switch", "GroundExclude"): "ground",
    ("switch", "GroundReadmit"): "ground", ("switch", "Readmit"): "readmit",
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
    if action == "GroundRecovery":
        return f"{who} leaves safe mode for {a.get('c')} (the ground's)"
    if action == "Readmit":
        return f"{who} readmits {a.get('r')} -> {a.get('c')}"
    if action == "HandOver":
        return (f"{who} hands the mastership to {a.get('to')} (epoch {a.get('epoch')}), "
                f"readmitting {a.get('r')} -> {a.get('c')}")
    return f"{node} switch.{action}"


def describe_launcher(action: str, argument: str) -> str:
    return f"{action} {argument}".strip()


class Fold:
    """Trace lines in, events out. `state` is what the events' patches add up to (the
    page rebuilds it the same way), and `faults` what the launcher (or a simulator's env
    lines) did, for `Measures`.

    The state: `nodes` (per node: what its own lines say, `seen` the time of its last
    event, `down` and `paused` what the launcher did to it), `path` (the configurations
    the Masters completed switches to, in order), `faults` and `measures`."""

    def __init__(self) -> None:
        self.state: dict[str, Any] = {"nodes": {}, "path": {}, "measures": {}, "faults": {}}
        self.events: list[dict[str, Any]] = []
        self.faults: list[dict[str, Any]] = []  # {"t_ns", "action", "argument"}, as analysis takes them
        self.relevant: list[analysis.TraceLine] = []  # what fault_metrics reads
        self.malformed = 0
        self.lines = 0
        self._marked: dict[str, int] = {}  # node -> time of its last event
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

    def raw_line(self, raw: bytes) -> None:
        """One line of a trace file, as read."""
        self.lines += 1
        if any(needle in raw for needle in _HEARTBEAT_TRAFFIC):
            head = _HEAD.match(raw)
            if head:  # read no further: the line marks its node alive, no more
                self._liveness(int(head.group(1)), head.group(2).decode("utf-8", "replace"))
                return
        try:
            line = json.loads(raw)
            t_ns, node = int(line["t_ns"]), line.get("node")
            fsm = str(line["fsm"])
            action = analysis.legacy_action(fsm, str(line["action"]))
            args, variables = line.get("args") or {}, line.get("vars") or {}
            if not isinstance(args, dict) or not isinstance(variables, dict):
                raise TypeError("args and vars must be objects")
        except (ValueError, KeyError, TypeError, AttributeError):
            self.malformed += 1
            return
        self.line(t_ns, None if node is None else str(node), fsm, action, args, variables)

    def line(self, t_ns: int, node: str | None, fsm: str, action: str,
             args: dict[str, Any], variables: dict[str, Any]) -> None:
        if fsm == "env":
            self._env(t_ns, action, args)
            return
        if node is None:
            return
        if (fsm, action) in _HEARTBEAT_ACTIONS:
            self._liveness(t_ns, node)
            return
        if (fsm, action) in MEASURED:
            self.relevant.append(analysis.TraceLine(t_ns, node, fsm, action, args, variables))
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

    def _changes(self, fsm: str, action: str, args: dict[str, Any],
                 variables: dict[str, Any]) -> dict[str, Any]:
        """The node's fields a line states."""
        changes: dict[str, Any] = {}
        if fsm == "heartbeat":
            if isinstance(variables.get("missed"), dict):
                changes["missed"] = {str(k): v for k, v in variables["missed"].items()}
            if isinstance(variables.get("failed"), list):
                changes["declared"] = _names(variables["failed"])
            if action == "Tick" and isinstance(args.get("suspect"), bool):
                changes["late"] = args["suspect"]
        elif fsm == "switch":
            changes.update({name: variables[key] for key, name in SWITCH_VARS.items() if key in variables})
            if isinstance(variables.get("stored"), dict):
                changes["stored"] = variables["stored"]
            if action in ("Hold", "Release", "LeaseLapsed"):
                changes["held"] = action == "Hold"
            if action in ("Resign", "Resigned", "LeaseLapsed"):
                changes["resigned"] = True
            elif action == "ReceiveCommand" and args.get("n") not in _names(args.get("out")):
                changes["resigned"] = False  # in the view again
        elif fsm == "election":
            changes.update({name: variables[key] for key, name in ELECTION_VARS.items() if key in variables})
        return changes

    def _path(self, t_ns: int, node: str, args: dict[str, Any], variables: dict[str, Any],
              patch: dict[str, Any] | None) -> dict[str, Any] | None:
        """A switch the Master completed: the next step of the path through the graph."""
        config = args.get("c") or variables.get("masterConfig")
        if config is None or str(config) == self._path_last:
            return patch
        self._path_last = str(config)
        step = {"t": t_ns, "c": str(config), "m": node, "epoch": variables.get("epoch")}
        patch = patch or {}
        patch["path"] = {str(len(self.state["path"])): step}
        return patch

    def _liveness(self, t_ns: int, node: str) -> None:
        """A line that changes nothing shown: an event only when the node's last one is
        SEEN_EVERY_NS old, to keep its mark fresh."""
        last = self._marked.get(node)
        if last is not None and t_ns - last < SEEN_EVERY_NS:
            return
        if len(self.events) >= EVENT_LIMIT and last is not None:
            return
        self._emit(t_ns, node, "", "", "seen", None, None)

    def _env(self, t_ns: int, action: str, args: dict[str, Any]) -> None:
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
            self._fault(t_ns, fault[0], fault[1], patch)
        self._emit(t_ns, node, "env", action, "fault", describe(node, "env", action, args), patch or None)

    def _fault(self, t_ns: int, action: str, argument: str, patch: dict[str, Any]) -> None:
        key = str(len(self.faults))
        self.faults.append({"t_ns": t_ns, "action": action, "argument": argument})
        patch["faults"] = {key: {"t": t_ns, "action": action, "argument": argument}}

    # -- the launcher's events ----------------------------------------------------------

    def launcher(self, event: dict[str, Any]) -> None:
        """One event of the launcher's log (Cluster._record)."""
        try:
            t_ns, action, argument = int(event["t_ns"]), str(event["action"]), str(event["argument"])
        except (KeyError, TypeError, ValueError):
            self.malformed += 1
            return
        patch: dict[str, Any] = {}
        node_changes = LAUNCHER_NODE_PATCH.get(action)
        if node_changes:
            patch["nodes"] = {argument: dict(node_changes)}
        self._fault(t_ns, action, argument, patch)
        self._emit(t_ns, argument if node_changes else None, "launcher", action, "fault",
                   None if action == "start" else describe_launcher(action, argument), patch)

    def measure(self, key: str, t_ns: int, figures: dict[str, Any], text: str | None) -> None:
        self._emit(t_ns, None, "", "", "measure", text, {"measures": {key: figures}})


_T_NS = re.compile(rb'^\{\s*"t_ns"\s*:\s*(\d+)')


def _in_time_order(launched: list[tuple[str, bytes]],
                   lines: list[tuple[str, bytes]]) -> list[tuple[int, bool, bytes]]:
    """A pass's launcher events and trace lines as (t_ns, is a trace line, text), merged by
    time. Each file keeps its order (a line whose time does not read, or goes back, sorts
    with its file's previous line): a node's lines are folded as it wrote them."""
    merged: list[tuple[int, bool, bytes]] = []
    for is_trace, found in ((False, launched), (True, lines)):
        last: dict[str, int] = {}
        for name, raw in found:
            head = _T_NS.match(raw)
            t_ns = max(int(head.group(1)) if head else 0, last.get(name, 0))
            last[name] = t_ns
            merged.append((t_ns, is_trace, raw))
    merged.sort(key=lambda item: item[0])  # stable
    return merged


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
    far: the last two faults are timed again after each pass that brought lines (a fault's
    window ends where the next one starts; lines of other nodes may still arrive late)."""

    def __init__(self, fold: Fold):
        self.fold = fold
        self.shown: dict[int, dict[str, Any]] = {}  # index among timed faults -> figures sent

    def update(self) -> None:
        timed = [f for f in self.fold.faults if f["action"] in TIMED]
        if not timed:
            return
        first = max(0, len(timed) - 2)
        since = timed[first]["t_ns"]
        lines = self.fold.relevant
        # Lines before the oldest fault still timed are never needed again.
        keep = next((k for k, x in enumerate(lines) if x.t_ns >= since), len(lines))
        if keep > 0:
            del lines[:keep]
        window = sorted(lines, key=lambda x: x.t_ns)
        for offset, metrics in enumerate(analysis.fault_metrics(window, timed[first:])):
            index = first + offset
            figures = metrics.as_dict()
            if self.shown.get(index) == figures:
                continue
            self.shown[index] = figures
            known = [figures[k] for k in FIGURES if figures[k] is not None]
            t_ns = metrics.t_ns + int(max(known, default=0) * 1e6)
            text = None
            if figures["total_ms"] is not None:
                text = _measure_text(figures)
            self.fold.measure(str(index), t_ns, figures, text)


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
    into events. `start()` runs `poll_once` on a thread of its own every `poll_s`."""

    def __init__(self, run_dir: Path, mission_path: Path | None = None, poll_s: float = POLL_S):
        self.run_dir = run_dir
        self.mission_path = mission_path
        self.poll_s = poll_s
        self.lock = threading.Condition()
        self.fold = Fold()
        self.measures = Measures(self.fold)
        self.traces = Tail(run_dir, TRACE_GLOB)
        self.launcher = Tail(run_dir, EVENTS_FILE)
        self.mission: dict[str, Any] | None = None
        self.mission_error: str | None = None
        self.mission_source: Path | None = None
        self.dropped = 0  # events not kept past EVENT_LIMIT
        self.truncated = False  # EVENT_LIMIT_HARD reached: nothing more is kept
        self.finished = False
        self.closing = False
        self.passes = 0
        # Tells a page that reconnects whether it talks to the console it knew.
        self.instance = secrets.token_hex(8)
        self._from_report = False
        self._mission_tried: tuple[Path, int] | None = None
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
            more = self.poll_once()
            if not more:
                time.sleep(self.poll_s)

    def poll_once(self) -> bool:
        """One pass over the run directory; True when a file has more to read at once."""
        self._read_mission()
        lines, more_traces = self.traces.poll()
        launched, more_events = self.launcher.poll()
        if not launched and not self._from_report and not self.launcher.files:
            launched = self._report_events()
        with self.lock:
            before = len(self.fold.events)
            for _, is_trace, raw in _in_time_order(launched, lines):
                if self.truncated:
                    break
                if is_trace:
                    self.fold.raw_line(raw)
                    continue
                try:
                    self.fold.launcher(json.loads(raw))
                except ValueError:
                    self.fold.malformed += 1
            if lines or launched:
                self.measures.update()
            self._limit(before)
            self.finished = (self.run_dir / REPORT_FILE).is_file()
            self.passes += 1
            self.lock.notify_all()
        return more_traces or more_events

    def _limit(self, before: int) -> None:
        """Past EVENT_LIMIT, this pass's checkpoints and liveness marks are counted, not
        kept (their patches are in the server's state: the page misses their detail only);
        at EVENT_LIMIT_HARD nothing more is kept."""
        events = self.fold.events
        start = max(before, EVENT_LIMIT)
        if len(events) <= start:
            return
        kept = [e for e in events[start:] if e["k"] not in ("checkpoint", "seen")]
        self.dropped += len(events) - start - len(kept)
        del events[start:]
        room = max(0, EVENT_LIMIT_HARD - len(events))
        self.dropped += max(0, len(kept) - room)
        for event in kept[:room]:
            event["i"] = len(events)
            events.append(event)
        if len(events) >= EVENT_LIMIT_HARD:
            self.truncated = True

    def _report_events(self) -> list[tuple[str, bytes]]:
        """A run directory without the launcher's event log (an older run): its report's
        events, once the report is there."""
        report = self.run_dir / REPORT_FILE
        if not report.is_file():
            return []
        self._from_report = True
        try:
            events = json.loads(report.read_text(encoding="utf-8")).get("events") or []
        except (OSError, ValueError, AttributeError):
            return []
        return [(REPORT_FILE, json.dumps(e).encode()) for e in events if isinstance(e, dict)]

    def _read_mission(self) -> None:
        """The mission, once its file is there and reads (an image being written is read
        again when it changes)."""
        if self.mission is not None:
            return
        path = self.mission_path or find_image(self.run_dir)
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
        with self.lock:
            self.mission, self.mission_source, self.mission_error = mission, path, None

    # -- what handlers read (under self.lock) --------------------------------------------

    def status(self) -> dict[str, Any]:
        files = sorted(p.name for p in self.traces.files)
        return {
            "run_dir": str(self.run_dir),
            "exists": self.run_dir.is_dir(),
            "trace_files": files,
            "waiting": not files,
            "lines": self.fold.lines,
            "malformed": self.fold.malformed + self.traces.oversized,
            "events": len(self.fold.events),
            "dropped": self.dropped,
            "truncated": self.truncated,
            "finished": self.finished,
            "mission": str(self.mission_source) if self.mission_source else None,
            "mission_error": self.mission_error,
            "passes": self.passes,
            "instance": self.instance,
        }

    def signature(self) -> tuple[Any, ...]:
        """What of the status a page shows, apart from the events: a change is sent."""
        return (len(self.traces.files), self.finished, self.truncated, self.mission_error,
                self.mission_source)

    def events_since(self, since: int, limit: int = STREAM_BATCH_MAX) -> list[dict[str, Any]]:
        return self.fold.events[max(0, since):max(0, since) + limit]


# --- 5. The HTTP server ---------------------------------------------------------------------


class ConsoleServer(ThreadingHTTPServer):
    """The console's HTTP server on 127.0.0.1. `port` 0 takes any free port (`url`)."""

    daemon_threads = True
    allow_reuse_address = True

    def __init__(self, feed: Feed, port: int = 0, static_dir: Path = STATIC_DIR):
        self.feed = feed
        self.static_dir = static_dir
        self.streams = 0
        self.streams_lock = threading.Lock()
        super().__init__(("127.0.0.1", port), ConsoleHandler)

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.server_address[1]}/"

    def start(self) -> threading.Thread:
        """The feed's thread and the server's, both daemons; `close()` ends them."""
        self.feed.start()
        thread = threading.Thread(target=self.serve_forever, kwargs={"poll_interval": 0.2},
                                  name="console-http", daemon=True)
        thread.start()
        return thread

    def close(self) -> None:
        self.feed.stop()
        self.shutdown()
        self.server_close()


def _json_bytes(value: Any) -> bytes:
    return json.dumps(value, separators=(",", ":")).encode()


class ConsoleHandler(BaseHTTPRequestHandler):
    server: ConsoleServer
    protocol_version = "HTTP/1.1"
    server_version = "keel-console"

    def log_message(self, format: str, *args: Any) -> None:
        pass  # the console prints its URL and nothing per request

    def do_HEAD(self) -> None:
        self.do_GET()

    def do_GET(self) -> None:
        # Only pages asked for as 127.0.0.1 or localhost: a web page elsewhere cannot reach
        # the console through a name it points at this address (DNS rebinding).
        host = (self.headers.get("Host") or "").rsplit(":", 1)[0]
        if host not in ("127.0.0.1", "localhost"):
            self._send(HTTPStatus.FORBIDDEN, b"the console answers to 127.0.0.1 only\n", "text/plain")
            return
        parts = urlsplit(self.path)
        query = parse_qs(parts.query)
        feed = self.server.feed
        try:
            if parts.path in STATIC_FILES:
                name, content_type = STATIC_FILES[parts.path]
                self._send(HTTPStatus.OK, (self.server.static_dir / name).read_bytes(), content_type)
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
            else:
                self._send(HTTPStatus.NOT_FOUND, b"no such page\n", "text/plain")
        except (BrokenPipeError, ConnectionResetError):
            pass  # the browser went away

    def _since(self, query: dict[str, list[str]]) -> int:
        text = (query.get("since") or [self.headers.get("Last-Event-ID") or "0"])[0]
        try:
            return max(0, int(text))
        except ValueError:
            return 0

    def _send(self, status: HTTPStatus, body: bytes, content_type: str) -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        if self.command != "HEAD":
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
            with server.streams_lock:
                server.streams -= 1

    def _pump(self, since: int) -> None:
        feed = self.server.feed
        mission_sent = False
        shown: tuple[Any, ...] = ()
        while True:
            with feed.lock:
                def fresh(since: int = since, mission_sent: bool = mission_sent,
                          shown: tuple[Any, ...] = shown) -> bool:
                    return (feed.closing or len(feed.fold.events) > since
                            or (feed.mission is not None and not mission_sent)
                            or feed.signature() != shown)

                if not feed.lock.wait_for(fresh, timeout=KEEPALIVE_S):
                    body = b": keepalive\n\n"
                elif feed.closing:
                    return
                else:
                    events = feed.events_since(since)
                    message: dict[str, Any] = {"events": events, "status": feed.status()}
                    if feed.mission is not None and not mission_sent:
                        message["mission"] = feed.mission
                        mission_sent = True
                    shown = feed.signature()
                    since += len(events)
                    data = json.dumps(message, separators=(",", ":"))
                    body = f"id: {since}\ndata: {data}\n\n".encode()
            self.wfile.write(body)
            self.wfile.flush()


def serve(run_dir: Path, port: int = 0, mission_path: Path | None = None) -> ConsoleServer:
    """A started console of `run_dir` (the feed's and the server's threads running).
    Raises OSError when the port cannot be bound."""
    server = ConsoleServer(Feed(run_dir, mission_path), port)
    server.start()
    return server


def main_console(args: Any) -> int:
    """`keel-cluster console RUN_DIR`: serves until Ctrl-C. Exit codes: 0 stopped by
    Ctrl-C (or SIGTERM); 2 bad input (no such run directory, a mission that cannot be
    read); 3 the server could not start (the port is taken)."""
    import signal
    import sys

    run_dir = Path(args.run_dir)
    if not run_dir.is_dir():
        print(f"keel-cluster console: {run_dir}: no such run directory", file=sys.stderr)
        return 2
    mission_path = Path(args.mission) if args.mission else None
    if mission_path is not None:
        try:
            read_mission(mission_path)
        except ConsoleError as error:
            print(f"keel-cluster console: {error}", file=sys.stderr)
            return 2
    try:
        server = serve(run_dir, args.port, mission_path)
    except OSError as error:
        print(f"keel-cluster console: cannot listen on 127.0.0.1:{args.port}: {error.strerror}",
              file=sys.stderr)
        return 3
    print(f"keel-cluster: console of {run_dir} at {server.url} (Ctrl-C ends it)", file=sys.stderr, flush=True)
    stop = threading.Event()
    previous = signal.signal(signal.SIGTERM, lambda *_: stop.set())
    try:
        while not stop.wait(0.5):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGTERM, previous)
        server.close()
    return 0
