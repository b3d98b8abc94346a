"""``keel-verify load MISSION.yaml [--json]``: load a mission and print it normalised.

This is the command-line face of the one reader of mission YAML (``keel_verify.mission``,
under ``config/schema/README.md``); no C++ program reads YAML. ``keel-mission IMAGE --json``
prints the same JSON, up to whitespace and key order, for the image ``keel-verify compile``
writes from the mission.
"""

from __future__ import annotations

import argparse
import json
import sys

from keel_verify.mission import MissionError, load_mission


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("load", help="load a mission file and print it normalised")
    parser.add_argument("mission", help="mission file (YAML, schema 1)")
    parser.add_argument("--json", action="store_true", help="print the normalised mission as JSON")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        mission = load_mission(args.mission)
    except MissionError as error:
        for e in error.errors:
            print(e, file=sys.stderr)
        return 2 if error.is_input_error else 1
    if args.json:
        json.dump(mission.to_json(), sys.stdout, indent=2)
        print()
    else:
        print(
            f"{args.mission}: mission {mission.name}: {len(mission.nodes)} nodes, "
            f"{len(mission.tasks)} tasks, {len(mission.phases)} phases, "
            f"{sum(len(p.configurations) for p in mission.phases.values())} configurations"
        )
    return 0
