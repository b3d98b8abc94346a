"""What the benchmark and the reliability campaign share: the mission summary, derived
mission files (another heartbeat period), waiting on status lines, executables of the
build, and the machine's load."""

from __future__ import annotations

import fcntl
import os
import re
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from keel_cluster.launcher import Cluster, LaunchError

ROOT = Path(os.environ.get("KEEL_ROOT", Path(__file__).resolve().parents[3]))


@dataclass
class MissionSummary:
    name: str
    nodes: list[str]
    processing: list[str]
    storage: list[str]
    phases: list[str]  # file order; the first is the initial phase
    initial_config: str
    phase_cycle: list[str]  # the initial phase and the first phase it can switch to
    period_ms: int
    miss_limit: int
    graph: Graph | None = None


SAFE = "SAFE"
# An online configuration (docs/missions.md, "Placement modes"): the configuration the
# Master's placer computed, as a node's status names it. Prescribed beyond the graph of a
# phase placed graph+online or online.
ONLINE = "online"


@dataclass
class Graph:
    """The mission's reconfiguration graph, as keel-node's core applies it
    (core/fsm/topology.cpp, Topology::walk), to say what configuration the graph
    prescribes after the failures and phase commands a campaign injected."""

    matters: dict[str, set[str]]  # configuration -> nodes whose failure needs an edge
    uses: dict[str, set[str]]  # configuration -> its master and task hosts
    hosts: dict[str, set[str]]  # configuration -> its task hosts
    on_failure: dict[str, dict[str, str]]  # configuration -> failed node -> next (or SAFE)
    on_phase: dict[str, dict[str, str]]  # configuration -> phase -> configuration
    initial_of: dict[str, str]  # configuration -> its phase's initial configuration
    order: list[str]  # the nodes in file order (their ids)
    # configuration -> readmitted node -> next configuration (the mission's on_recovery)
    on_recovery: dict[str, dict[str, str]] = field(default_factory=dict)
    # configuration -> its phase's placement (graph, online, graph+online)
    placement: dict[str, str] = field(default_factory=dict)
    # phase -> its initial configuration
    phase_initial: dict[str, str] = field(default_factory=dict)
    # configuration -> its master
    master: dict[str, str] = field(default_factory=dict)

    def online_beyond(self, config: str) -> bool:
        """Whether the placer answers where the graph of `config`'s phase ends."""
        return self.placement.get(config, "graph") != "graph"

    def _walk(self, config: str, failed: set[str]) -> str:
        pending = [n for n in self.order if n in failed]
        for _ in range(len(pending) + 1):
            hit = next((n for n in pending if n in self.matters.get(config, set())), None)
            if hit is None:
                break
            pending.remove(hit)
            config = self.on_failure.get(config, {}).get(hit, SAFE)
            if config == SAFE:
                return SAFE
        return SAFE if self.uses.get(config, set()) & failed else config

    def after_recovery(self, base: str, failed: set[str], current: str = SAFE,
                       node: str = "") -> str:
        """The configuration the cluster moves to when `node` is readmitted in `current`
        and only `failed` remain failed (Topology::recovery_target): the mission's
        on_recovery edge from `current` when it has one, else the walk from the phase's
        initial configuration through `failed` in id order, from `base`, the last
        configuration before safe mode (it fixes the phase)."""
        edge = self.on_recovery.get(current, {}).get(node)
        if edge is not None:
            return edge
        config = self._walk(self.initial_of[base], failed)
        if self.online_beyond(base):
            # core/fsm/online.hpp: an online phase is placed; a graph+online one returns to
            # the graph where it is not SAFE (and its master is the Master's or the node's,
            # which the campaign does not follow: the graph's), else the placer.
            if self.placement.get(base) == "online" or config == SAFE:
                return ONLINE
        return config

    def after_failure(self, config: str, node: str, failed: set[str]) -> str:
        """The configuration after `node` fails in `config`, `failed` being every node
        failed so far (including `node`). A failure that matters and has no edge, or a
        configuration reached whose master or a task host has failed, is safe mode."""
        if config in (SAFE, ONLINE):
            # Once online, the placer answers every failure (SAFE only where the essential
            # tasks fit nowhere, which the campaign does not foresee).
            return config
        if node not in self.matters.get(config, set()):
            return config
        nxt = self.on_failure.get(config, {}).get(node, SAFE)
        if nxt == SAFE or self.uses.get(nxt, set()) & failed:
            return ONLINE if self.online_beyond(config) else SAFE
        return nxt

    def after_phase(self, config: str, phase: str, failed: set[str]) -> str | None:
        """The configuration a phase command leads to, or None when it is refused: safe
        mode is terminal, and an edge into a configuration that uses a failed node is
        refused (ReconfigurationManager::on_phase)."""
        if config == SAFE:
            return None
        initial = self.phase_initial.get(phase)
        if config == ONLINE:
            # From an online configuration: the target phase's configuration of the failed
            # set where it is not SAFE and the phase is not online; else its placer.
            target = self._walk(initial, failed) if initial else SAFE
            if target != SAFE and self.placement.get(target) != "online":
                return target
            return ONLINE if initial and self.online_beyond(initial) else None
        nxt = self.on_phase.get(config, {}).get(phase)
        if nxt is None or self.hosts.get(nxt, set()) & failed:
            return ONLINE if initial and self.online_beyond(initial) else None
        return nxt


def _graph(raw: dict[str, Any], storage: list[str]) -> Graph:
    matters: dict[str, set[str]] = {}
    uses: dict[str, set[str]] = {}
    hosts_of: dict[str, set[str]] = {}
    on_failure: dict[str, dict[str, str]] = {}
    on_phase: dict[str, dict[str, str]] = {}
    on_recovery: dict[str, dict[str, str]] = {}
    initial_of: dict[str, str] = {}
    placement: dict[str, str] = {}
    phase_initial: dict[str, str] = {}
    masters: dict[str, str] = {}
    for phase_name, phase in raw["phases"].items():
        phase_initial[str(phase_name)] = str(phase["initial"])
        for name, config in (phase.get("configurations") or {}).items():
            initial_of[str(name)] = str(phase["initial"])
            placement[str(name)] = str(phase.get("placement") or "graph")
            masters[str(name)] = str(config["master"])
            hosts = {str(n) for n in (config.get("tasks") or {}).values()}
            hosts_of[str(name)] = hosts
            uses[str(name)] = {str(config["master"])} | hosts
            # The Storage node matters where a checkpointed task is placed (Topology::build).
            keeps = any((raw["tasks"].get(t) or {}).get("checkpoint") for t in (config.get("tasks") or {}))
            matters[str(name)] = (uses[str(name)] | {str(n) for n in config.get("observers") or []}
                                  | (set(storage) if keeps else set()))
        for name, edges in (phase.get("on_failure") or {}).items():
            on_failure[str(name)] = {str(n): str(t) for n, t in (edges or {}).items()}
        for name, edges in (phase.get("on_recovery") or {}).items():
            on_recovery[str(name)] = {str(n): str(t) for n, t in (edges or {}).items()}
        for target, edges in (phase.get("on_phase") or {}).items():
            for name, nxt in (edges or {}).items():
                on_phase.setdefault(str(name), {})[str(target)] = str(nxt)
    return Graph(matters, uses, hosts_of, on_failure, on_phase, initial_of,
                 [str(n) for n in raw["nodes"]], on_recovery, placement, phase_initial, masters)


def image_as_mission(content: dict[str, Any]) -> dict[str, Any]:
    """A mission image's `content` (config/schema/README.md, "The mission image") in the
    shape of the YAML mission: nodes, tasks and phases by name, placements and edges as
    maps."""
    phases: dict[str, Any] = {}
    for phase in content["phases"]:
        on_failure: dict[str, dict[str, str]] = {}
        for edge in phase.get("on_failure") or []:
            on_failure.setdefault(str(edge["config"]), {})[str(edge["node"])] = str(edge["next"])
        on_phase: dict[str, dict[str, str]] = {}
        for edge in phase.get("on_phase") or []:
            on_phase.setdefault(str(edge["phase"]), {})[str(edge["from"])] = str(edge["to"])
        on_recovery: dict[str, dict[str, str]] = {}
        for edge in phase.get("on_recovery") or []:
            on_recovery.setdefault(str(edge["config"]), {})[str(edge["node"])] = str(edge["next"])
        phases[str(phase["name"])] = {
            "initial": phase["initial"],
            "tasks": list(phase.get("tasks") or []),
            "configurations": {
                str(c["name"]): {"master": c["master"], "observers": list(c["observers"]),
                                 "tasks": {str(t): str(n) for t, n in c["tasks"]}}
                for c in phase["configurations"]},
            "on_failure": on_failure,
            "on_recovery": on_recovery,
            "on_phase": on_phase,
            "placement": str(phase.get("placement") or "graph"),
        }
    return {
        "mission": content["mission"],
        "heartbeat": content["heartbeat"],
        "tolerance": content.get("tolerance"),
        "nodes": {str(n["name"]): {k: v for k, v in n.items() if k not in ("name", "id")}
                  for n in content["nodes"]},
        "tasks": {str(t["name"]): {k: v for k, v in t.items() if k not in ("name", "id")}
                  for t in content["tasks"]},
        "phases": phases,
    }


def read_mission(path: Path) -> dict[str, Any]:
    """The mission as a plain dictionary in the YAML's shape, from a YAML file or from a
    mission image (checked: its hash must match; keel-node checks it again)."""
    from keel_cluster.launcher import is_image

    if is_image(path):
        from keel_verify.image import ImageError, load_image

        try:
            return image_as_mission(load_image(path)["content"])
        except ImageError as error:
            raise LaunchError(str(error)) from None
    return yaml.safe_load(path.read_text(encoding="utf-8"))


def summarize(path: Path) -> MissionSummary:
    """The few facts the benchmark needs, read with PyYAML (or from a mission image). The
    mission is validated by keel-node itself when the cluster starts (exit 2 with
    file:line:col)."""
    try:
        raw = read_mission(path)
        nodes: dict[str, Any] = raw["nodes"]
        phases: dict[str, Any] = raw["phases"]
        heartbeat: dict[str, Any] = raw["heartbeat"]
        names = list(phases)
        first = phases[names[0]]
        cycle = [names[0]]
        targets = [p for p in (first.get("on_phase") or {}) if p != names[0]]
        if targets:
            cycle.append(targets[0])
        storage = [str(n) for n, node in nodes.items() if node.get("role") == "storage"]
        return MissionSummary(
            name=str(raw["mission"]),
            nodes=[str(n) for n in nodes],
            processing=[str(n) for n, node in nodes.items() if node.get("kind") == "processing"],
            storage=storage,
            phases=names,
            initial_config=str(first["initial"]),
            phase_cycle=cycle,
            period_ms=int(heartbeat["period_ms"]),
            miss_limit=int(heartbeat["miss_limit"]),
            graph=_graph(raw, storage),
        )
    except (OSError, yaml.YAMLError, KeyError, TypeError, ValueError, AttributeError, IndexError) as error:
        raise LaunchError(f"{path}: not a mission the benchmark can read ({error!r})") from None


_FLOW = re.compile(r"^(heartbeat:\s*\{.*?period_ms:\s*)(\d+)")
_BLOCK = re.compile(r"^(\s+period_ms:\s*)(\d+)")


def with_heartbeat_period(source: Path, period_ms: int, destination: Path) -> Path:
    """A copy of the mission with heartbeat.period_ms replaced (miss_limit kept), checked
    by loading it back."""
    lines = source.read_text(encoding="utf-8").splitlines(keepends=True)
    done = False
    for index, line in enumerate(lines):
        if not line.startswith("heartbeat:"):
            continue
        if _FLOW.match(line):
            lines[index] = _FLOW.sub(lambda m: f"{m.group(1)}{period_ms}", line, count=1)
            done = True
        else:
            for follow in range(index + 1, min(index + 4, len(lines))):
                if _BLOCK.match(lines[follow]):
                    lines[follow] = _BLOCK.sub(lambda m: f"{m.group(1)}{period_ms}", lines[follow], count=1)
                    done = True
                    break
        break
    if not done:
        raise LaunchError(f"{source}: no heartbeat.period_ms to replace")
    destination.parent.mkdir(parents=True, exist_ok=True)
    destination.write_text("".join(lines), encoding="utf-8")
    if summarize(destination).period_ms != period_ms:
        raise LaunchError(f"{destination}: heartbeat period not replaced")
    return destination


def wait_for(predicate: Callable[[], Any], timeout_s: float, poll_s: float = 0.01) -> Any:
    """The predicate's first truthy value, or None after timeout_s."""
    deadline = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() >= deadline:
            return None
        time.sleep(poll_s)


def master_status(cluster: Cluster) -> tuple[str, dict[str, Any]] | None:
    """The acting Master: of the running, unpaused nodes that say Master, the one of the
    highest epoch (a stopped Master's last status is stale)."""
    masters = [(int(status.get("epoch", 0) or 0), name, status)
               for name, status in cluster.statuses().items()
               if status.get("role") == "Master" and cluster.nodes[name].running
               and name not in cluster.paused]
    if not masters:
        return None
    _, name, status = max(masters, key=lambda m: (m[0], m[1]))
    return name, status


def settled(cluster: Cluster, config: str | None = None) -> dict[str, Any] | None:
    """The master's status once every task it expects runs on exactly one alive node (and,
    if given, its configuration is `config`)."""
    found = master_status(cluster)
    if found is None:
        return None
    _, status = found
    if config is not None and status.get("config") != config:
        return None
    if status.get("driving") is False:  # a Master handed the view, or mid-switch
        return None
    expected = set(status.get("expected_tasks", []))
    running: dict[str, int] = {}
    for name, other in cluster.statuses().items():
        if not cluster.nodes[name].running or name in cluster.paused:
            continue
        for task in other.get("tasks", []):
            running[task] = running.get(task, 0) + 1
    if any(running.get(task) != 1 for task in expected):
        return None
    return status


def find_executable(name: str, relative: list[str]) -> Path | None:
    build = Path(os.environ.get("KEEL_BUILD_DIR", ROOT / "build" / "default"))
    for candidate in [build / r for r in relative]:
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return candidate
    for candidate in sorted(build.rglob(name)) if build.is_dir() else []:
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return candidate
    on_path = shutil.which(name)
    return Path(on_path) if on_path else None


def load_average() -> list[float]:
    return [round(x, 2) for x in os.getloadavg()]


# 230: the highest domain the credentials' governance and permissions cover
# (keel_cluster.security.DOMAIN_MAX; Cyclone's port mapping would allow 232).
DOMAIN_FIRST, DOMAIN_LAST = 201, 230
LOCK_FOLDER = Path(tempfile.gettempdir()) / "keel-cluster-domains"


class DomainLease:
    """A DDS domain id held for as long as one cluster runs, so that two clusters never
    share a domain: not two from one benchmark, nor from a benchmark and a campaign run at
    the same time (their nodes have the same names and addresses and would take each
    other's messages). Ids 201..230 (the highest the DDS Security governance covers), apart
    from the 1..200 the node tests and the launcher's default use; each is held with an
    exclusive lock on a file, released when the process ends or release() is called."""

    def __init__(self, seed: int, timeout_s: float = 120.0):
        LOCK_FOLDER.mkdir(parents=True, exist_ok=True)
        ids = list(range(DOMAIN_FIRST, DOMAIN_LAST + 1))
        start = (os.getpid() + seed) % len(ids)
        ids = ids[start:] + ids[:start]
        deadline = time.monotonic() + timeout_s
        self.handle: Any = None
        self.domain_id = 0
        while self.handle is None:
            for candidate in ids:
                handle = open(LOCK_FOLDER / f"{candidate}.lock", "w")  # noqa: SIM115 - held until release()
                try:
                    fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except OSError:
                    handle.close()
                    continue
                self.handle, self.domain_id = handle, candidate
                break
            if self.handle is None:
                if time.monotonic() > deadline:
                    raise LaunchError(f"no free DDS domain in {DOMAIN_FIRST}..{DOMAIN_LAST} for {timeout_s:g} s")
                time.sleep(0.5)

    def release(self) -> None:
        if self.handle is not None:
            fcntl.flock(self.handle, fcntl.LOCK_UN)
            self.handle.close()
            self.handle = None


class TraceFollower:
    """Counts one trace action across a run directory's trace files as they grow, reading
    only what was appended since the last call (a trace grows to megabytes in a long run)."""

    def __init__(self, run_dir: Path, action: str):
        self.run_dir = run_dir
        self.needle = f'"action":"{action}"'
        self.offsets: dict[Path, int] = {}
        self.count = 0

    def poll(self) -> int:
        for path in sorted(self.run_dir.glob("*.trace.ndjson")):
            start = self.offsets.get(path, 0)
            with open(path, "rb") as handle:
                handle.seek(start)
                chunk = handle.read()
            # Only whole lines: a line being written is read on the next call.
            end = chunk.rfind(b"\n") + 1
            self.count += chunk[:end].decode("utf-8", errors="replace").count(self.needle)
            self.offsets[path] = start + end
        return self.count


def leased_cluster(mission: Path, nodes: list[str], run_dir: Path, node_binary: Path, *, use_netns: bool,
                   seed: int, insecure: bool = False, security_profile: str = "encrypt",
                   security_dir: Path | None = None, node_args: list[str] | None = None) -> Cluster:
    """A quiet Cluster on a DDS domain no other cluster of this machine's benchmarks uses;
    secured unless `insecure`, with the credentials in security_dir (shared by the runs of
    one benchmark or campaign: made once, reused while valid); `node_args` go to every
    keel-node."""
    lease = DomainLease(seed)
    cluster = Cluster(mission, nodes, run_dir, node_binary, use_netns=use_netns, domain_id=lease.domain_id,
                      echo=False, insecure=insecure, security_profile=security_profile,
                      security_dir=security_dir, extra_args=node_args)
    cluster.lease = lease
    return cluster
