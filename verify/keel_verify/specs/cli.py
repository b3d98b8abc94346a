"""``keel-verify specs``: model-check the protocol specs, and make sure TLC rejects
every mutant.

    keel-verify specs                          every model and mutant of spec/manifest.json
    keel-verify specs --model MCHeartbeat      one model (repeatable)
    keel-verify specs --mutant SwitchActivateEarly
    keel-verify specs --mission config/earth_observation.yaml
    keel-verify specs --json                   one JSON object, for CI

Exit codes: 0 every model passed (with the manifest's distinct-state count) and every
mutant was rejected for its property with its exit code; 1 a property failed or a result
was not the expected one; 2 input error (unknown model, bad manifest or mission, spec
that does not parse); 3 undecided (TLC could not finish: time limit, evaluation error,
out of memory). Undecided is never a pass.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from . import counterexample
from .mission_models import MissionModelError, mission_models
from .models import ManifestError, Model, Mutant, load_manifest, retarget_cfg, update_counts
from .tlc import INPUT_ERROR, PASS, UNDECIDED, VIOLATION, TlcResult, find_jar, run_tlc

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_INPUT_ERROR = 2
EXIT_UNDECIDED = 3


@dataclass
class Outcome:
    """One model or mutant: what was expected, what TLC said, and whether they agree."""

    name: str
    kind: str  # "model" | "mutant"
    spec: str
    expected: dict[str, object]
    result: TlcResult
    status: str  # "ok" | "failed" | "input-error" | "undecided"
    summary: str
    description: str = ""
    notes: list[str] = field(default_factory=list)

    def as_json(self) -> dict[str, object]:
        data: dict[str, object] = {
            "name": self.name,
            "kind": self.kind,
            "spec": self.spec,
            "status": self.status,
            "summary": self.summary,
            "expected": self.expected,
            **self.result.as_json(),
        }
        if self.description:
            data["description"] = self.description
        if self.result.trace:
            data["counterexample"] = [
                {
                    "state": state.number,
                    "action": state.action,
                    "back_to": state.back_to,
                    "changes": [
                        {"var": name, "old": old, "new": new} for name, old, new in diff
                    ],
                }
                for state, diff in counterexample.step_changes(self.result.trace)
            ]
        return data


def register(subparsers: argparse._SubParsersAction) -> None:  # noqa: SLF001
    parser = subparsers.add_parser(
        "specs",
        help="model-check the protocol specs (TLC) and their mutants",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--model", action="append", default=[], metavar="NAME",
                        help="check only this model (repeatable)")
    parser.add_argument("--mutant", action="append", default=[], metavar="NAME",
                        help="check only this mutant (repeatable)")
    parser.add_argument("--witness", action="append", dest="mutant", metavar="NAME",
                        help="check only this witness (repeatable; witnesses are "
                             "checked with the mutants)")
    parser.add_argument("--no-mutants", action="store_true", help="check the models only")
    parser.add_argument("--mission", metavar="MISSION.yaml",
                        help="check the specs with this mission's nodes, priority order "
                             "and miss limit instead of the CI models")
    parser.add_argument("--max-lossy-links", type=int, default=1, metavar="K",
                        help="with --mission: at most K heartbeat links in a loss streak "
                             "at once (bounds the Heartbeat model; default 1)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--counterexamples", action="store_true",
                        help="print the counterexample of every violation, also expected ones")
    parser.add_argument("--list", action="store_true", help="list the models and mutants")
    parser.add_argument("--update-manifest", action="store_true",
                        help="record the distinct-state counts TLC found in spec/manifest.json")
    parser.add_argument("--workers", default="auto", help="TLC worker threads (default auto)")
    parser.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                        help="time limit per TLC run (undecided when reached)")
    parser.add_argument("--spec-dir", default=None, help="the spec folder (default: spec/)")
    parser.add_argument("--tlc-jar", default=None, help="TLC jar (default: $KEEL_TLC_JAR)")
    parser.set_defaults(func=run)


def _spec_dir(explicit: str | None) -> Path:
    if explicit:
        return Path(explicit)
    root = os.environ.get("KEEL_ROOT")
    if root:
        return Path(root) / "spec"
    return Path(__file__).resolve().parents[3] / "spec"


def check_model(model: Model, jar: Path, spec_dir: Path, args: argparse.Namespace,
                compare_count: bool) -> Outcome:
    result = run_tlc(jar, spec_dir, model.module, model.cfg_text, model.extra_files,
                     workers=args.workers, timeout_s=args.timeout)
    expected: dict[str, object] = {"verdict": PASS, "distinct_states": model.distinct_states}
    notes: list[str] = []
    if result.verdict == PASS:
        status, summary = "ok", "passed"
        if compare_count and not args.update_manifest:
            if model.distinct_states is None:
                status = "failed"
                summary = "passed, but the manifest records no distinct-state count"
                notes.append("run with --update-manifest to record it")
            elif model.distinct_states != result.distinct_states:
                status = "failed"
                summary = (f"passed, but found {result.distinct_states:,} distinct states "
                           f"where the manifest records {model.distinct_states:,}")
                notes.append("the spec or model changed: review, then --update-manifest")
    elif result.verdict == VIOLATION:
        status = "failed"
        summary = f"{result.property} violated (TLC exit {result.exit_code})"
    elif result.verdict == INPUT_ERROR:
        status, summary = "input-error", f"{result.meaning} (TLC exit {result.exit_code})"
    else:
        status, summary = "undecided", result.message or result.meaning
    return Outcome(model.name, "model", model.spec, expected, result, status, summary,
                   notes=notes)


def check_mutant(mutant: Mutant, base: Model, jar: Path, spec_dir: Path,
                 args: argparse.Namespace) -> Outcome:
    try:
        cfg = retarget_cfg(base.cfg_text, mutant.specification, mutant.property,
                           mutant.constants, invariant=mutant.kind == "witness")
    except ManifestError as error:
        failed = TlcResult(None, INPUT_ERROR, str(error), 0.0)
        return Outcome(mutant.name, mutant.kind, base.spec, {}, failed, "input-error",
                       str(error))
    result = run_tlc(jar, spec_dir, mutant.module, cfg, base.extra_files,
                     workers=args.workers, timeout_s=args.timeout)
    expected: dict[str, object] = {
        "verdict": VIOLATION, "exit_code": mutant.exit_code, "property": mutant.property,
    }
    witness = mutant.kind == "witness"
    if result.verdict == VIOLATION:
        if result.exit_code == mutant.exit_code and result.property == mutant.property:
            status = "ok"
            summary = (f"reached: TLC found a state that violates {result.property}"
                       if witness else
                       f"rejected: {result.property} violated (TLC exit {result.exit_code})")
        else:
            status = "failed"
            summary = (f"rejected for the wrong reason: {result.property} "
                       f"(TLC exit {result.exit_code}), expected {mutant.property} "
                       f"(exit {mutant.exit_code})")
    elif result.verdict == PASS:
        status = "failed"
        summary = (f"NOT reached: no state violates {mutant.property}; the property it "
                   "guards is vacuous in this model" if witness else
                   f"NOT rejected: TLC found no violation of {mutant.property}; "
                   "the property (or the model) cannot tell this bug apart")
    elif result.verdict == INPUT_ERROR:
        status, summary = "input-error", f"{result.meaning} (TLC exit {result.exit_code})"
    else:
        status, summary = "undecided", result.message or result.meaning
    return Outcome(mutant.name, mutant.kind, base.spec, expected, result, status, summary,
                   description=mutant.description)


def exit_code_of(outcomes: list[Outcome]) -> int:
    statuses = {outcome.status for outcome in outcomes}
    if "failed" in statuses:
        return EXIT_FAILED
    if "input-error" in statuses:
        return EXIT_INPUT_ERROR
    if UNDECIDED in statuses:
        return EXIT_UNDECIDED
    return EXIT_OK


_LABELS = {"ok": "ok", "failed": "FAILED", "input-error": "ERROR", "undecided": "UNDECIDED"}


def print_outcome(outcome: Outcome, show_trace: bool) -> None:
    result = outcome.result
    label = _LABELS[outcome.status]
    facts = []
    if result.distinct_states is not None:
        facts.append(f"{result.distinct_states:,} states")
    if result.depth is not None and outcome.kind == "model":
        facts.append(f"depth {result.depth}")
    facts.append(f"{result.seconds:.1f} s")
    if result.cpu_seconds:
        facts.append(f"cpu {result.cpu_seconds:.1f} s")
    print(f"{label:<9} {outcome.kind:<6} {outcome.name:<28} {outcome.summary}  "
          f"[{', '.join(facts)}]")
    if outcome.description:
        print(f"          {outcome.description}")
    for note in outcome.notes:
        print(f"          {note}")
    if result.trace and (show_trace or outcome.status != "ok"):
        print(f"          counterexample ({len(result.trace)} states; "
              "only the variables that changed):")
        print(counterexample.render(result.trace))
        print()
    if outcome.status in ("input-error", "undecided") and result.output:
        tail = [line for line in result.output.splitlines() if line.strip()][-8:]
        for line in tail:
            print(f"          | {line}")


def _stop_on_sigterm(signum: int, frame: object) -> None:
    # Raising here unwinds subprocess.run, which then kills the TLC process it started
    # (a time-out of CTest sends SIGTERM): no model checker is left running.
    raise SystemExit(128 + signum)


def run(args: argparse.Namespace) -> int:
    signal.signal(signal.SIGTERM, _stop_on_sigterm)
    spec_dir = _spec_dir(args.spec_dir)
    try:
        manifest = load_manifest(spec_dir)
    except ManifestError as error:
        print(f"keel-verify specs: {error}", file=sys.stderr)
        return EXIT_INPUT_ERROR

    mission_name = None
    mission_facts: dict[str, object] | None = None
    if args.mission:
        try:
            mission_name, models, mission_facts = mission_models(
                Path(args.mission), args.max_lossy_links
            )
        except MissionModelError as error:
            print(f"keel-verify specs: {args.mission}: {error}", file=sys.stderr)
            return EXIT_INPUT_ERROR
        mutants: list[Mutant] = []
        compare_count = False
    else:
        models, mutants, compare_count = manifest.models, manifest.mutants, True

    known = {model.name for model in models} | {mutant.name for mutant in mutants}
    unknown = [name for name in args.model + args.mutant if name not in known]
    if unknown:
        print(f"keel-verify specs: unknown model or mutant: {', '.join(unknown)} "
              f"(known: {', '.join(sorted(known))})", file=sys.stderr)
        return EXIT_INPUT_ERROR
    if args.model or args.mutant:
        models = [m for m in models if m.name in args.model]
        mutants = [m for m in mutants if m.name in args.mutant]
    if args.no_mutants:
        mutants = []

    if args.list:
        for model in models:
            print(f"model   {model.name:<28} {model.spec}")
        for mutant in mutants:
            verb = "must reach ~" if mutant.kind == "witness" else "must break "
            print(f"{mutant.kind:<7} {mutant.name:<28} {verb}{mutant.property} "
                  f"(exit {mutant.exit_code})")
        return EXIT_OK

    jar = find_jar(args.tlc_jar)
    if jar is None:
        print("keel-verify specs: TLC jar not found; set KEEL_TLC_JAR or run ./keel setup",
              file=sys.stderr)
        return EXIT_INPUT_ERROR

    if mission_facts and not args.json:
        print(f"mission {mission_name}: nodes {', '.join(mission_facts['nodes'])}; "  # type: ignore[arg-type]
              f"priority {' > '.join(mission_facts['priority'])}; "  # type: ignore[arg-type]
              f"monitors {', '.join(mission_facts['monitors'])}; "  # type: ignore[arg-type]
              f"miss limit {mission_facts['miss_limit']}; start-up grace "
              f"{mission_facts['startup_grace_periods']} periods; "
              f"storage {mission_facts['storage']}")
        print(f"  environment bound of the Heartbeat model: at most "
              f"{mission_facts['max_lossy_links']} link(s) in a loss streak at once "
              "(--max-lossy-links)")
    started = time.monotonic()
    outcomes: list[Outcome] = []
    explicit = bool(args.model or args.mutant) or args.counterexamples
    for model in models:
        outcome = check_model(model, jar, spec_dir, args, compare_count)
        outcomes.append(outcome)
        if not args.json:
            print_outcome(outcome, explicit)
            sys.stdout.flush()
    by_name = {model.name: model for model in manifest.models}
    for mutant in mutants:
        outcome = check_mutant(mutant, by_name[mutant.base], jar, spec_dir, args)
        outcomes.append(outcome)
        if not args.json:
            print_outcome(outcome, explicit)
            sys.stdout.flush()
    seconds = time.monotonic() - started

    if args.update_manifest and not args.mission:
        counts = {o.name: o.result.distinct_states for o in outcomes
                  if o.kind == "model" and o.result.verdict == PASS
                  and o.result.distinct_states is not None}
        update_counts(manifest, counts)  # type: ignore[arg-type]

    code = exit_code_of(outcomes)
    if args.json:
        print(json.dumps({
            "ok": code == EXIT_OK,
            "exit_code": code,
            "mission": mission_name,
            "instantiation": mission_facts,
            "seconds": round(seconds, 2),
            "results": [outcome.as_json() for outcome in outcomes],
        }, indent=2))
    else:
        passed = sum(1 for o in outcomes if o.kind == "model" and o.status == "ok")
        rejected = sum(1 for o in outcomes if o.kind == "mutant" and o.status == "ok")
        reached = sum(1 for o in outcomes if o.kind == "witness" and o.status == "ok")
        n_models = sum(1 for o in outcomes if o.kind == "model")
        n_mutants = sum(1 for o in outcomes if o.kind == "mutant")
        n_witnesses = sum(1 for o in outcomes if o.kind == "witness")
        verdict = {EXIT_OK: "all as expected", EXIT_FAILED: "FAILED",
                   EXIT_INPUT_ERROR: "input error", EXIT_UNDECIDED: "UNDECIDED"}[code]
        witnesses = f", {reached}/{n_witnesses} witnesses reached" if n_witnesses else ""
        print(f"\n{passed}/{n_models} models passed, {rejected}/{n_mutants} mutants rejected"
              f"{witnesses} in {seconds:.1f} s: {verdict}")
    return code
