"""``keel-verify specs``: model-check the protocol specs, and make sure TLC rejects
every mutant.

    keel-verify specs                          every model and mutant of spec/manifest.json
    keel-verify specs --model MCHeartbeat      one model (repeatable)
    keel-verify specs --mutant SwitchActivateEarly
    keel-verify specs --mission config/earth_observation.yaml
    keel-verify specs --json                   one JSON object (--format json)
    keel-verify specs --format sarif           SARIF 2.1.0; also junit, github

While TLC runs, a line on stderr every few seconds (--progress-interval) says how far it
got: depth, states generated, distinct states, states left on the queue.

Runs go side by side, one more than the processors (--jobs: a run waits on its JVM's
start, its disk and its output for about a tenth of its time, which the extra run fills),
the largest first; each TLC then has the processors left to it as workers (--workers
auto). Results are printed in the order above whatever order they finish in.

A model the manifest marks "simulate" is checked in TLC's simulation mode (its traces,
depth and seed, one worker, so that the run is reproducible): it passes when TLC finds no
violation in those behaviours and checked the number of states the manifest records.

Exit codes: 0 every model passed (with the manifest's distinct-state count) and every
mutant was rejected for its property with its exit code; 1 a property failed or a result
was not the expected one; 2 input error (unknown model, bad manifest or mission, spec
that does not parse); 3 undecided (TLC could not finish: time limit, evaluation error,
out of memory). Undecided is never a pass. 4 internal error.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import sys
import time
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from .. import report, resources
from . import counterexample
from .mission_models import MissionModelError, mission_models
from .models import (
    ManifestError,
    Model,
    Mutant,
    Simulation,
    can_probe,
    load_manifest,
    probe_model,
    probe_results,
    retarget_cfg,
    update_counts,
)
from .tlc import (
    INPUT_ERROR,
    PASS,
    UNDECIDED,
    VIOLATION,
    Progress,
    TlcResult,
    run_tlc,
    stop_all,
)

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
    module: str = ""  # the TLA+ module TLC checked
    config: str = ""  # the model's .cfg file in spec/, if it has one

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
    parser.add_argument("--separate-witnesses", action="store_true",
                        help="check each witness in a TLC run of its own (by default a "
                             "witness is looked for in its model's run when that model is "
                             "checked too)")
    parser.add_argument("--all", action="store_true",
                        help="also the larger models, mutants and witnesses the manifest "
                             "marks \"bench\" (CI leaves them to ./keel bench specs)")
    parser.add_argument("--mission", metavar="MISSION.yaml",
                        help="check the specs with this mission's nodes, priority order "
                             "and miss limit instead of the CI models")
    parser.add_argument("--max-lossy-links", type=int, default=1, metavar="K",
                        help="with --mission: at most K heartbeat links in a loss streak "
                             "at once (bounds the Heartbeat model; default 1)")
    report.add_format_arguments(parser)
    parser.add_argument("--progress-interval", type=float, default=5.0, metavar="SECONDS",
                        help="while TLC runs, report its progress on stderr about every "
                             "SECONDS (default 5; 0: only TLC's own reports are read, "
                             "nothing is printed)")
    parser.add_argument("--counterexamples", action="store_true",
                        help="print the counterexample of every violation, also expected ones")
    parser.add_argument("--list", action="store_true", help="list the models and mutants")
    parser.add_argument("--update-manifest", action="store_true",
                        help="record the distinct-state counts TLC found in spec/manifest.json")
    parser.add_argument("--jobs", default="auto", metavar="N",
                        help="TLC runs at once (default auto: one more than the "
                             "processors this process may use)")
    parser.add_argument("--workers", default="auto",
                        help="TLC worker threads per run (default auto: the processors "
                             "divided among the --jobs)")
    parser.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                        help="time limit per TLC run (undecided when reached)")
    parser.add_argument("--spec-dir", default=None,
                        help="the spec folder (default: the checkout's spec/, else the "
                             "copy installed with keel-verify)")
    parser.add_argument("--tlc-jar", default=None,
                        help="TLC jar (default: $KEEL_TLC_JAR, the checkout's .cache/tlc/, "
                             "~/.cache/keel/tlc/)")
    parser.set_defaults(func=run)


def _spec_dir(explicit: str | None) -> Path:
    return Path(explicit) if explicit else resources.spec_dir()


def progress_printer(name: str, interval_s: float) -> Callable[[Progress], None] | None:
    """Prints how far TLC got on ``name``, at most about once every ``interval_s``."""
    if interval_s <= 0:
        return None
    last = [0.0]

    def show(progress: Progress) -> None:
        # TLC's own reports come on top of the probe's: keep to the interval.
        if progress.seconds - last[0] < 0.8 * interval_s:
            return
        last[0] = progress.seconds
        print(f"keel-verify: specs: {name}: {progress.seconds:.0f} s: depth {progress.depth}, "
              f"{progress.states_generated:,} states generated, "
              f"{progress.distinct_states:,} distinct, {progress.queue:,} on the queue",
              file=sys.stderr, flush=True)

    return show


# A model whose whole state space is smaller than this, and every mutant and witness run
# (which stops at its first violation), runs on the JVM's quick compiler alone: measured
# on the CI set, that halves the short runs and costs the long ones up to a third. Up to
# 50,000 states it still saves CPU-seconds (C2's compiler threads run beside the worker:
# the eight CI models from 10,000 to 50,000 states took 48.5-52.2 CPU-s quick against
# 63.8-73.4 with C2), which is what counts when every processor runs a TLC.
QUICK_BELOW_STATES = 50_000


def _processors() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def _jobs(value: str) -> int:
    if value == "auto":
        # One more run than processors: each run spends about a tenth of its wall time
        # off the processor (the JVM's start, its state files, its output read here).
        # Measured on the CI set, 2 cores: 195.5 s with two at once, 170.1 s with three.
        return _processors() + 1
    try:
        jobs = int(value)
    except ValueError:
        jobs = 0
    if jobs < 1:
        raise ValueError(f"--jobs must be a positive number or auto, not {value!r}")
    return jobs


def _workers(value: str, jobs: int) -> str:
    if value != "auto" or jobs == 1:
        return value
    return str(max(1, _processors() // jobs))


def _tlc(jar: Path, spec_dir: Path, name: str, module: str, cfg_text: str,
         extra_files: dict[str, str], args: argparse.Namespace, quick: bool,
         simulation: Simulation | None = None) -> TlcResult:
    # A simulation runs on one worker: its seed then gives the same behaviours every time.
    result = run_tlc(jar, spec_dir, module, cfg_text, extra_files,
                     workers="1" if simulation is not None else args.workers,
                     timeout_s=args.timeout, progress_s=args.progress_interval,
                     on_progress=progress_printer(name, args.progress_interval), quick=quick,
                     simulate=simulation.tlc_args() if simulation is not None else None)
    if simulation is not None:
        result.simulation = simulation.as_json()
    return result


def check_model(model: Model, jar: Path, spec_dir: Path, args: argparse.Namespace,
                compare_count: bool, witnesses: list[Mutant] | None = None) -> list[Outcome]:
    """The model's outcome, then one per witness looked for in its run (probe_model)."""
    simulation = model.simulate
    quick = (simulation is None and model.distinct_states is not None
             and model.distinct_states < QUICK_BELOW_STATES)
    module, cfg_text, extra_files = model.module, model.cfg_text, model.extra_files
    if witnesses:
        module, cfg_text, extra_files = probe_model(model, witnesses)
    result = _tlc(jar, spec_dir, model.name, module, cfg_text, extra_files, args, quick, simulation)
    # What the manifest records and the run is held to: distinct states, or the states a
    # simulation checked (reproducible: a fixed seed, one worker).
    what = "distinct states" if simulation is None else "states checked in simulation"
    found = result.distinct_states if simulation is None else result.states_checked
    recorded = model.recorded_count
    expected: dict[str, object] = {"verdict": PASS, "distinct_states": model.distinct_states}
    if simulation is not None:
        expected = {"verdict": PASS, "states_checked": model.states_checked,
                    "simulation": simulation.as_json()}
    notes: list[str] = []
    if simulation is not None:
        notes.append(f"simulation: {simulation.traces:,} random behaviours of at most "
                     f"{simulation.depth} states (seed {simulation.seed}), not every "
                     "behaviour")
    if result.verdict == PASS:
        status, summary = "ok", "passed"
        if compare_count and not args.update_manifest:
            if recorded is None:
                status = "failed"
                summary = f"passed, but the manifest records no count of {what}"
                notes.append("run with --update-manifest to record it")
            elif recorded != found:
                status = "failed"
                summary = (f"passed, but found {found or 0:,} {what} "
                           f"where the manifest records {recorded:,}")
                notes.append("the spec or model changed: review, then --update-manifest")
    elif result.verdict == VIOLATION:
        status = "failed"
        summary = f"{result.property} violated (TLC exit {result.exit_code})"
    elif result.verdict == INPUT_ERROR:
        status, summary = "input-error", f"{result.meaning} (TLC exit {result.exit_code})"
    else:
        status, summary = "undecided", result.message or result.meaning
    outcome = Outcome(model.name, "model", model.spec, expected, result, status, summary,
                      notes=notes, module=model.module, config=model.config)
    return [outcome, *probed_outcomes(model, witnesses or [], result)]


def probed_outcomes(model: Model, witnesses: list[Mutant], run: TlcResult) -> list[Outcome]:
    """The witnesses looked for in ``model``'s run: reached when its output names them; not
    reached (the property they guard is vacuous) when the run went through every state;
    undecided when it stopped before that."""
    reached = probe_results(run.output)
    finished = run.verdict == PASS
    outcomes = []
    for witness in witnesses:
        result = TlcResult(run.exit_code, run.verdict, f"looked for in {model.name}'s run", 0.0,
                           property=witness.property)
        if witness.name in reached:
            status = "ok"
            summary = (f"reached: {model.name}'s run found a state that violates "
                       f"{witness.property}")
        elif finished:
            status = "failed"
            summary = (f"NOT reached: no state of {model.name}'s run violates "
                       f"{witness.property}; the property it guards is vacuous in this model")
        else:
            status = "undecided"
            summary = (f"not reached before {model.name}'s run stopped ({run.meaning}); "
                       f"check it alone: keel-verify specs --witness {witness.name}")
        outcomes.append(Outcome(witness.name, "witness", model.spec,
                                {"verdict": "reached", "in": model.name, "property": witness.property},
                                result, status, summary, description=witness.description,
                                module=model.module, config=model.config))
    return outcomes


def check_mutant(mutant: Mutant, base: Model, jar: Path, spec_dir: Path,
                 args: argparse.Namespace) -> Outcome:
    try:
        # A witness, and a mutant TLC must reject with exit 12, name an invariant: checked as
        # one also when the base model does not list it (a property it leaves out on purpose).
        cfg = retarget_cfg(base.cfg_text, mutant.specification, mutant.property,
                           mutant.constants,
                           invariant=mutant.kind == "witness" or mutant.exit_code == 12)
    except ManifestError as error:
        failed = TlcResult(None, INPUT_ERROR, str(error), 0.0)
        return Outcome(mutant.name, mutant.kind, base.spec, {}, failed, "input-error",
                       str(error), module=mutant.module, config=base.config)
    result = _tlc(jar, spec_dir, mutant.name, mutant.module, cfg, base.extra_files, args,
                  quick=True, simulation=mutant.simulate)
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
                   description=mutant.description, module=mutant.module, config=base.config)


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
    if result.simulation is not None:
        facts.append(f"simulation: {result.simulation['traces']:,} traces, depth "
                     f"<= {result.simulation['depth']}, seed {result.simulation['seed']}")
        if result.states_checked is not None:
            facts.append(f"{result.states_checked:,} states checked")
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
    # Raising here unwinds run_all, which kills every TLC process still running (a
    # time-out of CTest sends SIGTERM): no model checker is left running.
    raise SystemExit(128 + signum)


# --------------------------------------------------------------------------------------
# CI reports

RULES = [
    report.Rule("property-violated", "TLC found a behaviour of a model that violates one of "
                                     "its properties"),
    report.Rule("state-count-changed", "a model passed, but with another distinct-state count "
                                       "than spec/manifest.json records"),
    report.Rule("mutant-not-rejected", "TLC did not reject a deliberately broken spec for the "
                                       "property it must break"),
    report.Rule("witness-not-reached", "TLC reached no state a property needs: the property is "
                                       "vacuous in the model"),
    report.Rule("input-error", "a spec, model, manifest or mission cannot be used"),
    report.Rule("undecided", "TLC could not finish (time limit, evaluation error, out of "
                             "memory): not a pass"),
]


def _rule(outcome: Outcome) -> str:
    if outcome.status in ("input-error", "undecided"):
        return outcome.status
    if outcome.kind == "mutant":
        return "mutant-not-rejected"
    if outcome.kind == "witness":
        return "witness-not-reached"
    return "property-violated" if outcome.result.verdict == VIOLATION else "state-count-changed"


def _location(outcome: Outcome, rule: str, spec_dir: Path, manifest: Path) -> tuple[str, int, int]:
    """Where a finding about ``outcome`` points: the violated property's definition, the
    mutant's module, the manifest's entry of a changed count, else the model's module."""
    module = spec_dir / f"{outcome.module}.tla"
    if outcome.kind == "mutant":
        return str(spec_dir / "mutants" / f"{outcome.module}.tla"), 1, 1
    if rule == "state-count-changed":
        line, col = report.find_line(manifest, rf'"name":\s*"{re.escape(outcome.name)}"')
        return str(manifest), line, col
    prop = outcome.result.property or str(outcome.expected.get("property") or "")
    if prop and rule in ("property-violated", "witness-not-reached"):
        candidates = [module, *sorted(spec_dir.glob("*.tla"))]
        for candidate in candidates:
            line, col = report.find_line(candidate, rf"^{re.escape(prop)}\b[^=\n]*==")
            if (line, col) != (1, 1):
                return str(candidate), line, col
    if module.is_file():
        return str(module), 1, 1
    spec = spec_dir / f"{outcome.spec}.tla"
    return (str(spec) if spec.is_file() else str(manifest)), 1, 1


def build_report(outcomes: list[Outcome], code: int, verdict: str, seconds: float,
                 spec_dir: Path, manifest: Path, title: str) -> report.Report:
    """A finding per outcome that is not as expected, a test case per model, mutant or
    witness."""
    findings, cases = [], []
    for outcome in outcomes:
        details = [line for line in (outcome.description, *outcome.notes) if line]
        if outcome.result.trace:
            details.append(counterexample.render(outcome.result.trace))
        status = {"ok": report.PASSED, "failed": report.FAILED}.get(outcome.status,
                                                                     report.ERRORED)
        cases.append(report.Case(outcome.name, f"keel-verify.specs.{outcome.kind}", status,
                                 outcome.summary, "\n".join(details), outcome.result.seconds))
        if outcome.status == "ok":
            continue
        rule = _rule(outcome)
        file, line, col = _location(outcome, rule, spec_dir, manifest)
        message = f"{outcome.kind} {outcome.name}: {outcome.summary}"
        if outcome.result.trace:
            last = outcome.result.trace[-1]
            message += (f" (counterexample: {len(outcome.result.trace)} states, the last by "
                        f"{last.action})")
        data = outcome.as_json()
        properties = {key: data[key] for key in ("spec", "verdict", "exit_code", "property",
                                                  "distinct_states", "counterexample")
                      if key in data}
        findings.append(report.Finding(rule, message, file, line, col,
                                       report.WARNING if rule == "undecided" else report.ERROR,
                                       properties))
    return report.Report("specs", title, verdict, code, RULES, findings, cases, seconds)


def _stop(args: argparse.Namespace, message: str, file: str, code: int = EXIT_INPUT_ERROR) -> int:
    """An error before any model ran: one line on stderr (and a report in a CI format)."""
    if args.format not in report.CI_FORMATS:  # there, the report's summary says it
        print(f"keel-verify specs: {message}", file=sys.stderr)
    else:
        finding = report.Finding("input-error", message, file)
        report.emit(report.Report("specs", "protocol specs", f"input error: {message}", code,
                                  RULES, [finding]), args.format)
    return code


def summary_line(outcomes: list[Outcome], code: int, seconds: float) -> str:
    def count(kind: str, ok: bool = False) -> int:
        return sum(1 for o in outcomes if o.kind == kind and (o.status == "ok" or not ok))

    verdict = {EXIT_OK: "all as expected", EXIT_FAILED: "FAILED",
               EXIT_INPUT_ERROR: "input error", EXIT_UNDECIDED: "UNDECIDED"}[code]
    witnesses = (f", {count('witness', True)}/{count('witness')} witnesses reached"
                 if count("witness") else "")
    return (f"{count('model', True)}/{count('model')} models passed, "
            f"{count('mutant', True)}/{count('mutant')} mutants rejected{witnesses} in "
            f"{seconds:.1f} s: {verdict}")


# --------------------------------------------------------------------------------------
# The command


def run_all(runs: list[tuple[int, Callable[[], Outcome | list[Outcome]]]], jobs: int,
            show: Callable[[Outcome], object]) -> list[Outcome]:
    """Every run, ``jobs`` at a time, the costliest (first of each pair) first; the
    outcomes in the order of ``runs``, each shown as soon as it and all before it are in.
    Stopped (SIGTERM, Ctrl-C): every TLC still running is killed."""
    order = sorted(range(len(runs)), key=lambda i: -runs[i][0])
    futures: dict[int, Future[Outcome | list[Outcome]]] = {}
    outcomes: list[Outcome] = []
    pool = ThreadPoolExecutor(max_workers=jobs, thread_name_prefix="tlc-run")
    try:
        for i in order:
            futures[i] = pool.submit(runs[i][1])
        for i in range(len(runs)):
            done = futures[i].result()
            for outcome in done if isinstance(done, list) else [done]:
                outcomes.append(outcome)
                show(outcome)
            sys.stdout.flush()
    except BaseException:
        for future in futures.values():
            future.cancel()
        stop_all()
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    return outcomes


def run(args: argparse.Namespace) -> int:
    signal.signal(signal.SIGTERM, _stop_on_sigterm)
    spec_dir = _spec_dir(args.spec_dir)
    try:
        manifest = load_manifest(spec_dir)
    except ManifestError as error:
        return _stop(args, str(error), str(spec_dir / "manifest.json"))

    mission_name = None
    mission_facts: dict[str, object] | None = None
    if args.mission:
        try:
            mission_name, models, mission_facts = mission_models(
                Path(args.mission), args.max_lossy_links
            )
        except MissionModelError as error:
            return _stop(args, f"{args.mission}: {error}", args.mission)
        mutants: list[Mutant] = []
        compare_count = False
    else:
        models, mutants, compare_count = manifest.models, manifest.mutants, True

    known = {model.name for model in models} | {mutant.name for mutant in mutants}
    unknown = [name for name in args.model + args.mutant if name not in known]
    if unknown:
        return _stop(args, f"unknown model or mutant: {', '.join(unknown)} "
                           f"(known: {', '.join(sorted(known))})", str(manifest.path))
    if args.model or args.mutant:
        models = [m for m in models if m.name in args.model]
        mutants = [m for m in mutants if m.name in args.mutant]
    elif not args.all:
        models = [m for m in models if not m.bench]
        mutants = [m for m in mutants if not m.bench]
    if args.no_mutants:
        mutants = []
    elif args.model:
        # A model asked for by name brings its witnesses (looked for in its run, or with
        # --separate-witnesses each in a run of its own).
        named = set(args.model)
        mutants += [m for m in manifest.mutants
                    if m.kind == "witness" and m.base in named and m not in mutants]
    # Witnesses are looked for in their model's own run when it is checked here, unless
    # asked for by name (their counterexample then shows how) or --separate-witnesses.
    probed: dict[str, list[Mutant]] = {}
    if not (args.separate_witnesses or args.counterexamples or args.mission):
        run_models = {model.name: model for model in models}
        for mutant in mutants:
            if (mutant.kind == "witness" and mutant.name not in args.mutant
                    and mutant.base in run_models
                    and can_probe(run_models[mutant.base], mutant, spec_dir)):
                probed.setdefault(mutant.base, []).append(mutant)
        folded = {w.name for group in probed.values() for w in group}
        mutants = [m for m in mutants if m.name not in folded]

    if args.list:
        for model in models:
            how = (f" (simulation: {model.simulate.traces} traces, depth {model.simulate.depth})"
                   if model.simulate is not None else "")
            print(f"model   {model.name:<28} {model.spec}{how}")
        for witnesses in probed.values():
            for witness in witnesses:
                print(f"witness {witness.name:<28} must reach ~{witness.property} (in "
                      f"{witness.base}'s run)")
        for mutant in mutants:
            verb = "must reach ~" if mutant.kind == "witness" else "must break "
            print(f"{mutant.kind:<7} {mutant.name:<28} {verb}{mutant.property} "
                  f"(exit {mutant.exit_code})")
        return EXIT_OK

    try:
        jar = resources.require_tlc(args.tlc_jar).jar
    except resources.ToolMissing as error:
        return _stop(args, str(error), str(manifest.path))

    text = args.format == "text"
    if mission_facts and text:
        print(f"mission {mission_name}: nodes {', '.join(mission_facts['nodes'])}; "  # type: ignore[arg-type]
              f"priority {' > '.join(mission_facts['priority'])}; "  # type: ignore[arg-type]
              f"monitors {', '.join(mission_facts['monitors'])}; "  # type: ignore[arg-type]
              f"miss limit {mission_facts['miss_limit']}; start-up grace "
              f"{mission_facts['startup_grace_periods']} periods; "
              f"storage {mission_facts['storage']}")
        print(f"  environment bound of the Heartbeat model: at most "
              f"{mission_facts['max_lossy_links']} link(s) in a loss streak at once "
              "(--max-lossy-links)")
    try:
        jobs = _jobs(args.jobs)
    except ValueError as error:
        return _stop(args, str(error), str(manifest.path))
    started = time.monotonic()
    explicit = bool(args.model or args.mutant) or args.counterexamples
    by_name = {model.name: model for model in manifest.models}
    runs: list[tuple[int, Callable[[], Outcome | list[Outcome]]]] = [
        (model.recorded_count or 10**9,
         lambda model=model: check_model(model, jar, spec_dir, args, compare_count,
                                         probed.get(model.name)))
        for model in models]
    runs += [((by_name[mutant.base].distinct_states or 10**9) // 2,
              lambda mutant=mutant: check_mutant(mutant, by_name[mutant.base], jar, spec_dir,
                                                 args))
             for mutant in mutants]
    jobs = max(1, min(jobs, len(runs)))
    args.workers = _workers(args.workers, jobs)

    def show(outcome: Outcome) -> None:
        if text:
            print_outcome(outcome, explicit)

    outcomes = run_all(runs, jobs, show)
    seconds = time.monotonic() - started

    if args.update_manifest and not args.mission:
        counts = {o.name: (o.result.states_checked if o.result.simulation is not None
                           else o.result.distinct_states)
                  for o in outcomes if o.kind == "model" and o.result.verdict == PASS}
        counts = {name: count for name, count in counts.items() if count is not None}
        update_counts(manifest, counts)  # type: ignore[arg-type]

    code = exit_code_of(outcomes)
    if args.format == "json":
        print(json.dumps({
            "ok": code == EXIT_OK,
            "exit_code": code,
            "mission": mission_name,
            "instantiation": mission_facts,
            "seconds": round(seconds, 2),
            "results": [outcome.as_json() for outcome in outcomes],
        }, indent=2))
    elif args.format in report.CI_FORMATS:
        title = f"mission {mission_name}" if mission_name else "protocol specs"
        report.emit(build_report(outcomes, code, summary_line(outcomes, code, seconds),
                                 seconds, spec_dir, manifest.path, title), args.format)
    else:
        print(f"\n{summary_line(outcomes, code, seconds)}")
    return code
