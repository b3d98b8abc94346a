"""The Z3 encoding of a mission's reachable states, and the search for violations.

Encoding (bounded model checking, exact because every failure step fails a new node, so
no path has more than ``depth`` failures):

* Level i is the state after i detected failures. Its variables are one Boolean per
  configuration a path may be in at that level (``pre``: right after the failure,
  ``at``: after any number of planned on_phase moves, which leave F unchanged), one per
  tolerated node for the node failing at step i (``lab``), and one per tolerated node
  for "has failed by level i" (``failed``). Exactly one configuration and one failing
  node per level while the path is ``active``; a node fails at most once.
* The decision graph is the transition relation: ``at[i][c] ∧ lab[i+1][x] →
  pre[i+1][next(c, x)]`` for every edge (an explicit edge, or the self-loop of a node
  that matters to nothing); an edge to SAFE or a missing edge ends the path, which the
  relation states as ``¬(at[i][c] ∧ lab[i+1][x])``.
* Validity is a set of candidate findings per configuration (``model.py``), each with a
  condition over ``failed[i]``: a node failed, every storage node failed, few enough
  processing nodes failed, or nothing (a static fault, violated as soon as the
  configuration is reachable).

For each level, one query asks "is some candidate violated in a reachable state at
this level?" Candidates are grouped per configuration; a satisfiable answer is decoded,
every candidate of the groups it makes true is resolved (from the model, or by a query
with that candidate as assumption), and the groups are then blocked, so the loop ends
with every distinct violation found, each with a shortest failure sequence. An
unsatisfiable answer at every level is the proof. Levels are added to one incremental
solver; ``unknown`` stops the search and the verdict is undecided.
"""

from __future__ import annotations

import itertools
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import z3

from keel_verify.check.model import SAFE, DecisionGraph, Finding, Key
from keel_verify.check.result import Step, Violation


class Undecided(Exception):
    """The solver answered unknown (timeout, resource limit)."""


@dataclass
class Candidate:
    finding: Finding
    phase: str
    condition: z3.BoolRef
    # How the counterexample ends after the state: a failure of ``node`` leading to
    # ``to`` ("?" for a missing edge), or an on_phase move into ``to``.
    end: Step | None = None


class Prover:
    def __init__(
        self,
        graph: DecisionGraph,
        timeout_s: float | None = None,
        progress: Callable[[str], None] | None = None,
    ):
        self.graph = graph
        self.solver = z3.SolverFor("QF_FD")
        if timeout_s is not None:
            self.solver.set("timeout", max(1, int(timeout_s * 1000)))
        self.progress = progress or (lambda _msg: None)
        self.found: dict[Key, Violation] = {}
        self.pre: list[dict[str, z3.BoolRef]] = []
        self.at: list[dict[str, z3.BoolRef]] = []
        self.lab: list[dict[str, z3.BoolRef]] = [{}]
        self.failed: list[dict[str, z3.BoolRef]] = []
        self.active: list[z3.BoolRef] = []
        self._fresh = itertools.count()
        self.queries = 0
        self.encode_s = 0.0
        self.solve_s = 0.0
        closure_needed = any(p.on_phase for p in graph.mission.phases.values())
        self._closure: dict[str, set[str]] = {}
        self._has_phase_moves = closure_needed

    # ------------------------------------------------------------------ encoding

    def _bool(self, prefix: str) -> z3.BoolRef:
        return z3.Bool(f"{prefix}!{next(self._fresh)}")

    def _exactly_one(self, literals: list[z3.BoolRef], active: z3.BoolRef | None) -> None:
        s = self.solver
        if len(literals) > 1:
            s.add(z3.AtMost(*literals, 1))
        if active is None:
            s.add(z3.Or(literals))
        else:
            s.add(z3.Implies(active, z3.Or(literals)))
            for lit in literals:
                s.add(z3.Implies(lit, active))

    def _closure_of(self, config: str) -> set[str]:
        if config not in self._closure:
            self._closure[config] = self.graph.phase_closure({config})
        return self._closure[config]

    def _after_phase_moves(self, i: int, pre: dict[str, z3.BoolRef], level: set[str]) -> None:
        """at[i] = pre[i] followed by on_phase moves (static: they do not change F)."""
        active = self.active[i] if i > 0 else None
        if not self._has_phase_moves:
            self.at.append(pre)
            return
        sources: dict[str, list[z3.BoolRef]] = {c: [] for c in level}
        for c0, lit in pre.items():
            for c in self._closure_of(c0):
                sources[c].append(lit)
        at = {c: z3.Bool(f"at{i}_{c}") for c in sorted(level)}
        for c, lit in at.items():
            self.solver.add(z3.Implies(lit, z3.Or(sources[c])))
        self._exactly_one(list(at.values()), active)
        self.at.append(at)

    def add_level(self, i: int, level: set[str]) -> None:
        start = time.perf_counter()
        g = self.graph
        s = self.solver
        if i == 0:
            self.active.append(z3.BoolVal(True))
            self.failed.append({x: z3.BoolVal(False) for x in g.tolerance_nodes})
            pre = {c: z3.Bool(f"pre0_{c}") for c in dict.fromkeys(g.initials())}
            self._exactly_one(list(pre.values()), None)
        else:
            active = z3.Bool(f"active{i}")
            s.add(z3.Implies(active, self.active[i - 1]))
            self.active.append(active)
            lab = {x: z3.Bool(f"fail{i}_{x}") for x in g.tolerance_nodes}
            self._exactly_one(list(lab.values()), active)
            before = self.failed[i - 1]
            failed: dict[str, z3.BoolRef] = {}
            for x, lit in lab.items():
                if z3.is_false(before[x]):
                    failed[x] = lit
                else:
                    s.add(z3.Implies(lit, z3.Not(before[x])))
                    f = z3.Bool(f"failed{i}_{x}")
                    s.add(f == z3.Or(before[x], lit))
                    failed[x] = f
            self.failed.append(failed)
            self.lab.append(lab)
            targets: dict[str, list[tuple[z3.BoolRef, z3.BoolRef]]] = {}
            dead: list[tuple[z3.BoolRef, z3.BoolRef]] = []
            for c, here in self.at[i - 1].items():
                for x in g.tolerance_nodes:
                    edge = g.edge(c, x)
                    if edge.target is None or edge.target == SAFE:
                        dead.append((here, lab[x]))
                    else:
                        targets.setdefault(edge.target, []).append((here, lab[x]))
            pre = {c: z3.Bool(f"pre{i}_{c}") for c in sorted(targets)}
            for c, causes in targets.items():
                for here, fail in causes:
                    s.add(z3.Or(z3.Not(here), z3.Not(fail), pre[c]))
            for here, fail in dead:
                s.add(z3.Or(z3.Not(here), z3.Not(fail)))
            if pre:
                self._exactly_one(list(pre.values()), active)
            else:
                s.add(z3.Not(active))
        self.pre.append(pre)
        self._after_phase_moves(i, pre, level)
        self.encode_s += time.perf_counter() - start

    # ------------------------------------------------------------------ candidates

    def _state_condition(self, config: str, i: int, finding_filter: set[Key] | None,
                         phase_for_key: str, wrap: Callable[[Finding], Finding]
                         ) -> list[tuple[Finding, z3.BoolRef]]:
        """Findings of ``config`` under failed[i] with their conditions."""
        facts = self.graph.facts(config)
        failed = self.failed[i]
        out: list[tuple[Finding, z3.BoolRef]] = []
        for finding in facts.static:
            out.append((wrap(finding), z3.BoolVal(True)))
        for fact in facts.on_failed:
            if len(fact.all_of) > i:
                continue  # needs more failures than this level has
            out.append((wrap(fact.finding), z3.And([failed[n] for n in fact.all_of])))
        if facts.count_rule is not None:
            finding, failing, max_failed = facts.count_rule
            cond = (z3.BoolVal(True) if i <= max_failed or not failing
                    else z3.AtMost(*[failed[n] for n in failing], max_failed))
            out.append((wrap(finding), cond))
        if finding_filter is not None:
            out = [(f, c) for f, c in out if f.key(phase_for_key) not in finding_filter]
        return out

    def candidates(self, i: int, config: str) -> list[Candidate]:
        g = self.graph
        phase = g.phase_of[config]
        c = g.configs[config]
        failed = self.failed[i]
        found = set(self.found)
        out: list[Candidate] = []
        for finding, cond in self._state_condition(config, i, found, phase, lambda f: f):
            out.append(Candidate(finding, phase, cond))
        if i < g.depth:
            for x in g.tolerance_nodes:
                edge = g.edge(config, x)
                alive = z3.Not(failed[x])
                if edge.target is None:
                    f = Finding("missing-transition", config, None, x,
                                f"no on_failure edge of {config} for the failure of {x}, which "
                                f"{self._why_matters(config, x)}")
                    out.append(Candidate(f, phase, alive, Step("failure", "?", node=x)))
                    continue
                if edge.target == SAFE and i + 1 <= g.tolerated:
                    f = Finding("safe-mode-within-tolerance", config, None, x,
                                f"the failure of {x} in {config} enters SAFE after {i + 1} "
                                f"failure(s); the mission tolerates {g.tolerated}")
                    out.append(Candidate(f, phase, alive, Step("failure", SAFE, node=x)))
                if x == c.master and edge.target not in (SAFE, config):
                    new_master = g.configs[edge.target].master
                    picks = self._elected(config, new_master, i, x)
                    f = Finding("master-mismatch", config, None, x,
                                f"master {x} of {config} fails and {edge.target} names master "
                                f"{new_master}, but the election picks the first alive observer "
                                f"of {config}")
                    out.append(Candidate(f, phase, z3.And(alive, z3.Not(picks)),
                                         Step("failure", edge.target, node=x)))
        for target_phase, target in g.phase_moves(config):
            if target is None:
                f = Finding("phase-transition-invalid", config, None, None,
                            f"on_phase {target_phase} has no entry for {config}",
                            target=target_phase)
                out.append(Candidate(f, phase, z3.BoolVal(True),
                                     Step("phase", "?", phase=target_phase)))
                continue

            def wrap(inner: Finding, tp: str = target_phase, t: str = target) -> Finding:
                return Finding("phase-transition-invalid", config, inner.task, inner.node,
                               f"on_phase {tp} moves {config} to {t}, which is invalid: "
                               f"{inner.message}", target=tp)

            for finding, cond in self._state_condition(target, i, found, phase, wrap):
                out.append(Candidate(finding, phase, cond, Step("phase", target, phase=target_phase)))
        roles = dict.fromkeys((c.master, *c.observers))
        for node in roles:
            if not g.mission.nodes[node].is_processing:
                continue
            for task, missing in g.essential_gaps(node):
                f = Finding("safe-mode-unhostable", config, task, node,
                            f"{node} can become master ({'master' if node == c.master else 'observer'}"
                            f" in {config}) but lacks {', '.join(missing)}, which essential task "
                            f"{task} requires in safe mode")
                if f.key(phase) not in found:
                    out.append(Candidate(f, phase, z3.BoolVal(True)))
        return out

    def _why_matters(self, config: str, node: str) -> str:
        c = self.graph.configs[config]
        if node == c.master:
            return "is its master"
        if node in c.observers:
            return "is its observer"
        hosted = [t for t, n in c.placement.items() if n == node]
        if hosted:
            return f"hosts {', '.join(hosted)}"
        return "is the storage node of its checkpointed tasks"

    def _elected(self, config: str, new_master: str, i: int, master: str) -> z3.BoolRef:
        """True when the election after ``master`` fails picks ``new_master``."""
        failed = self.failed[i]

        def down(n: str) -> z3.BoolRef:
            if n == master:
                return z3.BoolVal(True)
            return failed.get(n, z3.BoolVal(False))

        observers = self.graph.configs[config].observers
        for j, observer in enumerate(observers):
            if observer == new_master:
                return z3.And(z3.Not(down(observer)), *[down(o) for o in observers[:j]])
        return z3.BoolVal(False)

    # ------------------------------------------------------------------ search

    def _check(self, *assumptions: z3.BoolRef) -> bool:
        start = time.perf_counter()
        result = self.solver.check(*assumptions)
        self.solve_s += time.perf_counter() - start
        self.queries += 1
        if result == z3.unknown:
            raise Undecided(self.solver.reason_unknown())
        return result == z3.sat

    def search_level(self, i: int) -> int:
        """Find every violation first reachable at level i; returns how many."""
        start = time.perf_counter()
        groups: list[tuple[z3.BoolRef, str, list[Candidate]]] = []
        for config in self.at[i]:
            cands = self.candidates(i, config)
            if not cands:
                continue
            glit = self._bool(f"group{i}_{config}")
            self.solver.add(z3.Implies(glit, self.at[i][config]))
            self.solver.add(z3.Implies(glit, z3.Or([c.condition for c in cands])))
            groups.append((glit, config, cands))
        self.encode_s += time.perf_counter() - start
        if not groups:
            return 0
        query = self._bool(f"query{i}")
        self.solver.add(z3.Implies(query, z3.Or([glit for glit, _, _ in groups])))
        before = len(self.found)
        while self._check(query):
            model = self.solver.model()
            hits = [grp for grp in groups if z3.is_true(model.eval(grp[0], model_completion=True))]
            assert hits, "a model of the query makes some group true"
            for glit, config, cands in hits:
                self._resolve(i, config, cands, model)
                self.solver.add(z3.Not(glit))
        return len(self.found) - before

    def _resolve(self, i: int, config: str, cands: list[Candidate], model: z3.ModelRef) -> None:
        here = self.at[i][config]
        for cand in cands:
            key = cand.finding.key(cand.phase)
            if key in self.found:
                continue
            if z3.is_true(model.eval(cand.condition, model_completion=True)):
                self.found[key] = self._decode(model, i, config, cand)
                continue
            lit = self._bool("cand")
            self.solver.add(z3.Implies(lit, z3.And(here, cand.condition)))
            if self._check(lit):
                self.found[key] = self._decode(self.solver.model(), i, config, cand)

    def _decode(self, model: z3.ModelRef, i: int, config: str, cand: Candidate) -> Violation:
        g = self.graph

        def chosen(literals: dict[str, z3.BoolRef]) -> str:
            for name, lit in literals.items():
                if z3.is_true(model.eval(lit, model_completion=True)):
                    return name
            raise AssertionError("a level of an active path has a configuration")

        steps: list[Step] = []
        failures: list[str] = []
        current = chosen(self.pre[0])
        steps.append(Step("start", current, phase=g.phase_of[current]))
        for j in range(i + 1):
            if j > 0:
                node = chosen(self.lab[j])
                failures.append(node)
                current = chosen(self.pre[j])
                steps.append(Step("failure", current, node=node))
            target = chosen(self.at[j])
            for phase, nxt in g.phase_path(current, target):
                steps.append(Step("phase", nxt, phase=phase))
            current = target
        assert current == config, "the decoded path ends in the violating configuration"
        if cand.end is not None:
            steps.append(cand.end)
            if cand.end.event == "failure" and cand.end.node is not None:
                failures.append(cand.end.node)
        f = cand.finding
        message = f.message
        if f.kind == "master-mismatch":
            elected = g.election(config, frozenset(failures))
            message += f" ({elected})" if elected else " (none is alive: the next is SAFE)"
        return Violation(kind=f.kind, phase=cand.phase, config=f.config, task=f.task, node=f.node,
                         message=message, failures=failures, steps=steps, target=f.target)

    def run(self) -> dict[str, Any]:
        g = self.graph
        levels = g.levels()
        for i, level in enumerate(levels):
            t0 = time.perf_counter()
            self.add_level(i, level)
            n = self.search_level(i)
            self.progress(f"level {i}/{len(levels) - 1}: {len(level)} configurations, "
                          f"{n} new violations, {time.perf_counter() - t0:.2f} s")
        return {
            "levels": len(levels),
            "states_bound": sum(len(level) for level in levels),
            "queries": self.queries,
            "encode_s": round(self.encode_s, 3),
            "solve_s": round(self.solve_s, 3),
        }


def stderr_progress(message: str) -> None:
    print(f"keel-verify: {message}", file=sys.stderr, flush=True)
