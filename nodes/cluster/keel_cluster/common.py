"""What the benchmark and the reliability campaign share: the mission summary, derived
mission files (another heartbeat period), waiting on status lines, executables of the
build, and the machine's load."""

from __future__ import annotations

import os
import re
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass
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


def summarize(path: Path) -> MissionSummary:
    """The few facts the benchmark needs, read with PyYAML. The mission is validated by
    keel-node itself when the cluster starts (exit 2 with file:line:col)."""
    try:
        raw = yaml.safe_load(path.read_text(encoding="utf-8"))
        nodes: dict[str, Any] = raw["nodes"]
        phases: dict[str, Any] = raw["phases"]
        heartbeat: dict[str, Any] = raw["heartbeat"]
        names = list(phases)
        first = phases[names[0]]
        cycle = [names[0]]
        targets = [p for p in (first.get("on_phase") or {}) if p != names[0]]
        if targets:
            cycle.append(targets[0])
        return MissionSummary(
            name=str(raw["mission"]),
            nodes=[str(n) for n in nodes],
            processing=[str(n) for n, node in nodes.items() if node.get("kind") == "processing"],
            storage=[str(n) for n, node in nodes.items() if node.get("role") == "storage"],
            phases=names,
            initial_config=str(first["initial"]),
            phase_cycle=cycle,
            period_ms=int(heartbeat["period_ms"]),
            miss_limit=int(heartbeat["miss_limit"]),
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
    for name, status in cluster.statuses().items():
        if status.get("role") == "Master" and cluster.nodes[name].running:
            return name, status
    return None


def settled(cluster: Cluster, config: str | None = None) -> dict[str, Any] | None:
    """The master's status once every task it expects runs on exactly one alive node (and,
    if given, its configuration is `config`)."""
    found = master_status(cluster)
    if found is None:
        return None
    _, status = found
    if config is not None and status.get("config") != config:
        return None
    expected = set(status.get("expected_tasks", []))
    running: dict[str, int] = {}
    for name, other in cluster.statuses().items():
        if not cluster.nodes[name].running:
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


def domain_sequence(seed: int) -> Callable[[], int]:
    """A fresh DDS domain id per cluster, so a cluster never meets a previous one's late
    packets: 201..232 (the highest ids Cyclone's port mapping allows), apart from the
    1..200 the node tests and the launcher's default use."""
    state = {"next": (os.getpid() + seed) % 32}

    def take() -> int:
        value = 201 + state["next"]
        state["next"] = (state["next"] + 1) % 32
        return value

    return take
