"""Generated missions for the benchmark and the oracle tests, and mutations that break them.

``generate(nodes, tolerance, seed)`` builds a valid mission constructively: N processing
nodes, 4N tasks, a storage node and an interface node, and a complete decision graph
with one configuration per set of at most ``tolerance`` failed processing nodes. Masters
and observers follow one election order (master = first alive node of the order,
observers = the next two alive ones), so a master failure always hands over to the first
alive observer; tasks are placed first-fit along a per-task preference ring, which keeps
most tasks where they were when a node fails. Failure sets beyond the tolerance go to
SAFE. The result is plain data (the YAML document) so mutations can edit it.

``MUTATIONS`` maps every violation kind a loadable mission can have to a function that
breaks exactly that rule somewhere in a generated mission (others may break with it).
"""

from __future__ import annotations

import itertools
import json
import random
import re
from collections.abc import Callable
from typing import Any

import yaml

from keel_verify.mission import (
    Configuration,
    Heartbeat,
    Mission,
    Node,
    Phase,
    Resources,
    Task,
    Tolerance,
)

Data = dict[str, Any]

TASK_CPU = 10
TASK_MEM_MB = 32


def _name(prefix: str, failed: tuple[int, ...]) -> str:
    return prefix + ("0" if not failed else "_".join(str(i + 1) for i in failed))


def generate(nodes: int, tolerance: int, seed: int = 0, phases: int = 2,
             tasks_per_node: int = 4, spares: int = 0, placement: str = "graph") -> Data:
    """A valid mission of ``nodes`` processing nodes tolerating ``tolerance`` failures.

    ``spares`` adds processing nodes that may fail but host nothing and are never master
    or observer: their failures keep the configuration (no edge), so the failure sets
    reachable in one configuration multiply (2^spares) while the graph stays the same.

    ``placement`` is every phase's (docs/missions.md, "Placement modes and what is
    proved"): ``online`` keeps each phase's initial configuration alone, with no failure
    edges (capacity is sized for the tolerance all the same); ``graph+online`` keeps the
    graph.
    """
    assert placement in ("graph", "online", "graph+online")
    assert nodes >= 2 and 0 <= tolerance < nodes, "at least one processing node must remain"
    rng = random.Random(seed)
    pn = [f"PN{i + 1}" for i in range(nodes)]
    alive_min = nodes - tolerance
    # fpga on half the nodes when enough of them survive every tolerated failure set.
    fpga_nodes = {p for i, p in enumerate(pn) if i % 2 == 0}
    if len(fpga_nodes) <= tolerance:
        fpga_nodes = set(pn)
    n_tasks = max(4, tasks_per_node * nodes)  # camera, sink, and an essential task at least
    kinds = []
    for i in range(n_tasks - 2):
        if i == 0:
            kinds.append("essential")
        elif rng.random() < 0.25:
            kinds.append("fpga")
        elif rng.random() < 0.1:
            kinds.append("checkpoint")
        else:
            kinds.append("plain")
    total_cpu = (n_tasks - 2) * TASK_CPU
    fpga_cpu = kinds.count("fpga") * TASK_CPU
    # Room for every task on the nodes that survive, and for the fpga tasks on the fpga
    # nodes that survive, plus slack for first-fit.
    need = max(-(-total_cpu * 3 // (2 * alive_min)),
               -(-fpga_cpu * 3 // (2 * (len(fpga_nodes) - tolerance))))
    cpu = max(100, need // 10 * 10 + 10)
    mem = cpu * 4 * TASK_MEM_MB // TASK_CPU
    node_data: Data = {}
    for p in pn:
        caps = ["eigen"] + (["fpga"] if p in fpga_nodes else [])
        node_data[p] = {"kind": "processing", "capabilities": caps,
                        "capacity": {"cpu": cpu, "mem_mb": mem}}
    node_data["ST1"] = {"kind": "interface", "role": "storage", "capabilities": ["disk"],
                        "capacity": {"cpu": 40, "mem_mb": 4096}}
    node_data["IF1"] = {"kind": "interface", "role": "interface", "capabilities": ["camera"],
                        "capacity": {"cpu": 40, "mem_mb": 512}}
    tasks: Data = {"camera": {"port": 1000, "requires": ["camera"],
                              "load": {"cpu": TASK_CPU, "mem_mb": TASK_MEM_MB}},
                   "sink": {"port": 1001, "requires": ["disk"],
                            "load": {"cpu": TASK_CPU, "mem_mb": TASK_MEM_MB}}}
    for i, kind in enumerate(kinds):
        task: Data = {"port": 2000 + i, "load": {"cpu": TASK_CPU, "mem_mb": TASK_MEM_MB}}
        if kind == "essential":
            task.update({"requires": ["eigen"], "essential": True, "checkpoint": True})
        elif kind == "fpga":
            task["requires"] = ["fpga"]
        elif kind == "checkpoint":
            task["checkpoint"] = True
        tasks[f"t{i}"] = task
    for i in range(spares):
        node_data[f"SP{i + 1}"] = {"kind": "processing", "capabilities": ["eigen"],
                                   "capacity": {"cpu": cpu, "mem_mb": mem}}
    data: Data = {
        "mission": f"generated-{nodes}n-k{tolerance}-s{seed}" + (f"-sp{spares}" if spares else ""),
        "schema": 1,
        "heartbeat": {"period_ms": 100, "miss_limit": 3},
        "tolerance": {"node_failures": tolerance,
                      "nodes": list(pn) + [f"SP{i + 1}" for i in range(spares)]},
        "nodes": node_data,
        "tasks": tasks,
        "phases": {},
    }
    all_tasks = list(tasks)
    phase_specs = [("observation", "O", all_tasks)]
    if phases >= 2:
        phase_specs.append(("downlink", "D", [t for t in all_tasks if t != "camera"]))
    for phase, prefix, phase_tasks in phase_specs:
        graph = _phase(data, pn, tolerance if placement != "online" else 0, prefix, phase_tasks)
        if placement == "online":
            del graph["on_failure"]
        if placement != "graph":
            graph = {"placement": placement, **graph}
        data["phases"][phase] = graph
    if placement != "graph":
        data["mission"] += "-" + placement.replace("+", "-")
    if phases >= 2:
        p0, p1 = phase_specs[0][0], phase_specs[1][0]
        names0 = list(data["phases"][p0]["configurations"])
        names1 = list(data["phases"][p1]["configurations"])
        data["phases"][p0]["on_phase"] = {p1: dict(zip(names0, names1, strict=True))}
        data["phases"][p1]["on_phase"] = {p0: dict(zip(names1, names0, strict=True))}
    return data


def _phase(data: Data, pn: list[str], tolerance: int, prefix: str,
           phase_tasks: list[str]) -> Data:
    nodes = data["nodes"]
    tasks = data["tasks"]
    index = {p: i for i, p in enumerate(pn)}
    configurations: Data = {}
    on_failure: Data = {}
    # Per task: a fixed home (camera, sink) or a preference ring with a per-task stride,
    # which spreads a failed node's tasks over several others.
    fixed: dict[str, str] = {}
    rings: dict[str, list[str]] = {}
    needs: dict[str, set[str]] = {}
    for t_index, task in enumerate(phase_tasks):
        requires = set(tasks[task].get("requires", []))
        needs[task] = requires
        if "camera" in requires:
            fixed[task] = "IF1"
        elif "disk" in requires:
            fixed[task] = "ST1"
        else:
            home = (t_index - 2) % len(pn) if t_index >= 2 else 0
            stride = 1 + (t_index % max(1, len(pn) - 1))
            ring = [pn[(home + j * stride) % len(pn)] for j in range(len(pn))]
            ring += [p for p in pn if p not in ring]
            rings[task] = [p for p in dict.fromkeys(ring)
                           if requires <= set(nodes[p]["capabilities"])]
    cpu_limit = {p: nodes[p]["capacity"]["cpu"] for p in pn}
    for size in range(tolerance + 1):
        for failed in itertools.combinations(range(len(pn)), size):
            down = {pn[i] for i in failed}
            alive = [p for p in pn if p not in down]
            name = _name(prefix, failed)
            placement: dict[str, str] = {}
            used: dict[str, int] = {}
            # The most constrained tasks first, so first-fit leaves them room.
            for task in sorted(phase_tasks, key=lambda t: len(rings.get(t, pn))):
                if task in fixed:
                    placement[task] = fixed[task]
                    continue
                for p in rings[task]:
                    if p in down or used.get(p, 0) + TASK_CPU > cpu_limit[p]:
                        continue
                    placement[task] = p
                    used[p] = used.get(p, 0) + TASK_CPU
                    break
                else:  # pragma: no cover - capacity is sized so first-fit always succeeds
                    raise AssertionError(f"no node for {task} under failures {sorted(down)}")
            placement = {t: placement[t] for t in phase_tasks}
            configurations[name] = {"master": alive[0], "observers": alive[1:3],
                                    "tasks": placement}
            edges = {}
            for x in pn:
                if x in down:
                    continue
                if size < tolerance:
                    edges[x] = _name(prefix, tuple(sorted(failed + (index[x],))))
                else:
                    edges[x] = "SAFE"
            on_failure[name] = edges
    return {"tasks": list(phase_tasks), "initial": prefix + "0",
            "configurations": configurations, "on_failure": on_failure}


# ------------------------------------------------------------------------------ output


_PLAIN = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")
_RESERVED_WORDS = {"true", "false", "null", "yes", "no", "on", "off", "y", "n", "~"}


def to_yaml(data: Data, comment: str | None = None) -> str:
    """YAML text with one line per node, task, configuration and edge map."""
    out = [f"# {line}" for line in (comment or f"Generated: {data['mission']}").splitlines()]
    for key in ("mission", "schema", "heartbeat", "tolerance"):
        if key in data:
            out.append(f"{key}: {flow(data[key])}")
    for section in ("nodes", "tasks"):
        out.append(f"{section}:" if data[section] else f"{section}: {{}}")
        for name, value in data[section].items():
            out.append(f"  {name}: {flow(value)}")
    out.append("phases:")
    for name, phase in data["phases"].items():
        out.append(f"  {name}:")
        for key, value in phase.items():
            if key in ("configurations", "on_failure", "on_phase", "params") and value:
                out.append(f"    {key}:")
                for inner, item in value.items():
                    out.append(f"      {inner}: {flow(item)}")
            elif key not in ("on_failure", "on_phase", "params"):
                out.append(f"    {key}: {flow(value)}")
    return "\n".join(out) + "\n"


def flow(value: Any) -> str:
    """One value in YAML flow style, read back identically by the mission loader."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "null"
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, str):
        if _PLAIN.match(value) and value.lower() not in _RESERVED_WORDS:
            return value
        # Non-ASCII text as it is: JSON's \u escapes of a character beyond U+FFFF are a
        # surrogate pair, which YAML does not read as one character.
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(flow(v) for v in value) + "]"
    assert isinstance(value, dict), f"cannot write {type(value).__name__} as YAML"
    return "{" + ", ".join(f"{flow(k)}: {flow(v)}" for k, v in value.items()) + "}"


# ------------------------------------------------------------------------------ mutations


def _configs(data: Data) -> list[tuple[str, str, Data]]:
    return [(p, c, cfg) for p, phase in data["phases"].items()
            for c, cfg in phase["configurations"].items()]


def _failed_of(name: str) -> list[str]:
    tail = name[1:]
    return [] if tail == "0" else [f"PN{i}" for i in tail.split("_")]


def _pick(rng: random.Random, items: list[Any]) -> Any:
    assert items, "a generated mission has something to mutate"
    return items[rng.randrange(len(items))]


def _non_initial(data: Data) -> list[tuple[str, str, Data]]:
    return [(p, c, cfg) for p, c, cfg in _configs(data) if _failed_of(c)]


def mutate_missing_transition(data: Data, rng: random.Random) -> None:
    phase, name, cfg = _pick(rng, _configs(data))
    tolerated = set(data["tolerance"]["nodes"])
    node = _pick(rng, sorted({cfg["master"], *cfg["tasks"].values()} & tolerated))
    del data["phases"][phase]["on_failure"][name][node]


def mutate_task_on_failed_node(data: Data, rng: random.Random) -> None:
    _, name, cfg = _pick(rng, _non_initial(data))
    task = _pick(rng, [t for t, n in cfg["tasks"].items() if n.startswith("PN")])
    cfg["tasks"][task] = _pick(rng, _failed_of(name))


def mutate_capability(data: Data, rng: random.Random) -> None:
    _, _, cfg = _pick(rng, _configs(data))
    task = _pick(rng, [t for t, n in cfg["tasks"].items() if n in ("IF1", "ST1")])
    cfg["tasks"][task] = cfg["master"]


def mutate_capacity(data: Data, rng: random.Random) -> None:
    task = _pick(rng, [t for t in data["tasks"] if t.startswith("t")])
    data["tasks"][task]["load"]["cpu"] = 10_000


def mutate_task_missing(data: Data, rng: random.Random) -> None:
    _, _, cfg = _pick(rng, _configs(data))
    del cfg["tasks"][_pick(rng, list(cfg["tasks"]))]


def mutate_master_invalid(data: Data, rng: random.Random) -> None:
    _, name, cfg = _pick(rng, _configs(data))
    failed = _failed_of(name)
    cfg["master"] = _pick(rng, failed) if failed and rng.random() < 0.5 else "ST1"


def mutate_observer_invalid(data: Data, rng: random.Random) -> None:
    _, name, cfg = _pick(rng, _configs(data))
    choice = rng.randrange(3)
    if choice == 0:
        cfg["observers"] = []
    elif choice == 1:
        cfg["observers"] = [*cfg["observers"], "IF1"]
    else:
        cfg["observers"] = [cfg["master"], *cfg["observers"]]


def mutate_master_mismatch(data: Data, rng: random.Random) -> None:
    handovers = [(p, c, cfg) for p, c, cfg in _configs(data)
                 if data["phases"][p]["on_failure"][c].get(cfg["master"], "SAFE") != "SAFE"]
    phase, name, cfg = _pick(rng, handovers)
    if len(cfg["observers"]) >= 2:
        cfg["observers"] = [cfg["observers"][1], cfg["observers"][0], *cfg["observers"][2:]]
    else:  # the successor names a master the election cannot pick
        target = data["phases"][phase]["on_failure"][name][cfg["master"]]
        data["phases"][phase]["configurations"][target]["master"] = cfg["master"]


def mutate_storage_unavailable(data: Data, rng: random.Random) -> None:
    data["nodes"]["ST1"]["role"] = "interface"


def mutate_safe_within_tolerance(data: Data, rng: random.Random) -> None:
    k = data["tolerance"]["node_failures"]
    choices = [(p, c) for p, c, _ in _configs(data) if len(_failed_of(c)) < k]
    phase, name = _pick(rng, choices)
    edges = data["phases"][phase]["on_failure"][name]
    edges[_pick(rng, list(edges))] = "SAFE"


def mutate_phase_transition_invalid(data: Data, rng: random.Random) -> None:
    phases = [p for p, ph in data["phases"].items() if ph.get("on_phase")]
    phase = _pick(rng, phases)
    (target_phase, mapping), = data["phases"][phase]["on_phase"].items()
    source = _pick(rng, [c for c in mapping if _failed_of(c)])
    if rng.random() < 0.5:
        del mapping[source]
    else:
        mapping[source] = data["phases"][target_phase]["initial"]


def mutate_safe_mode_unhostable(data: Data, rng: random.Random) -> None:
    _, _, cfg = _pick(rng, _configs(data))
    node = _pick(rng, cfg["observers"] or [cfg["master"]])
    caps = data["nodes"][node]["capabilities"]
    data["nodes"][node]["capabilities"] = [c for c in caps if c != "eigen"]


def mutate_port_conflict(data: Data, rng: random.Random) -> None:
    a, b = rng.sample(list(data["tasks"]), 2)
    data["tasks"][b]["port"] = data["tasks"][a]["port"]


def mutate_unknown_reference(data: Data, rng: random.Random) -> None:
    _, _, cfg = _pick(rng, _configs(data))
    cfg["master"] = "PN99"


MUTATIONS: dict[str, Callable[[Data, random.Random], None]] = {
    "missing-transition": mutate_missing_transition,
    "task-on-failed-node": mutate_task_on_failed_node,
    "capability": mutate_capability,
    "capacity": mutate_capacity,
    "task-missing": mutate_task_missing,
    "master-invalid": mutate_master_invalid,
    "observer-invalid": mutate_observer_invalid,
    "master-mismatch": mutate_master_mismatch,
    "storage-unavailable": mutate_storage_unavailable,
    "safe-mode-within-tolerance": mutate_safe_within_tolerance,
    "phase-transition-invalid": mutate_phase_transition_invalid,
    "safe-mode-unhostable": mutate_safe_mode_unhostable,
    "port-conflict": mutate_port_conflict,
    "unknown-reference": mutate_unknown_reference,
}


def mutate(data: Data, kind: str, seed: int) -> Data:
    """A deep copy of ``data`` with the rule ``kind`` broken."""
    copy = yaml.safe_load(yaml.safe_dump(data))
    MUTATIONS[kind](copy, random.Random(seed))
    copy["mission"] = f"{data['mission']}-{kind}"
    return copy


def to_mission(data: Data, path: str = "<generated>") -> Mission:
    """The :class:`Mission` of generated data without writing and parsing YAML (the
    benchmark uses it to time the prover apart from the loader; lines are 0)."""
    nodes = {
        name: Node(name=name, kind=raw["kind"],
                   role=raw.get("role", "interface") if raw["kind"] == "interface" else None,
                   capabilities=tuple(raw.get("capabilities", [])),
                   capacity=Resources(raw.get("capacity", {}).get("cpu"),
                                      raw.get("capacity", {}).get("mem_mb")))
        for name, raw in data["nodes"].items()
    }
    tasks = {
        name: Task(name=name, port=raw["port"], component=raw.get("component", name),
                   requires=tuple(raw.get("requires", [])),
                   load=Resources(raw.get("load", {}).get("cpu", 0),
                                  raw.get("load", {}).get("mem_mb", 0)),
                   essential=raw.get("essential", False), checkpoint=raw.get("checkpoint", False),
                   inputs=tuple(raw.get("inputs", [])), period_ms=raw.get("period_ms"),
                   health=None, params={})
        for name, raw in data["tasks"].items()
    }
    phases = {}
    for name, raw in data["phases"].items():
        configurations = {
            c: Configuration(name=c, phase=name, master=cfg["master"],
                             observers=tuple(cfg.get("observers", [])),
                             placement=dict(cfg["tasks"]))
            for c, cfg in raw["configurations"].items()
        }
        phases[name] = Phase(name=name, tasks=tuple(raw.get("tasks", list(tasks))),
                             initial=raw["initial"], configurations=configurations,
                             on_failure={c: dict(e) for c, e in raw.get("on_failure", {}).items()},
                             on_phase={p: dict(m) for p, m in raw.get("on_phase", {}).items()},
                             params={})
    tolerance = data["tolerance"]
    return Mission(name=data["mission"], path=path,
                   heartbeat=Heartbeat(data["heartbeat"]["period_ms"],
                                       data["heartbeat"]["miss_limit"]),
                   tolerance=Tolerance(tolerance["node_failures"],
                                       tuple(tolerance.get("nodes", list(nodes)))),
                   nodes=nodes, tasks=tasks, phases=phases)
