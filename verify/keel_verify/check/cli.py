"""``keel-verify check MISSION.yaml [--json] [--max-failures K] [--suggest]``.

Proves with Z3 that under every sequence of tolerated node failures, and every planned
phase change, the mission's decision graph only selects valid placements (DESIGN.md,
"Mission file (schema 1)"). Exit codes: 0 proved, 1 violations, 2 input error,
3 undecided.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from typing import Any, TextIO

from keel_verify.check.core import InputError, check_file
from keel_verify.check.result import PROVED, UNDECIDED, CheckResult
from keel_verify.mission import Mission

EXIT_PROVED = 0
EXIT_VIOLATIONS = 1
EXIT_INPUT_ERROR = 2
EXIT_UNDECIDED = 3


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "check",
        help="prove a mission's decision graph valid under every tolerated failure sequence",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("mission", help="mission file (YAML, schema 1)")
    parser.add_argument("--json", action="store_true", help="print one JSON object (DESIGN.md)")
    parser.add_argument("--max-failures", type=int, metavar="K", default=None,
                        help="explore failure sequences of at most K failures "
                             "(default: every tolerated node)")
    parser.add_argument("--suggest", action="store_true",
                        help="propose a valid configuration for each violation (Z3)")
    parser.add_argument("--timeout", type=float, metavar="S", default=None,
                        help="give up after S seconds per solver query (undecided, exit 3)")
    parser.add_argument("--progress", action="store_true",
                        help="report every level of the search on stderr")
    parser.set_defaults(func=run)


def progress_reporter(enabled: bool, command: str = "check") -> Any:
    start = time.perf_counter()

    def report(message: str) -> None:
        # Long runs report on their own; short ones stay quiet unless asked.
        if enabled or message.startswith("load") or time.perf_counter() - start > 2.0:
            print(f"keel-verify: {command}: {message}", file=sys.stderr, flush=True)

    return report


def summary(result: CheckResult) -> str:
    st = result.stats
    head = f"{result.file}: mission {result.mission}"
    if result.status == PROVED:
        return (f"{head}: PROVED valid under every sequence of up to {st['depth']} failures of "
                f"{st['tolerance_nodes']} tolerated nodes (node_failures {st['node_failures']}): "
                f"{st['configurations']} configurations in {st['phases']} phase(s), "
                f"{st['queries']} solver queries, {st['seconds']:.2f} s")
    if result.status == UNDECIDED and not result.violations:
        return f"{head}: UNDECIDED: the solver answered unknown ({result.reason}); not proved"
    counts = Counter(v.kind for v in result.violations)
    listed = ", ".join(f"{k} {n}" for k, n in sorted(counts.items()))
    total = len(result.violations)
    tail = "" if result.status != UNDECIDED else f"; search incomplete ({result.reason})"
    return f"{head}: {total} violation{'s' if total != 1 else ''} ({listed}){tail}"


def print_human(result: CheckResult, out: TextIO) -> None:
    print(summary(result), file=out)
    for v in result.violations:
        print(f"{v.file}:{v.line}: {v.kind}: {v.message}", file=out)
        if v.steps:
            failures = ", ".join(v.failures) if v.failures else "none"
            print(f"    phase {v.phase}; failures: {failures}", file=out)
            print(f"    path: {v.path_text()}", file=out)
        if v.suggestion:
            for line in v.suggestion.splitlines():
                print(f"    suggest: {line}", file=out)


def to_json(result: CheckResult) -> dict[str, Any]:
    return {
        "mission": result.mission,
        "file": result.file,
        "valid": result.valid,
        "result": result.status,
        "reason": result.reason or None,
        "violations": [v.to_json() for v in result.violations],
        "stats": result.stats,
    }


def input_error_json(path: str, error: InputError) -> dict[str, Any]:
    """The ``--json`` object for a file that cannot be checked (exit 2)."""
    return {
        "mission": None,
        "file": path,
        "valid": False,
        "result": "input-error",
        "violations": [
            {"kind": "schema", "rule": e.rule, "file": e.file, "line": e.line,
             "col": e.col, "message": e.message, "phase": None, "failures": [],
             "path": [], "config": None, "task": None, "node": None}
            for e in error.errors
        ],
        "stats": {},
    }


def _attach_suggestions(result: CheckResult, mission: Mission) -> None:
    from keel_verify.synth.suggest import suggest

    for v in result.violations:
        v.suggestion = suggest(mission, v)


def run(args: argparse.Namespace) -> int:
    if args.max_failures is not None and args.max_failures < 0:
        print("keel-verify: check: --max-failures must be 0 or more", file=sys.stderr)
        return EXIT_INPUT_ERROR
    try:
        result, mission = check_file(args.mission, args.max_failures, args.timeout,
                                     progress_reporter(args.progress))
    except InputError as error:
        if args.json:
            json.dump(input_error_json(args.mission, error), sys.stdout, indent=2)
            print()
        for e in error.errors:
            print(e, file=sys.stderr)
        return EXIT_INPUT_ERROR
    if args.suggest and mission is not None and result.violations:
        _attach_suggestions(result, mission)
    if args.json:
        json.dump(to_json(result), sys.stdout, indent=2)
        print()
    else:
        print_human(result, sys.stdout)
    if result.violations:
        return EXIT_VIOLATIONS
    if result.status == UNDECIDED:
        return EXIT_UNDECIDED
    return EXIT_PROVED
