"""One semantics of the decision graph: the verifier and the runtime read it alike.

The prover's reading is `DecisionGraph.edge` (verify/README.md, "The semantics,
precisely"); the runtime's is what keel-node's state machines decide when a node fails
(`keel-graph-walk`, tests/verify/graph_walk.cpp: `ReconfigurationManager::take_over` for
the master's failure, `exclude` for any other node's, over `Topology::walk`). For every
mission `keel-verify compile` proves, from every state the prover explores (configuration,
failed set) and every failure it explores from there, both must name the same next
configuration. The two readings once differed in two places, decided as follows:

- an explicit edge for a node that matters to nothing: the prover followed it, the runtime
  kept the configuration. Both follow it now (`Topology::walk`).
- an edge for a node other than the master that leads to a configuration another node is
  the master of: the prover followed it, the runtime entered SAFE (the Master drives the
  switch and stays Master). The verifier now reports it (`master-mismatch`), so no proved
  mission has one.

The missions: `keel_verify.generate`'s (2 to 6 processing nodes, spares, one or two
phases; their graphs have edges for nodes that matter to nothing), the same with edges
added at random where they still prove, and the shipped missions. `KEEL_GRAPH_MISSIONS`
sets how many generated ones (default 60).
"""

from __future__ import annotations

import contextlib
import io
import os
import random
import subprocess
from collections import deque
from pathlib import Path

import pytest
from explicit import explore
from keel_verify.check.model import SAFE, DecisionGraph
from keel_verify.cli import main
from keel_verify.generate import generate, to_mission, to_yaml
from keel_verify.mission import load_mission
from keel_verify.trace import switch

ROOT = Path(__file__).resolve().parents[2]
COUNT = int(os.environ.get("KEEL_GRAPH_MISSIONS", "60"))
SHIPPED = sorted((ROOT / "config").glob("*.yaml"))

State = tuple[str, frozenset[str]]


def walk_binary() -> Path:
    build = os.environ.get("KEEL_BUILD_DIR")
    path = Path(build) / "tests" / "verify" / "keel-graph-walk" if build else None
    if path is None or not path.is_file():
        pytest.skip("keel-graph-walk is not built (KEEL_BUILD_DIR): checked under CTest")
    return path


def compiled(mission: Path, image: Path) -> bool:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        code = main(["compile", str(mission), "-o", str(image)])
    assert code in (0, 1), f"compile exit {code} ({mission})"
    return code == 0


def explored(graph: DecisionGraph) -> list[tuple[State, str, str]]:
    """Every (state, failing node, next configuration) the prover explores: from each
    phase's initial configuration with nothing failed, failures of tolerance nodes up to the
    depth, and on_phase moves."""
    start = [(c, frozenset()) for c in dict.fromkeys(graph.initials())]
    seen: set[State] = set(start)
    queue: deque[State] = deque(start)
    steps: list[tuple[State, str, str]] = []
    while queue:
        config, failed = queue.popleft()
        following: list[State] = []
        if len(failed) < graph.depth:
            for x in graph.tolerance_nodes:
                if x in failed:
                    continue
                target = graph.edge(config, x).target
                assert target is not None, f"a proved mission has no edge of {config} for {x}"
                steps.append(((config, failed), x, target))
                if target != SAFE:
                    following.append((target, failed | {x}))
        following += [(t, failed) for _, t in graph.phase_moves(config) if t is not None]
        for state in following:
            if state not in seen:
                seen.add(state)
                queue.append(state)
    return steps


def runtime_reads(image: Path, steps: list[tuple[State, str, str]]) -> list[str]:
    queries = "".join(f"{config} {x} {' '.join(sorted(failed))}\n"
                      for (config, failed), x, _ in steps)
    done = subprocess.run([str(walk_binary()), str(image)], input=queries, capture_output=True,
                          text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


def disagreements(mission: Path, image: Path) -> tuple[list[str], int, int]:
    """The steps the two readers decide differently (as messages), how many steps were
    compared, and how many of them follow an explicit edge for a node that matters to
    nothing to another configuration."""
    graph = DecisionGraph(load_mission(str(mission)))
    steps = explored(graph)
    runtime = runtime_reads(image, steps)
    assert len(runtime) == len(steps)
    # Beyond the graph of a graph+online phase, where the graph says SAFE, the runtime's
    # placer answers (core/fsm/online.hpp; keel-place --prove proves its answers): SAFE in
    # the verifier's reading of the graph, "online" in the runtime's.
    def beyond(config: str, target: str, actual: str) -> bool:
        placement = graph.mission.phases[graph.phase_of[config]].placement
        return placement == "graph+online" and target == "SAFE" and actual in ("online", "SAFE")

    wrong = [f"{mission.name}: {x} fails in {config} with {sorted(failed) or 'none'} failed: "
             f"the verifier goes to {target}, the runtime to {actual}"
             for ((config, failed), x, target), actual in zip(steps, runtime, strict=True)
             if actual != target and not beyond(config, target, actual)]
    unmattering = sum(1 for (config, _failed), x, target in steps
                      if x not in graph.matters(config) and target != config)
    return wrong, len(steps), unmattering


def with_random_edges(data: dict, seed: int) -> dict:
    """Edges added for nodes that matter to nothing, each to another configuration of the
    phase with the same master (the only kind a proof can accept)."""
    rng = random.Random(seed)
    mission = to_mission(data)
    graph = DecisionGraph(mission)
    for phase in data["phases"].values():
        names = list(phase["configurations"])
        for config in names:
            idle = [x for x in graph.tolerance_nodes if x not in graph.matters(config)]
            if not idle or rng.random() < 0.5:
                continue
            x = rng.choice(idle)
            master = phase["configurations"][config]["master"]
            same = [c for c in names if c != config
                    and phase["configurations"][c]["master"] == master]
            if same:
                phase["on_failure"].setdefault(config, {})[x] = rng.choice(same)
    return data


def generated(seed: int) -> dict:
    rng = random.Random(seed)
    nodes = rng.randrange(2, 7)
    return generate(nodes, rng.randrange(1, min(2, nodes - 1) + 1), seed=seed,
                    phases=rng.choice([1, 2]), tasks_per_node=rng.randrange(1, 3),
                    spares=rng.randrange(0, 3))


def test_the_runtime_reads_every_proved_graph_as_the_verifier_does(tmp_path: Path) -> None:
    walk_binary()
    compared = unmattering = proved = varied = 0
    wrong: list[str] = []
    for seed in range(COUNT):
        for variant, data in (("generated", generated(seed)),
                              ("edges", with_random_edges(generated(seed), seed))):
            mission = tmp_path / f"{variant}-{seed}.yaml"
            mission.write_text(to_yaml(data), encoding="utf-8")
            image = tmp_path / f"{variant}-{seed}.json"
            if not compiled(mission, image):
                continue  # an added edge the proof refuses (or a spare the generator's
                # tolerance leaves without an observer): nothing flies, nothing to compare
            proved += 1
            varied += variant == "edges"
            found, steps, idle = disagreements(mission, image)
            wrong += found
            compared += steps
            unmattering += idle
    assert not wrong, (f"{len(wrong)} of {compared} steps read differently:\n"
                       + "\n".join(wrong[:20]))
    # Not vacuous: many steps, and many of them an edge for a node that matters to nothing
    # (the runtime's walk once skipped those), on the generator's graphs and varied ones.
    assert proved >= COUNT and varied >= COUNT // 4, (proved, varied)
    assert compared >= 50 * COUNT and unmattering >= 4 * COUNT, (compared, unmattering)


def test_trace_validation_readmits_as_the_runtime_does(tmp_path: Path) -> None:
    # keel-verify trace's model of a readmission (switch._recovery: the on_recovery edge,
    # else the walk from the phase's initial configuration) against the runtime's
    # (Topology::recovery_target), for every explored state and every failed node in it.
    walk_binary()
    compared = 0
    wrong: list[str] = []
    for seed in range(COUNT):
        data = with_random_edges(generated(seed), seed)
        path = tmp_path / f"recover-{seed}.yaml"
        path.write_text(to_yaml(data), encoding="utf-8")
        image = tmp_path / f"recover-{seed}.json"
        if not compiled(path, image):
            continue
        mission = load_mission(str(path))
        graph = DecisionGraph(mission)
        storage = next(iter(mission.storage_nodes), None)
        states = sorted({(config, failed) for (config, failed), _x, _t in explored(graph)
                         if failed}, key=lambda s: (s[0], sorted(s[1])))
        queries = [(config, x, failed) for config, failed in states for x in sorted(failed)]
        done = subprocess.run(
            [str(walk_binary()), str(image)], capture_output=True, text=True, timeout=120,
            check=False, input="".join(f"recover {c} {x} {' '.join(sorted(f))}\n"
                                       for c, x, f in queries))
        assert done.returncode == 0, done.stderr
        for (config, x, failed), runtime in zip(queries, done.stdout.split(), strict=True):
            traced = switch._recovery(config, x, set(failed - {x}), mission, storage,
                                      graph.phase_of)
            compared += 1
            if traced != runtime:
                wrong.append(f"{path.name}: readmitting {x} in {config} with "
                             f"{sorted(failed)} failed: trace validation {traced}, "
                             f"the runtime {runtime}")
    assert not wrong, "\n".join(wrong[:20])
    assert compared >= 2 * COUNT, compared


@pytest.mark.parametrize("mission", SHIPPED, ids=lambda p: p.stem)
def test_the_shipped_missions_read_alike(tmp_path: Path, mission: Path) -> None:
    walk_binary()
    image = tmp_path / f"{mission.stem}.json"
    assert compiled(mission, image), mission
    found, steps, _ = disagreements(mission, image)
    assert not found, "\n".join(found)
    assert steps > 0


def test_an_edge_that_hands_the_cluster_to_another_master_on_a_workers_failure_is_refused(
        tmp_path: Path) -> None:
    # The runtime enters SAFE on such an edge (the Master drives the switch and stays): the
    # verifier now says so at the edge, naming both masters.
    data = generate(4, 1, seed=3, phases=1)
    phase = next(iter(data["phases"].values()))
    configs = phase["configurations"]
    initial = phase["initial"]
    master = configs[initial]["master"]
    worker, other = next((x, c) for x in phase["on_failure"][initial] if x != master
                         for c, cfg in configs.items() if cfg["master"] not in (master, x))
    phase["on_failure"][initial][worker] = other
    mission = tmp_path / "hand-off-on-failure.yaml"
    mission.write_text(to_yaml(data), encoding="utf-8")
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        code = main(["check", str(mission), "--suggest"])
    assert code == 1, out.getvalue()
    assert (f"master-mismatch: {worker}, not the master, fails in {initial} and {other} names "
            f"master {configs[other]['master']}, but the master {master} drives the switch "
            "and stays master") in out.getvalue()
    # The smallest fix first: the edge the generator wrote, to the configuration that keeps
    # the master.
    kept = generate(4, 1, seed=3, phases=1)["phases"][next(iter(data["phases"]))]
    right = kept["on_failure"][initial][worker]
    assert (f"suggest: set on_failure {initial}: {{{worker}: {right}}} (configuration {right} "
            f"is valid under failures {worker} and its master is {master})") in out.getvalue()
    # The explicit-state oracle reads the rule as the prover does.
    assert ("master-mismatch", next(iter(data["phases"])), initial, "", worker, "") in \
        explore(load_mission(str(mission))).violations
