"""An explicit-state checker of the mission contract: the oracle the Z3 prover is tested
against, written from docs/missions.md without sharing code with ``keel_verify.check``.

Plain breadth-first search over states (phase, configuration, F), F a frozenset of failed
nodes, one failure at a time, over every on_phase move. It returns the set of violation
keys (kind, phase, config, task, node, target) exactly as the prover names them, plus
the shortest failure sequence of each. Exponential in the number of tolerated nodes that
matter to nothing; fine for tests and for the benchmark's comparison.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

from keel_verify.mission import SAFE, Mission

Key = tuple[str, str, str, str, str, str]


@dataclass
class ExplicitResult:
    violations: dict[Key, list[str]] = field(default_factory=dict)  # key -> failures
    states: int = 0

    @property
    def kinds(self) -> set[str]:
        return {k[0] for k in self.violations}

    @property
    def valid(self) -> bool:
        return not self.violations


def _config_index(mission: Mission) -> dict[str, tuple[str, object]]:
    return {name: (phase.name, cfg) for phase in mission.phases.values()
            for name, cfg in phase.configurations.items()}


def invalidities(mission: Mission, config_name: str, failed: frozenset[str]
                 ) -> list[tuple[str, str, str, str]]:
    """(kind, task, node, why) for every validity rule ``config_name`` breaks under F."""
    phase_name, cfg = _config_index(mission)[config_name]
    phase = mission.phases[phase_name]
    out: list[tuple[str, str, str, str]] = []
    placement: dict[str, str] = cfg.placement  # type: ignore[attr-defined]
    master: str = cfg.master  # type: ignore[attr-defined]
    observers: tuple[str, ...] = cfg.observers  # type: ignore[attr-defined]
    for task in phase.tasks:
        if task not in placement:
            out.append(("task-missing", task, "", "not placed"))
    cpu: dict[str, int] = {}
    mem: dict[str, int] = {}
    for task, node in placement.items():
        if task not in phase.tasks:
            out.append(("task-missing", task, node, "not a task of the phase"))
        spec = mission.tasks[task]
        if not set(spec.requires) <= set(mission.nodes[node].capabilities):
            out.append(("capability", task, node, "capability"))
        if node in failed:
            out.append(("task-on-failed-node", task, node, "failed"))
        cpu[node] = cpu.get(node, 0) + (spec.load.cpu or 0)
        mem[node] = mem.get(node, 0) + (spec.load.mem_mb or 0)
    for node, used_cpu in cpu.items():
        cap = mission.nodes[node].capacity
        if (cap.cpu is not None and used_cpu > cap.cpu) or (
            cap.mem_mb is not None and mem[node] > cap.mem_mb
        ):
            out.append(("capacity", "", node, "capacity"))
    if not mission.nodes[master].is_processing or master in failed:
        out.append(("master-invalid", "", master, "master"))
    for i, obs in enumerate(observers):
        if (obs == master or obs in observers[:i] or not mission.nodes[obs].is_processing
                or obs in failed):
            out.append(("observer-invalid", "", obs, "observer"))
    alive_processing = [n for n, node in mission.nodes.items()
                        if node.is_processing and n not in failed]
    all_processing = [n for n, node in mission.nodes.items() if node.is_processing]
    if not observers and len(all_processing) >= 2 and len(alive_processing) >= 2:
        out.append(("observer-invalid", "", "", "no observer"))
    if any(mission.tasks[t].checkpoint for t in placement):
        storage = [n for n, node in mission.nodes.items() if node.is_storage]
        if not any(s not in failed for s in storage):
            out.append(("storage-unavailable", "", "", "storage"))
    return out


def explore(mission: Mission, max_failures: int | None = None) -> ExplicitResult:
    index = _config_index(mission)
    tolerance = list(dict.fromkeys(mission.tolerance.nodes))
    depth = len(tolerance) if max_failures is None else min(len(tolerance), max_failures)
    k = mission.tolerance.node_failures
    result = ExplicitResult()

    def report(key: Key, failures: list[str]) -> None:
        if key[0] == "safe-mode-unhostable":
            key = (key[0], "", "", key[3], key[4], "")
        known = result.violations.get(key)
        if known is None or len(failures) < len(known):
            result.violations[key] = failures

    start = [(p.name, p.initial, frozenset(), ()) for p in mission.phases.values()]
    seen: dict[tuple[str, frozenset[str]], tuple[str, tuple[str, ...]]] = {}
    queue: deque[tuple[str, str, frozenset[str], tuple[str, ...]]] = deque(start)
    while queue:
        phase_name, config, failed, sequence = queue.popleft()
        if (config, failed) in seen:
            continue
        seen[(config, failed)] = (phase_name, sequence)
        result.states += 1
        cfg = index[config][1]
        phase = mission.phases[phase_name]
        for kind, task, node, _ in invalidities(mission, config, failed):
            report((kind, phase_name, config, task, node, ""), list(sequence))
        # Safe mode must be hostable by every node that can become master.
        for role_node in (cfg.master, *cfg.observers):  # type: ignore[attr-defined]
            n = mission.nodes[role_node]
            if not n.is_processing:
                continue
            for task in mission.tasks.values():
                if task.essential and not set(task.requires) <= set(n.capabilities):
                    report(("safe-mode-unhostable", phase_name, config, task.name, role_node, ""),
                           list(sequence))
        # Failures.
        if len(failed) < depth:
            placement = cfg.placement  # type: ignore[attr-defined]
            matters = set(placement.values()) | {cfg.master} | set(cfg.observers)  # type: ignore[attr-defined]
            if any(mission.tasks[t].checkpoint for t in placement):
                matters |= {n for n, node in mission.nodes.items() if node.is_storage}
            edges = phase.on_failure.get(config, {})
            for x in tolerance:
                if x in failed:
                    continue
                after = failed | {x}
                seq = (*sequence, x)
                if x in edges:
                    nxt = edges[x]
                elif x in matters:
                    report(("missing-transition", phase_name, config, "", x, ""), list(seq))
                    continue
                else:
                    nxt = config
                if nxt == SAFE:
                    if len(after) <= k:
                        report(("safe-mode-within-tolerance", phase_name, config, "", x, ""),
                               list(seq))
                    continue
                if x == cfg.master:  # type: ignore[attr-defined]
                    elected = next((o for o in cfg.observers if o not in after), None)  # type: ignore[attr-defined]
                    if index[nxt][1].master != elected:  # type: ignore[attr-defined]
                        report(("master-mismatch", phase_name, config, "", x, ""), list(seq))
                elif (index[nxt][1].master not in after | {cfg.master}  # type: ignore[attr-defined]
                      and mission.nodes[index[nxt][1].master].is_processing):  # type: ignore[attr-defined]
                    # Another node's failure: the master drives the switch and stays (a
                    # target master that is failed or not processing is master-invalid).
                    report(("master-mismatch", phase_name, config, "", x, ""), list(seq))
                queue.append((phase_name, nxt, after, seq))
        # Planned phase changes.
        for target_phase, mapping in phase.on_phase.items():
            if config not in mapping:
                report(("phase-transition-invalid", phase_name, config, "", "", target_phase),
                       list(sequence))
                continue
            target = mapping[config]
            for _kind, task, node, _ in invalidities(mission, target, failed):
                report(("phase-transition-invalid", phase_name, config, task, node, target_phase),
                       list(sequence))
            queue.append((target_phase, target, failed, sequence))
    # Recovery edges: readmitting n in a reached (C, F) must lead to a reached state.
    for (config, failed), (phase_name, sequence) in seen.items():
        for node, target in mission.phases[phase_name].on_recovery.get(config, {}).items():
            if node in failed and (target, failed - {node}) not in seen:
                report(("recovery-unproven", phase_name, config, "", node, ""), list(sequence))
    return result
