"""Generated missions for the oracle agreement tests: valid ones, ones broken by a named
mutation of ``keel_verify.generate``, and ones broken at random (edges retargeted or
removed, placements moved, observers shuffled, interface or spare nodes made failable so
that configurations keep themselves when a node that matters to nothing fails)."""

from __future__ import annotations

import random
from typing import Any

from keel_verify.generate import MUTATIONS, generate, mutate

LOADER_KINDS = {"port-conflict", "unknown-reference"}


def _random_mutation(data: dict[str, Any], rng: random.Random) -> None:
    phases = data["phases"]
    phase = rng.choice(list(phases))
    configs = list(phases[phase]["configurations"])
    config = rng.choice(configs)
    cfg = phases[phase]["configurations"][config]
    processing = [n for n, v in data["nodes"].items() if v["kind"] == "processing"]
    choice = rng.randrange(8)
    if choice == 0:  # retarget an edge
        edges = phases[phase]["on_failure"].setdefault(config, {})
        if edges:
            edges[rng.choice(list(edges))] = rng.choice([*configs, "SAFE"])
    elif choice == 1:  # drop an edge
        edges = phases[phase]["on_failure"].get(config, {})
        if edges:
            del edges[rng.choice(list(edges))]
    elif choice == 2:  # move a task
        if cfg["tasks"]:
            cfg["tasks"][rng.choice(list(cfg["tasks"]))] = rng.choice(list(data["nodes"]))
    elif choice == 3:  # shuffle or trim observers
        observers = list(cfg["observers"])
        rng.shuffle(observers)
        cfg["observers"] = observers[: rng.randrange(len(observers) + 1)]
    elif choice == 4:  # the interface and storage nodes may fail too
        data["tolerance"]["nodes"] = [*data["tolerance"]["nodes"], "IF1", "ST1"]
    elif choice == 5:  # a spare processing node that nothing uses, and may fail
        name = f"PN{len(processing) + 1}"
        data["nodes"][name] = {"kind": "processing", "capabilities": ["eigen"],
                               "capacity": {"cpu": 100, "mem_mb": 1000}}
        data["tolerance"]["nodes"] = [*data["tolerance"]["nodes"], name]
    elif choice == 6:  # retarget an on_phase entry
        for mapping in phases[phase].get("on_phase", {}).values():
            if mapping:
                source = rng.choice(list(mapping))
                target_phase = next(p for p in phases if p != phase)
                mapping[source] = rng.choice(list(phases[target_phase]["configurations"]))
    else:  # change the master
        cfg["master"] = rng.choice(processing)


def case(seed: int) -> tuple[str, dict[str, Any]]:
    """(label, mission data) for one seed: a third valid, a third mutated by kind, a third
    mutated at random."""
    rng = random.Random(seed)
    nodes = rng.randint(2, 5)
    tolerance = rng.randint(0, min(2, nodes - 1))
    phases = rng.randint(1, 2)
    data = generate(nodes, tolerance, seed=seed, phases=phases, tasks_per_node=rng.randint(1, 2))
    data["mission"] = f"oracle-{seed}"
    flavour = seed % 3
    if flavour == 0:
        return "valid", data
    if flavour == 1:
        kinds = [k for k in MUTATIONS if k not in LOADER_KINDS]
        if phases < 2:
            kinds.remove("phase-transition-invalid")
        if tolerance == 0:
            kinds.remove("safe-mode-within-tolerance")
        kind = rng.choice(kinds)
        try:
            return kind, mutate(data, kind, seed)
        except AssertionError:  # nothing of that shape to mutate in this mission
            return "valid", data
    for _ in range(rng.randint(1, 3)):
        _random_mutation(data, rng)
    return "random", data
