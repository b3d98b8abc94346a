"""The explicit-state heartbeat checker (keel_verify/trace/explicit_heartbeat.py) is an exact
port of spec/trace/TraceHeartbeat.tla: on keel-sim traces of both missions, and on many
deterministic mutants of them, it gives TLC's verdict, gets stuck at TLC's line and finds
as many distinct states as TLC. Mutants of the port itself are caught by that comparison,
and engine.check's modes never let a disagreement pass."""

from __future__ import annotations

import copy
import dataclasses
import importlib.util
import os
import random
import sys
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from types import ModuleType

import pytest
from conftest import ROOT, sim_trace, tlc_jar

sys.path.insert(0, str(ROOT / "verify"))

from keel_verify.trace import engine, explicit_heartbeat, heartbeat, tlc_trace  # noqa: E402
from keel_verify.trace.load import Line, load  # noqa: E402
from keel_verify.trace.mission_facts import Facts, facts  # noqa: E402

PROTOTYPE3 = ROOT / "config" / "prototype3.yaml"
EARTH_OBSERVATION = ROOT / "config" / "earth_observation.yaml"
# Seeds whose random fault plans reach every kind of heartbeat line: prototype3 seed 7
# (blocked links, a restart, a resignation, readmissions), seed 11 (a deaf node: suspect
# Ticks, a resignation, an exclusion declared), earth-observation seed 31 (a restart,
# deafness, resignation, exclusions, ten readmissions).
RUNS = [(PROTOTYPE3, 7), (PROTOTYPE3, 11), (EARTH_OBSERVATION, 31)]
SPEC_DIR = ROOT / "spec"
TLC_WORKERS = int(os.environ.get("KEEL_TRACE_JOBS", "2"))


@dataclasses.dataclass
class Case:
    """One heartbeat job and TLC's answer for it."""

    name: str
    job: engine.Job
    tlc: tlc_trace.Run | None = None

    def tlc_answer(self) -> tuple[str, int | None, int | None]:
        assert self.tlc is not None
        return self.tlc.outcome, self.tlc.max_l, self.tlc.distinct_states


def port_answer(job: engine.Job) -> tuple[str, int | None, int | None]:
    assert job.explicit is not None
    run = job.explicit()
    return run.outcome, run.max_l, run.distinct_states


def run_tlc(cases: list[Case]) -> None:
    """TLC's verdict, first unexplained line (-dump) and distinct states for each case."""
    jar = tlc_jar()

    def one(case: Case) -> tlc_trace.Run:
        job = case.job
        return tlc_trace.run(jar, SPEC_DIR, job.module_name(), job.module_text(),
                             job.cfg_text(), 600, dump=True,
                             extra_files={f"{job.data_name()}.tla": job.data_text()})

    with ThreadPoolExecutor(max_workers=max(1, TLC_WORKERS)) as pool:
        for case, answer in zip(cases, pool.map(one, cases), strict=True):
            case.tlc = answer
            assert answer.outcome in ("accepted", "stuck"), (case.name, answer.message,
                                                             answer.output[-2000:])


# --------------------------------------------------------------------------------------
# Mutants of a trace: each changes one line of one node, deterministically


def _hb(lines: list[Line], node: str, action: str | None = None) -> list[int]:
    return [i for i, line in enumerate(lines) if line.node == node and line.fsm == "heartbeat"
            and (action is None or line.action == action)]


def _copy(line: Line, **changes: object) -> Line:
    return dataclasses.replace(line, args=copy.deepcopy(line.args),
                               vars=copy.deepcopy(line.vars), **changes)


def _toggle(names: list[str], name: str) -> list[str]:
    return sorted(set(names) ^ {name})


Mutation = Callable[[list[Line], str, list[str], random.Random], tuple[str, list[Line], int]]


def change_missed(lines: list[Line], node: str, nodes: list[str],
                  rng: random.Random) -> tuple[str, list[Line], int]:
    at = rng.choice(_hb(lines, node, "Tick"))
    line = _copy(lines[at])
    watched = rng.choice(sorted(line.vars["missed"]))
    line.vars["missed"][watched] += 1 if line.vars["missed"][watched] == 0 else \
        rng.choice([1, -1])
    return f"missed[{watched}] changed", [*lines[:at], line, *lines[at + 1:]], at


def drop_receive(lines: list[Line], node: str, nodes: list[str],
                 rng: random.Random) -> tuple[str, list[Line], int]:
    at = rng.choice(_hb(lines, node, "ReceiveHeartbeat"))
    return "a ReceiveHeartbeat dropped", [*lines[:at], *lines[at + 1:]], at


def duplicate_receive(lines: list[Line], node: str, nodes: list[str],
                      rng: random.Random) -> tuple[str, list[Line], int]:
    at = rng.choice(_hb(lines, node, "ReceiveHeartbeat"))
    return "a ReceiveHeartbeat twice", [*lines[:at + 1], _copy(lines[at]), *lines[at + 1:]], at


def swap(lines: list[Line], node: str, nodes: list[str],
         rng: random.Random) -> tuple[str, list[Line], int]:
    own = _hb(lines, node)
    k = rng.randrange(len(own) - 1)
    a, b = own[k], own[k + 1]
    out = list(lines)
    out[a], out[b] = lines[b], lines[a]
    return f"{lines[a].action} and {lines[b].action} swapped", out, a


def declare_other_node(lines: list[Line], node: str, nodes: list[str],
                       rng: random.Random) -> tuple[str, list[Line], int]:
    at = rng.choice(_hb(lines, node, "DeclareFailed"))
    line = _copy(lines[at])
    line.args["n"] = rng.choice([n for n in nodes if n not in (node, line.args["n"])])
    return "a DeclareFailed of another node", [*lines[:at], line, *lines[at + 1:]], at


def declare_early(lines: list[Line], node: str, nodes: list[str],
                  rng: random.Random) -> tuple[str, list[Line], int]:
    # The declaration one period early, logged as the state then was (failed aside): only
    # DeclareFailed's guard (missed >= DeclareAt) tells it from a good one.
    at = rng.choice([i for i in _hb(lines, node, "DeclareFailed")
                     if lines[i].args.get("reason", "missed") == "missed"])
    ticks = [i for i in _hb(lines, node, "Tick") if i < at]
    tick = ticks[-2]
    declared = lines[at].args["n"]
    line = _copy(lines[at], t_ns=lines[tick].t_ns)
    line.vars = copy.deepcopy(lines[tick].vars)
    line.vars["failed"] = sorted({*line.vars.get("failed", []), declared})
    return "a DeclareFailed a period early", [*lines[:tick + 1], line, *lines[tick + 1:]], tick


def declare_reason(lines: list[Line], node: str, nodes: list[str],
                   rng: random.Random) -> tuple[str, list[Line], int]:
    at = rng.choice(_hb(lines, node, "DeclareFailed"))
    line = _copy(lines[at])
    line.args["reason"] = "excluded" if line.args.get("reason", "missed") == "missed" \
        else "missed"
    return "a DeclareFailed's reason changed", [*lines[:at], line, *lines[at + 1:]], at


def spurious_tick(lines: list[Line], node: str, nodes: list[str],
                  rng: random.Random) -> tuple[str, list[Line], int]:
    ticks = _hb(lines, node, "Tick")
    k = rng.randrange(len(ticks) - 1)
    at = rng.choice([i for i in _hb(lines, node) if ticks[k] < i < ticks[k + 1]] or
                    [ticks[k]])
    return "a spurious Tick", [*lines[:at + 1], _copy(lines[ticks[k]]), *lines[at + 1:]], at


def flip_suspect(lines: list[Line], node: str, nodes: list[str],
                 rng: random.Random) -> tuple[str, list[Line], int]:
    at = rng.choice(_hb(lines, node, "Tick"))
    line = _copy(lines[at])
    line.args["suspect"] = line.args.get("suspect") is not True
    return "suspect flipped", [*lines[:at], line, *lines[at + 1:]], at


def flip_late(lines: list[Line], node: str, nodes: list[str],
              rng: random.Random) -> tuple[str, list[Line], int]:
    at = rng.choice(_hb(lines, node, "Tick"))
    line = _copy(lines[at])
    line.args["late"] = line.args.get("late") is not True
    return "late flipped", [*lines[:at], line, *lines[at + 1:]], at


def _toggle_var(var: str) -> Mutation:
    def mutate(lines: list[Line], node: str, nodes: list[str],
               rng: random.Random) -> tuple[str, list[Line], int]:
        at = rng.choice([i for i in _hb(lines, node) if var in lines[i].vars])
        line = _copy(lines[at])
        name = rng.choice([n for n in nodes if n != node])
        line.vars[var] = _toggle(line.vars[var], name)
        return f"{name} toggled in {var}", [*lines[:at], line, *lines[at + 1:]], at
    return mutate


def drop_marker(lines: list[Line], node: str, nodes: list[str],
                rng: random.Random) -> tuple[str, list[Line], int]:
    at = rng.choice([i for i, line in enumerate(lines) if line.node == node
                     and line.fsm == "election" and line.action == "ReceiveCommand"])
    return "a view change dropped", [*lines[:at], *lines[at + 1:]], at


MUTATIONS: list[Mutation] = [
    change_missed, drop_receive, duplicate_receive, swap, declare_other_node, declare_early,
    declare_reason, spurious_tick, flip_suspect, flip_late, _toggle_var("failed"),
    _toggle_var("heard"), _toggle_var("heardOnce"), drop_marker,
]
# Lines of the whole trace kept after the mutated one: the job stays short for TLC.
MARGIN = 120


def mutant_cases(name: str, lines: list[Line], mission: Facts, seed: int) -> list[Case]:
    """A mutant of each kind but every third (which one depends on the seed), of a node
    that has the lines the kind changes: each kind is tried on two traces of three."""
    rng = random.Random(seed)
    cases = []
    for k, mutate in enumerate(MUTATIONS):
        if (k + seed) % 3 == 0:
            continue
        order = list(mission.nodes)
        rng.shuffle(order)
        for node in order:
            try:
                what, mutated, at = mutate(lines, node, mission.nodes, rng)
            except (IndexError, ValueError, KeyError, TypeError):
                continue  # this node has no line of that kind
            job = next(j for j in heartbeat.jobs(mutated[:at + MARGIN], mission)
                       if j.subject == node)
            cases.append(Case(f"{name} {node}: {what} (trace line {at + 1})", job))
            break
    return cases


# --------------------------------------------------------------------------------------
# Fixtures: the traces, their jobs and mutants, and TLC's answers (computed once)


@pytest.fixture(scope="module")
def traces(tmp_path_factory: pytest.TempPathFactory) -> list[tuple[str, list[Line], Facts]]:
    out = []
    folder = tmp_path_factory.mktemp("explicit")
    for mission_path, seed in RUNS:
        trace, _ = sim_trace(folder, seed, duration="10s", mission=mission_path)
        out.append((f"{mission_path.stem} seed {seed}", load([str(trace)]),
                    facts(mission_path)))
    return out


@pytest.fixture(scope="module")
def real_cases(traces: list[tuple[str, list[Line], Facts]]) -> list[Case]:
    cases = [Case(f"{name} {job.subject}", job) for name, lines, mission in traces
             for job in heartbeat.jobs(lines, mission)]
    run_tlc(cases)
    return cases


@pytest.fixture(scope="module")
def mutants(traces: list[tuple[str, list[Line], Facts]]) -> list[Case]:
    cases = [case for k, (name, lines, mission) in enumerate(traces)
             for case in mutant_cases(name, lines, mission, seed=1000 + k)]
    run_tlc(cases)
    return cases


def disagreements(cases: list[Case]) -> list[str]:
    out = []
    for case in cases:
        port = port_answer(case.job)
        if port != case.tlc_answer():
            out.append(f"{case.name}: TLC {case.tlc_answer()}, port {port}")
    return out


# --------------------------------------------------------------------------------------
# 1. Real traces


def test_the_port_agrees_with_tlc_on_simulator_traces(real_cases: list[Case]) -> None:
    assert len(real_cases) == 4 + 4 + 6
    assert not disagreements(real_cases), "\n".join(disagreements(real_cases))
    # The runs are behaviours of the spec; the kinds of line the port has arms for occur.
    assert all(case.tlc_answer()[0] == "accepted" for case in real_cases)
    actions = {line.action for case in real_cases for line in case.job.lines}
    assert {"Tick", "SendHeartbeat", "ReceiveHeartbeat", "DeclareFailed", "Readmit",
            "Rejoin", "ReceiveCommand", "Restart", "Resign"} <= actions
    suspect = [line for case in real_cases for line in case.job.lines
               if line.action == "Tick" and line.args.get("suspect") is True]
    assert suspect


# --------------------------------------------------------------------------------------
# 2. Broken traces


def test_the_port_agrees_with_tlc_on_broken_traces(mutants: list[Case]) -> None:
    assert len(mutants) >= 24, [case.name for case in mutants]
    assert not disagreements(mutants), "\n".join(disagreements(mutants))
    verdicts = [case.tlc_answer()[0] for case in mutants]
    rejected, accepted = verdicts.count("stuck"), verdicts.count("accepted")
    # Not vacuous: most are rejected (each at its own line), and some are behaviours too
    # (a heartbeat received twice, a late flag on a counting Tick, ...).
    assert rejected >= 15 and accepted >= 3, (rejected, accepted)
    assert len({case.tlc_answer()[1] for case in mutants if case.tlc_answer()[0] == "stuck"}) \
        >= 10


def test_the_port_agrees_with_tlc_under_other_constants(real_cases: list[Case]) -> None:
    # The guards the shipped jobs never close: the loss bound without the environment's
    # exemptions (every Tick's `lossy` empty: a crashed node's third lost heartbeat in a
    # row has no explanation), late boots (nodes that never boot here, so Tick waits for
    # them only MaxBootDelay periods), and a small budget of hidden steps. The job: the
    # shortest with a declaration of a missed node that each guard closes as expected in
    # the port (TLC must then agree with it).
    variants: list[dict[str, int]] = [{}, {"max_late_boots": 1, "max_boot_delay": 2},
                                      {"max_hidden": 3}]

    def variant_cases(job: engine.Job) -> list[Case]:
        port = job.explicit
        assert isinstance(port, heartbeat.ExplicitPort)
        assert port.constants.max_loss == 2  # MissLimit 3 - 1: the spec's bound
        cases = []
        for changes in variants:
            constants = dataclasses.replace(port.constants, **changes)
            varied = dataclasses.replace(job, constants=heartbeat.cfg_constants(constants),
                                         explicit=dataclasses.replace(port, constants=constants))
            if not changes:  # the environment unread
                assert any(port.lossy), "no Tick of the job has an exemption"
                varied = dataclasses.replace(
                    varied, records=[heartbeat._record(heartbeat._fields(ln, a, port.nodes))
                                     for ln, a in zip(port.lines, port.actions, strict=True)],
                    explicit=dataclasses.replace(port, constants=constants,
                                                 lossy=[[] for _ in port.lines]))
            cases.append(Case(f"{job.subject} with {changes or 'no exemption'}", varied))
        return cases

    candidates = sorted((case.job for case in real_cases if any(
        line.action == "DeclareFailed" and line.args.get("reason", "missed") == "missed"
        for line in case.job.lines)), key=lambda job: len(job.lines))
    cases = next((cases for cases in map(variant_cases, candidates)
                  if [port_answer(case.job)[0] for case in cases] == ["stuck", "accepted", "stuck"]),
                 None)
    assert cases is not None, "no real trace's job is closed by each guard"
    run_tlc(cases)
    assert not disagreements(cases), "\n".join(disagreements(cases))
    assert [case.tlc_answer()[0] for case in cases] == ["stuck", "accepted", "stuck"]


# --------------------------------------------------------------------------------------
# 3. Mutants of the port are caught


def _port_mutant(old: str, new: str) -> ModuleType:
    """explicit_heartbeat.py with one piece of text replaced (it must occur once)."""
    path = Path(explicit_heartbeat.__file__)
    source = path.read_text()
    assert source.count(old) == 1, f"the port no longer has {old!r}: update this test"
    name = "explicit_heartbeat_mutant"
    module = importlib.util.module_from_spec(importlib.util.spec_from_loader(name, None))
    sys.modules[name] = module
    try:
        exec(compile(source.replace(old, new), str(path), "exec"), module.__dict__)
    finally:
        del sys.modules[name]
    return module


PORT_MUTANTS = {
    # DeclareFailed without its guard missed[M][n] >= DeclareAt(M, n).
    "no-declare-guard": ("if layout.missed_of(missed, n) < declare_at:", "if False:"),
    # A Tick line's logged missed counts not compared (Matches).
    "tick-ignores-missed": ("after & domain != want_missed", "False"),
    # A suspect Tick that counts its misses (TickBy(Always) for SuspectTick).
    "suspect-tick-counts": ("counts = e.kind == TICK", "counts = True"),
    # ReceiveLine without its rule for a node already heard in the period.
    "no-second-heartbeat": ("if heard & n:\n                after = s",
                            "if False:\n                after = s"),
    # Forget(n) without n's message counted as heard in the period.
    "forget-not-heard": ("heard | n, missed & missed_clear[n],",
                         "heard, missed & missed_clear[n],"),
}


@pytest.mark.parametrize("mutant", sorted(PORT_MUTANTS))
def test_a_mutant_of_the_port_disagrees_with_tlc(mutant: str, real_cases: list[Case],
                                                 mutants: list[Case],
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    broken = _port_mutant(*PORT_MUTANTS[mutant])
    monkeypatch.setattr(heartbeat, "explicit_heartbeat", broken)
    found = disagreements(real_cases + mutants)
    assert found, f"the port mutant {mutant} agrees with TLC on every trace"


# --------------------------------------------------------------------------------------
# engine.check: the modes, and a disagreement is never a pass


def _smallest(cases: list[Case], outcome: str) -> Case:
    return min((case for case in cases if case.tlc_answer()[0] == outcome),
               key=lambda case: len(case.job.lines))


def test_engine_takes_the_ports_acceptance_without_tlc(real_cases: list[Case]) -> None:
    case = real_cases[0]
    # No TLC to run: were it asked, the verdict could not be "accepted".
    result = engine.check(case.job, Path("/nonexistent/tlatools.jar"), SPEC_DIR, 60)
    assert (result.verdict, result.checker) == (engine.ACCEPTED, "explicit")
    assert result.distinct_states == case.tlc_answer()[2]


def test_engine_modes_agree_and_a_disagreement_is_undecided(real_cases: list[Case],
                                                            mutants: list[Case]) -> None:
    jar = tlc_jar()
    good, bad = _smallest(real_cases, "accepted"), _smallest(mutants, "stuck")
    both = engine.check(good.job, jar, SPEC_DIR, 600, checker="both")
    assert (both.verdict, both.checker, both.notes) == (engine.ACCEPTED, "both", [])
    # A rejected trace: the port gets stuck, TLC finds the same line and diagnoses it.
    result = engine.check(bad.job, jar, SPEC_DIR, 600, checker="explicit")
    assert result.verdict == engine.MISMATCH, result.message
    assert result.line is bad.job.lines[bad.tlc_answer()[1] - 1]
    # A port that rejects what TLC accepts: undecided, never a silent pass or a mismatch.
    wrong = dataclasses.replace(good.job, explicit=lambda: explicit_heartbeat.ExplicitRun(
        explicit_heartbeat.STUCK, 0.0, 1, max_l=1))
    for checker in ("explicit", "both"):
        result = engine.check(wrong, jar, SPEC_DIR, 600, checker=checker)
        assert result.verdict == engine.UNDECIDED, (checker, result.verdict)
        assert "disagree" in result.message
    # A port that accepts what TLC rejects ("both"): undecided too.
    lenient = dataclasses.replace(bad.job, explicit=lambda: explicit_heartbeat.ExplicitRun(
        explicit_heartbeat.ACCEPTED, 0.0, 1))
    result = engine.check(lenient, jar, SPEC_DIR, 600, checker="both")
    assert result.verdict == engine.UNDECIDED and "disagree" in result.message
    with pytest.raises(ValueError):
        engine.check(good.job, jar, SPEC_DIR, 600, checker="fast")


def test_a_line_the_port_does_not_cover_goes_to_tlc(real_cases: list[Case]) -> None:
    case = real_cases[0]
    port = case.job.explicit
    assert isinstance(port, heartbeat.ExplicitPort)
    records = list(port.records())
    at = next(i for i, record in enumerate(records) if record["action"] == "Tick")
    records[at] = {**records[at], "heard": [1]}  # a set of integers: TLC's to judge
    run = explicit_heartbeat.check(port.constants, records)
    assert run.outcome == explicit_heartbeat.UNSUPPORTED and f"line {at + 1}" in run.message
