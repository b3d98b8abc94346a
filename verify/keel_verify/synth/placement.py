"""Valid placements by Z3: one configuration of a phase under a set of failed nodes.

The placement problem: every task of the phase on exactly one alive node that offers the
task's capabilities, the summed load of every node within its capacity (cpu and mem_mb),
an alive storage node when a checkpointed task is placed. Among the solutions, the one
that keeps the most tasks where the ``parents`` (the configurations a failure leads here
from) had them, so each failure moves as few tasks as it can.

Roles are not a search: master and observers follow the election order (``roles``), so
that after a master failure the next configuration's master is the first alive observer
of the one before, which is what the election picks.
"""

from __future__ import annotations

from collections.abc import Iterable

import z3

from keel_verify.mission import Mission

Placement = dict[str, str]


class Infeasible(Exception):
    """No valid placement exists under these failures."""


def election_order(mission: Mission, preferred: Iterable[str] = ()) -> list[str]:
    """Processing nodes that can host every essential task in safe mode, the preferred
    ones (an initial configuration's master and observers) first."""
    essential = [t for t in mission.tasks.values() if t.essential]

    def capable(node: str) -> bool:
        caps = set(mission.nodes[node].capabilities)
        return all(set(t.requires) <= caps for t in essential)

    order = [n for n in preferred if n in mission.nodes and mission.nodes[n].is_processing]
    order += [n for n in mission.processing_nodes if n not in order]
    return [n for n in dict.fromkeys(order) if capable(n)]


def roles(mission: Mission, order: list[str], failed: frozenset[str],
          observers: int = 2) -> tuple[str, list[str]]:
    alive = [n for n in order if n not in failed]
    if not alive:
        raise Infeasible("no processing node that can host safe mode is alive")
    alive_processing = [n for n in mission.processing_nodes if n not in failed]
    chosen = alive[1 : 1 + observers]
    if len(alive_processing) >= 2 and not chosen:
        raise Infeasible(
            "two processing nodes are alive but only one can host safe mode, so no observer "
            "can be chosen")
    return alive[0], chosen


def place(mission: Mission, phase: str, failed: frozenset[str],
          parents: list[Placement]) -> Placement:
    """A valid placement of ``phase``'s tasks under ``failed`` with the fewest moves
    from ``parents``. Raises :class:`Infeasible`."""
    tasks = list(mission.phases[phase].tasks)
    alive = [n for n in mission.nodes if n not in failed]
    if any(mission.tasks[t].checkpoint for t in tasks) and not any(
        mission.nodes[n].is_storage for n in alive
    ):
        raise Infeasible("checkpointed tasks and no alive storage node")
    candidates: dict[str, list[str]] = {}
    for t in tasks:
        requires = set(mission.tasks[t].requires)
        candidates[t] = [n for n in alive if requires <= set(mission.nodes[n].capabilities)]
        if not candidates[t]:
            raise Infeasible(f"no alive node offers what task {t} requires")
    # First let Z3 place only what must move (its node failed) or what the parents
    # disagree on, keeping the rest where it is: a small problem, solved fast, and the
    # move count stays at what the failure forces. Only when the kept tasks leave no room
    # is the whole phase re-placed (still with the fewest moves).
    pinned: Placement = {}
    for t in tasks:
        # A parent that had the task on a node failed since has no say: the task must
        # move there anyway. The task stays put when the other parents agree.
        homes = {p.get(t) for p in parents} & set(candidates[t])
        if len(homes) == 1:
            pinned[t] = next(iter(homes))
    # Tasks kept on a node that the kept tasks alone overload may move as well.
    cpu: dict[str, int] = {}
    mem: dict[str, int] = {}
    for t, n in pinned.items():
        cpu[n] = cpu.get(n, 0) + (mission.tasks[t].load.cpu or 0)
        mem[n] = mem.get(n, 0) + (mission.tasks[t].load.mem_mb or 0)
    for n in cpu:
        cap = mission.nodes[n].capacity
        if (cap.cpu is not None and cpu[n] > cap.cpu) or (
            cap.mem_mb is not None and mem[n] > cap.mem_mb
        ):
            pinned = {t: home for t, home in pinned.items() if home != n}
    result = _solve(mission, tasks, candidates, parents, pinned)
    if result is None and pinned:
        result = _solve(mission, tasks, candidates, parents, {})
    if result is None:
        raise Infeasible("the alive nodes' capacity cannot hold the phase's tasks")
    return result


def _solve(mission: Mission, tasks: list[str], candidates: dict[str, list[str]],
           parents: list[Placement], pinned: Placement) -> Placement | None:
    free = [t for t in tasks if t not in pinned]
    used_cpu: dict[str, int] = {}
    used_mem: dict[str, int] = {}
    for t, n in pinned.items():
        load = mission.tasks[t].load
        used_cpu[n] = used_cpu.get(n, 0) + (load.cpu or 0)
        used_mem[n] = used_mem.get(n, 0) + (load.mem_mb or 0)
    for n in used_cpu:
        cap = mission.nodes[n].capacity
        if (cap.cpu is not None and used_cpu[n] > cap.cpu) or (
            cap.mem_mb is not None and used_mem[n] > cap.mem_mb
        ):
            return None
    if not free:
        return dict(pinned)
    opt = z3.Optimize()
    choice: dict[tuple[str, str], z3.BoolRef] = {}
    for t in free:
        lits = []
        for n in candidates[t]:
            lit = z3.Bool(f"{t}@{n}")
            choice[(t, n)] = lit
            lits.append(lit)
        opt.add(z3.PbEq([(lit, 1) for lit in lits], 1))
    nodes = {n for t in free for n in candidates[t]}
    for n in nodes:
        cap = mission.nodes[n].capacity
        for limit, used, attr in ((cap.cpu, used_cpu.get(n, 0), "cpu"),
                                  (cap.mem_mb, used_mem.get(n, 0), "mem_mb")):
            if limit is None:
                continue
            terms = [(choice[(t, n)], getattr(mission.tasks[t].load, attr) or 0)
                     for t in free if (t, n) in choice]
            terms = [(lit, w) for lit, w in terms if w > 0]
            if terms:
                opt.add(z3.PbLe(terms, limit - used))
    for parent in parents:
        for t in free:
            home = parent.get(t)
            if home is not None and (t, home) in choice:
                opt.add_soft(choice[(t, home)], 1)
    if opt.check() != z3.sat:
        return None
    model = opt.model()
    placement = dict(pinned)
    for (t, n), lit in choice.items():
        if z3.is_true(model.eval(lit, model_completion=True)):
            placement[t] = n
    assert all(t in placement for t in tasks), "every task is placed"
    return {t: placement[t] for t in tasks}
