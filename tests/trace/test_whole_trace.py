"""Whole-trace validation: partitions, resignations, safe mode and a Storage node out of
reach are validated line by line (spec/trace/TraceConfigSwitch.tla, spec/README.md "Trace
validation"). Each new step has a witness (a real keel-sim trace with that line kind,
validated in full: exit 0) and each new guard a hand-broken trace it rejects at the
broken line."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest
from conftest import ROOT, binary, explain, first_unexplained, sim_trace, validate

P3 = ROOT / "config" / "prototype3.yaml"
EO = ROOT / "config" / "earth_observation.yaml"


def lines_of(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def write(path: Path, lines: list[dict]) -> Path:
    path.write_text("".join(json.dumps(line, separators=(",", ":")) + "\n" for line in lines))
    return path


def kinds(lines: list[dict]) -> set[str]:
    """The actions of a trace, and SAFE when a switch line names safe mode."""
    out = {line["action"] for line in lines}
    if any(line["fsm"] == "switch" and line["args"].get("c") == "SAFE" for line in lines):
        out.add("SAFE")
    return out


def fully_validated(trace: Path, mission: Path = P3, fsm: list[str] | None = None) -> dict:
    code, report, stderr = validate(trace, mission=mission, fsm=fsm)
    assert code == 0, explain(report) + stderr + json.dumps(report.get("coverage"))
    for protocol, counted in report["coverage"].items():
        assert counted["validated"] == counted["total"] > 0, protocol
    return report


def index(lines: list[dict], action: str, start: int = 0, fsm: str = "switch",
          **match: object) -> int:
    return next(i for i, line in enumerate(lines)
                if i >= start and line["fsm"] == fsm and line["action"] == action
                and all(line["args"].get(k) == v for k, v in match.items()))


def scenario_trace(tmp_path: Path, name: str) -> Path:
    scenario = ROOT / "tests" / "sim" / "testdata" / f"{name}.txt"
    done = subprocess.run([str(binary("keel-sim")), "scenario", str(scenario), "--trace-dir",
                           str(tmp_path)], capture_output=True, text=True, timeout=300,
                          check=False, env=dict(os.environ, KEEL_ROOT=str(ROOT)))
    trace = tmp_path / f"{name}.ndjson"
    assert trace.is_file(), done.stdout + done.stderr
    return trace


def rejected_at(tmp_path: Path, name: str, lines: list[dict], line: int,
                mission: Path = P3) -> dict:
    """The switch lines of a broken trace are rejected (exit 1) at line `line`."""
    code, report, stderr = validate(write(tmp_path / name, lines), mission=mission,
                                    fsm=["switch"])
    assert code == 1, explain(report) + stderr
    where = first_unexplained(report)
    assert where["line"] == line, explain(report)
    return where


# --------------------------------------------------------------------------------------
# Witnesses: real runs with the newly covered line kinds, every protocol line validated
# (heartbeat, election and switch: exit 0).

# seed -> line kinds its keel-sim run (prototype3, 5 s) has that validation used to stop at.
WITNESSES = {
    3: {"Partition"},
    6: {"Partition", "SAFE", "AskHolders", "StateOutOfReach"},
    7: {"Block", "LeaseLapsed", "Resign", "Resigned"},
    11: {"Resign", "Resigned", "SAFE"},
    20: {"Partition", "SAFE", "AskHolders", "Readmit"},
}


@pytest.mark.parametrize("seed", sorted(WITNESSES))
def test_runs_with_partitions_resignations_and_safe_mode_validate_in_full(
        tmp_path: Path, seed: int) -> None:
    trace, _ = sim_trace(tmp_path, seed, duration="5s")
    assert WITNESSES[seed] <= kinds(lines_of(trace))
    fully_validated(trace)


def test_an_earth_observation_resignation_with_its_final_flush_validates(tmp_path: Path) -> None:
    # Seed 11: the Master's lease lapses; it resigns, stops `aocs` and flushes its final
    # checkpoint (the Storage node stores it), then an Observer takes over.
    trace, _ = sim_trace(tmp_path, 11, duration="5s", mission=EO)
    lines = lines_of(trace)
    at = index(lines, "Resign")
    assert any(line["action"] == "FlushCheckpoint" and line["args"].get("final")
               for line in lines[at:at + 4])
    fully_validated(trace, mission=EO)


@pytest.mark.parametrize("name, kind", [("ground_recovery", "GroundRecovery"),
                                        ("ground_holds_a_node_out", "GroundExclude"),
                                        ("worker_resigns", "AskExclusion"),
                                        ("state_out_of_reach", "StateOutOfReach")])
def test_scenarios_with_ground_commands_and_resignations_validate_in_full(
        tmp_path: Path, name: str, kind: str) -> None:
    trace = scenario_trace(tmp_path, name)
    assert kind in kinds(lines_of(trace))
    fully_validated(trace, fsm=["switch"])


def test_a_trace_written_before_one_name_per_meaning_validates_as_it_did(
        seed20: list[dict], tmp_path: Path) -> None:
    # Before the rename the election's Suspect and the switch's Exclude were both logged
    # as DeclareFailed (spec/NAMES.md, "Renamed actions"): such a trace reads under today's
    # names and validates in full (the same trace with today's names is a witness above).
    renamed = [{**line, "action": "DeclareFailed"}
               if (line["fsm"], line["action"]) in {("election", "Suspect"), ("switch", "Exclude")}
               else line for line in seed20]
    assert sum(a != b for a, b in zip(seed20, renamed, strict=True)) >= 2
    assert {line["fsm"] for line in renamed if line["action"] == "DeclareFailed"} >= {
        "heartbeat", "election", "switch"}
    fully_validated(write(tmp_path / "old-names.ndjson", renamed))


# --------------------------------------------------------------------------------------
# Broken traces: each new guard rejects the line that breaks it.

@pytest.fixture(scope="module")
def seed20(tmp_path_factory: pytest.TempPathFactory) -> list[dict]:
    """Partition {PN2, ST1} | {PN1, PN3}: PN2 and ST1 are excluded alive (fenced), the
    cluster enters SAFE (PN1 runs taskB, gathered from PN3, which holds it), then the
    Master readmits ST1 (out of SAFE, into P3) and PN2 (into P1)."""
    trace, _ = sim_trace(tmp_path_factory.mktemp("seed20"), 20, duration="5s")
    return lines_of(trace)


def test_an_excluded_node_that_runs_on_is_caught(seed20: list[dict], tmp_path: Path) -> None:
    # PN2, cut off and declared, is fenced: it may adopt commands and stop what it held,
    # never run. A checkpoint of a task it still runs, after its exclusion, has no step.
    lines = list(seed20)
    declared = index(lines, "Exclude", f="PN2")
    forged = {"t_ns": lines[declared]["t_ns"], "node": "PN2", "fsm": "switch",
              "action": "FlushCheckpoint",
              "args": {"n": "PN2", "t": "taskA", "version": 99, "final": False},
              "vars": {"role": "Observer", "epoch": 1, "seq": 1, "config": "P1",
                       "stage": "Stable", "active": ["taskA"], "unflushed": [],
                       "version": {"taskA": 99}}}
    lines.insert(declared + 2, forged)
    rejected_at(tmp_path, "fenced-runs.ndjson", lines, declared + 3)


def test_a_safe_mode_entry_the_graph_does_not_make_is_caught(seed20: list[dict],
                                                             tmp_path: Path) -> None:
    # PN2's failure in P1 leads to P3 (an edge): entering SAFE instead is no step.
    lines = list(seed20)
    at = index(lines, "Exclude", f="PN2")
    assert lines[at]["args"]["c"] == "P3"
    lines[at] = {**lines[at], "args": {**lines[at]["args"], "c": "SAFE"},
                 "vars": {**lines[at]["vars"], "masterConfig": "SAFE"}}
    rejected_at(tmp_path, "bad-safe-entry.ndjson", lines, at + 1)


def test_a_safe_exit_onto_an_excluded_node_is_caught(seed20: list[dict], tmp_path: Path) -> None:
    # The Master leaves SAFE by readmitting ST1 into P3 (PN2 still excluded). P1 places
    # taskA on PN2: leaving SAFE for it is no step.
    lines = list(seed20)
    at = index(lines, "Readmit", r="ST1")
    assert lines[at]["args"]["c"] == "P3" and lines[at]["vars"]["failed"] == ["PN2"]
    assert any(line["fsm"] == "switch" and line["vars"].get("masterConfig") == "SAFE"
               for line in lines[:at])
    lines[at] = {**lines[at], "args": {**lines[at]["args"], "c": "P1"},
                 "vars": {**lines[at]["vars"], "masterConfig": "P1"}}
    rejected_at(tmp_path, "bad-safe-exit.ndjson", lines, at + 1)


def test_a_restore_below_a_holders_version_is_caught(seed20: list[dict], tmp_path: Path) -> None:
    # In SAFE, with ST1 excluded, PN1 gathers taskB from PN3, which handed it off. Starting
    # it lower, silently or as a reported loss (StateOutOfReach), is no step: PN3 runs,
    # and holds the newer version.
    lines = list(seed20)
    ask = index(lines, "AskHolders")
    activate = index(lines, "Activate", ask, t="taskB")
    assert lines[activate]["args"]["version"] > 1
    assert lines[activate]["args"]["restored"] is True
    lower = {**lines[activate], "args": {**lines[activate]["args"], "version": 1},
             "vars": {**lines[activate]["vars"], "version": {"taskB": 1}}}
    silent = lines[:activate] + [lower] + lines[activate + 1:]
    rejected_at(tmp_path, "bad-restore.ndjson", silent, activate + 1)
    report = {**lines[ask], "action": "StateOutOfReach",
              "args": {"n": lines[ask]["args"]["n"], "t": "taskB", "version": 1}}
    reported = lines[:activate] + [report, lower] + lines[activate + 1:]
    rejected_at(tmp_path, "bad-out-of-reach.ndjson", reported, activate + 1)


@pytest.fixture(scope="module")
def seed7(tmp_path_factory: pytest.TempPathFactory) -> list[dict]:
    """PN1, the Master, is cut off by one-way blocks; its lease lapses and it resigns;
    PN2 takes over (PN1 fenced); later PN2's lease lapses and it resigns too."""
    trace, _ = sim_trace(tmp_path_factory.mktemp("seed7"), 7, duration="5s")
    return lines_of(trace)


@pytest.mark.parametrize("flip, node", [(True, "PN1"), (False, "PN1"), (False, "ST1")])
def test_a_receive_command_line_that_misstates_its_step_down_is_rejected(
        seed7: list[dict], tmp_path: Path, flip: bool, node: str) -> None:
    # A ReceiveCommand line says whether its node stepped down (was Master, is not): the
    # Master's own command at boot says no, a deposed Master's says yes, the Storage node
    # (never Master) always no; any of them flipped is no step of the spec.
    lines = json.loads(json.dumps(seed7))
    at = next(i for i, x in enumerate(lines) if x["fsm"] == "election" and x["node"] == node
              and x["action"] == "ReceiveCommand" and x["args"].get("stepDown") is flip)
    lines[at]["args"]["stepDown"] = not flip
    code, result, _ = validate(write(tmp_path / "step-down.ndjson", lines), mission=P3,
                               fsm=["election"])
    assert code == 1
    assert first_unexplained(result)["line"] == at + 1


def test_a_resignation_by_another_node_is_caught(seed7: list[dict], tmp_path: Path) -> None:
    # The Master PN1 resigns. PN3, an Observer, cannot resign in its place (a Worker or
    # Observer asks to be excluded: AskExclusion); PN1 cannot resign for PN2.
    lines = list(seed7)
    at = index(lines, "Resign", n="PN1")
    by_other = {**lines[at], "node": "PN3", "args": {"n": "PN3"},
                "vars": {**lines[at]["vars"], "role": "Observer"}}
    rejected_at(tmp_path, "bad-resign.ndjson", lines[:at] + [by_other] + lines[at + 1:],
                at + 1)
    # A line of PN1 naming PN2 as the node that resigns contradicts itself: refused as
    # input at that line (keel_verify.trace.load.ACTOR).
    for_other = {**lines[at], "args": {"n": "PN2"}}
    bad = write(tmp_path / "bad-resign-for.ndjson", lines[:at] + [for_other] + lines[at + 1:])
    code, _, stderr = validate(bad, mission=P3, fsm=["switch"])
    assert code == 2 and f"{bad}:{at + 1}: a switch Resign line of PN1 whose args name n='PN2'" \
        in stderr, stderr


def test_a_resigned_master_that_drives_again_is_caught(seed7: list[dict], tmp_path: Path) -> None:
    # After its Resign line PN1 may only stop and flush: a phase change it starts is no
    # step (without the resignation, RequestPhase P1 -> S1 is enabled here).
    lines = list(seed7)
    at = index(lines, "Resigned", n="PN1")
    drive = {"t_ns": lines[at]["t_ns"], "node": "PN1", "fsm": "switch",
             "action": "RequestPhase", "args": {"m": "PN1", "c": "S1", "phase": "science"},
             "vars": {"masterConfig": "S1", "masterSeq": 2, "epoch": 1, "failed": []}}
    rejected_at(tmp_path, "bad-resigned-drives.ndjson",
                lines[:at + 1] + [drive] + lines[at + 1:], at + 2)


@pytest.mark.parametrize("target", ["P2", "S1"])
def test_a_ground_command_the_runtime_refuses_is_caught(tmp_path: Path, target: str) -> None:
    # ground_recovery: SAFE is left by a ground command for P1. P2 (another node is its
    # master) and S1 (another phase than SAFE was entered in) are no step.
    lines = lines_of(scenario_trace(tmp_path, "ground_recovery"))
    at = index(lines, "GroundRecovery", m="PN1")
    assert lines[at]["args"]["c"] == "P1"
    lines[at] = {**lines[at], "args": {**lines[at]["args"], "c": target},
                 "vars": {**lines[at]["vars"], "masterConfig": target}}
    rejected_at(tmp_path, f"bad-ground-{target}.ndjson", lines, at + 1)


def test_refusing_a_ground_command_the_spec_allows_is_caught(tmp_path: Path) -> None:
    # ground_recovery: S1 and P2 are refused (RefuseGroundCommand lines, validated as steps
    # that change nothing), P1 is accepted. A refusal of P1 there is no step: the refusal
    # is checked against GroundRecoverySwitch's guard.
    lines = lines_of(scenario_trace(tmp_path, "ground_recovery"))
    refusals = [i for i, line in enumerate(lines) if line["action"] == "RefuseGroundCommand"]
    assert [lines[i]["args"]["c"] for i in refusals] == ["S1", "P2"]
    at = index(lines, "GroundRecovery", m="PN1")
    refused = {**lines[at], "action": "RefuseGroundCommand",
               "args": {"m": "PN1", "c": "P1", "why": "forged"}, "vars": {}}
    rejected_at(tmp_path, "bad-refusal.ndjson", lines[:at] + [refused] + lines[at:], at + 1)


def test_an_exclusion_on_a_ground_hold_the_master_does_not_have_is_caught(tmp_path: Path) -> None:
    # ground_holds_a_node_out: the Master excludes PN3 on the ground's hold (its Exclude
    # says ground), after its GroundExclude line. Without the Master's GroundExclude line
    # it holds PN3 out nowhere: the Exclude is no step (EvidenceSuffices).
    lines = lines_of(scenario_trace(tmp_path, "ground_holds_a_node_out"))
    at = index(lines, "Exclude", f="PN3")
    assert lines[at]["args"]["ground"] is True and lines[at]["args"]["own"] is False
    hold = index(lines, "GroundExclude", f="PN3")
    assert hold < at
    masters = [i for i in range(at) if lines[i]["action"] == "GroundExclude"
               and lines[i]["node"] == lines[at]["node"]]
    assert masters
    kept = [line for i, line in enumerate(lines) if i not in masters]
    rejected_at(tmp_path, "bad-ground-exclude.ndjson", kept, at + 1 - len(masters))


def test_a_readmission_elsewhere_than_the_graph_says_is_caught(tmp_path: Path) -> None:
    # PN3 restarts while P4 runs (PN3 failed); readmitted, the graph leads back to P1 (the
    # smaller failed set: none). P3 is PN1's too and uses no failed node, but it is not
    # where the graph leads: readmitting into it is no step. The real trace validates.
    lines = lines_of(scenario_trace(tmp_path, "restart_then_failure"))
    at = index(lines, "Readmit", r="PN3")
    assert lines[at]["args"]["c"] == "P1" and lines[at]["vars"]["failed"] == []
    fully_validated(write(tmp_path / "real.ndjson", lines), fsm=["switch"])
    lines[at] = {**lines[at], "args": {**lines[at]["args"], "c": "P3"},
                 "vars": {**lines[at]["vars"], "masterConfig": "P3"}}
    rejected_at(tmp_path, "bad-readmit-target.ndjson", lines, at + 1)


# --------------------------------------------------------------------------------------
# The exclusion-evidence rule (spec/Quorum.tla rule 1; TraceConfigSwitch's
# EvidenceSuffices): a Master's Exclude logs why it excludes, and is checked.

def test_exclusions_on_evidence_and_on_a_nodes_own_word_validate(tmp_path: Path) -> None:
    # Witnesses, one of each kind of evidence: master_restarts excludes PN3 on two of three
    # members' declarations; worker_resigns excludes PN3 on its own word (AskExclusion).
    counted = lines_of(scenario_trace(tmp_path, "master_restarts"))
    at = index(counted, "Exclude", f="PN3")
    assert counted[at]["args"]["own"] is False
    assert len(counted[at]["args"]["ev"]) == 2 and len(counted[at]["args"]["mem"]) == 3
    fully_validated(write(tmp_path / "counted.ndjson", counted), fsm=["switch"])
    own = lines_of(scenario_trace(tmp_path, "worker_resigns"))
    at = index(own, "Exclude", f="PN3")
    assert own[at]["args"]["own"] is True
    fully_validated(write(tmp_path / "own.ndjson", own), fsm=["switch"])


@pytest.fixture(scope="module")
def restarts(tmp_path_factory: pytest.TempPathFactory) -> list[dict]:
    return lines_of(scenario_trace(tmp_path_factory.mktemp("restarts"), "master_restarts"))


def evidence(lines: list[dict], at: int, **args: object) -> list[dict]:
    out = list(lines)
    out[at] = {**out[at], "args": {**out[at]["args"], **args}}
    return out


def test_an_exclusion_on_too_few_declarations_is_caught(restarts: list[dict],
                                                        tmp_path: Path) -> None:
    # Three members, PN3 excluded: two declarations needed; one (the Master's own, as the
    # single-report-exclusion mutant decides) is no step, and the reason is named.
    at = index(restarts, "Exclude", f="PN3")
    assert restarts[at]["args"]["ev"] == ["PN1", "PN2"]
    where = rejected_at(tmp_path, "one-report.ndjson", evidence(restarts, at, ev=["PN1"]),
                        at + 1)
    assert where["action_enabled"] is False
    assert any("needs 2" in why for why in where["why"]), where["why"]


@pytest.mark.parametrize("change", [
    {"mem": ["PN1", "PN3"], "ev": ["PN1"]},  # a member left out to shrink the quorum
    {"mem": ["PN1", "PN2", "PN3", "ST1"], "ev": ["PN1", "ST1"]},  # a non-monitor counted
    {"ev": ["PN1", "PN3"]},  # the excluded node's own "declaration" counted
    {"own": True, "mem": [], "ev": []},  # its own word, which PN3 never gave
    {"ground": True, "mem": [], "ev": []},  # the ground's hold, which no node took
])
def test_evidence_the_rule_does_not_allow_is_caught(restarts: list[dict], tmp_path: Path,
                                                    change: dict) -> None:
    at = index(restarts, "Exclude", f="PN3")
    rejected_at(tmp_path, "bad-evidence.ndjson", evidence(restarts, at, **change), at + 1)


def test_a_declaration_nobody_made_is_caught(restarts: list[dict], tmp_path: Path) -> None:
    # PN2's evidence counts only if PN2's monitor declared PN3 before: with its heartbeat
    # DeclareFailed line moved after the Master's exclusion, the same evidence is no step.
    at = index(restarts, "Exclude", f="PN3")
    report = next(i for i in range(at) if restarts[i]["fsm"] == "heartbeat"
                  and restarts[i]["action"] == "DeclareFailed" and restarts[i]["node"] == "PN2"
                  and restarts[i]["args"]["n"] == "PN3")
    late = {**restarts[report], "t_ns": restarts[at]["t_ns"] + 1}  # lines merge by time
    moved = restarts[:report] + restarts[report + 1:at + 1] + [late] + restarts[at + 1:]
    where = rejected_at(tmp_path, "unmade.ndjson", moved, at)
    assert any("never declared" in why for why in where["why"]), where["why"]


def test_a_take_over_on_too_little_evidence_is_caught(tmp_path: Path) -> None:
    # master_failure: PN2 takes over from the crashed PN1 on PN2's and PN3's declarations
    # (two of three members). A take-over on its own declaration alone, or on none, is no
    # step; the real trace validates.
    lines = lines_of(scenario_trace(tmp_path, "master_failure"))
    at = index(lines, "BecomeMaster", n="PN2")
    assert lines[at]["args"]["ev"] == {"PN1": ["PN2", "PN3"]}
    assert lines[at]["args"]["was"] == [] and lines[at]["vars"]["failed"] == ["PN1"]
    fully_validated(write(tmp_path / "real.ndjson", lines), fsm=["switch"])
    for name, ev in (("one", {"PN1": ["PN2"]}), ("none", {})):
        where = rejected_at(tmp_path, f"take-over-{name}.ndjson", evidence(lines, at, ev=ev),
                            at + 1)
        assert any("take-over that excludes it needs 2" in why for why in where["why"]), where


@pytest.mark.parametrize("reason", ["restarted", "excluded"])
def test_a_forged_own_word_is_caught(restarts: list[dict], tmp_path: Path, reason: str) -> None:
    # master_restarts: PN1 declares the crashed PN3 `missed`. Had it declared it
    # `restarted` (PN3 never restarted) or `excluded` (no view excluded PN3, and PN3 never
    # resigned), its own word would stand in for the evidence: that line is no step.
    at = next(i for i, line in enumerate(restarts) if line["fsm"] == "heartbeat"
              and line["action"] == "DeclareFailed" and line["node"] == "PN1"
              and line["args"]["n"] == "PN3")
    assert restarts[at]["args"]["reason"] == "missed"
    assert not any(line["action"] == "Restart" and line["args"].get("n") == "PN3"
                   for line in restarts[:at])
    where = rejected_at(tmp_path, f"forged-{reason}.ndjson",
                        evidence(restarts, at, reason=reason), at + 1)
    assert where["action"] == "DeclareFailed" and where["fsm"] == "heartbeat", where


def test_a_take_over_that_calls_a_node_failed_before_is_caught(tmp_path: Path) -> None:
    # master_failure: no view excluded PN1 before PN2 takes over; a BecomeMaster line that
    # says it did (`was`) to need no evidence for PN1 is no step.
    lines = lines_of(scenario_trace(tmp_path, "master_failure"))
    at = index(lines, "BecomeMaster", n="PN2")
    rejected_at(tmp_path, "take-over-was.ndjson", evidence(lines, at, was=["PN1"], ev={}),
                at + 1)
