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

Constraints are written as SMT-LIB text and parsed by Z3 in batches: building the same
terms one by one through the Python API costs about ten times more than solving them.
Conditions are small trees (``Expr``) so the same condition can be written for Z3 and
evaluated against a model.
"""

from __future__ import annotations

import itertools
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import z3

from keel_verify.check.model import SAFE, DecisionGraph, Finding, Key
from keel_verify.check.result import Step, Violation


class Undecided(Exception):
    """The solver answered unknown (timeout, resource limit)."""


# A condition: "true", "false", a variable name, or ("not" | "and" | "or", [Expr]), or
# ("atmost", [names], k).
Expr = str | tuple[Any, ...]
TRUE: Expr = "true"
FALSE: Expr = "false"


def smt(e: Expr) -> str:
    if isinstance(e, str):
        return e
    op = e[0]
    if op == "not":
        return f"(not {smt(e[1])})"
    if op == "atmost":
        names, k = e[1], e[2]
        return f"((_ at-most {k}) {' '.join(names)})" if names else "true"
    parts = [smt(x) for x in e[1]]
    if not parts:
        return "true" if op == "and" else "false"
    if len(parts) == 1:
        return parts[0]
    return f"({op} {' '.join(parts)})"


def evaluate(e: Expr, value: Callable[[str], bool]) -> bool:
    if isinstance(e, str):
        return e == "true" if e in ("true", "false") else value(e)
    op = e[0]
    if op == "not":
        return not evaluate(e[1], value)
    if op == "atmost":
        return sum(1 for n in e[1] if value(n)) <= e[2]
    if op == "and":
        return all(evaluate(x, value) for x in e[1])
    return any(evaluate(x, value) for x in e[1])


def neg(e: Expr) -> Expr:
    if e == TRUE:
        return FALSE
    if e == FALSE:
        return TRUE
    return ("not", e)


def conj(*parts: Expr) -> Expr:
    items = [p for p in parts if p != TRUE]
    if any(p == FALSE for p in items):
        return FALSE
    if not items:
        return TRUE
    return items[0] if len(items) == 1 else ("and", items)


@dataclass
class Candidate:
    finding: Finding
    phase: str
    condition: Expr
    # How the counterexample ends after the state: a failure of ``node`` leading to
    # ``to`` ("?" for a missing edge), or an on_phase move into ``to``.
    end: Step | None = None


class Prover:
    def __init__(
        self,
        graph: DecisionGraph,
        timeout_s: float | None = None,
        progress: Callable[[str], None] | None = None,
        prune: bool = True,
    ):
        # prune=False sends every candidate to Z3, also those the dataflow bounds refute
        # (the lemmas still hold); the tests use it to show the verdicts do not depend on
        # the pruning.
        self.prune = prune
        self.graph = graph
        # A context of its own: the counterexample Z3 picks among equally short ones
        # depends on the terms its context already holds, so a shared context would make
        # a check's output depend on the checks run before it in the same process.
        self.context = z3.Context()
        self.solver = z3.SolverFor("QF_FD", ctx=self.context)
        if timeout_s is not None:
            self.solver.set("timeout", max(1, int(timeout_s * 1000)))
        self.progress = progress or (lambda _msg: None)
        self.found: dict[Key, Violation] = {}
        self.pre: list[dict[str, str]] = []
        self.at: list[dict[str, str]] = []
        self.lab: list[dict[str, str]] = [{}]
        self.failed: list[dict[str, str]] = []
        self.active: list[str] = []
        self.levels: list[dict[str, tuple[int, int]]] = []
        self._bit = {x: 1 << j for j, x in enumerate(graph.tolerance_nodes)}
        self._config_id = {c: j for j, c in enumerate(graph.configs)}
        self._node_id = {x: j for j, x in enumerate(graph.tolerance_nodes)}
        self._fresh = itertools.count()
        self._buffer: list[str] = []
        self._closure: dict[tuple[str, bool], set[str]] = {}
        self._has_phase_moves = any(p.on_phase for p in graph.mission.phases.values())
        self.queries = 0
        self.encode_s = 0.0
        self.solve_s = 0.0

    # ------------------------------------------------------------------ emission

    def _declare(self, name: str) -> str:
        self._buffer.append(f"(declare-const {name} Bool)")
        return name

    def _fresh_var(self, prefix: str) -> str:
        return self._declare(f"{prefix}.{next(self._fresh)}")

    def _assert(self, text: str) -> None:
        self._buffer.append(f"(assert {text})")

    def _flush(self) -> None:
        if self._buffer:
            self.solver.from_string("\n".join(self._buffer))
            self._buffer.clear()

    def _exactly_one(self, names: list[str], active: str | None) -> None:
        if len(names) > 1:
            self._assert(f"((_ at-most 1) {' '.join(names)})")
        any_of = smt(("or", names))
        if active is None:
            self._assert(any_of)
        else:
            self._assert(f"(=> {active} {any_of})")
            for name in names:
                self._assert(f"(=> {name} {active})")

    # ------------------------------------------------------------------ encoding

    def _closure_of(self, config: str, after_failure: bool) -> set[str]:
        key = (config, after_failure)
        if key not in self._closure:
            self._closure[key] = self.graph.phase_closure({config}, after_failure)
        return self._closure[key]

    def _after_phase_moves(self, i: int, pre: dict[str, str],
                           level: dict[str, tuple[int, int]]) -> None:
        """at[i] = pre[i] followed by on_phase moves (static: they do not change F)."""
        active = self.active[i] if i > 0 else None
        if not self._has_phase_moves:
            self.at.append(pre)
            return
        sources: dict[str, list[str]] = {c: [] for c in level}
        for c0, lit in pre.items():
            for c in sorted(self._closure_of(c0, i > 0)):
                sources[c].append(lit)
        at = {c: self._declare(f"at{i}.{self._config_id[c]}") for c in sorted(level)}
        for c, lit in at.items():
            self._assert(f"(=> {lit} {smt(('or', sources[c]))})")
        self._exactly_one(list(at.values()), active)
        self.at.append(at)

    def add_level(self, i: int, level: dict[str, tuple[int, int]]) -> None:
        start = time.perf_counter()
        g = self.graph
        if i == 0:
            self.active.append("true")
            self.failed.append({x: FALSE for x in g.tolerance_nodes})
            pre = {c: self._declare(f"pre0.{self._config_id[c]}")
                   for c in dict.fromkeys(g.initials())}
            self._exactly_one(list(pre.values()), None)
        else:
            active = self._declare(f"active{i}")
            if i > 1:
                self._assert(f"(=> {active} {self.active[i - 1]})")
            self.active.append(active)
            lab = {x: self._declare(f"fail{i}.{self._node_id[x]}") for x in g.tolerance_nodes}
            self._exactly_one(list(lab.values()), active)
            before = self.failed[i - 1]
            failed: dict[str, str] = {}
            for x, lit in lab.items():
                if before[x] == FALSE:
                    failed[x] = lit
                else:
                    self._assert(f"(=> {lit} (not {before[x]}))")
                    f = self._declare(f"failed{i}.{self._node_id[x]}")
                    self._assert(f"(= {f} (or {before[x]} {lit}))")
                    failed[x] = f
            self.failed.append(failed)
            self.lab.append(lab)
            targets: dict[str, list[tuple[str, str]]] = {}
            for c, here in self.at[i - 1].items():
                must = self.levels[i - 1][c][0]
                for j, x in enumerate(g.tolerance_nodes):
                    if must >> j & 1:
                        continue  # failed on every path here: the lemmas rule it out
                    edge = g.edge(c, x)
                    if edge.target is None or edge.target == SAFE:
                        self._assert(f"(or (not {here}) (not {lab[x]}))")
                    else:
                        targets.setdefault(edge.target, []).append((here, lab[x]))
            pre = {c: self._declare(f"pre{i}.{self._config_id[c]}") for c in sorted(targets)}
            for c, causes in targets.items():
                for here, fail in causes:
                    self._assert(f"(or (not {here}) (not {fail}) {pre[c]})")
            if pre:
                self._exactly_one(list(pre.values()), active)
            else:
                self._assert(f"(not {active})")
        self.pre.append(pre)
        self._after_phase_moves(i, pre, level)
        if i > 0:
            self._lemmas(i, level)
        self.encode_s += time.perf_counter() - start

    def _lemmas(self, i: int, level: dict[str, tuple[int, int]]) -> None:
        """State the dataflow's bounds must ⊆ F ⊆ may for every configuration of the
        level. They follow from the transition relation (the oracle tests check the
        verdicts against an explicit-state search); stating them lets the solver refute
        most candidates by propagation instead of by search over failure orders."""
        failed = self.failed[i]
        for c, here in self.at[i].items():
            must, may = level[c]
            for j, x in enumerate(self.graph.tolerance_nodes):
                if must >> j & 1:
                    self._assert(f"(or (not {here}) {failed[x]})")
                elif not may >> j & 1:
                    self._assert(f"(or (not {here}) (not {failed[x]}))")

    # ------------------------------------------------------------------ candidates

    def _state_condition(self, config: str, i: int, may: int, finding_filter: set[Key],
                         phase_for_key: str, wrap: Callable[[Finding], Finding]
                         ) -> list[tuple[Finding, Expr]]:
        """Findings of ``config`` under failed[i] with their conditions; ``may`` bounds
        the failed set of the state, so findings that need other failures are left out
        (the lemma F ⊆ may refutes them)."""
        facts = self.graph.facts(config)
        failed = self.failed[i]
        bit = self._bit
        out: list[tuple[Finding, Expr]] = []
        for finding in facts.static:
            out.append((wrap(finding), TRUE))
        for node, tasks in facts.hosted.items():
            if i and (may & bit[node] or not self.prune):
                for finding in self.graph.hosted_findings(config, node, tasks):
                    out.append((wrap(finding), failed[node]))
        for fact in facts.on_failed:
            if len(fact.all_of) > i or (self.prune and any(not may & bit[n] for n in fact.all_of)):
                continue
            out.append((wrap(fact.finding), conj(*[failed[n] for n in fact.all_of])))
        if facts.count_rule is not None:
            finding, failing, max_failed = facts.count_rule
            cond: Expr = (TRUE if i <= max_failed or not failing
                          else ("atmost", [failed[n] for n in failing], max_failed))
            out.append((wrap(finding), cond))
        return [(f, c) for f, c in out if f.key(phase_for_key) not in finding_filter]

    def candidates(self, i: int, config: str) -> list[Candidate]:
        g = self.graph
        phase = g.phase_of[config]
        c = g.configs[config]
        failed = self.failed[i]
        found = set(self.found)
        must, may = self.levels[i][config]
        bit = self._bit
        out: list[Candidate] = []
        for finding, cond in self._state_condition(config, i, may, found, phase, lambda f: f):
            out.append(Candidate(finding, phase, cond))
        if i < g.depth:
            for x in g.tolerance_nodes:
                if self.prune and must & bit[x]:
                    continue  # x has failed on every path here (lemma: must ⊆ F)
                edge = g.edge(config, x)
                alive = neg(failed[x])
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
                if x == c.master and edge.target != SAFE:
                    new_master = g.configs[edge.target].master
                    picks = self._elected(config, new_master, i, x)
                    f = Finding("master-mismatch", config, None, x,
                                f"master {x} of {config} fails and {edge.target} names master "
                                f"{new_master}, but the election picks the first alive observer "
                                f"of {config}")
                    out.append(Candidate(f, phase, conj(alive, neg(picks)),
                                         Step("failure", edge.target, node=x)))
                elif (edge.target is not None and edge.target != SAFE
                      and g.configs[edge.target].master not in (c.master, x)
                      and g.configs[edge.target].master in g.processing):
                    # The Master excludes x and drives the switch itself: an edge for another
                    # node's failure cannot hand the cluster to another master (the runtime
                    # enters SAFE instead: ReconfigurationManager::exclude). A target whose
                    # master cannot be one (not processing, failed) is master-invalid there.
                    new_master = g.configs[edge.target].master
                    f = Finding("master-mismatch", config, None, x,
                                f"{x}, not the master, fails in {config} and {edge.target} names "
                                f"master {new_master}, but the master {c.master} drives the "
                                f"switch and stays master")
                    out.append(Candidate(f, phase, conj(alive, neg(failed.get(new_master, FALSE))),
                                         Step("failure", edge.target, node=x)))
        for target_phase, target in g.phase_moves(config, i > 0):
            if target is None:
                f = Finding("phase-transition-invalid", config, None, None,
                            f"on_phase {target_phase} has no entry for {config}",
                            target=target_phase)
                if f.key(phase) not in found:
                    out.append(Candidate(f, phase, TRUE, Step("phase", "?", phase=target_phase)))
                continue

            def wrap(inner: Finding, tp: str = target_phase, t: str = target) -> Finding:
                return Finding("phase-transition-invalid", config, inner.task, inner.node,
                               f"on_phase {tp} moves {config} to {t}, which is invalid: "
                               f"{inner.message}", target=tp)

            for finding, cond in self._state_condition(target, i, may, found, phase, wrap):
                end = Step("phase", target, phase=target_phase)
                out.append(Candidate(finding, phase, cond, end))
        roles = dict.fromkeys((c.master, *c.observers))
        for node in roles:
            if not g.mission.nodes[node].is_processing:
                continue
            for task, missing in g.essential_gaps(node):
                role = "master" if node == c.master else "observer"
                f = Finding("safe-mode-unhostable", config, task, node,
                            f"{node} can become master ({role} in {config}) but lacks "
                            f"{', '.join(missing)}, which essential task {task} requires in "
                            f"safe mode")
                if f.key(phase) not in found:
                    out.append(Candidate(f, phase, TRUE))
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

    def _elected(self, config: str, new_master: str, i: int, master: str) -> Expr:
        """True when the election after ``master`` fails picks ``new_master``."""
        failed = self.failed[i]

        def down(n: str) -> Expr:
            return TRUE if n == master else failed.get(n, FALSE)

        observers = self.graph.configs[config].observers
        for j, observer in enumerate(observers):
            if observer == new_master:
                return conj(neg(down(observer)), *[down(o) for o in observers[:j]])
        return FALSE

    # ------------------------------------------------------------------ search

    def _check(self, *assumptions: str) -> bool:
        self._flush()
        start = time.perf_counter()
        result = self.solver.check(*[z3.Bool(a, self.context) for a in assumptions])
        self.solve_s += time.perf_counter() - start
        self.queries += 1
        if result == z3.unknown:
            raise Undecided(self.solver.reason_unknown())
        return result == z3.sat

    def search_level(self, i: int) -> int:
        """Find every violation first reachable at level i; returns how many."""
        start = time.perf_counter()
        groups: list[tuple[str, str, list[Candidate]]] = []
        for config, here in self.at[i].items():
            cands = self.candidates(i, config)
            if not cands:
                continue
            glit = self._fresh_var(f"group{i}")
            self._assert(f"(=> {glit} {here})")
            self._assert(f"(=> {glit} {smt(('or', [c.condition for c in cands]))})")
            groups.append((glit, config, cands))
        self.encode_s += time.perf_counter() - start
        if not groups:
            return 0
        query = self._fresh_var(f"query{i}")
        self._assert(f"(=> {query} {smt(('or', [glit for glit, _, _ in groups]))})")
        before = len(self.found)
        while self._check(query):
            model = self.solver.model()
            value = self._valuation(model)
            hits = [grp for grp in groups if value(grp[0])]
            assert hits, "a model of the query makes some group true"
            for glit, config, cands in hits:
                self._resolve(i, config, cands, value)
                self._assert(f"(not {glit})")
        return len(self.found) - before

    @staticmethod
    def _valuation(model: z3.ModelRef) -> Callable[[str], bool]:
        cache: dict[str, bool] = {}

        def value(name: str) -> bool:
            if name not in cache:
                cache[name] = z3.is_true(model.eval(z3.Bool(name, model.ctx),
                                                    model_completion=True))
            return cache[name]

        return value

    def _resolve(self, i: int, config: str, cands: list[Candidate],
                 value: Callable[[str], bool]) -> None:
        here = self.at[i][config]
        for cand in cands:
            key = cand.finding.key(cand.phase)
            if key in self.found:
                continue
            if evaluate(cand.condition, value):
                self.found[key] = self._decode(value, i, config, cand)
                continue
            lit = self._fresh_var("cand")
            self._assert(f"(=> {lit} {smt(conj(here, cand.condition))})")
            if self._check(lit):
                model_value = self._valuation(self.solver.model())
                self.found[key] = self._decode(model_value, i, config, cand)

    def _decode(self, value: Callable[[str], bool], i: int, config: str,
                cand: Candidate) -> Violation:
        g = self.graph

        def chosen(literals: dict[str, str]) -> str:
            for name, lit in literals.items():
                if value(lit):
                    return name
            raise AssertionError("a level of an active path has a configuration")

        failures = [chosen(self.lab[j]) for j in range(1, i + 1)]
        steps = self._fewest_phase_moves(failures, config)
        if cand.end is not None:
            steps.append(cand.end)
            if cand.end.event == "failure" and cand.end.node is not None:
                failures.append(cand.end.node)
        f = cand.finding
        message = f.message
        if f.kind == "master-mismatch" and f.node == g.configs[config].master:
            elected = g.election(config, frozenset(failures))
            message += f" ({elected})" if elected else " (none is alive: the next is SAFE)"
        return Violation(kind=f.kind, phase=cand.phase, config=f.config, task=f.task, node=f.node,
                         message=message, failures=failures, steps=steps, target=f.target)

    def _fewest_phase_moves(self, failures: list[str], config: str) -> list[Step]:
        """The model fixes the failure sequence and the final configuration; among the
        paths with that sequence (all reach the same F), print one with the fewest
        on_phase moves. Edges depend only on (configuration, node), so every path found
        here is a path of the decision graph."""
        g = self.graph
        start = [(0, c) for c in dict.fromkeys(g.initials())]
        parent: dict[tuple[int, str], tuple[tuple[int, str], Step] | None] = {
            s: None for s in start}
        queue: deque[tuple[int, str]] = deque(start)
        goal = (len(failures), config)
        while queue and goal not in parent:
            j, c = queue.popleft()
            moves: list[tuple[bool, tuple[int, str], Step]] = []
            if j < len(failures):
                edge = g.edge(c, failures[j])
                if edge.target is not None and edge.target != SAFE:
                    moves.append((True, (j + 1, edge.target),
                                  Step("failure", edge.target, node=failures[j])))
            for phase, target in g.phase_moves(c, j > 0):
                if target is not None:
                    moves.append((False, (j, target), Step("phase", target, phase=phase)))
            for free, state, step in moves:
                if state not in parent:
                    parent[state] = ((j, c), step)
                    # 0-1 BFS: failure steps cost nothing, phase moves one.
                    (queue.appendleft if free else queue.append)(state)
        assert goal in parent, "the model's failure sequence is a path of the graph"
        steps: list[Step] = []
        state = goal
        while parent[state] is not None:
            prev, step = parent[state]  # type: ignore[misc]
            steps.append(step)
            state = prev
        steps.append(Step("start", state[1], phase=g.phase_of[state[1]]))
        return steps[::-1]

    def run(self) -> dict[str, Any]:
        g = self.graph
        start = time.perf_counter()
        levels = self.levels = g.levels()
        self.encode_s += time.perf_counter() - start
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
