"""What the trace specs take from the mission: nodes, succession, limits, placements."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..mission import Mission
from ..specs.mission_models import cluster, load_for_models, startup_grace_periods


@dataclass
class Facts:
    mission: Mission
    nodes: list[str]  # every node, in file order
    priority: list[str]  # processing nodes in succession order
    monitors: list[str]  # the initial configuration's Master and Observers
    storage: str | None
    miss_limit: int
    startup_grace: int  # periods a never-heard node is given (>= miss_limit)
    tie_grace: int = 0  # heartbeat.tie_grace: periods of a tie (0: the ground is no voter)
    period_ns: int = 0  # the heartbeat period


def facts(path: Path) -> Facts:
    mission = load_for_models(path)
    nodes, priority, monitors, storage = cluster(mission)
    return Facts(mission, nodes, priority, monitors, storage, mission.heartbeat.miss_limit,
                 startup_grace_periods(mission), mission.heartbeat.tie_grace,
                 mission.heartbeat.period_ms * 1_000_000)
