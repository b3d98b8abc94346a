"""Recovery edges (``on_recovery``): a readmission must land in a state already proved.

When the Master readmits node n while the cluster is in configuration C with the failed
set F (n in F), the cluster moves to ``on_recovery[C][n]`` = T with the failed set
F - {n}; without an edge it moves to the configuration of the smaller failed set, the
walk of the decision graph from the phase's initial configuration through F - {n}
(docs/fault-model.md, "Reintegration"), a state the failure exploration reaches by
construction. A recovery edge is sound when, for every reachable (C, F) with n in F, the
state (T, F - {n}) is one the failure exploration reaches: that state is then proved like
every other (valid within the tolerance, every failure edge present, phase moves
checked), and so is everything after it. Otherwise it is a ``recovery-unproven``
violation, with the path to (C, F) and the recovery step as its counterexample.

The reachable states are enumerated explicitly (configuration and failed set, at most
``graph.depth`` failures), and only for missions that have recovery edges.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from keel_verify.check.model import DecisionGraph
from keel_verify.check.result import Step, Violation
from keel_verify.mission import SAFE

State = tuple[str, frozenset[str]]


def has_recovery_edges(graph: DecisionGraph) -> bool:
    return any(p.on_recovery for p in graph.mission.phases.values())


def reachable_states(graph: DecisionGraph) -> dict[State, tuple[State | None, Step]]:
    """Every (configuration, failed set) the failure exploration reaches, each with the
    state before it and the step that led there (breadth first: shortest paths)."""
    parent: dict[State, tuple[State | None, Step]] = {}
    queue: deque[State] = deque()
    for phase in graph.mission.phases.values():
        state: State = (phase.initial, frozenset())
        if state not in parent:
            parent[state] = (None, Step("start", phase.initial, phase=phase.name))
            queue.append(state)
    while queue:
        state = queue.popleft()
        config, failed = state
        moves: list[tuple[State, Step]] = []
        for target_phase, target in graph.phase_moves(config):
            if target is not None:
                moves.append(((target, failed), Step("phase", target, phase=target_phase)))
        if len(failed) < graph.depth:
            for node in graph.tolerance_nodes:
                if node in failed:
                    continue
                edge = graph.edge(config, node)
                if edge.target is None or edge.target == SAFE:
                    continue
                moves.append(((edge.target, failed | {node}), Step("failure", edge.target, node)))
        for nxt, step in moves:
            if nxt not in parent:
                parent[nxt] = (state, step)
                queue.append(nxt)
    return parent


def _path(parent: dict[State, tuple[State | None, Step]], state: State) -> list[Step]:
    steps: list[Step] = []
    current: State | None = state
    while current is not None:
        before, step = parent[current]
        steps.append(step)
        current = before
    return steps[::-1]


def check_recovery(graph: DecisionGraph,
                   progress: Callable[[str], None] | None = None) -> list[Violation]:
    """The ``recovery-unproven`` violations of the mission's recovery edges, one per edge
    (its shortest counterexample)."""
    if not has_recovery_edges(graph):
        return []
    parent = reachable_states(graph)
    if progress is not None:
        progress(f"recovery edges: {len(parent)} reachable states enumerated")
    by_failed: dict[tuple[str, frozenset[str]], list[str]] = {}
    for config, failed in parent:
        by_failed.setdefault((graph.phase_of[config], failed), []).append(config)
    found: dict[tuple[str, str], Violation] = {}
    for state in parent:  # breadth-first order: the first counterexample is a shortest one
        config, failed = state
        phase = graph.mission.phases[graph.phase_of[config]]
        for node, target in phase.on_recovery.get(config, {}).items():
            if node not in failed or (config, node) in found:
                continue
            rest = failed - {node}
            if (target, rest) in parent:
                continue
            steps = _path(parent, state) + [Step("recovery", target, node)]
            failures = [s.node for s in steps if s.event == "failure" and s.node is not None]
            rest_text = f"failed {{{', '.join(sorted(rest))}}}" if rest else "nothing failed"
            problems = graph.invalid_under(target, rest)
            why = (f": {problems[0].message}" if problems
                   else ": no failure sequence reaches it, so its failure edges are not proved")
            proved = sorted(by_failed.get((phase.name, rest), []))
            found[(config, node)] = Violation(
                kind="recovery-unproven", phase=phase.name, config=config, task=None, node=node,
                message=(f"readmitting {node} in {config} moves to {target} with "
                         f"{rest_text}, a state the failure exploration never reaches{why}"),
                failures=failures, steps=steps,
                suggestion=(f"point the edge at a configuration reached with {rest_text}: "
                            f"{', '.join(proved)}" if proved else
                            f"remove the edge: no configuration of phase {phase.name} is "
                            f"reached with {rest_text}"),
            )
    return list(found.values())
