"""The decision graph of a mission as the checker sees it: what every rule of
docs/missions.md ("What `keel-verify check` proves") means for one configuration, one
failure set and one edge.

The prover (``prover.py``) turns these facts into Z3 constraints; nothing here explores
states. Facts split in two: those that do not depend on the set F of failed nodes
(capabilities, capacity, kinds, the shape of a configuration) are computed once per
configuration, and those that do are stated as "violated iff these nodes are in F"
(or, for the observer count and storage, a count over F), so the prover only has to
decide which failure sets are reachable.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

from keel_verify.mission import SAFE, Configuration, Mission

# Every violation kind of docs/missions.md, in the order reports list them.
KINDS: tuple[str, ...] = (
    "schema",
    "unknown-reference",
    "port-conflict",
    "component-missing",
    "missing-transition",
    "task-on-failed-node",
    "capability",
    "capacity",
    "task-missing",
    "master-invalid",
    "observer-invalid",
    "master-mismatch",
    "storage-unavailable",
    "safe-mode-within-tolerance",
    "phase-transition-invalid",
    "safe-mode-unhostable",
    "recovery-unproven",
)

# The key that makes two violations the same: (kind, phase, config, task, node, target).
Key = tuple[str, str, str, str, str, str]


@dataclass(frozen=True)
class Finding:
    """One rule broken by one configuration (or edge), before any path is attached."""

    kind: str
    config: str
    task: str | None
    node: str | None
    message: str
    target: str = ""  # on_phase target phase, part of the key of phase-transition-invalid

    def key(self, phase: str) -> Key:
        if self.kind == "safe-mode-unhostable":  # a property of the node, not of a state
            return (self.kind, "", "", self.task or "", self.node or "", "")
        return (self.kind, phase, self.config, self.task or "", self.node or "", self.target)


@dataclass(frozen=True)
class FailureFact:
    """A finding at a configuration that holds exactly when every node of ``all_of`` has
    failed (``all_of`` empty: never through F; see ``StateFacts.count_rule``)."""

    finding: Finding
    all_of: tuple[str, ...]


@dataclass
class StateFacts:
    """What makes a configuration invalid, split by dependence on F."""

    static: list[Finding] = field(default_factory=list)
    on_failed: list[FailureFact] = field(default_factory=list)
    # task-on-failed-node, grouped: tolerated node -> the tasks it hosts (findings are
    # made only for nodes that may have failed, see ``hosted_findings``).
    hosted: dict[str, list[str]] = field(default_factory=dict)
    # observers empty: invalid when at most ``max_failed`` of ``processing`` have failed
    # (that is, when two or more processing nodes are alive).
    count_rule: tuple[Finding, tuple[str, ...], int] | None = None


@dataclass(frozen=True)
class Edge:
    """What happens when ``node`` fails in ``config``."""

    config: str
    node: str
    target: str | None  # a configuration, SAFE, or None: a missing edge
    explicit: bool  # False: the node matters to nothing and the configuration is kept


class DecisionGraph:
    """A loaded mission's decision graph with the rules of docs/missions.md applied to it."""

    def __init__(self, mission: Mission, max_failures: int | None = None):
        self.mission = mission
        self.tolerance_nodes: tuple[str, ...] = tuple(dict.fromkeys(mission.tolerance.nodes))
        depth = len(self.tolerance_nodes)
        if max_failures is not None:
            depth = min(depth, max_failures)
        self.depth = depth
        self.tolerated = mission.tolerance.node_failures
        self.configs: dict[str, Configuration] = {}
        self.phase_of: dict[str, str] = {}
        for phase in mission.phases.values():
            for name, config in phase.configurations.items():
                self.configs[name] = config
                self.phase_of[name] = phase.name
        self.processing = tuple(mission.processing_nodes)
        self._caps = {n: frozenset(node.capabilities) for n, node in mission.nodes.items()}
        self._requires = {t: frozenset(task.requires) for t, task in mission.tasks.items()}
        self.storage = tuple(mission.storage_nodes)
        self._facts: dict[str, StateFacts] = {}
        self._matters: dict[str, frozenset[str]] = {}
        self._edges: dict[tuple[str, str], Edge] = {}
        self._closures: dict[tuple[str, bool], set[str]] = {}
        self._tolerance_set = frozenset(self.tolerance_nodes)
        self._gaps: dict[str, list[tuple[str, list[str]]]] = {}

    # ---------------------------------------------------------------- configurations

    def initials(self) -> list[str]:
        return [p.initial for p in self.mission.phases.values()]

    def checkpointed(self, config: str) -> list[str]:
        placement = self.configs[config].placement
        return [t for t in placement if self.mission.tasks[t].checkpoint]

    def matters(self, config: str) -> frozenset[str]:
        """Nodes whose failure needs an edge: hosts, master, observers, and the storage
        nodes when the configuration places a checkpointed task."""
        if config not in self._matters:
            c = self.configs[config]
            nodes = set(c.placement.values()) | {c.master} | set(c.observers)
            if self.checkpointed(config):
                nodes |= set(self.storage)
            self._matters[config] = frozenset(nodes)
        return self._matters[config]

    def facts(self, config: str) -> StateFacts:
        if config not in self._facts:
            self._facts[config] = self._compute_facts(config)
        return self._facts[config]

    def _compute_facts(self, name: str) -> StateFacts:
        mission = self.mission
        c = self.configs[name]
        phase = mission.phases[c.phase]
        facts = StateFacts()
        static = facts.static

        tolerance = self._tolerance_set
        for task in phase.tasks:
            if task not in c.placement:
                static.append(
                    Finding("task-missing", name, task, None,
                            f"configuration {name} does not place task {task} of phase "
                            f"{phase.name}")
                )
        phase_tasks = set(phase.tasks)
        caps = self._caps
        requires = self._requires
        hosted = facts.hosted
        for task, node in c.placement.items():
            if task not in phase_tasks:
                static.append(
                    Finding("task-missing", name, task, node,
                            f"configuration {name} places task {task}, which is not a task of "
                            f"phase {phase.name}")
                )
            if not requires[task] <= caps[node]:
                missing = [cap for cap in mission.tasks[task].requires if cap not in caps[node]]
                static.append(
                    Finding("capability", name, task, node,
                            f"configuration {name} places task {task} on {node}, which lacks "
                            f"{', '.join(missing)}")
                )
            if node in tolerance:
                hosted.setdefault(node, []).append(task)
        for node, load in self._loads(name).items():
            capacity = mission.nodes[node].capacity
            for resource, used, limit in (("cpu", load[0], capacity.cpu),
                                          ("mem_mb", load[1], capacity.mem_mb)):
                if limit is not None and used > limit:
                    static.append(
                        Finding("capacity", name, None, node,
                                f"configuration {name} loads {node} with {resource} {used} > "
                                f"capacity {limit}")
                    )

        master = c.master
        if not mission.nodes[master].is_processing:
            static.append(Finding("master-invalid", name, None, master,
                                  f"master {master} of {name} is not a processing node"))
        if master in tolerance:
            facts.on_failed.append(
                FailureFact(Finding("master-invalid", name, None, master,
                                    f"master {master} of {name} has failed"), (master,))
            )
        seen: set[str] = set()
        for observer in c.observers:
            if observer == master:
                static.append(Finding("observer-invalid", name, None, observer,
                                      f"observer {observer} of {name} is also its master"))
            elif observer in seen:
                static.append(Finding("observer-invalid", name, None, observer,
                                      f"observer {observer} of {name} is listed twice"))
            elif not mission.nodes[observer].is_processing:
                static.append(Finding("observer-invalid", name, None, observer,
                                      f"observer {observer} of {name} is not a processing node"))
            seen.add(observer)
            if observer in tolerance and observer != master:
                facts.on_failed.append(
                    FailureFact(Finding("observer-invalid", name, None, observer,
                                        f"observer {observer} of {name} has failed"), (observer,))
                )
        if not c.observers and len(self.processing) >= 2:
            failing = tuple(n for n in self.processing if n in tolerance)
            finding = Finding("observer-invalid", name, None, None,
                              f"configuration {name} has no observer while two or more "
                              f"processing nodes are alive")
            # alive = |processing| - |failing ∩ F| >= 2
            facts.count_rule = (finding, failing, len(self.processing) - 2)

        checkpointed = self.checkpointed(name)
        if checkpointed:
            task = checkpointed[0]
            if not self.storage:
                static.append(Finding("storage-unavailable", name, None, None,
                                      f"configuration {name} places checkpointed task {task} "
                                      f"and the mission has no storage node"))
            elif all(s in tolerance for s in self.storage):
                facts.on_failed.append(
                    FailureFact(Finding("storage-unavailable", name, None, None,
                                        f"configuration {name} places checkpointed task {task} "
                                        f"and no storage node is alive"), self.storage)
                )
        return facts

    def _loads(self, config: str) -> dict[str, tuple[int, int]]:
        loads: dict[str, tuple[int, int]] = {}
        for task, node in self.configs[config].placement.items():
            load = self.mission.tasks[task].load
            cpu, mem = loads.get(node, (0, 0))
            loads[node] = (cpu + (load.cpu or 0), mem + (load.mem_mb or 0))
        return loads

    @staticmethod
    def hosted_findings(config: str, node: str, tasks: list[str]) -> list[Finding]:
        return [Finding("task-on-failed-node", config, task, node,
                        f"configuration {config} places task {task} on failed node {node}")
                for task in tasks]

    def invalid_under(self, config: str, failed: frozenset[str]) -> list[Finding]:
        """Every rule ``config`` breaks when ``failed`` have failed."""
        facts = self.facts(config)
        found = list(facts.static)
        for node, tasks in facts.hosted.items():
            if node in failed:
                found += self.hosted_findings(config, node, tasks)
        found += [f.finding for f in facts.on_failed if all(n in failed for n in f.all_of)]
        if facts.count_rule is not None:
            finding, failing, max_failed = facts.count_rule
            if sum(1 for n in failing if n in failed) <= max_failed:
                found.append(finding)
        return found

    # ---------------------------------------------------------------- edges

    def edge(self, config: str, node: str) -> Edge:
        known = self._edges.get((config, node))
        if known is None:
            known = self._edges[(config, node)] = self._edge(config, node)
        return known

    def _edge(self, config: str, node: str) -> Edge:
        phase = self.mission.phases[self.phase_of[config]]
        edges = phase.on_failure.get(config, {})
        if node in edges:
            return Edge(config, node, edges[node], True)
        if node in self.matters(config):
            return Edge(config, node, None, True)
        return Edge(config, node, config, False)

    def phase_moves(self, config: str, after_failure: bool = False) -> list[tuple[str, str | None]]:
        """(target phase, target configuration or None when the entry is missing).
        ``after_failure``: a node has failed; a move into a phase placed online or
        graph+online is then the runtime's entry where it is usable and its placer's
        answer otherwise (core/fsm/online.hpp, phase_target): keel-place --prove proves
        those moves from every state it reaches, not the graph's proof (docs/missions.md)."""
        phase = self.mission.phases[self.phase_of[config]]
        return [(target, mapping.get(config)) for target, mapping in phase.on_phase.items()
                if not (after_failure and self.mission.phases[target].placement != "graph")]

    def phase_closure(self, configs: set[str], after_failure: bool = False) -> set[str]:
        """Configurations reachable from ``configs`` by on_phase moves (F is unchanged)."""
        seen = set(configs)
        queue = deque(configs)
        while queue:
            c = queue.popleft()
            for _, target in self.phase_moves(c, after_failure):
                if target is not None and target not in seen:
                    seen.add(target)
                    queue.append(target)
        return seen

    def phase_path(self, source: str, target: str) -> list[tuple[str, str]]:
        """Shortest on_phase path from source to target: [(phase, config), ...]."""
        if source == target:
            return []
        parent: dict[str, tuple[str, str, str]] = {}
        queue = deque([source])
        seen = {source}
        while queue:
            c = queue.popleft()
            for phase, nxt in self.phase_moves(c):
                if nxt is None or nxt in seen:
                    continue
                seen.add(nxt)
                parent[nxt] = (c, phase, nxt)
                if nxt == target:
                    steps: list[tuple[str, str]] = []
                    cur = target
                    while cur != source:
                        prev, ph, _ = parent[cur]
                        steps.append((ph, cur))
                        cur = prev
                    return steps[::-1]
                queue.append(nxt)
        raise AssertionError(f"{target} is not reachable from {source} by on_phase")

    def election(self, config: str, failed: frozenset[str]) -> str | None:
        """Whom the election picks when the master of ``config`` has failed: the first
        alive observer."""
        for observer in self.configs[config].observers:
            if observer not in failed:
                return observer
        return None

    def essential_gaps(self, node: str) -> list[tuple[str, list[str]]]:
        """Essential tasks ``node`` could not run in safe mode, with missing capabilities."""
        if node not in self._gaps:
            self._gaps[node] = self._essential_gaps(node)
        return self._gaps[node]

    def _essential_gaps(self, node: str) -> list[tuple[str, list[str]]]:
        caps = set(self.mission.nodes[node].capabilities)
        gaps = []
        for task in self.mission.tasks.values():
            if task.essential:
                missing = [r for r in task.requires if r not in caps]
                if missing:
                    gaps.append((task.name, missing))
        return gaps

    def levels(self) -> list[dict[str, tuple[int, int]]]:
        """Per number i of failures, the configurations a path may be in, each with two
        bitmasks over ``tolerance_nodes``: the nodes that have failed on *every* path to
        it (must) and those that have failed on *some* path (may).

        A forward dataflow over the graph, exact about edges and over-approximating
        about F: every reachable state (c, F) at level i has c in level i and
        must ⊆ F ⊆ may. A node in must cannot fail again, which removes the spurious
        self-loops of failed nodes; the prover states both masks as lemmas. Ends at the
        depth bound or when no configuration remains.
        """
        bit = {x: 1 << j for j, x in enumerate(self.tolerance_nodes)}
        level = self._close({c: (0, 0) for c in self.initials()}, False)
        result = [level]
        while len(result) <= self.depth and level:
            nxt: dict[str, tuple[int, int]] = {}
            for c, (must, may) in level.items():
                for x in self.tolerance_nodes:
                    if must & bit[x]:
                        continue
                    edge = self.edge(c, x)
                    if edge.target is None or edge.target == SAFE:
                        continue
                    _merge(nxt, edge.target, must | bit[x], may | bit[x])
            level = self._close(nxt, True)
            if level:
                result.append(level)
        return result

    def _close(self, pre: dict[str, tuple[int, int]], after_failure: bool) -> dict[str, tuple[int, int]]:
        """Add on_phase moves (which keep F) to a level."""
        out: dict[str, tuple[int, int]] = {}
        for c0, (must, may) in pre.items():
            key = (c0, after_failure)
            if key not in self._closures:
                self._closures[key] = self.phase_closure({c0}, after_failure)
            for c in sorted(self._closures[key]):
                _merge(out, c, must, may)
        return out

    def bits(self, mask: int) -> list[str]:
        return [x for j, x in enumerate(self.tolerance_nodes) if mask >> j & 1]


def _merge(level: dict[str, tuple[int, int]], config: str, must: int, may: int) -> None:
    if config in level:
        old_must, old_may = level[config]
        level[config] = (old_must & must, old_may | may)
    else:
        level[config] = (must, may)
