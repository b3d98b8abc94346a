"""The protocol models instantiated from a mission file.

``keel-verify specs --mission MISSION.yaml`` checks the specs with the mission's own
cluster instead of the CI models' three processing nodes:

* Heartbeat: every node of the mission is watched; the monitors are the Master and
  the Observers of the first phase's initial configuration; ``MissLimit`` is the
  mission's ``heartbeat.miss_limit`` and the channel may lose ``miss_limit - 1``
  heartbeats in a row (the most the accuracy property covers); ``StartupGrace`` is the
  mission's start-up grace in periods. Two models: every node booting at the start, and
  the Master alone watching a node that boots as late as the grace allows.
* MasterElection: ``Priority`` is that configuration's Master, its Observers in their
  listed (priority) order, then the other processing nodes in file order.
* ConfigSwitch: the processing nodes in the same priority order, the mission's storage
  node, and two abstract checkpointed tasks placed as in the CI model; four models
  (a phase change; one crash; both; two crashes, so a Master crash during a switch),
  each with the boot switch, a node that may boot late and the VIEW of MCConfigSwitch.

The environment budgets (crashes, restarts, false declarations, task steps) are those
of the CI models. Mission-sized state spaces are bounded by MCMaxLossyLinks (how many
links may be in a loss streak at once) in the Heartbeat model.
"""

from __future__ import annotations

import re
from pathlib import Path

from ..mission import Mission, MissionError, load_mission
from .models import Model

# The runtime's default start-up grace (Topology) when a mission does not set one.
DEFAULT_STARTUP_GRACE_MS = 2000

# Names the models already use; a node cannot be called like one of them.
_TAKEN = {
    "Nodes", "Monitors", "MissLimit", "MaxLoss", "MaxCrashes", "Priority", "NumObservers",
    "MaxRestarts", "MaxFalseSuspicions", "NoNode", "Storage", "Tasks", "ConfigIds",
    "InitialConfig", "Placement", "OnFailure", "OnPhase", "MaxPhaseChanges", "MaxVersion",
    "Init", "Next", "Spec", "FairSpec", "Tick", "Crash", "Restart", "TRUE", "FALSE",
    "Owner", "Rank", "Running", "Min", "N", "t1", "t2", "MCMaxLossyLinks",
}
_IDENTIFIER = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
# Node names MCConfigSwitch itself declares.
_CI_NODE_CONSTANTS = ("PN1", "PN2", "PN3")


class MissionModelError(Exception):
    """The mission cannot be turned into protocol models (exit 2)."""


def _check_names(names: list[str]) -> None:
    for name in names:
        if not _IDENTIFIER.match(name) or name in _TAKEN:
            raise MissionModelError(
                f"node name {name!r} cannot be used as a TLA+ model value; "
                "rename it (letters, digits and '_', not a name the specs define)"
            )


def cluster(mission: Mission) -> tuple[list[str], list[str], list[str], str | None]:
    """(all nodes, priority order, monitors, storage node) of a mission."""
    nodes = list(mission.nodes)
    processing = [name for name, node in mission.nodes.items() if node.kind == "processing"]
    storage = next((n for n, node in mission.nodes.items() if node.role == "storage"), None)
    if not mission.phases:
        raise MissionModelError("the mission has no phase")
    phase = next(iter(mission.phases.values()))
    initial = phase.configurations[phase.initial]
    order = [initial.master, *initial.observers]
    priority = order + [name for name in processing if name not in order]
    if len(priority) < 2:
        raise MissionModelError("the protocols need at least two processing nodes")
    _check_names(nodes)
    return nodes, priority, order, storage


def _set(names: list[str]) -> str:
    return "{" + ", ".join(names) + "}"


def startup_grace_periods(mission: Mission) -> int:
    """The heartbeat periods a never-heard node is given before it is declared, as the
    runtime computes them (Topology::startup_grace_periods): max(miss_limit,
    ceil(heartbeat.startup_grace_ms / period_ms)), the grace defaulting to 2000 ms."""
    heartbeat = mission.heartbeat
    grace_ms = getattr(heartbeat, "startup_grace_ms", DEFAULT_STARTUP_GRACE_MS)
    return max(heartbeat.miss_limit, -(-grace_ms // heartbeat.period_ms))


def load_for_models(path: Path) -> Mission:
    """The mission a model or trace spec is built from; loader errors as MissionModelError."""
    try:
        return load_mission(path)
    except MissionError as error:
        raise MissionModelError(str(error)) from error
    except OSError as error:
        raise MissionModelError(f"{path}: {error}") from error


def mission_models(
    path: Path, max_lossy_links: int = 1
) -> tuple[str, list[Model], dict[str, object]]:
    """The mission's name, its models (Heartbeat twice, MasterElection, ConfigSwitch four times) and
    the facts taken from it (nodes, priority, monitors, miss limit, bounds)."""
    mission = load_for_models(path)
    nodes, priority, monitors, storage = cluster(mission)
    miss_limit = mission.heartbeat.miss_limit
    processing = priority
    models: list[Model] = []

    grace = startup_grace_periods(mission)
    # The latest boot the accuracy property covers: boot delay + a loss streak < grace.
    boot_delay = grace - miss_limit

    def heartbeat_cfg(what: str, watchers: list[str], late: int, delay: int) -> str:
        return "\n".join([
            f"\\* Heartbeat for mission {mission.name}: {what}.",
            "CONSTANTS",
            f"    Nodes = {_set(nodes)}",
            f"    Monitors = {_set(watchers)}",
            f"    MissLimit = {miss_limit}",
            f"    MaxLoss = {miss_limit - 1}",
            "    MaxCrashes = 1",
            f"    StartupGrace = {grace}",
            f"    MaxLateBoots = {late}",
            f"    MaxBootDelay = {delay}",
            f"    MCMaxLossyLinks = {max_lossy_links}",
            "SYMMETRY MCSymmetry",
            "VIEW MCView",
            "ACTION_CONSTRAINT MCOneSenderAtATime",
            "CONSTRAINT MCLossConstraint",
            "SPECIFICATION Spec",
            "INVARIANTS",
            "    TypeOK",
            "    CompletenessInv",
            "    AccuracyInv",
            "CHECK_DEADLOCK TRUE",
            "",
        ])

    # Every node watched by the initial Master and Observers, all booting at the start; and
    # the start-up grace: one monitor (monitors share no state), a node booting as late
    # as the grace allows.
    models.append(Model("MissionHeartbeat", "Heartbeat", "MCHeartbeat",
                        heartbeat_cfg("every node watched by the Master and Observers of "
                                      "the initial configuration", monitors, 0, 0),
                        ["TypeOK", "CompletenessInv", "AccuracyInv"], None))
    models.append(Model("MissionHeartbeatStartup", "Heartbeat", "MCHeartbeat",
                        heartbeat_cfg(f"the start-up grace ({grace} periods): a node boots "
                                      f"up to {boot_delay} periods after the Master",
                                      monitors[:1], 1, boot_delay),
                        ["TypeOK", "CompletenessInv", "AccuracyInv"], None))

    election_module = "\n".join([
        "---- MODULE MissionMasterElection ----",
        f"\\* MasterElection for mission {mission.name} (generated by keel-verify specs).",
        "EXTENDS MasterElection",
        f"CONSTANTS {', '.join(processing)}",
        f"MissionPriority == <<{', '.join(processing)}>>",
        "====",
        "",
    ])
    election_cfg = "\n".join([
        f"\\* MasterElection for mission {mission.name}: priority {' > '.join(processing)}.",
        "CONSTANTS",
        *[f"    {name} = {name}" for name in processing],
        "    Priority <- MissionPriority",
        f"    NumObservers = {len(monitors) - 1}",
        "    MaxCrashes = 2",
        "    MaxRestarts = 1",
        "    MaxFalseSuspicions = 1",
        "    NoNode = NoNode",
        "SPECIFICATION FairSpec",
        "INVARIANTS",
        "    TypeOK",
        "    OneMasterPerEpochInv",
        "    MasterOwnsEpochInv",
        "    NoStaleMastershipInv",
        "PROPERTIES",
        "    EpochMonotoneProp",
        "    StaleCommandRejectedProp",
        "    MasterLiveness",
        "CHECK_DEADLOCK FALSE",
        "",
    ])
    models.append(Model("MissionMasterElection", "MasterElection", "MissionMasterElection",
                        election_cfg,
                        ["TypeOK", "OneMasterPerEpochInv", "MasterOwnsEpochInv",
                         "NoStaleMastershipInv", "EpochMonotoneProp",
                         "StaleCommandRejectedProp", "MasterLiveness"], None,
                        {"MissionMasterElection.tla": election_module}))

    declared = [name for name in processing if name not in _CI_NODE_CONSTANTS]
    switch_module = "\n".join([
        "---- MODULE MissionConfigSwitch ----",
        f"\\* ConfigSwitch for mission {mission.name} (generated by keel-verify specs).",
        "EXTENDS MCConfigSwitch",
        *([f"CONSTANTS {', '.join(declared)}"] if declared else []),
        f"MissionPriority == <<{', '.join(processing)}>>",
        "====",
        "",
    ])
    storage_name = storage or "StorageNode"
    # The CI model's budget (a crash and a phase change in one behaviour) is far larger
    # with four processing nodes than either alone; the mission-sized models check each
    # alone, and both together in MissionConfigSwitchPhaseCrash.
    # Every model has one node that may boot late (after it was declared failed, say).
    for name, crashes, phases, what in (
        ("MissionConfigSwitchPhase", 0, 1, "a planned phase change"),
        ("MissionConfigSwitch", 1, 0, "one crash during any switch"),
        ("MissionConfigSwitchPhaseCrash", 1, 1, "a crash during a planned phase change"),
        ("MissionConfigSwitchFailover", 2, 0, "a further failure and a Master crash"),
    ):
        crashes = min(crashes, len(processing) - 1)
        late_boots = min(1, len(processing) - 1 - crashes)
        constants = sorted(set(processing) | set(_CI_NODE_CONSTANTS))
        cfg = "\n".join([
            f"\\* ConfigSwitch for mission {mission.name}: {what}.",
            "CONSTANTS",
            *[f"    {node} = {node}" for node in constants],
            "    t1 = t1",
            "    t2 = t2",
            f"    Nodes = {_set(processing)}",
            "    Priority <- MissionPriority",
            f"    Storage = {storage_name}",
            "    Tasks = {t1, t2}",
            "    ConfigIds <- MCConfigIds",
            "    InitialConfig <- MCInitialConfig",
            "    Placement <- MCPlacement",
            "    OnFailure <- MCOnFailure",
            "    OnPhase <- MCOnPhase",
            f"    MaxCrashes = {crashes}",
            f"    MaxPhaseChanges = {phases}",
            "    MaxVersion = 1",
            f"    MaxLateBoots = {late_boots}",
            "VIEW MCView",
            "SPECIFICATION FairSpec",
            "INVARIANTS",
            "    TypeOK",
            "    NoDoubleActivationInv",
            "    ResumeLatestCheckpointInv",
            "PROPERTIES",
            "    SwitchConverges",
            "CHECK_DEADLOCK FALSE",
            "",
        ])
        models.append(Model(name, "ConfigSwitch", "MissionConfigSwitch", cfg,
                            ["TypeOK", "NoDoubleActivationInv", "ResumeLatestCheckpointInv",
                             "SwitchConverges"], None,
                            {"MissionConfigSwitch.tla": switch_module}))
    facts: dict[str, object] = {
        "nodes": nodes,
        "priority": priority,
        "monitors": monitors,
        "storage": storage,
        "miss_limit": miss_limit,
        "startup_grace_periods": grace,
        "max_lossy_links": max_lossy_links,
    }
    return mission.name, models, facts
