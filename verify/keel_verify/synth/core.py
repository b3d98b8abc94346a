"""Decision-graph synthesis: from a mission's nodes, tasks, tolerance and phases, a
complete decision graph whose every reachable configuration is valid.

One configuration per phase and per set F of at most ``tolerance.node_failures`` failed
tolerated nodes, placed by Z3 (``placement.py``) with the fewest task moves from the
configurations a single failure leads here from. Edges: from every configuration with
|F| below the tolerance, one per tolerated alive node to the configuration of F plus that
node (also for nodes that matter to nothing, so the failure set and the configuration
never drift apart); at the tolerance, SAFE for every node that matters. Planned phase
changes declared in the input map the configuration of F in one phase to that of F in
the other. Masters and observers follow one election order in every phase.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from keel_verify.mission import DEFAULT_STARTUP_GRACE_MS, SAFE, Mission
from keel_verify.synth.placement import Infeasible, election_order, place, roles

MAX_NAME = 63


@dataclass
class SynthResult:
    data: dict[str, Any]
    configurations: int = 0
    moves: list[int] = field(default_factory=list)  # tasks moved per failure edge
    seconds: float = 0.0


class SynthError(Exception):
    """The mission cannot tolerate what it declares: no valid configuration exists."""


def mission_to_data(mission: Mission) -> dict[str, Any]:
    """The mission's nodes, tasks and header in schema shape, defaults left out."""
    nodes: dict[str, Any] = {}
    for n in mission.nodes.values():
        raw: dict[str, Any] = {"kind": n.kind}
        if n.role is not None:
            raw["role"] = n.role
        if n.capabilities:
            raw["capabilities"] = list(n.capabilities)
        capacity = {k: v for k, v in (("cpu", n.capacity.cpu), ("mem_mb", n.capacity.mem_mb))
                    if v is not None}
        if capacity:
            raw["capacity"] = capacity
        nodes[n.name] = raw
    tasks: dict[str, Any] = {}
    for t in mission.tasks.values():
        raw = {"port": t.port}
        if t.component != t.name:
            raw["component"] = t.component
        if t.requires:
            raw["requires"] = list(t.requires)
        raw["load"] = {"cpu": t.load.cpu or 0, "mem_mb": t.load.mem_mb or 0}
        if t.inputs:
            raw["inputs"] = list(t.inputs)
        if t.essential:
            raw["essential"] = True
        if t.checkpoint:
            raw["checkpoint"] = True
        if t.period_ms is not None:
            raw["period_ms"] = t.period_ms
        if t.health is not None:
            raw["health"] = {k: v for k, v in (("min", t.health.min), ("max", t.health.max),
                                               ("deadline_ms", t.health.deadline_ms))
                             if v is not None}
        if t.params:
            raw["params"] = dict(t.params)
        if t.max_sample_bytes is not None:
            raw["max_sample_bytes"] = t.max_sample_bytes
        if t.max_state_bytes is not None:
            raw["max_state_bytes"] = t.max_state_bytes
        if t.priority is not None:
            raw["priority"] = t.priority
        if t.group is not None:
            raw["group"] = t.group
        tasks[t.name] = raw
    heartbeat: dict[str, Any] = {"period_ms": mission.heartbeat.period_ms,
                                 "miss_limit": mission.heartbeat.miss_limit}
    if mission.heartbeat.startup_grace_ms != DEFAULT_STARTUP_GRACE_MS:
        heartbeat["startup_grace_ms"] = mission.heartbeat.startup_grace_ms
    if mission.heartbeat.tie_grace:
        heartbeat["tie_grace"] = mission.heartbeat.tie_grace
    return {
        "mission": mission.name,
        "schema": 1,
        "heartbeat": heartbeat,
        "tolerance": {"node_failures": mission.tolerance.node_failures,
                      "nodes": list(mission.tolerance.nodes)},
        "nodes": nodes,
        "tasks": tasks,
        "phases": {},
    }


def synthesize(mission: Mission, progress: Callable[[str], None] | None = None) -> SynthResult:
    start = time.perf_counter()
    report = progress or (lambda _m: None)
    tolerance = list(dict.fromkeys(mission.tolerance.nodes))
    k = min(mission.tolerance.node_failures, len(tolerance))
    first_phase = next(iter(mission.phases.values()))
    first = first_phase.configurations[first_phase.initial]
    order = election_order(mission, (first.master, *first.observers))
    if not order:
        raise SynthError("no processing node can host every essential task in safe mode")
    result = SynthResult(mission_to_data(mission))
    sets = [frozenset(c) for size in range(k + 1) for c in itertools.combinations(tolerance, size)]
    names: dict[tuple[str, frozenset[str]], str] = {}
    for phase in mission.phases.values():
        base = phase.initial
        for index, failed in enumerate(sets):
            suffix = "_".join(n for n in tolerance if n in failed)
            name = f"{base}_{suffix}" if suffix else base
            names[(phase.name, failed)] = name if len(name) <= MAX_NAME else f"{base}x{index}"
    for phase in mission.phases.values():
        initial = phase.configurations[phase.initial]
        configs: dict[str, Any] = {}
        placements: dict[frozenset[str], dict[str, str]] = {}
        masters: dict[frozenset[str], tuple[str, list[str]]] = {}
        on_failure: dict[str, Any] = {}
        for n_done, failed in enumerate(sets):
            parents = ([dict(initial.placement)] if not failed
                       else [placements[failed - {x}] for x in tolerance if x in failed])
            try:
                placement = place(mission, phase.name, failed, parents)
                master, observers = roles(mission, order, failed)
            except Infeasible as why:
                which = ", ".join(sorted(failed)) or "no node"
                raise SynthError(f"phase {phase.name}: no valid configuration when {which} "
                                 f"failed: {why}") from None
            placements[failed] = placement
            masters[failed] = (master, observers)
            for parent in parents if failed else []:
                result.moves.append(sum(1 for t, n in placement.items() if parent.get(t) != n))
            configs[names[(phase.name, failed)]] = {"master": master, "observers": observers,
                                                    "tasks": placement}
            if (n_done + 1) % 200 == 0:
                report(f"phase {phase.name}: {n_done + 1}/{len(sets)} configurations")
        for failed in sets:
            name = names[(phase.name, failed)]
            edges: dict[str, str] = {}
            cfg = configs[name]
            matters = {cfg["master"], *cfg["observers"], *cfg["tasks"].values()}
            if any(mission.tasks[t].checkpoint for t in cfg["tasks"]):
                matters |= set(mission.storage_nodes)
            for x in tolerance:
                if x in failed:
                    continue
                if len(failed) < k:
                    edges[x] = names[(phase.name, failed | {x})]
                elif x in matters:
                    edges[x] = SAFE
            if edges:
                on_failure[name] = edges
        out_phase: dict[str, Any] = {"tasks": list(phase.tasks), "initial": phase.initial,
                                     "configurations": configs, "on_failure": on_failure}
        on_phase = {
            target: {names[(phase.name, f)]: names[(target, f)] for f in sets}
            for target in phase.on_phase
        }
        if on_phase:
            out_phase["on_phase"] = on_phase
        if phase.params:
            out_phase["params"] = {t: dict(v) for t, v in phase.params.items()}
        result.data["phases"][phase.name] = out_phase
        result.configurations += len(configs)
    keep_names(mission, result.data["phases"], {
        phase: {failed: name for (p, failed), name in names.items() if p == phase}
        for phase in mission.phases})
    result.seconds = time.perf_counter() - start
    return result


def reached(mission: Mission, phase_name: str) -> dict[frozenset[str], str]:
    """The configuration the mission's own graph reaches for each failed set, walking its
    failure edges from the phase's initial configuration; a set two orders of failures
    take to different configurations is left out (it names no one configuration)."""
    phase = mission.phases[phase_name]
    found: dict[frozenset[str], str] = {frozenset(): phase.initial}
    ambiguous: set[frozenset[str]] = set()
    frontier = [(frozenset(), phase.initial)]
    while frontier:
        failed, config = frontier.pop()
        for node, target in phase.on_failure.get(config, {}).items():
            if target == SAFE or node in failed or target not in phase.configurations:
                continue
            after = failed | {node}
            if after in found:
                if found[after] != target:
                    ambiguous.add(after)
                continue
            found[after] = target
            frontier.append((after, target))
    return {failed: name for failed, name in found.items() if failed not in ambiguous}


def keep_names(mission: Mission, phases: dict[str, Any],
               by_failed: dict[str, dict[frozenset[str], str]]) -> None:
    """The user's names survive where the graph keeps their meaning. A synthesised
    configuration that is one the mission has (the same master, observers and placement)
    takes that configuration's name; then one that holds the place of a configuration of
    the mission's graph (the one its edges reach for the same failed set, `by_failed`
    giving the synthesised one's) takes that name. Only one to one: a name the synthesis
    uses already, or an existing configuration two synthesised ones equal, is left alone."""
    renames: dict[str, dict[str, str]] = {}
    for phase_name, phase in phases.items():
        existing = mission.phases[phase_name].configurations
        configs = phase["configurations"]

        def body(master: str, observers: Any, tasks: dict[str, str]) -> tuple[Any, ...]:
            return (master, tuple(observers), tuple(sorted(tasks.items())))

        mine = {n: body(c["master"], c["observers"], c["tasks"]) for n, c in configs.items()}
        theirs = {n: body(c.master, c.observers, c.placement) for n, c in existing.items()}
        rename: dict[str, str] = {}
        for name, key in mine.items():
            matches = [n for n, k in theirs.items() if k == key]
            if (len(matches) == 1 and matches[0] != name and matches[0] not in configs
                    and list(mine.values()).count(key) == 1):
                rename[name] = matches[0]
        # By place: the name the mission's graph gives the same failed set.
        taken = (set(configs) - set(rename)) | set(rename.values())
        for failed, theirs_name in reached(mission, phase_name).items():
            name = by_failed[phase_name].get(failed)
            if (name is None or name in rename or name == theirs_name
                    or theirs_name in taken):
                continue
            rename[name] = theirs_name
            taken.add(theirs_name)
        renames[phase_name] = rename
    for phase_name, phase in phases.items():
        rename = renames[phase_name]
        if not rename:
            continue
        phase["configurations"] = {rename.get(n, n): c for n, c in phase["configurations"].items()}
        phase["on_failure"] = {rename.get(n, n): {x: rename.get(t, t) for x, t in edges.items()}
                               for n, edges in phase["on_failure"].items()}
        phase["initial"] = rename.get(phase["initial"], phase["initial"])
    for phase_name, phase in phases.items():
        for target, mapping in phase.get("on_phase", {}).items():
            ours, theirs = renames[phase_name], renames[target]
            phase["on_phase"][target] = {ours.get(n, n): theirs.get(t, t)
                                         for n, t in mapping.items()}
