"""Scenario files: timed faults and commands for an emulated cluster.

A scenario is YAML::

    duration: 12s                 # how long the run lasts (default 10s)
    events:                       # timed events, any order
      - at 5s kill PN2            # SIGKILL the node's process
      - at 6s restart PN2         # start it again
      - at 8s partition PN3       # cut PN3 off (link down in netns mode, transport otherwise)
      - at 9s heal PN3
      - at 10s phase downlink     # planned phase change: a ground command (the Master acts)
      - at 11s exclude PN3        # a ground command: PN3 is held out (it resigns) until readmitted
      - at 14s readmit PN3        # a ground command: PN3 may be readmitted again
      - at 16s update m2.yaml     # every node restarts on this mission's image (revision above)
      - at 12s recover C4         # a ground command: leave safe mode for C4 (the Master checks)
      - at 13s pause-task acca1   # a ground command: acca1 stops where it runs, stays placed
      - at 15s resume-task acca1  # a ground command: it runs again from its last state
      - at 17s designate PN2      # a ground command: the ground's vote for PN2 to take over a
                                  # tie (a mission with heartbeat.tie_grace; a secured run)
    random:                       # optional: a campaign drawn from a seed
      seed: 7
      kills: 2                    # node kills at random times, random processing nodes
      restart_after: 2s           # each killed node restarts this much later (omit: never)
      between: [2s, 9s]

Every error names the file, the line and what is wrong.
"""

from __future__ import annotations

import random
import re
from dataclasses import dataclass, field
from pathlib import Path

import yaml

ACTIONS = {"kill": 1, "restart": 1, "partition": 1, "heal": 1, "phase": 1, "deaf": 1, "pause": 1,
           "resume": 1, "recover": 1, "exclude": 1, "readmit": 1, "update": 1, "pause-task": 1,
           "resume-task": 1, "designate": 1}
_DURATION = re.compile(r"^(\d+(?:\.\d+)?)(ms|s|m)$")


class ScenarioError(Exception):
    pass


def parse_duration_s(text: str | int | float, where: str) -> float:
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        return float(text)
    match = _DURATION.match(str(text).strip())
    if not match:
        raise ScenarioError(f"{where}: '{text}' is not a duration (e.g. 300ms, 5s, 2m)")
    value, unit = float(match.group(1)), match.group(2)
    return value / 1000.0 if unit == "ms" else value * 60.0 if unit == "m" else value


@dataclass(frozen=True, order=True)
class Event:
    at_s: float
    action: str
    argument: str
    origin: str = field(default="", compare=False)

    def __str__(self) -> str:
        return f"at {self.at_s:g}s {self.action} {self.argument}"


@dataclass
class Scenario:
    duration_s: float = 10.0
    events: list[Event] = field(default_factory=list)


def parse_event(text: str, where: str, nodes: set[str], phases: set[str],
                configs: set[str] | None = None, tasks: set[str] | None = None) -> Event:
    words = str(text).split()
    if len(words) != 4 or words[0] != "at":
        raise ScenarioError(f"{where}: expected 'at TIME ACTION ARGUMENT', got '{text}'")
    at_s = parse_duration_s(words[1], where)
    action, argument = words[2], words[3]
    if action not in ACTIONS:
        raise ScenarioError(f"{where}: unknown action '{action}' (known: {', '.join(ACTIONS)})")
    if action == "phase":
        if argument not in phases:
            raise ScenarioError(f"{where}: phase '{argument}' is not in the mission")
    elif action == "update":
        # A new mission (YAML or image) every node restarts on (docs/operations.md).
        if not Path(argument).is_file():
            raise ScenarioError(f"{where}: update: no mission file {argument!r}")
    elif action == "recover":
        # A ground command leaving safe mode for a configuration (the Master decides).
        if configs is not None and argument not in configs:
            raise ScenarioError(f"{where}: configuration '{argument}' is not in the mission")
    elif action in ("pause-task", "resume-task"):
        # A ground command pausing a task where it runs, or resuming it (every node takes it).
        if tasks is not None and argument not in tasks:
            raise ScenarioError(f"{where}: task '{argument}' is not in the mission")
    elif argument not in nodes:
        raise ScenarioError(f"{where}: node '{argument}' is not in the mission")
    return Event(at_s, action, argument, where)


def load_scenario(path: str | Path, nodes: set[str], processing: list[str], phases: set[str],
                  configs: set[str] | None = None, tasks: set[str] | None = None) -> Scenario:
    name = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as error:
        raise ScenarioError(f"{name}: cannot read: {error.strerror}") from None
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f"{name}:{mark.line + 1}:{mark.column + 1}" if mark else name
        raise ScenarioError(f"{where}: not valid YAML") from None
    if root is None:
        return Scenario()
    if not isinstance(root, yaml.MappingNode):
        raise ScenarioError(f"{name}:1:1: a scenario is a mapping with duration, events, random")
    scenario = Scenario()
    for key_node, value_node in root.value:
        where = f"{name}:{key_node.start_mark.line + 1}:{key_node.start_mark.column + 1}"
        key = key_node.value
        value = yaml.safe_load(yaml.serialize(value_node))
        if key == "duration":
            scenario.duration_s = parse_duration_s(value, where)
        elif key == "events":
            if not isinstance(value_node, yaml.SequenceNode):
                raise ScenarioError(f"{where}: events must be a list of 'at TIME ACTION ARGUMENT'")
            for item in value_node.value:
                item_where = f"{name}:{item.start_mark.line + 1}:{item.start_mark.column + 1}"
                scenario.events.append(parse_event(item.value, item_where, nodes, phases, configs, tasks))
        elif key == "random":
            scenario.events.extend(_random_events(value, where, processing))
        else:
            raise ScenarioError(f"{where}: unknown key '{key}' (known: duration, events, random)")
    scenario.events.sort()
    late = [e for e in scenario.events if e.at_s >= scenario.duration_s]
    if late:
        raise ScenarioError(f"{late[0].origin}: event '{late[0]}' is after the end of the run")
    return scenario


def _random_events(spec: object, where: str, processing: list[str]) -> list[Event]:
    if not isinstance(spec, dict):
        raise ScenarioError(f"{where}: random must be a mapping (seed, kills, restart_after, between)")
    unknown = set(spec) - {"seed", "kills", "restart_after", "between"}
    if unknown:
        raise ScenarioError(f"{where}: unknown key(s) in random: {', '.join(sorted(unknown))}")
    rng = random.Random(spec.get("seed", 1))
    kills = int(spec.get("kills", 1))
    low, high = (parse_duration_s(x, where) for x in spec.get("between", ["2s", "8s"]))
    restart = spec.get("restart_after")
    restart_s = parse_duration_s(restart, where) if restart is not None else None
    events: list[Event] = []
    down: set[str] = set()
    for at_s in sorted(rng.uniform(low, high) for _ in range(kills)):
        candidates = [n for n in processing if n not in down]
        if not candidates:
            break
        node = rng.choice(candidates)
        events.append(Event(round(at_s, 3), "kill", node, f"{where} (seed)"))
        if restart_s is None:
            down.add(node)
        else:
            events.append(Event(round(at_s + restart_s, 3), "restart", node, f"{where} (seed)"))
    return events
