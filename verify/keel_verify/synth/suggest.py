"""``check --suggest``: a valid configuration, found by Z3, for each violation.

The suggestion is for the state the counterexample reaches: the configuration (or the
missing one) under the counterexample's failed nodes, placed with the fewest moves from
the configuration the user wrote, with the master the election picks where a master
failed. It is printed as a YAML line to paste, plus the edge to add when one is missing.
A missing edge is first offered to a configuration the mission already has that is valid
there (the smallest fix, and never a new configuration that repeats one).
"""

from __future__ import annotations

from keel_verify.check.model import DecisionGraph
from keel_verify.check.result import Violation
from keel_verify.generate import flow
from keel_verify.mission import SAFE, Mission
from keel_verify.synth.placement import Infeasible, election_order, place, roles

STATE_KINDS = {"task-on-failed-node", "capability", "capacity", "task-missing",
               "master-invalid", "observer-invalid", "storage-unavailable"}


def _config_line(mission: Mission, name: str, phase: str, failed: frozenset[str],
                 start_from: str | None, master_hint: str | None = None) -> str:
    parents = []
    preferred: list[str] = []
    if start_from is not None:
        c = mission.configuration(start_from)
        parents.append(dict(c.placement))
        preferred = [c.master, *c.observers]
    if master_hint is not None:
        preferred = [master_hint, *[n for n in preferred if n != master_hint]]
    placement = place(mission, phase, failed, parents)
    master, observers = roles(mission, election_order(mission, preferred), failed)
    body = {"master": master, "observers": observers, "tasks": placement}
    return f"{name}: {flow(body)}"


def _existing_target(mission: Mission, phase: str, config: str, node: str,
                     failed: frozenset[str]) -> str | None:
    """A configuration of the phase an edge for `node`'s failure in `config` may lead to:
    valid under `failed`, with the master the cluster has then (the same, or the one the
    election picks when `node` was the master); of several, the one that moves the fewest
    tasks. None when the mission has none."""
    graph = DecisionGraph(mission)
    source = mission.configuration(config)
    master = graph.election(config, failed) if node == source.master else source.master
    if master is None:
        return None
    fits = [(sum(1 for task, host in candidate.placement.items()
                 if source.placement.get(task) != host), name)
            for name, candidate in mission.phases[phase].configurations.items()
            if name != config and candidate.master == master
            and not graph.invalid_under(name, failed)]
    return min(fits)[1] if fits else None


def suggest(mission: Mission, v: Violation) -> str | None:
    if not v.steps:
        return None  # a loader finding: no state to repair
    failed = frozenset(v.failures)
    try:
        if v.kind == "safe-mode-unhostable":
            task = mission.tasks[v.task or ""]
            caps = mission.nodes[v.node or ""].capabilities
            missing = [r for r in task.requires if r not in caps]
            return (f"give {v.node} capabilities {', '.join(missing)}, or keep it out of every "
                    f"master and observer list")
        under = f" (valid under failures {', '.join(sorted(failed)) or 'none'})"
        if v.kind in STATE_KINDS:
            return ("replace with " + _config_line(mission, v.config, v.phase, failed, v.config)
                    + under)
        if v.kind in ("missing-transition", "safe-mode-within-tolerance"):
            # The smallest fix first: an edge to a configuration the mission has.
            existing = _existing_target(mission, v.phase, v.config, v.node or "", failed)
            if existing is not None:
                return (f"add on_failure {v.config}: {{{v.node}: {existing}}} (configuration "
                        f"{existing} is valid under failures {', '.join(sorted(failed))})")
            new = f"{v.config}_{v.node}"
            line = _config_line(mission, new, v.phase, failed, v.config)
            return (f"add on_failure {v.config}: {{{v.node}: {new}}} and configuration {line}"
                    + f" (valid under failures {', '.join(sorted(failed))})")
        if v.kind == "master-mismatch":
            # The smallest fix first: the edge to a configuration the mission has, with the
            # master the cluster has then.
            existing = _existing_target(mission, v.phase, v.config, v.node or "", failed)
            if existing is not None:
                return (f"set on_failure {v.config}: {{{v.node}: {existing}}} (configuration "
                        f"{existing} is valid under failures {', '.join(sorted(failed))} and "
                        f"its master is {mission.configuration(existing).master})")
            target = v.steps[-1].to
            source = mission.configuration(v.config)
            elected = (source.master if v.node != source.master else
                       next((o for o in source.observers if o not in failed), None))
            if elected is None:
                return f"send the failure of {v.node} in {v.config} to {SAFE}"
            return ("replace with " + _config_line(mission, target, v.phase, failed, target,
                                                   master_hint=elected) + under)
        if v.kind == "phase-transition-invalid":
            # A new target: the old one may be right for the other states that reach it.
            current = mission.phases[v.phase].on_phase.get(v.target, {}).get(v.config)
            name = f"{v.config}_{v.target}"
            line = _config_line(mission, name, v.target, failed, current)
            return f"set on_phase {v.target}: {{{v.config}: {name}}} and add {line}{under}"
    except Infeasible as why:
        return f"no valid configuration exists under failures {', '.join(sorted(failed))}: {why}"
    return None
