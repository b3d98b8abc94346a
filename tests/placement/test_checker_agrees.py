"""The runtime's checker of "valid under F" (core/placement/check.cpp, through keel-place
--batch) against the verifier's (verify/keel_verify/check/model.py, `invalid_under`): on
the shipped missions, generated ones, and generated ones whose loads, capacities,
capabilities, priorities and groups are drawn at random (`fuzzed`), every phase, random configurations (masters of
every kind, observers repeated or failed, tasks missing, extra or misplaced) under random
failed sets of tolerated nodes, the two report the same findings, (kind, task, node) for
(kind, task, node). And the placer's answers pass both checkers.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import random
import subprocess
from pathlib import Path

import pytest
from keel_verify.check.model import DecisionGraph
from keel_verify.cli import main
from keel_verify.generate import generate, to_yaml
from keel_verify.mission import Configuration, load_mission

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = sorted((ROOT / "config").glob("*.yaml"))
QUERIES = int(os.environ.get("KEEL_PLACEMENT_QUERIES", "400"))


def keel_place() -> Path:
    build = os.environ.get("KEEL_BUILD_DIR")
    path = Path(build) / "core" / "placement" / "keel-place" if build else None
    if path is None or not path.is_file():
        pytest.skip("keel-place is not built (KEEL_BUILD_DIR): checked under CTest")
    return path


def compiled(mission: Path, image: Path) -> None:
    # A fuzzed mission's graph need not hold: only its initial configurations are proved.
    depth = ["--max-failures", "0"] if mission.name.startswith("fuzzed-") else []
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        code = main(["compile", str(mission), "-o", str(image), *depth])
    assert code in (0, 1), f"compile exit {code} ({mission})"
    assert image.exists(), f"no image of {mission}"


def ask(image: Path, queries: list[dict]) -> list[dict]:
    run = subprocess.run([str(keel_place()), str(image), "--batch"], check=True, text=True,
                         input="".join(json.dumps(q) + "\n" for q in queries),
                         capture_output=True, timeout=120)
    answers = [json.loads(line) for line in run.stdout.splitlines()]
    assert len(answers) == len(queries), run.stderr
    return answers


def random_configuration(rng: random.Random, mission, phase) -> dict:
    nodes = list(mission.nodes)
    processing = list(mission.processing_nodes)
    master = rng.choice(processing if rng.random() < 0.8 else nodes)
    observers = [rng.choice(processing if rng.random() < 0.85 else nodes)
                 for _ in range(rng.randint(0, 3))]
    tasks = []
    for task in mission.tasks:
        of_phase = task in phase.tasks
        if (of_phase and rng.random() < 0.93) or (not of_phase and rng.random() < 0.05):
            tasks.append([task, rng.choice(nodes)])
    return {"master": master, "observers": observers, "tasks": tasks}


def python_findings(graph: DecisionGraph, phase: str, config: dict,
                    failed: frozenset[str]) -> set[tuple]:
    name = "__probe__"
    graph.configs[name] = Configuration(name=name, phase=phase, master=config["master"],
                                        observers=tuple(config["observers"]),
                                        placement={t: n for t, n in config["tasks"]})
    graph.phase_of[name] = phase
    graph._facts.pop(name, None)  # a new probe: its facts are computed again
    return {(f.kind, f.task, f.node) for f in graph.invalid_under(name, failed)}


def every_node_may_fail(graph: DecisionGraph) -> DecisionGraph:
    """The verifier judges failures of the mission's tolerated nodes only; the runtime's
    checker, any failed set. Compared over every node."""
    graph.tolerance_nodes = tuple(graph.mission.nodes)
    graph._tolerance_set = frozenset(graph.tolerance_nodes)
    return graph


def fuzzed(seed: int) -> dict:
    """A generated mission with its numbers and capabilities drawn at random: every load and
    capacity, every capability a node offers beyond what its initial placements need, every
    task's priority, and a group or none. Its initial configurations stay valid (each node's
    capacity at least what they load on it), so it compiles with --max-failures 0."""
    rng = random.Random(9000 + seed)
    data = generate(nodes=3 + seed % 5, tolerance=1 + seed % 2, seed=500 + seed)
    names = ["eigen", "fpga", "opencv", "radio", "disk", "camera"]
    for task in data["tasks"].values():
        task["load"] = {"cpu": rng.randint(0, 60), "mem_mb": rng.choice((0, 16, 64, 512))}
        task["priority"] = rng.randint(0, 9)
        if rng.random() < 0.3:
            task["group"] = f"g{rng.randint(0, 3)}"
    used: dict[str, dict[str, int]] = {}
    needed: dict[str, set[str]] = {}
    for phase in data["phases"].values():
        initial = phase["configurations"][phase["initial"]]
        load = {}
        for task, node in initial["tasks"].items():
            for what in ("cpu", "mem_mb"):
                load[(node, what)] = load.get((node, what), 0) + data["tasks"][task]["load"][what]
            needed.setdefault(node, set()).update(data["tasks"][task].get("requires", []))
        for (node, what), value in load.items():
            used.setdefault(node, {})[what] = max(used.get(node, {}).get(what, 0), value)
    # Safe mode runs the essential tasks on whichever processing node is Master.
    essential = [t for t in data["tasks"].values() if t.get("essential")]
    for name, node in data["nodes"].items():
        floor = dict(used.get(name, {}))
        if node["kind"] == "processing":
            needed.setdefault(name, set()).update(c for t in essential for c in t.get("requires", []))
            for what in ("cpu", "mem_mb"):
                floor[what] = max(floor.get(what, 0), sum(t["load"][what] for t in essential))
        node["capacity"] = {"cpu": max(floor.get("cpu", 0), rng.randint(0, 200)),
                            "mem_mb": max(floor.get("mem_mb", 0), rng.choice((0, 128, 1024, 4096)))}
        node["capabilities"] = sorted(needed.get(name, set())
                                      | {c for c in names if rng.random() < 0.3})
    return data


def missions(tmp_path: Path) -> list[Path]:
    out = list(SHIPPED)
    for seed in range(4):
        path = tmp_path / f"generated-{seed}.yaml"
        path.write_text(to_yaml(generate(nodes=3 + seed, tolerance=1 + seed % 2, seed=seed)))
        out.append(path)
    for seed in range(6):
        path = tmp_path / f"fuzzed-{seed}.yaml"
        path.write_text(to_yaml(fuzzed(seed)))
        out.append(path)
    return out


def test_the_runtime_checker_and_the_verifier_agree(tmp_path: Path) -> None:
    rng = random.Random(20261130)
    compared = invalid = 0
    kinds: set[str] = set()
    for path in missions(tmp_path):
        mission = load_mission(path)
        image = tmp_path / (path.stem + ".json")
        compiled(path, image)
        graph = every_node_may_fail(DecisionGraph(mission))
        tolerated = list(graph.tolerance_nodes)
        cases = []
        for _ in range(QUERIES):
            phase = rng.choice(list(mission.phases.values()))
            failed = frozenset(n for n in tolerated if rng.random() < 0.25)
            cases.append((phase.name, random_configuration(rng, mission, phase), failed))
        answers = ask(image, [{"op": "check", "phase": p, "failed": sorted(f), "config": c}
                              for p, c, f in cases])
        for (phase, config, failed), answer in zip(cases, answers):
            assert "error" not in answer, answer
            runtime = {(f["kind"], f["task"], f["node"]) for f in answer["findings"]}
            verifier = python_findings(graph, phase, config, failed)
            assert runtime == verifier, (
                f"{path.name} phase {phase} failed {sorted(failed)} {config}: "
                f"runtime only {runtime - verifier}, verifier only {verifier - runtime}")
            compared += 1
            invalid += bool(runtime)
            kinds |= {k for k, _, _ in runtime}
    # Not vacuous: valid and invalid configurations, and every rule broken somewhere.
    assert 0 < invalid < compared
    assert kinds >= {"task-missing", "task-on-failed-node", "capability", "capacity",
                     "master-invalid", "observer-invalid", "storage-unavailable"}, kinds


def test_every_placement_passes_both_checkers(tmp_path: Path) -> None:
    rng = random.Random(7)
    placed = shed = safe = 0
    for path in missions(tmp_path):
        mission = load_mission(path)
        image = tmp_path / (path.stem + ".json")
        compiled(path, image)
        graph = DecisionGraph(mission)
        tolerated = list(graph.tolerance_nodes)
        cases = []
        for phase in mission.phases.values():
            for _ in range(40):
                failed = sorted(n for n in tolerated if rng.random() < 0.3)
                cases.append((phase.name, failed))
        answers = ask(image, [{"op": "place", "phase": p, "failed": f} for p, f in cases])
        checks = []
        for (phase, failed), answer in zip(cases, answers):
            assert "error" not in answer, answer
            if answer["safe"]:
                safe += 1
                continue
            placed += 1
            shed += bool(answer["shed"])
            for task in answer["shed"]:
                assert not mission.tasks[task].essential, (phase, failed, answer)
            if not answer["shed"]:
                assert python_findings(graph, phase, answer["config"], frozenset(failed)) == set(), (
                    phase, failed, answer)
            checks.append({"op": "check", "phase": phase, "failed": failed,
                           "config": answer["config"], "shedding": True})
        for answer in ask(image, checks):
            assert answer["findings"] == [], answer
    assert placed > 0 and safe > 0 and shed > 0, (placed, shed, safe)


def test_a_query_naming_what_the_mission_lacks_is_answered_with_an_error(tmp_path: Path) -> None:
    image = tmp_path / "eo.json"
    compiled(ROOT / "config" / "earth_observation.yaml", image)
    answers = ask(image, [{"op": "check", "phase": "nope", "config": "C1"},
                          {"op": "place", "phase": "observation", "failed": ["PN9"]},
                          {"op": "check", "phase": "observation", "config": {"master": "PN1",
                                                                             "tasks": [["x", "PN1"]]}},
                          {"op": "fly"}])
    assert [a.get("error") for a in answers] == ["no phase nope", "no node PN9", "no task x",
                                                 "malformed query: " + answers[3]["error"][17:]]
