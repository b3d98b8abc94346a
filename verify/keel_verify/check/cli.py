"""``keel-verify check MISSION.yaml [--format F] [--max-failures K] [--suggest]``.

Proves with Z3 that under every sequence of tolerated node failures, and every planned
phase change, the mission's decision graph only selects valid placements
(docs/missions.md, "What `keel-verify check` proves"). Exit codes: 0 proved, 1 violations,
2 input error, 3 undecided, 4 internal error.

Formats: text (default), json (``--json``: the object docs/missions.md states), sarif (one
result per violation at file:line:col), junit (one test case per violation kind) and
github (``::error file=F,line=L,col=C::`` annotations).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from typing import Any, TextIO

from keel_verify import report
from keel_verify.check.components import ComponentsError, read_components
from keel_verify.check.core import InputError, check_file
from keel_verify.check.model import KINDS
from keel_verify.check.online import (
    ProverFailed,
    ProverUnavailable,
    incomplete,
    online_phases,
    run_prover,
    summary_lines,
    violations_of,
)
from keel_verify.check.result import PROVED, UNDECIDED, VIOLATED, CheckResult, Violation
from keel_verify.mission import LoadError, Mission

EXIT_PROVED = 0
EXIT_VIOLATIONS = 1
EXIT_INPUT_ERROR = 2
EXIT_UNDECIDED = 3
EXIT_INTERNAL_ERROR = 4


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "check",
        help="prove a mission's decision graph valid under every tolerated failure sequence",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("mission", help="mission file (YAML, schema 1)")
    report.add_format_arguments(parser)
    parser.add_argument("--max-failures", type=int, metavar="K", default=None,
                        help="explore failure sequences of at most K failures "
                             "(default: every tolerated node)")
    parser.add_argument("--suggest", action="store_true",
                        help="propose a valid configuration for each violation (Z3)")
    parser.add_argument("--timeout", type=float, metavar="S", default=None,
                        help="give up after S seconds per solver query (undecided, exit 3)")
    parser.add_argument("--progress", action="store_true",
                        help="report every level of the search on stderr")
    add_components_argument(parser)
    parser.set_defaults(func=run)


def add_components_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--components", metavar="BINARY|@FILE|A,B",
                        help="the components the node binary has: the keel-node binary "
                             "itself (asked with --list-components), a file of names "
                             "(@FILE, as --list-components prints them) or names separated "
                             "by commas; a task whose component is not among them is a "
                             "component-missing violation")


def components_of(args: argparse.Namespace) -> frozenset[str] | None:
    """The --components list, or None; raises ComponentsError."""
    spec = getattr(args, "components", None)
    return None if spec is None else read_components(spec)


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
        if incomplete(result.stats.get("online") or {"phases": []}):
            return f"{head}: UNDECIDED: {result.reason}; not proved"
        return f"{head}: UNDECIDED: the solver answered unknown ({result.reason}); not proved"
    # One cause, one count: consequences are counted apart (result.roots()).
    roots = result.roots()
    counts = Counter(v.kind for v in roots)
    listed = ", ".join(f"{k} {n}" for k, n in sorted(counts.items()))
    total = len(roots)
    more = len(result.violations) - total
    follow = ""
    if more:
        them = "it" if total == 1 else "them"
        follow = f"; {more} more follow{'s' if more == 1 else ''} from {them}"
    tail = "" if result.status != UNDECIDED else f"; search incomplete ({result.reason})"
    return f"{head}: {total} violation{'s' if total != 1 else ''} ({listed}){follow}{tail}"


def print_human(result: CheckResult, out: TextIO) -> None:
    # The online phases' proof first: the verdict stays the line a reader (and ./keel demo)
    # takes as the last of a proved mission's.
    online = result.stats.get("online")
    if online:
        for line in summary_lines(online):
            print(f"{result.file}: {line}", file=out)
    print(summary(result), file=out)
    for index, v in enumerate(result.violations):
        if v.cause is not None:
            continue  # printed under its cause
        print(f"{v.file}:{v.line}:{max(1, v.col)}: {v.kind}: {v.message}", file=out)
        if v.steps:
            failures = ", ".join(v.failures) if v.failures else "none"
            print(f"    phase {v.phase}; failures: {failures}", file=out)
            print(f"    path: {v.path_text()}", file=out)
        if v.suggestion:
            for line in v.suggestion.splitlines():
                print(f"    suggest: {line}", file=out)
        for c in result.consequences(index):
            print(f"    and so {c.file}:{c.line}:{max(1, c.col)}: {c.kind}: {c.message}", file=out)
            print(f"        path: {c.path_text()}", file=out)
            if c.suggestion:
                for line in c.suggestion.splitlines():
                    print(f"        suggest: {line}", file=out)
    for a in result.advisories:
        print(f"{a.file}:{a.line}: advisory {a.rule}: {a.message}", file=out)


def to_json(result: CheckResult) -> dict[str, Any]:
    return {
        "mission": result.mission,
        "file": result.file,
        "valid": result.valid,
        "result": result.status,
        "reason": result.reason or None,
        "violations": [v.to_json() for v in result.violations],
        "advisories": [a.to_json() for a in result.advisories],
        "stats": result.stats,
    }


def input_error_json(path: str, error: InputError) -> dict[str, Any]:
    """The ``--json`` object for a file that cannot be checked (exit 2)."""
    return {
        "mission": None,
        "file": path,
        "valid": False,
        "result": "input-error",
        "reason": None,
        "violations": [
            {"kind": "schema", "rule": e.rule, "file": e.file, "line": e.line,
             "col": e.col, "message": e.message, "phase": None, "failures": [],
             "path": [], "config": None, "task": None, "node": None}
            for e in error.errors
        ],
        "advisories": [],
        "stats": {},
    }


# What each violation kind means (docs/missions.md's table): the rules of a SARIF report.
KIND_DESCRIPTIONS: dict[str, str] = {
    "schema": "the file does not parse or breaks the schema",
    "unknown-reference": "a name that is not defined",
    "port-conflict": "two tasks share a port",
    "missing-transition": "a reachable configuration has no edge for the failure of a node "
                          "that matters",
    "task-on-failed-node": "a reachable configuration places a task on a failed node",
    "capability": "a task is placed on a node that lacks a capability it requires",
    "capacity": "the summed load placed on a node exceeds its capacity",
    "task-missing": "a configuration does not place exactly its phase's tasks",
    "master-invalid": "the master is failed or not a processing node",
    "observer-invalid": "an observer is failed, not processing, the master or listed twice, "
                        "or there is none",
    "master-mismatch": "after a master failure the next configuration names another master "
                       "than the election picks; after another node's failure, another "
                       "master than the current one",
    "storage-unavailable": "checkpointed tasks are placed and no storage node is alive",
    "safe-mode-within-tolerance": "SAFE is reached within the tolerated number of failures",
    "phase-transition-invalid": "an on_phase target is missing or invalid under the failures "
                                "reached so far",
    "safe-mode-unhostable": "a node that can become master lacks a capability an essential "
                            "task requires",
    "component-missing": "a task names a component the node binary given with --components "
                         "lacks (a node would refuse the mission at boot)",
    "recovery-unproven": "an on_recovery edge leads to a state no failure sequence reaches, "
                         "whose own edges are therefore not proved",
    "undecided": "the solver answered unknown or ran out of time: not proved",
}
# Advisories: notes, never violations (the verdict and the exit code ignore them).
ADVISORY_DESCRIPTIONS: dict[str, str] = {
    "unbounded-state": "a checkpointed task states no max_state_bytes: the protocol's domain "
                       "admits checkpoints of the capacity's 16 MiB",
}
assert set(KINDS) < set(KIND_DESCRIPTIONS)
RULES = [report.Rule(kind, text)
         for kind, text in {**KIND_DESCRIPTIONS, **ADVISORY_DESCRIPTIONS}.items()]


def _finding_message(v: Violation, cause: Violation | None = None) -> str:
    message = v.message
    if cause is not None:
        message += f" (follows from the {cause.kind} at line {cause.line})"
    if v.steps:
        failures = ", ".join(v.failures) if v.failures else "none"
        message += f" (phase {v.phase}; failures: {failures}; path: {v.path_text()})"
    if v.suggestion:
        message += f"; suggest: {' / '.join(v.suggestion.splitlines())}"
    return message


def build_report(command: str, path: str, result: CheckResult | None,
                 errors: list[LoadError] | None = None) -> report.Report:
    """check's outcome for the CI formats: a finding per violation (or input error) at its
    file:line:col, a test case per violation kind. ``errors``: the input errors of a file
    that could not be checked (``result`` is then None)."""
    cases: list[report.Case] = []
    findings: list[report.Finding] = []
    classname = f"keel-verify.{command}.{path}"
    if result is None:
        errors = errors or []
        findings = [report.Finding("schema", f"{e.rule}: {e.message}", e.file or path,
                                   e.line, e.col) for e in errors]
        for kind in KINDS:
            if kind == "schema":
                details = "\n".join(str(e) for e in errors)
                cases.append(report.Case(kind, classname, report.FAILED,
                                         f"{len(errors)} input error(s)", details))
            else:
                cases.append(report.Case(kind, classname, report.SKIPPED,
                                         "not checked: the file does not load"))
        verdict = (f"{path}: input error ({len(errors)} error"
                   f"{'s' if len(errors) != 1 else ''}): not checked")
        return report.Report(command, path, verdict, EXIT_INPUT_ERROR, RULES, findings, cases,
                             subject=path)

    for v in result.violations:
        cause = result.violations[v.cause] if v.cause is not None else None
        findings.append(report.Finding(v.kind, _finding_message(v, cause), v.file or path, v.line,
                                       v.col, properties={"phase": v.phase, "config": v.config,
                                                          "failures": list(v.failures)}))
    loaded = result.stats.get("loaded", True)
    seconds = float(result.stats.get("seconds", 0.0) or 0.0)
    for kind in KINDS:
        found = [v for v in result.violations if v.kind == kind]
        if found:
            causes = [result.violations[v.cause] if v.cause is not None else None for v in found]
            details = "\n".join(f"{v.file}:{v.line}:{max(1, v.col)}: {_finding_message(v, cause)}"
                                 for v, cause in zip(found, causes, strict=True))
            cases.append(report.Case(kind, classname, report.FAILED,
                                     f"{len(found)} violation{'s' if len(found) != 1 else ''}",
                                     details))
        elif not loaded:
            cases.append(report.Case(kind, classname, report.SKIPPED,
                                     "not checked: the mission does not load"))
        elif result.status == UNDECIDED:
            cases.append(report.Case(kind, classname, report.ERRORED,
                                     f"undecided: {result.reason}"))
        else:
            cases.append(report.Case(kind, classname, report.PASSED))
    if result.status == UNDECIDED:
        findings.append(report.Finding("undecided", f"not proved: {result.reason}",
                                       result.file or path, level=report.WARNING))
    for a in result.advisories:
        findings.append(report.Finding(a.rule, a.message, a.file or path, a.line,
                                       level=report.NOTE, properties={"task": a.task}))
    if result.violations:
        code = EXIT_VIOLATIONS
    else:
        code = EXIT_UNDECIDED if result.status == UNDECIDED else EXIT_PROVED
    return report.Report(command, result.mission or path, summary(result), code, RULES,
                         findings, cases, seconds, subject=path)


def _attach_suggestions(result: CheckResult, mission: Mission) -> None:
    from keel_verify.synth.suggest import suggest

    for v in result.violations:
        v.suggestion = suggest(mission, v)


def prove_online(result: CheckResult, mission: Mission, max_failures: int | None) -> None:
    """The phases placed online, proved by keel-place --prove (check/online.py): its
    violations join the graph's, its counts go to ``stats["online"]``. Raises
    ProverUnavailable and ProverFailed."""
    proof = run_prover(mission, result, max_failures)
    found = violations_of(mission, proof)
    result.stats["online"] = proof
    if found:
        result.violations.extend(found)
        result.status = VIOLATED
    elif incomplete(proof) and result.status == PROVED:
        result.status = UNDECIDED
        result.reason = incomplete(proof)


def run(args: argparse.Namespace) -> int:
    if args.max_failures is not None and args.max_failures < 0:
        print("keel-verify: check: --max-failures must be 0 or more", file=sys.stderr)
        return EXIT_INPUT_ERROR
    try:
        components = components_of(args)
    except ComponentsError as error:
        print(f"keel-verify: check: --components: {error}", file=sys.stderr)
        return EXIT_INPUT_ERROR
    try:
        result, mission = check_file(args.mission, args.max_failures, args.timeout,
                                     progress_reporter(args.progress), components=components)
    except InputError as error:
        if args.format == "json":
            json.dump(input_error_json(args.mission, error), sys.stdout, indent=2)
            print()
        elif args.format in report.CI_FORMATS:
            report.emit(build_report("check", args.mission, None, error.errors), args.format)
        if args.format != "github":  # the annotations already hold every error
            for e in error.errors:
                print(e, file=sys.stderr)
        return EXIT_INPUT_ERROR
    if mission is not None and online_phases(mission):
        try:
            prove_online(result, mission, args.max_failures)
        except ProverUnavailable as error:
            print(f"keel-verify: check: {args.mission}: {error}", file=sys.stderr)
            return EXIT_INPUT_ERROR
        except ProverFailed as error:
            print(f"keel-verify: internal error: {args.mission}: {error}", file=sys.stderr)
            return EXIT_INTERNAL_ERROR
    if args.suggest and mission is not None and result.violations:
        _attach_suggestions(result, mission)
    if args.format == "json":
        json.dump(to_json(result), sys.stdout, indent=2)
        print()
    elif args.format in report.CI_FORMATS:
        report.emit(build_report("check", args.mission, result), args.format)
    else:
        print_human(result, sys.stdout)
    if result.violations:
        return EXIT_VIOLATIONS
    if result.status == UNDECIDED:
        return EXIT_UNDECIDED
    return EXIT_PROVED
