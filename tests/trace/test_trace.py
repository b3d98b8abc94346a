"""keel-verify trace: simulator and cluster traces are behaviours of the specs; broken
traces and broken C++ (keel-sim --mutant) are rejected at the right line."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from conftest import (
    MISSION,
    ROOT,
    behaviour,
    binary,
    explain,
    first_unexplained,
    sim_trace,
    tlc_jar,
    validate,
)

sys.path.insert(0, str(ROOT / "verify"))


def lines_of(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def write(path: Path, lines: list[dict]) -> Path:
    path.write_text("".join(json.dumps(line, separators=(",", ":")) + "\n" for line in lines))
    return path


@pytest.fixture(scope="module")
def seed11(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A crash of the higher-priority Observer: declaration, switch to P3, migration."""
    trace, report = sim_trace(tmp_path_factory.mktemp("seed11"), 11)
    assert "crash PN2" in report
    return trace


def test_simulator_run_is_a_behaviour_of_all_three_specs(seed11: Path) -> None:
    code, report, stderr = validate(seed11)
    assert behaviour(code, report), explain(report) + stderr
    protocols = {r["protocol"] for r in report["results"]}
    assert protocols == {"heartbeat", "election", "switch"}
    assert {r["subject"] for r in report["results"] if r["protocol"] == "heartbeat"} == {
        "PN1", "PN2", "PN3", "ST1"}
    assert all(r["verdict"] == "accepted" for r in report["results"])
    assert report["validated_lines"] > 250


def test_an_earth_observation_run_is_validated_line_by_line(tmp_path: Path) -> None:
    # Whole-trace validation: seed 5 of the earth-observation mission (its phases place
    # different tasks, the Storage node runs the sink, PN2 crashes) is validated in full:
    # every heartbeat, election (the followers' too) and switch line (the Storage node's
    # and the lease's too). Exit 0 means exactly that.
    eo = ROOT / "config" / "earth_observation.yaml"
    trace, _ = sim_trace(tmp_path, 5, duration="5s", mission=eo)
    code, report, stderr = validate(trace, mission=eo)
    assert code == 0, explain(report) + stderr
    for protocol, counted in report["coverage"].items():
        assert counted["validated"] == counted["total"] > 0, protocol
    assert report["validated_lines"] == report["protocol_lines"]
    # One line the trace specs do not model (an action they do not know, e.g. of a newer
    # runtime) makes it undecided, counted and located: never a pass.
    lines = [json.loads(x) for x in trace.read_text().splitlines()]
    at = next(i for i, line in enumerate(lines) if line["fsm"] == "switch" and i > 100)
    unknown = {**lines[at], "action": "Rebalance", "args": {"n": lines[at]["node"]},
               "vars": {}}
    bad = tmp_path / "unknown-action.ndjson"
    bad.write_text("\n".join(json.dumps(x) for x in lines[:at] + [unknown] + lines[at:]) + "\n")
    code, report, _ = validate(bad, mission=eo, fsm=["switch"])
    assert code == 3 and behaviour(code, report), explain(report)
    switch = report["coverage"]["switch"]
    assert switch["validated"] < switch["total"]
    assert switch["first_unvalidated"] == f"{bad}:{at + 1}"


@pytest.mark.parametrize("seed", [2, 3])
def test_master_failover_and_restart_runs_validate(tmp_path: Path, seed: int) -> None:
    # Seed 2: PN3 crashes and restarts, then the Master PN1 crashes and PN2 takes over.
    # Seed 3: a crash, then a partition (validated through: the partition only decides
    # which messages arrive; see also test_whole_trace.py).
    trace, _ = sim_trace(tmp_path, seed, duration="5s")
    code, report, stderr = validate(trace, fsm=["election", "switch"])
    assert behaviour(code, report), explain(report) + stderr


def test_online_switches_validate_and_a_wrong_one_is_refused(tmp_path: Path) -> None:
    # Beyond the graph (docs/missions.md, "Placement modes"): seed 20 of the graph+online
    # earth-observation mission leaves the graph (an Exclude into an online configuration),
    # then readmits into online configurations. Each is a pseudo-configuration of the
    # switch spec, admitted where the verifier's checker accepts it under the switch's
    # failed set; the trace is a behaviour of it.
    online = ROOT / "config" / "earth_observation_online.yaml"
    trace, _ = sim_trace(tmp_path, 20, duration="5s", mission=online)
    lines = lines_of(trace)
    switched = [i for i, x in enumerate(lines) if x["fsm"] == "switch"
                and x["action"] in ("Exclude", "BecomeMaster", "Readmit") and x["args"].get("c") == "online"]
    assert switched, "the run never left the graph"
    code, report, stderr = validate(trace, mission=online, fsm=["switch"])
    assert behaviour(code, report), explain(report) + stderr
    # The same run against the graph-only mission: its phases place no online configuration.
    code, report, _ = validate(trace, mission=ROOT / "config" / "earth_observation.yaml", fsm=["switch"])
    assert code == 1, explain(report)
    assert first_unexplained(report)["line"] == switched[0] + 1
    # The Master's first online configuration with a task on a node its view excludes:
    # the checker refuses it, and the line is no behaviour.
    at = switched[0]
    wrong = json.loads(json.dumps(lines[at]))
    victim = wrong["vars"]["failed"][0]
    task = next(iter(wrong["args"]["online"]["host"]))
    wrong["args"]["online"]["host"][task] = victim
    bad = write(tmp_path / "wrong-online.ndjson", lines[:at] + [wrong] + lines[at + 1:])
    code, report, _ = validate(bad, mission=online, fsm=["switch"])
    assert code == 1, explain(report)
    assert first_unexplained(report)["line"] == at + 1


ALL_ONLINE = ROOT / "tests" / "sim" / "testdata" / "missions" / "earth_observation_all_online.yaml"


def _held_to_the_placer(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, gave_up: Callable[[dict], bool],
                        seed: int, master: str, entered: Callable[[dict], bool], honest_seed: int) -> None:
    """The mutant online-gives-up's run of `seed` is refused at its first line `gave_up`
    (safe mode where the placer places, with `master` Master); the honest run of
    `honest_seed` (three failures) has a line `entered` (safe mode the placer agrees to)
    and validates; without keel-place, it does not (nothing admitted unchecked)."""
    trace, _ = sim_trace(tmp_path, seed, duration=None, mission=ALL_ONLINE, mutant="online-gives-up")
    at = next(i for i, x in enumerate(lines_of(trace)) if gave_up(x))
    code, report, stderr = validate(trace, mission=ALL_ONLINE, fsm=["switch"])
    assert code == 1, explain(report) + stderr
    assert first_unexplained(report)["line"] == at + 1
    assert f"the placer places every essential task with {master} Master" in json.dumps(report)
    honest, _ = sim_trace(tmp_path, honest_seed, duration=None, mission=ALL_ONLINE,
                          extra=["--max-failures", "3"])
    assert any(entered(x) for x in lines_of(honest))
    code, report, stderr = validate(honest, mission=ALL_ONLINE, fsm=["switch"])
    assert behaviour(code, report), explain(report) + stderr
    monkeypatch.setenv("KEEL_PLACE", str(tmp_path / "no-keel-place"))
    code, report, _ = validate(honest, mission=ALL_ONLINE, fsm=["switch"])
    assert code == 1 and "not checked" in json.dumps(report), explain(report)


def _into_safe(action: str, line: dict) -> bool:
    return line["fsm"] == "switch" and line["action"] == action and line["args"].get("c") == "SAFE"


def test_safe_mode_from_an_online_configuration_is_held_to_the_placer(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # A Master that runs an online configuration answers a failure with the placer's
    # configuration, and safe mode only where the placer places no essential task
    # (core/fsm/online.hpp, failure_target): trace validation asks the nodes' own placer
    # (keel-place --batch) for each Exclude into SAFE from an online configuration. The
    # mutant online-gives-up (seed 2: PN4 fails in an online configuration) breaks no
    # checker of keel-sim; its trace is refused at that line. Not vacuous: seed 30 (three
    # failures) enters safe mode from an online configuration when ST1 fails (the
    # checkpointed aocs needs a Storage node), and the placer agrees.
    _held_to_the_placer(tmp_path, monkeypatch, lambda x: _into_safe("Exclude", x) and x["args"].get("f") == "PN4",
                        2, "PN1", lambda x: _into_safe("Exclude", x), 30)


def test_a_take_over_into_safe_mode_from_an_online_configuration_is_held_to_the_placer(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # A node that takes over from an online configuration answers with the placer's
    # configuration, itself Master, and with safe mode only where the placer places no
    # essential task (ReconfigurationManager::take_over, failure_target): trace validation
    # asks keel-place for each take-over (BecomeMaster) into SAFE from an online
    # configuration. The mutant online-gives-up (seed 31: PN1, the Master, fails; PN3
    # takes over) is refused at that line. Not vacuous: seed 115 (three failures) takes
    # over into safe mode from an online configuration with PN1, PN2 and ST1 failed, and
    # the placer agrees.
    _held_to_the_placer(tmp_path, monkeypatch, lambda x: _into_safe("BecomeMaster", x), 31, "PN3",
                        lambda x: _into_safe("BecomeMaster", x), 115)


def test_a_master_that_supersedes_its_own_command_deactivates_under_the_older_one(tmp_path: Path) -> None:
    # Seed 69 (three failures): PN3 takes over into SAFE at seq 1, excludes IF1 at seq 2 in
    # the same step, then delivers seq 1 to itself and deactivates acca0 under it while the
    # spec, which applied each own command at once, holds seq 2. Until its latest own
    # command is delivered, a Deactivate line's switch position is not compared (as a
    # final checkpoint's); the task it names still is: one the node does not run is refused.
    trace, _ = sim_trace(tmp_path, 69, duration=None, mission=ALL_ONLINE, extra=["--max-failures", "3"])
    lines = lines_of(trace)
    own = [i for i, x in enumerate(lines) if x["node"] == "PN3" and x["fsm"] == "switch"
           and x["action"] in ("BroadcastCommand", "ReceiveCommand", "Deactivate")]
    at = next(i for i in own if lines[i]["action"] == "Deactivate"
              and lines[i]["vars"].get("seq", 0) < lines[i]["vars"].get("masterSeq", 0))
    assert any(lines[i]["action"] == "BroadcastCommand" and lines[i]["args"]["seq"] == 2 for i in own if i < at)
    code, report, stderr = validate(trace, mission=ALL_ONLINE, fsm=["switch"])
    assert behaviour(code, report), explain(report) + stderr
    other = next(t for t in ("acca1", "aocs", "camera") if t != lines[at]["args"]["t"])
    wrong = {**lines[at], "args": {**lines[at]["args"], "t": other}}
    code, report, _ = validate(write(tmp_path / "wrong-task.ndjson", lines[:at] + [wrong] + lines[at + 1:]),
                               mission=ALL_ONLINE, fsm=["switch"])
    assert code == 1, explain(report)
    assert first_unexplained(report)["line"] == at + 1


# Seeded runs with the scenario files' kinds of faults at other, random points in time
# (the scenario files themselves are validated below).
SCENARIO_KINDS = {
    1: "lossy network (5% loss), two phase changes, an Observer crash",
    13: "two failures: the Master, then the lower-priority Observer",
    15: "a phase change, then the Master fails",
    21: "an Observer fails, then the storage node",
    23: "a worker's failure, then a phase change",
    7: "a one-way partition isolating the Master, a crash and a restart",
}


@pytest.mark.parametrize("seed", sorted(SCENARIO_KINDS))
def test_scenario_kinds_validate(tmp_path: Path, seed: int) -> None:
    trace, _ = sim_trace(tmp_path, seed, duration="3s")
    code, report, stderr = validate(trace, fsm=["election", "switch"])
    assert behaviour(code, report), SCENARIO_KINDS[seed] + "\n" + explain(report) + stderr


def test_a_variable_that_differs_is_reported_at_its_line(seed11: Path, tmp_path: Path) -> None:
    lines = [line for line in lines_of(seed11)
             if line["node"] == "PN3" and line["fsm"] == "heartbeat"]
    ticks = [i for i, line in enumerate(lines) if line["action"] == "Tick"]
    broken = ticks[3]
    watched = next(iter(lines[broken]["vars"]["missed"]))
    lines[broken]["vars"]["missed"][watched] += 1
    bad = write(tmp_path / "bad-missed.ndjson", lines)
    code, report, _ = validate(bad, fsm=["heartbeat"])
    assert code == 1
    where = first_unexplained(report)
    assert (where["file"], where["line"]) == (str(bad), broken + 1)
    assert where["action"] == "Tick" and where["action_enabled"] is True
    assert [d["var"] for d in where["differences"]] == ["missed"]


def test_an_impossible_action_is_reported_at_its_line(seed11: Path, tmp_path: Path) -> None:
    lines = [line for line in lines_of(seed11) if line["fsm"] in ("election", "env")]
    # PN3 claims epoch 2 while PN1 is the running Master and PN2 is ahead of it.
    first = lines[0]
    forged = {"t_ns": first["t_ns"], "node": "PN3", "fsm": "election",
              "action": "BecomeMaster", "args": {"n": "PN3", "epoch": 2},
              "vars": {"role": "Master", "epoch": 2, "leader": "PN3", "suspects": [],
                       "lastCommand": 0}}
    bad = write(tmp_path / "bad-election.ndjson", [forged, *lines])
    code, report, _ = validate(bad, fsm=["election"])
    assert code == 1
    where = first_unexplained(report)
    assert (where["line"], where["action"], where["action_enabled"]) == (1, "BecomeMaster", False)


def test_health_lines_annotate_and_do_not_break_validation(seed11: Path, tmp_path: Path) -> None:
    # keel-node writes a line per unhealthy task (fsm "health"); no spec has such an
    # action, so the validator reads it and leaves it out of every protocol.
    lines = lines_of(seed11)
    node_line = next(line for line in lines if line["fsm"] == "switch" and line["node"])
    health = {"t_ns": node_line["t_ns"], "node": node_line["node"], "fsm": "health",
              "action": "TaskUnhealthy",
              "args": {"n": node_line["node"], "t": "taskB", "kind": "out_of_bounds"},
              "vars": {"restarts": 0}}
    index = lines.index(node_line)
    annotated = write(tmp_path / "health.ndjson", lines[:index] + [health] + lines[index:])
    code, report, stderr = validate(annotated)
    assert behaviour(code, report), explain(report) + stderr
    unknown = write(tmp_path / "unknown-fsm.ndjson", [dict(health, fsm="healthy")])
    code, _, stderr = validate(unknown)
    assert code == 2 and "unknown fsm 'healthy'" in stderr


def test_a_malformed_line_is_an_input_error(seed11: Path, tmp_path: Path) -> None:
    text = seed11.read_text().splitlines()
    text[6] = text[6][:-5]
    bad = tmp_path / "truncated.ndjson"
    bad.write_text("\n".join(text) + "\n")
    code, _, stderr = validate(bad)
    assert code == 2
    assert f"{bad}:7: not JSON" in stderr
    missing = tmp_path / "no-fsm.ndjson"
    missing.write_text('{"t_ns": 1, "node": "PN1", "action": "Tick", "vars": {}}\n')
    code, _, stderr = validate(missing)
    assert code == 2 and f"{missing}:1: missing field(s) fsm" in stderr


def test_a_run_directory_with_the_image_and_no_yaml_needs_the_mission(seed11: Path, tmp_path: Path) -> None:
    # keel-cluster's run directory holds the image the nodes flew, not the YAML: its traces
    # are never read against another mission (prototype3, the default for bare files).
    run = tmp_path / "run"
    run.mkdir()
    (run / "PN1.trace.ndjson").write_text(seed11.read_text())
    (run / "earth_observation.image.json").write_text("{}")
    done = subprocess.run([sys.executable, "-m", "keel_verify.cli", "trace", str(run), "--tlc-jar", str(tlc_jar())],
                          capture_output=True, text=True, timeout=300, check=False,
                          env=dict(os.environ, PYTHONPATH=str(ROOT / "verify"), KEEL_ROOT=str(ROOT)))
    assert done.returncode == 2, done.stderr
    assert (f"{run} holds the mission's image (earth_observation.image.json), not its YAML: give the mission "
            "with --mission MISSION.yaml") in done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.parametrize("fsm, action, actor", [("switch", "Ack", "n"),
                                                ("heartbeat", "Tick", "m"),
                                                ("election", "ReceiveCommand", "n")])
def test_a_line_whose_args_name_another_node_as_the_one_acting_is_refused(
        seed11: Path, tmp_path: Path, fsm: str, action: str, actor: str) -> None:
    # A line is its node's: one whose args say another node acted (a changed `n` of an
    # Ack, `m` of a Tick) would be validated as the node's step with the other's name.
    lines = [json.loads(x) for x in seed11.read_text().splitlines()]
    at = next(i for i, x in enumerate(lines) if x["fsm"] == fsm and x["action"] == action
              and x["args"].get(actor) == x["node"])
    other = next(n for n in ("PN1", "PN2", "PN3") if n != lines[at]["node"])
    lines[at]["args"][actor] = other
    bad = write(tmp_path / "actor.ndjson", lines)
    code, _, stderr = validate(bad)
    assert code == 2, stderr
    assert (f"{bad}:{at + 1}: a {fsm} {action} line of {lines[at]['node']} whose args name "
            f"{actor}='{other}' as the node that acts") in stderr


def checkers_quiet(report: str) -> bool:
    return "VIOLATION" not in report


def test_election_without_epoch_check_is_caught_where_no_checker_fires(tmp_path: Path) -> None:
    # The mutant lets the lower-priority Observer claim the next epoch at once; seed 4
    # has the Master crash, and no simulator checker of the protocol's safety notices
    # anything. (Fault model 3's do: the epoch PN3 claims is not its own to open, so the
    # receivers refuse its Command, which NoHonestRefusalInv reports, and ValidConfigInv
    # sees PN3 hold that view; the trace up to there holds PN3's BecomeMaster.)
    trace, report = sim_trace(tmp_path, 4, duration="5s", mutant="election-no-epoch-check")
    violations = [line for line in report.splitlines() if line.startswith("VIOLATION")]
    assert all("is not PN3's to open" in line for line in violations), report
    code, result, _ = validate(trace, fsm=["election"])
    assert code == 1
    where = first_unexplained(result)
    assert where["action"] == "BecomeMaster" and where["node"] == "PN3"
    good, report = sim_trace(tmp_path, 4, duration="5s")
    assert behaviour(*validate(good, fsm=["election"])[:2])


def test_activation_before_deactivation_is_caught_where_no_checker_fires(tmp_path: Path) -> None:
    # Seed 11: PN2 crashes; the new configuration moves taskA to PN1, which the mutant
    # starts while still deactivating. The double activation never overlaps in time
    # (PN2 is down), so NoDoubleActivationInv's checker stays quiet.
    trace, report = sim_trace(tmp_path, 11, mutant="activate-before-deactivate")
    assert checkers_quiet(report), report
    code, result, _ = validate(trace, fsm=["switch"])
    assert code == 1
    where = first_unexplained(result)
    assert where["action"] == "Activate" and where["action_enabled"] is False
    assert where["vars"]["stage"] == "Deactivating"


def test_an_activation_before_every_members_prepared_is_caught(tmp_path: Path) -> None:
    # Rule 4 (docs/fault-model.md): a node takes its Master's Activate only once every other
    # member's Prepared of the same view has reached it. The mutant starts on the Master's
    # word alone; an honest Master sends that word only after every Prepared reached it, so
    # no simulator checker fires, but in seed 2 a member's Prepared to PN3 was still on its
    # way (or lost), and the ReceiveActivate line, which logs the peers the node holds, is
    # caught. The honest run of the same seed validates, its lines listing every member.
    trace, report = sim_trace(tmp_path, 2, duration="3s", mutant="no-peer-prepared")
    assert checkers_quiet(report), report
    code, result, _ = validate(trace, fsm=["switch"])
    assert code == 1, result
    where = first_unexplained(result)
    assert where["action"] == "ReceiveActivate", where
    honest, _ = sim_trace(tmp_path, 2, duration="3s")
    code, result, stderr = validate(honest, fsm=["switch"])
    assert code == 0, result + stderr
    activations = [json.loads(line)["args"] for line in honest.read_text().splitlines()
                   if '"ReceiveActivate"' in line]
    assert activations and all(len(a["peers"]) + len(a["out"]) == 3 for a in activations)


@pytest.mark.parametrize("reason", ["wrong", "left"])
def test_a_declaration_of_a_wrong_command_is_caught_on_an_honest_trace(
        seed11: Path, tmp_path: Path, reason: str) -> None:
    # A monitor declares a node failed for good when it refused that node's Command as no
    # Master's (reason "wrong", fault model 3). Every node of a validated run is honest, so
    # such a line means a check refused an honest Command: seed 11's first declaration
    # (PN2's crash, "missed") is turned into one and rejected at its line. So is one for
    # leaving the declarer's view (reason "left") when the node follows the declarer's epoch.
    lines = lines_of(seed11)
    first = next(i for i, line in enumerate(lines)
                 if line["fsm"] == "heartbeat" and line["action"] == "DeclareFailed")
    lines[first]["args"]["reason"] = reason
    bad = write(tmp_path / f"bad-{reason}.ndjson", lines)
    code, report, _ = validate(bad, fsm=["switch"])
    assert code == 1, report
    where = first_unexplained(report)
    assert (where["file"], where["line"]) == (str(bad), first + 1), where


def test_a_refusal_of_an_honest_message_is_caught_at_its_line(tmp_path: Path) -> None:
    # Rules 1 to 3 (docs/fault-model.md): a node that refuses a message (malformed,
    # unauthorized, no Master's, another view under its view's id) logs a Refused line,
    # which validation rejects: every node of a validated run is honest. The mutant
    # refuse-phase-edges refuses seed 1's phase change as no edge of the graph; its first
    # Refused line is where validation stops. The honest run of the seed has none, and
    # validates.
    trace, report = sim_trace(tmp_path, 1, duration="3s", mutant="refuse-phase-edges")
    assert "NoHonestRefusalInv" in report, report
    lines = lines_of(trace)
    refused = next(i for i, line in enumerate(lines) if line["action"] == "Refused")
    assert "no phase edge" in lines[refused]["args"]["why"], lines[refused]
    code, result, _ = validate(trace, fsm=["switch"])
    assert code == 1, result
    where = first_unexplained(result)
    assert (where["action"], where["line"]) == ("Refused", refused + 1), where
    honest, _ = sim_trace(tmp_path, 1, duration="3s")
    assert not any(line["action"] == "Refused" for line in lines_of(honest))
    code, result, stderr = validate(honest, fsm=["switch"])
    assert code == 0, result + stderr


def test_an_exclusion_followed_without_a_backing_is_caught(tmp_path: Path) -> None:
    # Rule 5 (docs/fault-model.md): a node follows a Command adding an exclusion only when
    # the exclusion is backed at it, and its Backed line says by what. Seed 11's lines (5 s)
    # validate, with a declaration and a silence among them; a line that names the
    # Command's sender as the declarer (its word alone), or a node that declared nothing,
    # is caught at that line.
    seed11, _report = sim_trace(tmp_path, 11, duration="5s")
    lines = lines_of(seed11)
    backed = [i for i, line in enumerate(lines) if line["action"] == "Backed"]
    kinds = {kind for i in backed for kind, _by in lines[i]["args"]["by"].values()}
    assert {"reported", "silent"} <= kinds, kinds
    code, report, stderr = validate(seed11, fsm=["switch"])
    assert code == 0, report + stderr
    first = next(i for i in backed
                 if any(kind == "reported" for kind, _by in lines[i]["args"]["by"].values()))
    args = lines[first]["args"]
    node = next(x for x, (kind, _by) in args["by"].items() if kind == "reported")
    declarers = {line["args"]["m"] for line in lines[:first]
                 if line["fsm"] == "heartbeat" and line["action"] == "DeclareFailed"
                 and line["args"]["n"] == node}
    silent = next(x for x in ("PN1", "PN2", "PN3", "ST1")
                  if x not in declarers and x != args["from"] and x != node)
    for by, name in ((args["from"], "sender"), (silent, "silent")):
        forged = lines_of(seed11)
        forged[first]["args"]["by"][node] = ["reported", by]
        bad = write(tmp_path / f"bad-backed-{name}.ndjson", forged)
        code, report, _ = validate(bad, fsm=["switch"])
        assert code == 1, report
        where = first_unexplained(report)
        assert (where["action"], where["line"]) == ("Backed", first + 1), where
    # Complete: the mutant unbacked-exclusions follows the same exclusions unchecked and
    # logs no Backed line; the first Command it follows that adds one is caught at its
    # ReceiveCommand line (no simulator checker fires: every node is honest).
    mutant, report = sim_trace(tmp_path, 11, duration="5s", mutant="unbacked-exclusions")
    assert checkers_quiet(report), report
    lines = lines_of(mutant)
    assert not any(line["action"] == "Backed" for line in lines)
    first = next(i for i, line in enumerate(lines)
                 if line["fsm"] == "switch" and line["action"] == "ReceiveCommand"
                 and line["args"]["from"] != line["args"]["n"]
                 and line["args"]["out"] and line["args"]["n"] not in line["args"]["out"])
    code, report, _ = validate(mutant, fsm=["switch"])
    assert code == 1, report
    where = first_unexplained(report)
    assert (where["action"], where["line"]) == ("ReceiveCommand", first + 1), where


def test_activation_at_boot_without_a_command_is_caught(tmp_path: Path) -> None:
    # The start-up before the boot switch: every node activates its initial tasks at boot.
    # The spec's nodes boot Stable with nothing active; only the boot switch activates.
    trace, _report = sim_trace(tmp_path, 11, mutant="boot-activates")
    code, result, _ = validate(trace, fsm=["switch"])
    assert code == 1
    where = first_unexplained(result)
    assert where["action"] == "Activate" and where["action_enabled"] is False
    assert where["vars"]["stage"] == "Stable" and where["vars"]["seq"] == 0


def test_a_tick_that_suspects_itself_without_cause_is_caught(seed11: Path, tmp_path: Path) -> None:
    # Self-suspicion (Exclusion.tla rule 1): a Tick that counts no miss must have heard no
    # one or run late. Forge one on a Tick where PN3 heard every node it watches (its
    # counts are all 0, the same whether it counted or not): only the cause tells it apart.
    lines = [line for line in lines_of(seed11)
             if line["node"] == "PN3" and line["fsm"] == "heartbeat"]
    assert behaviour(*validate(write(tmp_path / "good.ndjson", lines), fsm=["heartbeat"])[:2])
    at = next(i for i, line in enumerate(lines)
              if line["action"] == "Tick" and line["vars"]["heard"]
              and not any(line["vars"]["missed"].values()) and i > 10)
    lines[at] = {**lines[at], "args": {**lines[at]["args"], "suspect": True, "late": False,
                                       "silent": True}}
    bad = write(tmp_path / "bad-suspect.ndjson", lines)
    code, result, _ = validate(bad, fsm=["heartbeat"])
    assert code == 1
    where = first_unexplained(result)
    assert (where["line"], where["action"]) == (at + 1, "Tick")
    # The same line, late by its own measure, is a spec step.
    lines[at]["args"]["late"] = True
    assert behaviour(*validate(write(tmp_path / "late.ndjson", lines), fsm=["heartbeat"])[:2])


def _scenario_trace(tmp_path: Path, name: str) -> list[dict]:
    scenario = ROOT / "tests" / "sim" / "testdata" / f"{name}.txt"
    subprocess.run([str(binary("keel-sim")), "scenario", str(scenario), "--trace-dir",
                    str(tmp_path)], capture_output=True, text=True, timeout=300, check=False,
                   env=dict(os.environ, KEEL_ROOT=str(ROOT)))
    return lines_of(tmp_path / f"{name}.ndjson")


def test_a_monitor_that_keeps_a_readmitted_node_declared_is_caught(tmp_path: Path) -> None:
    # master_restarts: PN1 restarts and is handed its configuration back; every monitor
    # forgets what it declared of PN1 (heartbeat.Readmit) and PN1 forgets what it declared
    # while out (heartbeat.Rejoin). Validated through the readmission, line by line; a
    # Readmit that leaves PN1 declared is no step of the spec (Rejoin.tla's ReadmitBy).
    lines = _scenario_trace(tmp_path, "master_restarts")
    code, report, stderr = validate(tmp_path / "master_restarts.ndjson", fsm=["heartbeat"])
    assert code == 0, explain(report) + stderr
    assert report["coverage"]["heartbeat"]["validated"] == report["coverage"]["heartbeat"]["total"]
    at = next(i for i, line in enumerate(lines)
              if line["fsm"] == "heartbeat" and line["action"] == "Readmit")
    assert any(line["action"] == "Rejoin" for line in lines[at:])
    kept = lines[at]["args"]["n"]
    lines[at] = {**lines[at], "vars": {**lines[at]["vars"],
                                       "failed": sorted({*lines[at]["vars"]["failed"], kept})}}
    code, report, _ = validate(write(tmp_path / "bad-readmit.ndjson", lines), fsm=["heartbeat"])
    assert code == 1
    where = first_unexplained(report)
    assert (where["line"], where["action"]) == (at + 1, "Readmit")


def test_a_readmission_of_a_node_the_ground_holds_out_is_caught(tmp_path: Path) -> None:
    # ground_holds_a_node_out: the ground holds PN3 out, then lets it back (every node's
    # GroundExclude and GroundReadmit lines); later the Master PN1, handed its view back
    # once the ground readmits it. Validated line by line; without the Master's
    # GroundReadmit line its Readmit of PN3 is a readmission of a node it holds out,
    # rejected at that line; so is PN2's HandOver to PN1 without PN2's.
    lines = _scenario_trace(tmp_path, "ground_holds_a_node_out")
    mission = ROOT / "config" / "prototype3.yaml"
    code, report, stderr = validate(tmp_path / "ground_holds_a_node_out.ndjson", mission=mission)
    assert code == 0, explain(report) + stderr
    assert sum(x["action"] == "GroundExclude" for x in lines) >= 8  # every node, twice
    for acting, readmit in (("PN1", "Readmit"), ("PN2", "HandOver")):
        at = next(i for i, x in enumerate(lines) if x["action"] == readmit and x["node"] == acting)
        freed = max(i for i, x in enumerate(lines[:at]) if x["action"] == "GroundReadmit" and
                    x["node"] == acting and x["args"]["f"] == lines[at]["args"]["r"])
        bad = lines[:freed] + lines[freed + 1:]
        code, report, _ = validate(write(tmp_path / f"bad-{readmit}.ndjson", bad), mission=mission,
                                   fsm=["switch"])
        assert code == 1
        where = first_unexplained(report)
        assert (where["line"], where["action"]) == (at, readmit)


def test_a_paused_task_that_steps_is_caught(tmp_path: Path) -> None:
    # ground_pauses_a_task: the ground pauses the checkpointed taskA (every node's
    # GroundPause line), a phase change moves it while paused, and the ground resumes it.
    # Validated line by line. keel-sim --mutant pause-keeps-running (the pause taken, the
    # task left running) is rejected at the first checkpoint taskA writes after its
    # node's GroundPause line; without a node's GroundPause line, its GroundResume is a
    # resume of a task it does not hold paused, rejected at that line.
    mission = ROOT / "tests" / "sim" / "testdata" / "missions" / "prototype3_pausable.yaml"
    lines = _scenario_trace(tmp_path, "ground_pauses_a_task")
    code, report, stderr = validate(tmp_path / "ground_pauses_a_task.ndjson", mission=mission)
    assert code == 0, explain(report) + stderr
    assert sum(x["action"] == "GroundPause" for x in lines) == 4  # every node
    assert sum(x["action"] == "GroundResume" for x in lines) == 4
    mutant = tmp_path / "mutant"
    mutant.mkdir()
    scenario = ROOT / "tests" / "sim" / "testdata" / "ground_pauses_a_task.txt"
    subprocess.run([str(binary("keel-sim")), "scenario", str(scenario), "--trace-dir", str(mutant),
                    "--mutant", "pause-keeps-running"], capture_output=True, text=True, timeout=300,
                   check=False, env=dict(os.environ, KEEL_ROOT=str(ROOT)))
    broken = lines_of(mutant / "ground_pauses_a_task.ndjson")
    # PN2 runs taskA when the ground pauses it.
    paused = next(i for i, x in enumerate(broken) if x["action"] == "GroundPause" and x["node"] == "PN2")
    stepped = next(i for i, x in enumerate(broken) if i > paused and x["node"] == "PN2" and
                   x["action"] == "FlushCheckpoint" and x["args"]["t"] == "taskA")
    code, report, _ = validate(mutant / "ground_pauses_a_task.ndjson", mission=mission, fsm=["switch"])
    assert code == 1
    where = first_unexplained(report)
    assert (where["line"], where["action"]) == (stepped + 1, "FlushCheckpoint"), where
    pause = next(i for i, x in enumerate(lines) if x["action"] == "GroundPause" and x["node"] == "PN3")
    resume = next(i for i, x in enumerate(lines) if x["action"] == "GroundResume" and x["node"] == "PN3")
    code, report, _ = validate(write(tmp_path / "bad-resume.ndjson", lines[:pause] + lines[pause + 1:]),
                               mission=mission, fsm=["switch"])
    assert code == 1
    where = first_unexplained(report)
    assert (where["line"], where["action"]) == (resume, "GroundResume"), where


def test_a_take_over_on_the_grounds_vote_is_held_to_the_designation(tmp_path: Path) -> None:
    # ground_designates_a_master (heartbeat.tie_grace: 3): the last two monitors cut apart,
    # both stop, the ground designates PN2, which takes over excluding PN1 and ST1 on its
    # own declarations and the ground's vote (its BecomeMaster line: gm, vote). Validated
    # line by line, GroundDesignate, StandDown and StandUp as lease lines. The take-over is
    # rejected at its line without the vote (one declaration of two needed where the
    # ground is a member), without PN2's GroundDesignate line, before the designation's
    # wait is over, or saying the ground is no member of a view of two monitors.
    mission = ROOT / "tests" / "sim" / "testdata" / "missions" / "prototype3_tie_grace.yaml"
    lines = _scenario_trace(tmp_path, "ground_designates_a_master")
    code, report, stderr = validate(tmp_path / "ground_designates_a_master.ndjson", mission=mission)
    assert code == 0, explain(report) + stderr
    assert report["coverage"]["switch"]["validated"] == report["coverage"]["switch"]["total"]
    taken = next(i for i, x in enumerate(lines) if x["fsm"] == "switch" and x["action"] == "BecomeMaster")
    assert lines[taken]["node"] == "PN2" and lines[taken]["args"]["vote"] == ["PN1", "ST1"]
    assert lines[taken]["args"]["gm"] is True
    designated = next(i for i, x in enumerate(lines) if x["action"] == "GroundDesignate" and x["node"] == "PN2")

    def rejected_at_the_take_over(name: str, broken: list[dict], at: int) -> None:
        code, report, _ = validate(write(tmp_path / name, broken), mission=mission, fsm=["switch"])
        assert code == 1, name
        where = first_unexplained(report)
        assert (where["line"], where["action"]) == (at + 1, "BecomeMaster"), (name, where)

    without_vote = json.loads(json.dumps(lines))
    del without_vote[taken]["args"]["vote"]
    rejected_at_the_take_over("no-vote.ndjson", without_vote, taken)
    rejected_at_the_take_over("no-designation.ndjson", lines[:designated] + lines[designated + 1:],
                              taken - 1)
    waiting = json.loads(json.dumps(lines))
    waiting[designated]["args"]["wait"] = 5  # the take-over 88 ms after: within the wait
    rejected_at_the_take_over("within-wait.ndjson", waiting, taken)
    no_ground = json.loads(json.dumps(lines))
    no_ground[taken]["args"]["gm"] = False
    rejected_at_the_take_over("no-ground.ndjson", no_ground, taken)


def test_a_node_that_holds_its_tasks_and_still_steps_is_caught(tmp_path: Path) -> None:
    # checkpointed_observer_cut_off: PN3, cut off, holds taskB (its Hold line, the lease
    # lapsed) and writes no checkpoint until it is excluded. Validated line by line. A
    # checkpoint of taskB one step further right after the Hold line is a step of a node
    # that holds its tasks, rejected at that line; the same line just before the Hold line
    # is a step like any other (the check is the Hold line's).
    lines = _scenario_trace(tmp_path, "checkpointed_observer_cut_off")
    code, report, stderr = validate(tmp_path / "checkpointed_observer_cut_off.ndjson", fsm=["switch"])
    assert code == 0, explain(report) + stderr
    at = next(i for i, x in enumerate(lines) if x["action"] == "Hold" and x["node"] == "PN3")
    version = lines[at]["vars"]["version"]["taskB"]
    step = {"t_ns": lines[at]["t_ns"], "node": "PN3", "fsm": "switch", "action": "FlushCheckpoint",
            "args": {"n": "PN3", "t": "taskB", "version": version + 1, "final": False},
            "vars": {**lines[at]["vars"], "version": {"taskB": version + 1}}}
    held = {**lines[at], "vars": {**lines[at]["vars"], "version": {"taskB": version + 1}}}
    code, report, _ = validate(write(tmp_path / "bad-hold.ndjson", lines[:at + 1] + [step] + lines[at + 1:]),
                               fsm=["switch"])
    assert code == 1
    where = first_unexplained(report)
    assert (where["line"], where["action"]) == (at + 2, "FlushCheckpoint"), where
    code, report, stderr = validate(write(tmp_path / "step-then-hold.ndjson",
                                          lines[:at] + [step, held] + lines[at + 1:]), fsm=["switch"])
    assert code == 0, explain(report) + stderr


def test_an_exclusion_on_a_declaration_its_master_withdrew_is_caught(tmp_path: Path) -> None:
    # worker_failure: PN1 excludes PN3 on its own declaration and PN2's. Had PN1 withdrawn
    # its declaration first (a heartbeat Withdraw line: PN3 proved alive), its own would
    # be no evidence: the Exclude line is rejected, and the report says why. Declared
    # again after the withdrawal, it counts.
    lines = _scenario_trace(tmp_path, "worker_failure")
    at = next(i for i, x in enumerate(lines) if x["action"] == "Exclude" and x["fsm"] == "switch")
    assert lines[at]["args"]["m"] == "PN1" and "PN1" in lines[at]["args"]["ev"]
    declared = max(i for i, x in enumerate(lines[:at]) if x["fsm"] == "heartbeat" and
                   x["action"] == "DeclareFailed" and x["node"] == "PN1" and x["args"]["n"] == "PN3")
    withdraw = {"t_ns": lines[declared]["t_ns"], "node": "PN1", "fsm": "heartbeat", "action": "Withdraw",
                "args": {"m": "PN1", "n": "PN3"},
                "vars": {**lines[declared]["vars"], "failed": []}}
    bad = lines[:declared + 1] + [withdraw] + lines[declared + 1:]
    code, report, _ = validate(write(tmp_path / "bad-withdrawn.ndjson", bad), fsm=["switch"])
    assert code == 1
    where = first_unexplained(report)
    assert (where["line"], where["action"]) == (at + 2, "Exclude"), where
    assert "withdrawn" in json.dumps(report), explain(report)
    again = lines[:declared] + [withdraw] + lines[declared:]
    code, report, stderr = validate(write(tmp_path / "declared-again.ndjson", again), fsm=["switch"])
    assert code == 0, explain(report) + stderr


def test_an_exclusion_on_a_report_that_expired_is_caught(tmp_path: Path) -> None:
    # worker_failure: PN1 excludes PN3 on its own declaration and PN2's report. Had PN2
    # withdrawn its declaration three of PN1's periods before (three PN1 heartbeat Tick
    # lines after the withdrawal, the one of the step that excludes included), its last
    # report no longer counts at PN1 (a report counts two periods, and arrives within
    # one): the Exclude line is rejected, and the report says why. Two, it still counts.
    lines = _scenario_trace(tmp_path, "worker_failure")
    at = next(i for i, x in enumerate(lines) if x["action"] == "Exclude" and x["fsm"] == "switch")
    assert "PN2" in lines[at]["args"]["ev"]
    declared = max(i for i, x in enumerate(lines[:at]) if x["fsm"] == "heartbeat" and
                   x["action"] == "DeclareFailed" and x["node"] == "PN2" and x["args"]["n"] == "PN3")
    tick = next(x for x in reversed(lines[:at]) if x["fsm"] == "heartbeat" and x["action"] == "Tick"
                and x["node"] == "PN1")
    t = lines[declared]["t_ns"]
    withdraw = {"t_ns": t, "node": "PN2", "fsm": "heartbeat", "action": "Withdraw",
                "args": {"m": "PN2", "n": "PN3"}, "vars": {**lines[declared]["vars"], "failed": []}}
    between = sum(1 for x in lines[declared:at] if x["fsm"] == "heartbeat" and x["action"] == "Tick"
                  and x["node"] == "PN1")
    assert between < 2
    for periods, rejected in ((3, True), (2, False)):
        ticks = [{**tick, "t_ns": t} for _ in range(periods - between)]
        edited = lines[:declared + 1] + [withdraw, *ticks] + lines[declared + 1:]
        code, report, stderr = validate(write(tmp_path / f"expired-{periods}.ndjson", edited), fsm=["switch"])
        if rejected:
            assert code == 1
            where = first_unexplained(report)
            assert (where["line"], where["action"]) == (at + 2 + len(ticks), "Exclude"), where
            assert "had ended 3 or more of PN1's periods before" in json.dumps(report), explain(report)
        else:
            assert code == 0, explain(report) + stderr


def test_a_withdrawal_of_a_node_not_declared_is_caught(tmp_path: Path) -> None:
    # one_way_partition: PN1 declares PN3, then hears it and withdraws the declaration (its
    # heartbeat Withdraw line, Heartbeat's Forget). Validated; the same Withdraw line
    # before the declaration is a withdrawal of a node the monitor does not hold failed,
    # rejected at that line.
    lines = _scenario_trace(tmp_path, "one_way_partition")
    code, report, stderr = validate(tmp_path / "one_way_partition.ndjson", fsm=["heartbeat"])
    assert code == 0, explain(report) + stderr
    at = next(i for i, x in enumerate(lines) if x["action"] == "Withdraw")
    withdrawn = lines[at]
    declared = max(i for i, x in enumerate(lines[:at]) if x["fsm"] == "heartbeat" and
                   x["action"] == "DeclareFailed" and x["node"] == withdrawn["node"] and
                   x["args"]["n"] == withdrawn["args"]["n"])
    early = {**withdrawn, "t_ns": lines[declared]["t_ns"]}
    bad = lines[:declared] + [early] + lines[declared:at] + lines[at + 1:]
    code, report, _ = validate(write(tmp_path / "bad-withdraw.ndjson", bad), fsm=["heartbeat"])
    assert code == 1
    where = first_unexplained(report)
    assert (where["line"], where["action"]) == (declared + 1, "Withdraw"), where


@pytest.mark.parametrize("seed", [1, 2])
def test_runs_with_the_grounds_pauses_are_behaviours_of_the_specs(tmp_path: Path, seed: int) -> None:
    # keel-sim --ground-pauses: the ground pauses the checkpointed taskA and resumes it,
    # around the seed's faults (seed 1: a phase change moves it while paused and its host
    # crashes; seed 2: the Master crashes while it is paused); every line validated.
    mission = ROOT / "tests" / "sim" / "testdata" / "missions" / "prototype3_pausable.yaml"
    trace, report = sim_trace(tmp_path, seed, duration="5s", mission=mission, extra=["--ground-pauses"])
    assert "pause-task taskA" in report
    code, result, stderr = validate(trace, mission=mission)
    assert behaviour(code, result), explain(result) + stderr


def test_a_hand_over_into_an_epoch_the_new_master_does_not_own_is_caught(tmp_path: Path) -> None:
    # master_restarts: PN2 hands the view back to PN1 in PN1's next epoch (4, owned by
    # PN1), and the election lines follow it through (TraceElection's HandOver). A hand-over
    # into epoch 5 (PN2's own) is no step of the mapping: the guard names the owner.
    lines = _scenario_trace(tmp_path, "master_restarts")
    code, report, stderr = validate(tmp_path / "master_restarts.ndjson", fsm=["election"])
    assert code == 0, explain(report) + stderr
    at = next(i for i, line in enumerate(lines) if line["action"] == "HandOver")
    lines[at] = {**lines[at], "args": {**lines[at]["args"], "epoch": lines[at]["args"]["epoch"] + 1}}
    code, report, _ = validate(write(tmp_path / "bad-handover.ndjson", lines), fsm=["election"])
    assert code == 1
    assert first_unexplained(report)["line"] == at + 1


def test_a_warm_boot_validates_and_one_beside_a_node_still_down_is_caught(tmp_path: Path) -> None:
    # whole_cluster_power_cycle: every node restarts from its saved state and PN1
    # warm-boots (TraceElection's WarmBoot: every node waits, the first epoch PN1 owns
    # above every epoch). Validated by all three specs. The same line while PN2 is still
    # down, or into an epoch PN1 does not own, is no step of the spec.
    lines = _scenario_trace(tmp_path, "whole_cluster_power_cycle")
    code, report, stderr = validate(tmp_path / "whole_cluster_power_cycle.ndjson")
    assert code == 0, explain(report) + stderr
    at = next(i for i, line in enumerate(lines) if line["action"] == "WarmBoot")
    assert lines[at]["args"]["epoch"] == 4, lines[at]
    late = next(i for i, line in enumerate(lines)
                if line["fsm"] == "env" and line["action"] == "Restart" and line["args"]["n"] == "PN2")
    early = [dict(line) for line in lines]
    moved = {**early[late], "t_ns": early[at]["t_ns"] + 1}
    early = early[:late] + early[late + 1:at + 1] + [moved] + early[at + 1:]
    code, report, _ = validate(write(tmp_path / "bad-early.ndjson", early), fsm=["election"])
    assert code == 1
    assert first_unexplained(report)["action"] == "WarmBoot"
    wrong = [dict(line) for line in lines]
    wrong[at] = {**wrong[at], "args": {**wrong[at]["args"], "epoch": 5},
                 "vars": {**wrong[at]["vars"], "epoch": 5}}
    code, report, _ = validate(write(tmp_path / "bad-epoch.ndjson", wrong), fsm=["election"])
    assert code == 1
    assert first_unexplained(report)["line"] == at + 1


def test_a_warm_boot_by_or_beside_a_fenced_node_validates(tmp_path: Path) -> None:
    # prototype3 seed 40, three faults and 3 % loss: PN1 restarts and obeys PN3's epoch-3
    # SAFE Command, which excludes it (it runs fenced); PN3 and PN2 then restart. Every
    # node is idle (two wait, PN1 runs fenced) and PN1 warm-boots: MasterElection's
    # WarmBoot counts a fenced node as idle, which the election job reads from the
    # node's switch line of that Command (`out`). Without the exclusion there, PN1
    # follows a Master, and the warm boot is no step.
    trace = tmp_path / "seed40.ndjson"
    subprocess.run([str(binary("keel-sim")), "run", str(MISSION), "--seed", "40",
                    "--max-failures", "3", "--loss", "3%", "--trace", str(trace)],
                   capture_output=True, text=True, timeout=300, check=False)
    lines = lines_of(trace)
    at = next((i for i, line in enumerate(lines) if line["action"] == "WarmBoot"), None)
    assert at is not None, "no warm boot in this run: choose another seed"
    booter = lines[at]["node"]
    fenced_at = max(i for i, line in enumerate(lines[:at])
                    if line["node"] == booter and line["fsm"] == "switch"
                    and line["action"] == "ReceiveCommand")
    assert booter in lines[fenced_at]["args"]["out"], lines[fenced_at]
    code, report, stderr = validate(trace)
    assert code == 0, explain(report) + stderr
    # The switch job: a fenced node's take-over is a step only as a warm boot (it comes
    # back as the Master of a view that excludes no one); without `warm` it is a line of
    # an excluded node, which takes no part.
    take_over = next(i for i, line in enumerate(lines) if i > at and line["node"] == booter
                     and line["fsm"] == "switch" and line["action"] == "BecomeMaster")
    assert lines[take_over]["args"].get("warm") is True, lines[take_over]
    cold = [dict(line) for line in lines]
    cold[take_over] = {**cold[take_over], "args": {
        k: v for k, v in cold[take_over]["args"].items() if k != "warm"}}
    code, report, _ = validate(write(tmp_path / "cold.ndjson", cold), fsm=["switch"])
    assert code == 1
    assert first_unexplained(report)["line"] == take_over + 1
    unfenced = [dict(line) for line in lines]
    unfenced[fenced_at] = {**unfenced[fenced_at], "args": {
        **unfenced[fenced_at]["args"],
        "out": [n for n in unfenced[fenced_at]["args"]["out"] if n != booter]}}
    code, report, _ = validate(write(tmp_path / "unfenced.ndjson", unfenced), fsm=["election"])
    assert code == 1
    assert first_unexplained(report)["action"] == "WarmBoot"


def test_a_crash_before_a_late_boot_is_no_crash_of_the_election(tmp_path: Path) -> None:
    # prototype3 seed 98, three faults and 3 % loss: PN2 crashes before its late boot (the
    # crash cancels the boot; its Boot line is its first boot), then suspects PN1. To
    # MasterElection a late node is alive and silent from the start: the crash is no
    # step, and PN2's lines after its boot are. A crash after the boot still is: PN2's
    # suspicion after it is a dead node's line.
    trace = tmp_path / "seed98.ndjson"
    subprocess.run([str(binary("keel-sim")), "run", str(MISSION), "--seed", "98",
                    "--max-failures", "3", "--loss", "3%", "--trace", str(trace)],
                   capture_output=True, text=True, timeout=300, check=False)
    lines = lines_of(trace)
    env = [(i, line["action"], line["args"].get("n")) for i, line in enumerate(lines)
           if line["fsm"] == "env"]
    crash = next((i for i, action, n in env if action == "Crash" and n == "PN2"), None)
    boot = next((i for i, action, n in env if action == "Boot" and n == "PN2"), None)
    assert crash is not None and boot is not None and crash < boot, env
    code, report, stderr = validate(trace, fsm=["election"])
    assert code == 0, explain(report) + stderr
    suspect = next(i for i, line in enumerate(lines) if i > boot and line["node"] == "PN2"
                   and line["fsm"] == "election")
    dead = lines[:suspect] + [{**lines[crash], "t_ns": lines[suspect]["t_ns"]}] + lines[suspect:]
    code, report, _ = validate(write(tmp_path / "dead.ndjson", dead), fsm=["election"])
    assert code == 1
    assert first_unexplained(report)["line"] == suspect + 2


def test_a_node_that_boots_into_a_view_that_excludes_it_is_fenced(tmp_path: Path) -> None:
    # prototype3 seed 71, three faults and 3 % loss: ST1 boots late, after PN2's take-over
    # excluded it, and learns of its exclusion from PN2's Command. From that line it runs
    # nothing (fenced), and with the Storage node out PN2's resignation keeps taskB's
    # final state itself (a hand-off). An Ack of ST1 after that Command is the line of an
    # excluded node taking part: rejected.
    trace = tmp_path / "seed71.ndjson"
    subprocess.run([str(binary("keel-sim")), "run", str(MISSION), "--seed", "71",
                    "--max-failures", "3", "--loss", "3%", "--trace", str(trace)],
                   capture_output=True, text=True, timeout=300, check=False)
    lines = lines_of(trace)
    boot = next((i for i, line in enumerate(lines) if line["fsm"] == "env"
                 and line["action"] == "Boot" and line["args"]["n"] == "ST1"), None)
    assert boot is not None, "ST1 does not boot late in this run: choose another seed"
    told = next(i for i, line in enumerate(lines) if i > boot and line["node"] == "ST1"
                and line["fsm"] == "switch" and line["action"] == "ReceiveCommand")
    assert "ST1" in lines[told]["args"]["out"], lines[told]
    code, report, stderr = validate(trace, fsm=["switch"])
    assert code == 0, explain(report) + stderr
    ack = {**lines[told], "action": "Ack", "args": {"n": "ST1", "kind": "Prepared"},
           "vars": {**lines[told]["vars"], "stage": "Prepared"}}
    bad = write(tmp_path / "bad.ndjson", lines[:told + 1] + [ack] + lines[told + 1:])
    code, report, _ = validate(bad, fsm=["switch"])
    assert code == 1
    assert first_unexplained(report)["line"] == told + 2


def test_a_take_over_into_a_configuration_whose_master_is_dead_is_caught(tmp_path: Path) -> None:
    # master_failure: PN2 takes over into P2 (its own). Into P1, whose master PN1 is dead,
    # it is no step: TakeOver needs the configuration's master to be the new Master.
    lines = _scenario_trace(tmp_path, "master_failure")
    assert behaviour(*validate(write(tmp_path / "good.ndjson", lines), fsm=["switch"])[:2])
    at = next(i for i, line in enumerate(lines)
              if line["fsm"] == "switch" and line["action"] == "BecomeMaster")
    assert lines[at]["args"]["c"] == "P2"
    lines[at] = {**lines[at], "args": {**lines[at]["args"], "c": "P1"},
                 "vars": {**lines[at]["vars"], "config": "P1", "masterConfig": "P1"}}
    code, report, _ = validate(write(tmp_path / "bad-takeover.ndjson", lines), fsm=["switch"])
    assert code == 1
    assert first_unexplained(report)["line"] == at + 1


def test_restarts_and_readmissions_are_validated_and_a_bogus_readmission_is_caught(tmp_path: Path) -> None:
    # restart_then_failure: PN3 restarts, is declared for it, readmitted (the Master's
    # Readmit switch, an epoch of its own), then PN2 fails. Every protocol line is
    # validated. A readmission of a node the Master never excluded is no step.
    lines = _scenario_trace(tmp_path, "restart_then_failure")
    code, report, stderr = validate(write(tmp_path / "good.ndjson", lines))
    assert code == 0, explain(report) + stderr
    at = next(i for i, line in enumerate(lines)
              if line["fsm"] == "switch" and line["action"] == "Readmit")
    assert lines[at]["args"]["r"] == "PN3"
    lines[at] = {**lines[at], "args": {**lines[at]["args"], "r": "PN2"}}
    code, report, _ = validate(write(tmp_path / "bad-readmit.ndjson", lines), fsm=["switch"])
    assert code == 1
    assert first_unexplained(report)["line"] == at + 1


def test_a_stale_store_and_a_resume_below_it_are_caught(tmp_path: Path) -> None:
    # master_failure: the Storage node stores taskB's versions 1, 2, 3, ... A store that
    # moves the version back (a stale write accepted) is no step: the Storage node keeps
    # only newer versions, and only versions their writer reached.
    lines = _scenario_trace(tmp_path, "master_failure")
    stores = [i for i, line in enumerate(lines) if line["action"] == "StoreCheckpoint"]
    at = stores[3]
    back = {**lines[at], "args": {**lines[at]["args"], "version": 1},
            "vars": {"stored": {lines[at]["args"]["t"]: 1}}}
    forged = lines[:at + 1] + [back] + lines[at + 1:]
    code, report, _ = validate(write(tmp_path / "bad-store.ndjson", forged), fsm=["switch"])
    assert code == 1
    assert first_unexplained(report)["line"] == at + 2
    ahead = {**lines[at], "args": {**lines[at]["args"], "version": 10 ** 6},
             "vars": {"stored": {lines[at]["args"]["t"]: 10 ** 6}}}
    forged = lines[:at] + [ahead] + lines[at + 1:]
    code, report, _ = validate(write(tmp_path / "bad-store-ahead.ndjson", forged), fsm=["switch"])
    assert code == 1
    assert first_unexplained(report)["line"] == at + 1


def test_declaring_a_never_heard_node_at_the_miss_limit_is_caught(tmp_path: Path) -> None:
    # late_boot: PN3 boots 470 ms late; prototype3's start-up grace is 2000 ms (20
    # periods), so PN1 counts it to 4 missed periods and declares nothing. A DeclareFailed
    # at the miss limit (3), what a monitor without the grace does, is no spec step.
    scenario = ROOT / "tests" / "sim" / "testdata" / "late_boot.txt"
    subprocess.run([str(binary("keel-sim")), "scenario", str(scenario), "--trace-dir",
                    str(tmp_path)], capture_output=True, text=True, timeout=300, check=False)
    lines = lines_of(tmp_path / "late_boot.ndjson")
    assert behaviour(*validate(tmp_path / "late_boot.ndjson", fsm=["heartbeat"])[:2])
    at = next(i for i, line in enumerate(lines)
              if line["node"] == "PN1" and line["action"] == "Tick"
              and line["vars"]["missed"].get("PN3") == 3)
    assert "PN3" not in lines[at]["vars"]["heardOnce"]
    declare = {**lines[at], "action": "DeclareFailed",
               "args": {"m": "PN1", "n": "PN3", "reason": "missed"},
               "vars": {**lines[at]["vars"], "failed": ["PN3"]}}
    bad = write(tmp_path / "graceless.ndjson", lines[:at + 1] + [declare] + lines[at + 1:])
    code, result, _ = validate(bad, fsm=["heartbeat"])
    assert code == 1
    where = first_unexplained(result)
    assert where["action"] == "DeclareFailed" and where["node"] == "PN1"
    assert where["action_enabled"] is False


def test_a_monitor_that_loses_a_live_connected_node_beyond_the_bound_is_caught(
        tmp_path: Path) -> None:
    # one_way_partition: PN3's messages to PN1 are lost (keel-sim's `Block` line), and PN1
    # declares PN3 on its missed heartbeats. With the environment's line the losses are
    # beyond the bound on a faulty link: a behaviour. Without it, PN3 sent every period
    # on a link nothing cut, and PN1 heard nothing for MissLimit periods: more than
    # MaxLoss (MissLimit - 1) losses in a row, which Heartbeat.tla's channel never does;
    # what a monitor that drops a live node's heartbeats logs. Rejected at PN1's Tick
    # that counts the third miss, before the declaration.
    scenario = ROOT / "tests" / "sim" / "testdata" / "one_way_partition.txt"
    subprocess.run([str(binary("keel-sim")), "scenario", str(scenario), "--trace-dir",
                    str(tmp_path)], capture_output=True, text=True, timeout=300, check=False)
    lines = lines_of(tmp_path / "one_way_partition.ndjson")
    block = [line for line in lines if line["fsm"] == "env" and line["action"] == "Block"]
    assert [(b["args"]["from"], b["args"]["to"]) for b in block] == [("PN3", "PN1")]
    assert any(line["node"] == "PN1" and line["action"] == "DeclareFailed"
               and line["args"] == {"m": "PN1", "n": "PN3", "reason": "missed"}
               for line in lines)
    assert behaviour(*validate(tmp_path / "one_way_partition.ndjson", fsm=["heartbeat"])[:2])
    bad = write(tmp_path / "unexplained.ndjson", [line for line in lines if line not in block])
    code, result, _ = validate(bad, fsm=["heartbeat"])
    assert code == 1
    where = first_unexplained(result)
    assert where["node"] == "PN1" and where["action"] == "Tick"
    assert where["vars"]["missed"]["PN3"] == 3


def test_a_burst_of_losses_the_simulator_drew_is_named_and_needed(tmp_path: Path) -> None:
    # 10 % loss on every message: keel-sim draws, on some link, MissLimit heartbeats lost
    # in a row and says so (`LossBurst`). With those lines the run is a behaviour of the
    # heartbeat spec; without them a monitor missed a node that sent every period on a
    # link nothing cut, beyond MaxLoss: rejected at a Tick.
    trace, mission = tmp_path / "loss.ndjson", ROOT / "config" / "earth_observation.yaml"
    subprocess.run([str(binary("keel-sim")), "run", str(mission), "--seed", "1", "--loss",
                    "10%", "--max-failures", "0", "--duration", "3s", "--trace", str(trace)],
                   capture_output=True, text=True, timeout=300, check=False)
    lines = lines_of(trace)
    bursts = [line for line in lines if line["fsm"] == "env" and line["action"] == "LossBurst"]
    assert bursts, "no burst drawn: choose another seed"
    assert all(b["args"]["since_ns"] <= b["t_ns"] and b["args"]["n"] != b["args"]["m"]
               for b in bursts)
    code, result, stderr = validate(trace, fsm=["heartbeat"], mission=mission)
    assert behaviour(code, result), explain(result) + stderr
    bad = write(tmp_path / "unexplained.ndjson", [line for line in lines if line not in bursts])
    code, result, _ = validate(bad, fsm=["heartbeat"], mission=mission)
    assert code == 1
    assert first_unexplained(result)["action"] == "Tick"


def test_cli_prints_file_line_and_differences(seed11: Path, tmp_path: Path) -> None:
    lines = [line for line in lines_of(seed11)
             if line["node"] == "PN1" and line["fsm"] == "heartbeat"]
    sends = [i for i, line in enumerate(lines) if line["action"] == "SendHeartbeat"]
    lines.insert(sends[2] + 1, dict(lines[sends[2]]))  # two heartbeats in one period
    bad = write(tmp_path / "twice.ndjson", lines)
    command = [sys.executable, "-m", "keel_verify.cli", "trace", str(bad), "--fsm", "heartbeat",
               "--mission", str(ROOT / "config" / "prototype3.yaml")]
    done = subprocess.run(command, capture_output=True, text=True, timeout=600, check=False,
                          env=dict(os.environ, PYTHONPATH=str(ROOT / "verify"),
                                   KEEL_ROOT=str(ROOT)))
    assert done.returncode == 1, done.stdout + done.stderr
    assert f"{bad}:{sends[2] + 2}: heartbeat.SendHeartbeat n=PN1" in done.stdout
    assert "is not enabled" in done.stdout


def test_real_cluster_run_with_a_kill_validates(tmp_path: Path) -> None:
    # keel-cluster: four keel-node processes on loopback DDS; PN3 (taskB's host) is killed
    # and taskB moves to PN1. Every node's trace goes into the run directory. As in
    # tests/node, the miss limit is 4 so that a loaded build machine does not starve a
    # node into a false declaration (ConfigSwitch's failures are crashes).
    from conftest import binary

    node = binary("keel-node")
    mission = tmp_path / "prototype3-loaded.yaml"
    text = (ROOT / "config" / "prototype3.yaml").read_text()
    mission.write_text(text.replace("miss_limit: 3}", "miss_limit: 4}"))
    scenario = tmp_path / "kill.yaml"
    scenario.write_text("duration: 4s\nevents:\n  - at 2s kill PN3\n")
    launcher = Path(sys.executable).parent / "keel-cluster"
    if not launcher.is_file():
        pytest.skip("keel-cluster is not installed in this Python environment")
    for attempt in range(2):  # a cluster that fails to start is not a validation result
        run_dir = tmp_path / f"run{attempt}"
        done = subprocess.run([str(launcher), "run", str(mission), "--scenario",
                               str(scenario), "--run-dir", str(run_dir), "--node-binary",
                               str(node), "--quiet"],
                              capture_output=True, text=True, timeout=120, check=False)
        if done.returncode == 0:
            break
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    traces = sorted(run_dir.glob("*.trace.ndjson"))
    assert len(traces) == 4
    code, report, stderr = validate(run_dir, mission=mission)
    assert behaviour(code, report), explain(report) + stderr
    assert {r["protocol"] for r in report["results"]} == {"heartbeat", "election", "switch"}


def test_a_real_cluster_power_cycle_validates(tmp_path: Path) -> None:
    # keel-node processes on loopback DDS: every node is killed at once and started again
    # from its state file; PN1 warm-boots. The launcher's kills and starts are the traces'
    # environment lines (as keel-cluster campaign writes them), so the specs know every
    # node rebooted: the WarmBoot line, the take-over it drives and the restarts are steps.
    try:
        from keel_cluster.campaign import write_env_lines
        from keel_cluster.launcher import Cluster
    except ImportError:
        pytest.skip("keel-cluster is not installed in this Python environment")
    mission = tmp_path / "prototype3-loaded.yaml"
    mission.write_text((ROOT / "config" / "prototype3.yaml").read_text().replace(
        "miss_limit: 3}", "miss_limit: 4}"))
    run_dir = tmp_path / "run"
    names = ["PN1", "PN2", "PN3", "ST1"]
    with Cluster(mission, names, run_dir, binary("keel-node"), domain_id=1 + (os.getpid() * 7) % 200,
                 echo=False) as cluster:
        def settled(epoch_above: int) -> bool:
            status = cluster.statuses().get("PN1", {})
            return (status.get("role") == "Master" and int(status.get("epoch", 0)) > epoch_above
                    and any("taskB" in s.get("tasks", []) for s in cluster.statuses().values()))

        import time
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and not settled(0):
            time.sleep(0.05)
        assert settled(0), cluster.statuses()
        time.sleep(0.5)
        for name in names:
            cluster.kill(name)
        for name in ["ST1", "PN3", "PN2", "PN1"]:
            cluster.start(name)
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and not settled(1):
            time.sleep(0.05)
        assert settled(1), cluster.statuses()
        time.sleep(0.5)
        events = list(cluster.events)
    write_env_lines(run_dir, events)
    lines = [json.loads(x) for f in run_dir.glob("*.trace.ndjson") for x in f.read_text().splitlines() if x]
    assert any(x["action"] == "WarmBoot" for x in lines)
    code, report, stderr = validate(run_dir, mission=mission)
    assert behaviour(code, report), explain(report) + stderr


SCENARIO_FILES = sorted((ROOT / "tests" / "sim" / "testdata").glob("*.txt"))
SCENARIO_MISSION = re.compile(r"^mission (\S+)", re.MULTILINE)


@pytest.mark.parametrize("scenario", SCENARIO_FILES, ids=lambda p: p.stem)
def test_scenario_file_traces_validate(tmp_path: Path, scenario: Path) -> None:
    """Every scenario file (the paper's situations) traced by keel-sim, checked against all
    three specs: every protocol line validated (partitions, resignations, safe mode, a
    Storage node out of reach included), exit 0."""
    done = subprocess.run(
        [str(binary("keel-sim")), "scenario", str(scenario), "--trace-dir", str(tmp_path)],
        capture_output=True, text=True, timeout=120, check=False, env=dict(os.environ, KEEL_ROOT=str(ROOT)),
    )
    assert done.returncode == 0, done.stdout + done.stderr
    trace = tmp_path / f"{scenario.stem}.ndjson"
    assert trace.is_file() and trace.stat().st_size > 0, done.stdout
    match = SCENARIO_MISSION.search(scenario.read_text())
    assert match, f"{scenario}: no 'mission PATH' command"
    code, report, stderr = validate(trace, mission=ROOT / match.group(1))
    assert code == 0, explain(report) + stderr + json.dumps(report.get("coverage"))


# Mutants whose rule no random fault plan reaches, on the scenario that reaches it: no
# simulator checker fires there (the cut-off node's tasks run unseen), the trace shows it.
@pytest.mark.parametrize("mutant, scenario", [
    ("no-lease", "checkpointed_observer_cut_off"),
    ("no-joint-views", "partition_cuts_switch_to_more_monitors"),
    ("quorum-before-fix", "partition_cuts_phase_switch"),
])
def test_a_scenarios_mutant_is_rejected_where_the_real_run_validates(
        tmp_path: Path, mutant: str, scenario: str) -> None:
    path = ROOT / "tests" / "sim" / "testdata" / f"{scenario}.txt"
    match = SCENARIO_MISSION.search(path.read_text())
    assert match
    done = subprocess.run(
        [str(binary("keel-sim")), "scenario", str(path), "--mutant", mutant, "--seed", "5",
         "--trace-dir", str(tmp_path)],
        capture_output=True, text=True, timeout=120, check=False,
        env=dict(os.environ, KEEL_ROOT=str(ROOT)))
    assert done.returncode == 0 and "ran " in done.stdout, done.stdout + done.stderr
    code, report, stderr = validate(tmp_path / f"{scenario}.ndjson", mission=ROOT / match.group(1))
    assert code == 1, explain(report) + stderr
    assert first_unexplained(report)["protocol"] == "switch", explain(report)


def test_a_start_without_the_storage_node_that_keeps_the_lineage_is_caught(tmp_path: Path) -> None:
    # Seed 241 (30 s; a partition PN1 PN2 | PN3 ST1 from 11.2 to 11.9 s): taskB starts
    # without the Storage node (StateOutOfReach) and goes on from scratch. When the Storage
    # node is back, the flush of the lineage the task went on with is below the version
    # stored before. With the lineage opened (the runtime), the Storage node takes it; the
    # mutant keeps the old lineage, the Storage node keeps the abandoned version and
    # acknowledges the flush: PN1's "Prepared" is then not enabled. No simulator checker
    # sees it. (The seed was 3 before every simulated node ran on a clock of its own.)
    trace, report = sim_trace(tmp_path, 241, duration="30s", mutant="lineage-kept")
    assert checkers_quiet(report), report
    code, result, _ = validate(trace, fsm=["switch"])
    assert code == 1
    where = first_unexplained(result)
    assert where["action"] == "Ack" and where["node"] == "PN1"
    assert where["action_enabled"] is False
    good, report = sim_trace(tmp_path, 241, duration="30s")
    assert checkers_quiet(report), report
    # Every line of the run, the election's too.
    code, result, _ = validate(good)
    assert code == 0, json.dumps(result)[:3000]
    assert any("lineages of task states" in note for job in result["results"]
               for note in job.get("notes", []))


def test_a_readmission_by_the_readmitted_nodes_own_command_validates(tmp_path: Path) -> None:
    # Seed 9 (10 s): PN1 crashes; PN3, excluded meanwhile, is readmitted by a Command it
    # sends itself: the Command proves it alive first (it is forgotten and counts as heard
    # in the period), then the Readmit line. Every line of the run validates.
    trace, report = sim_trace(tmp_path, 9, duration="10s")
    assert checkers_quiet(report), report
    code, result, _ = validate(trace)
    assert code == 0, json.dumps(result)[:3000]


def test_a_start_that_opens_no_newer_lineage_is_caught(tmp_path: Path) -> None:
    # Seed 3 (30 s): PN1 starts taskB without the Storage node and opens lineage [1, 3]
    # (its "opened"), accepted in full by test_a_start_without_the_storage_node_...
    # Forged: the start names the initial lineage as the one it opens (and runs in it),
    # no newer than the state it starts from: OpenLineage is not enabled.
    trace, _ = sim_trace(tmp_path, 3, duration="30s")
    lines = lines_of(trace)
    at = next(i for i, line in enumerate(lines)
              if line["action"] == "Activate" and "opened" in line["args"])
    lines[at]["args"]["opened"] = [0, 0]
    lines[at]["vars"].pop("lineage", None)
    code, result, _ = validate(write(tmp_path / "forged.ndjson", lines), fsm=["switch"])
    assert code == 1
    where = first_unexplained(result)
    assert where["action"] == "Activate" and where["action_enabled"] is False


def test_a_running_state_that_changes_lineage_unopened_is_caught(seed11: Path,
                                                                 tmp_path: Path) -> None:
    # Only a start opens a lineage (an Activate line with `opened`), and only a restore
    # from the Storage node adopts another. Forged: from PN3's fifth periodic checkpoint
    # of taskB on, taskB's state is of lineage [1, 1] everywhere (PN3's lines, the Storage
    # node's, every later line): a consistent run but for the silent jump, which Steps
    # must refuse.
    lines = lines_of(seed11)
    flushes = [i for i, line in enumerate(lines)
               if line["action"] == "FlushCheckpoint" and line["node"] == "PN3"
               and line["args"].get("t") == "taskB" and line["args"].get("final") is False]
    assert len(flushes) > 5
    for line in lines[flushes[4]:]:
        if line["fsm"] != "switch":
            continue
        if line["args"].get("t") == "taskB" and isinstance(line["args"].get("version"), int):
            line["args"]["lineage"] = [1, 1]
        if "taskB" in (line["vars"].get("version") or {}):
            line["vars"].setdefault("lineage", {})["taskB"] = [1, 1]
        if "taskB" in (line["vars"].get("stored") or {}):
            line["vars"].setdefault("storedLineage", {})["taskB"] = [1, 1]
    code, result, _ = validate(write(tmp_path / "forged.ndjson", lines), fsm=["switch"])
    assert code == 1, json.dumps(result)[:3000]
    where = first_unexplained(result)
    assert (where["line"], where["action"]) == (flushes[4] + 1, "FlushCheckpoint"), where


def test_a_line_between_the_store_and_its_ack_lists_the_task_unflushed(
        tmp_path: Path) -> None:
    # Seed 7 (20 s, 10 % loss): PN2 stops taskB in a switch and flushes it, and receives
    # the next Command before the Storage node's ack: its ReceiveCommand line still lists
    # taskB unflushed. The spec's FlushCheckpoint is the store and the ack at once.
    trace, report = sim_trace(tmp_path, 7, duration="20s", loss="10%")
    assert checkers_quiet(report), report
    lines = lines_of(trace)
    at = next(i for i, line in enumerate(lines)
              if line["action"] == "ReceiveCommand" and line["fsm"] == "switch"
              and line["vars"].get("unflushed") and line["node"] == "PN2")
    code, result, _ = validate(trace, fsm=["switch"])
    assert code == 0, json.dumps(result)[:3000]
    # The relaxation is that task only: a task the node runs is never "unflushed".
    lines[at]["vars"]["unflushed"] = ["taskA"]
    code, result, _ = validate(write(tmp_path / "forged.ndjson", lines), fsm=["switch"])
    assert code == 1
    assert first_unexplained(result)["line"] == at + 1


def test_a_heartbeat_from_the_monitor_itself_is_a_mismatch(seed11: Path,
                                                          tmp_path: Path) -> None:
    # A ReceiveHeartbeat whose sender is the monitor itself: no order of hidden sends
    # covers it. It is a line nothing explains (exit 1, at that line), not a TLC error.
    lines = lines_of(seed11)
    at = next(i for i, line in enumerate(lines) if line["fsm"] == "heartbeat"
              and line["action"] == "ReceiveHeartbeat" and line["node"] == "PN1")
    lines[at]["args"]["n"] = "PN1"
    code, result, _ = validate(write(tmp_path / "self.ndjson", lines), fsm=["heartbeat"])
    assert code == 1, json.dumps(result)[:3000]
    where = first_unexplained(result)
    assert (where["line"], where["subject"]) == (at + 1, "PN1")


@pytest.mark.parametrize("checker", ["explicit", "tlc"])
def test_a_monitor_that_counts_a_period_it_should_suspect_is_caught(tmp_path: Path,
                                                                    checker: str) -> None:
    # Seed 11: PN3 goes deaf; the mutant without self-suspicion counts the periods in which
    # it heard no one (its Tick logs silent) and declares everyone. Rule 1 (Exclusion.tla):
    # a monitor that logs a cause to suspect itself must not count. The real run's trace
    # validates; the mutant's is rejected at the first silent counting Tick.
    real, _ = sim_trace(tmp_path, 11, duration="6s")
    code, result, _ = validate(real, fsm=["heartbeat"], extra=["--checker", checker])
    assert code == 0, explain(result)
    trace, _report = sim_trace(tmp_path, 11, duration="6s", mutant="no-self-suspicion")
    code, result, _ = validate(trace, fsm=["heartbeat"], extra=["--checker", checker])
    assert code == 1, explain(result)
    where = first_unexplained(result)
    line = json.loads(trace.read_text().splitlines()[where["line"] - 1])
    assert line["action"] == "Tick" and line["node"] == "PN3"
    assert line["args"]["silent"] is True and "suspect" not in line["args"]


# The node driver's rule 2 on traces (core/node/driver.hpp): a StoreCheckpoint line stands
# for a durable write, and a restarted Storage node logs what it read back from its disk
# (Recovered), never below a StoreCheckpoint line it logged (TraceConfigSwitch's
# `written`). Seed 6 of each disk-fault campaign: the correct driver's run validates; a
# driver that lets the line (and the acknowledgement) go before the write, or takes a
# failed write for a written one, is rejected at the Storage node's Recovered line.
@pytest.mark.parametrize("mutant, faults", [
    ("release-held-early", "storage-power-loss"),
    ("ignore-failed-write", "storage-full"),
])
def test_a_store_line_the_disk_lost_is_caught_when_the_storage_node_recovers(
        tmp_path: Path, mutant: str, faults: str) -> None:
    traces = {}
    for variant in ("none", mutant):
        trace = tmp_path / f"{variant}.ndjson"
        done = subprocess.run(
            [str(binary("keel-sim")), "run", str(MISSION), "--seed", "6", "--disk-faults", faults,
             "--mutant", variant, "--trace", str(trace)],
            capture_output=True, text=True, timeout=120, check=False)
        assert trace.is_file(), done.stdout + done.stderr
        traces[variant] = trace
    assert any(line["action"] == "Recovered" for line in lines_of(traces["none"]))
    code, report, stderr = validate(traces["none"], fsm=["switch"])
    assert code == 0, explain(report) + stderr
    code, report, stderr = validate(traces[mutant], fsm=["switch"])
    assert code == 1, explain(report) + stderr
    where = first_unexplained(report)
    assert where["action"] == "Recovered", explain(report)


# The driver's rule 1 on traces: a node's state is durable before a message that depends
# on it leaves. A restarted node logs the state it read back from its disk (Restored: its
# view, and `saved`, its epoch), never older than what it said that others logged
# (TraceConfigSwitch's `received`): the epoch of a Command of its another node received,
# the view of a Prepared of its another node received (HeardPrepared). Seed 1 of
# master-power-loss: the correct driver's run validates; the same Restored line with an
# epoch below the initial Master's Commands, or a view below its Prepared of the boot
# switch, is rejected there.
def test_a_restored_state_older_than_what_the_node_said_is_caught(tmp_path: Path) -> None:
    trace = tmp_path / "none.ndjson"
    done = subprocess.run(
        [str(binary("keel-sim")), "run", str(MISSION), "--seed", "1", "--disk-faults",
         "master-power-loss", "--trace", str(trace)],
        capture_output=True, text=True, timeout=120, check=False)
    assert trace.is_file(), done.stdout + done.stderr
    lines = lines_of(trace)
    at = next(i for i, line in enumerate(lines) if line["action"] == "Restored")
    restored = lines[at]
    assert restored["node"] == "PN1" and restored["args"]["saved"] >= 1, restored
    assert (restored["args"]["epoch"], restored["args"]["seq"]) >= (1, 1), restored
    code, report, stderr = validate(trace, fsm=["switch"])
    assert code == 0, explain(report) + stderr
    for name, args in (("epoch", {"saved": 0}), ("view", {"epoch": 1, "seq": 0})):
        bad = [dict(line) for line in lines]
        bad[at] = {**restored, "args": {**restored["args"], **args}}
        code, report, _ = validate(write(tmp_path / f"bad-{name}.ndjson", bad), fsm=["switch"])
        assert code == 1, name
        assert first_unexplained(report)["line"] == at + 1, name
    # A receipt of a Prepared its sender never acked is no step.
    heard = next(i for i, line in enumerate(lines) if line["action"] == "HeardPrepared")
    forged = {**lines[heard], "args": {**lines[heard]["args"], "epoch": 9, "seq": 9}}
    bad = lines[:heard] + [forged] + lines[heard + 1:]
    code, report, _ = validate(write(tmp_path / "bad-heard.ndjson", bad), fsm=["switch"])
    assert code == 1
    assert first_unexplained(report)["line"] == heard + 1
    # The driver mutant save-after-send, run on past keel-sim's checker: the initial
    # Master's Prepared of the phase switch left before its save, the members logged it
    # (HeardPrepared), and the power loss took the save: rejected at its Restored line.
    mutant = tmp_path / "save-after-send.ndjson"
    subprocess.run([str(binary("keel-sim")), "run", str(MISSION), "--seed", "1",
                    "--disk-faults", "master-power-loss", "--mutant", "save-after-send",
                    "--keep-going", "--trace", str(mutant)],
                   capture_output=True, text=True, timeout=120, check=False)
    code, report, stderr = validate(mutant, fsm=["switch"])
    assert code == 1, explain(report) + stderr
    where = first_unexplained(report)
    assert where["action"] == "Restored" and where["node"] == "PN1", explain(report)


def test_a_rolled_back_restart_is_not_held_to_what_the_node_said_before(tmp_path: Path) -> None:
    # prototype3 seed 4: PN2 restarts from a state that went back on purpose (keel-sim's
    # rolled-back restart, `rolled_back` on its Restart line: a lost write, a restored
    # file), to a view older than its Prepared of the boot switch that others heard. The
    # environment's doing: the run validates. The same restart without the flag is a
    # driver that lost a state it said: rejected at PN2's Restored line.
    trace, _ = sim_trace(tmp_path, 4, duration=None)
    lines = lines_of(trace)
    at = next((i for i, line in enumerate(lines) if line["fsm"] == "env"
               and line["action"] == "Restart" and line["args"].get("rolled_back")), None)
    assert at is not None, "no rolled-back restart in this run: choose another seed"
    node = lines[at]["args"]["n"]
    restored = next(i for i, line in enumerate(lines)
                    if i > at and line["node"] == node and line["action"] == "Restored")
    code, report, stderr = validate(trace, fsm=["switch"])
    assert code == 0, explain(report) + stderr
    kept = [dict(line) for line in lines]
    kept[at] = {**kept[at], "args": {"n": node}}
    code, report, _ = validate(write(tmp_path / "kept.ndjson", kept), fsm=["switch"])
    assert code == 1
    assert first_unexplained(report)["line"] == restored + 1


# A hand-over names its receiver's boot (fault model 2, reintegration): in keel-sim's
# master-power-loss seed 3 PN2 hands the view back to PN1 just after PN1 lost power, and
# repeats it to PN1's next boot. That boot refuses it, and the trace is a behaviour of every
# spec; under the mutant hand-over-any-boot it takes the view meant for the boot that ended
# and is Master of an epoch PN2 had taken over from it, which the election's spec rejects.
def test_a_hand_over_meant_for_a_boot_that_ended_is_refused(tmp_path: Path) -> None:
    traces = {}
    for variant in ("none", "hand-over-any-boot"):
        trace = tmp_path / f"{variant}.ndjson"
        done = subprocess.run(
            [str(binary("keel-sim")), "run", str(MISSION), "--seed", "3", "--disk-faults",
             "master-power-loss", "--mutant", variant, "--trace", str(trace)],
            capture_output=True, text=True, timeout=120, check=False)
        assert trace.is_file(), done.stdout + done.stderr
        traces[variant] = trace
    assert any(line["action"] == "HandOver" for line in lines_of(traces["none"]))
    code, report, stderr = validate(traces["none"])
    assert code == 0, explain(report) + stderr
    code, report, stderr = validate(traces["hand-over-any-boot"], fsm=["election"])
    assert code == 1, explain(report) + stderr
    where = first_unexplained(report)
    assert where["action"] == "ReceiveCommand" and where["node"] == "PN1", explain(report)


# A Master handed the view that cannot get every voter's acknowledgement in time gives it
# up before its boot switch (NodeProtocol::enforce_lease, hand_overs_given_up): its
# AskExclusion line, as a Master of masterSeq 0, validates (keel-sim prototype3 seed 111:
# PN2 hands P1 to PN1 in epoch 4, PN1 gives it up, and PN2 takes over again). The rule is
# no blank cheque: the same line from a Master that commands (PN2, just after it took
# over in epoch 2) is rejected at that line.
def test_a_hand_over_given_up_validates_and_a_commanding_masters_ask_is_caught(
        tmp_path: Path) -> None:
    trace, _report = sim_trace(tmp_path, 111, duration=None)
    lines = lines_of(trace)
    handed = [x["args"]["to"] for x in lines if x["action"] == "HandOver"]
    asks = [x for x in lines if x["action"] == "AskExclusion" and x["node"] in handed
            and x["vars"].get("role") == "Master" and x["vars"].get("seq") == 0]
    assert asks, "no hand-over given up in this run"
    code, report, stderr = validate(trace, fsm=["switch"])
    assert code == 0, explain(report) + stderr

    took = next(i for i, x in enumerate(lines)
                if x["fsm"] == "switch" and x["action"] == "BecomeMaster" and x["node"] == "PN2")
    forged = dict(asks[0], node="PN2", t_ns=lines[took]["t_ns"], args={"n": "PN2"},
                  vars=dict(lines[took]["vars"]))
    broken = tmp_path / "commanding-master-asks.ndjson"
    broken.write_text("".join(json.dumps(x) + "\n"
                              for x in lines[:took + 1] + [forged] + lines[took + 1:]))
    code, report, stderr = validate(broken, fsm=["switch"])
    assert code == 1, explain(report) + stderr
    where = first_unexplained(report)
    assert where["action"] == "AskExclusion" and where["node"] == "PN2", explain(report)


# Rule 5's "word" backing of a restarted node by a node that is no monitor: PN1 crashes and
# restarts, and ST1, hearing its new boot, backs PN2's exclusion of it by PN1's own word
# with no Report line of its own (keel-sim prototype3 seed 248). The env Restart line is
# that word; the run validates. A "word" of a node that neither restarted nor resigned is
# caught at its Backed line.
def test_a_restart_backs_an_exclusion_at_a_node_that_is_no_monitor(tmp_path: Path) -> None:
    trace, _report = sim_trace(tmp_path, 248, duration=None)
    lines = lines_of(trace)
    restarted = {x["args"]["n"] for x in lines if x["fsm"] == "env" and x["action"] == "Restart"}
    monitors_declaring = {(x["args"]["m"], x["args"]["n"]) for x in lines
                          if x["fsm"] == "heartbeat" and x["action"] == "DeclareFailed"}
    words = [i for i, x in enumerate(lines) if x["action"] == "Backed"
             and any(kind == "word" and node in restarted
                     and (x["node"], node) not in monitors_declaring
                     for node, (kind, _by) in x["args"]["by"].items())]
    assert words, "no restart backed by its word at a node that did not declare it"
    code, report, stderr = validate(trace, fsm=["switch"])
    assert code == 0, explain(report) + stderr
    first = words[0]
    silent = next(x for x in ("PN1", "PN2", "PN3")
                  if x not in restarted and x != lines[first]["args"]["from"]
                  and x not in lines[first]["args"]["by"]
                  and not any(y["action"] in ("Resign", "AskExclusion") and y["node"] == x
                              for y in lines[:first]))
    forged = lines_of(trace)
    forged[first]["args"]["by"][silent] = ["word", silent]
    bad = tmp_path / "word-of-a-silent-node.ndjson"
    bad.write_text("".join(json.dumps(x) + "\n" for x in forged))
    code, report, stderr = validate(bad, fsm=["switch"])
    assert code == 1, explain(report) + stderr
    where = first_unexplained(report)
    assert (where["action"], where["line"]) == ("Backed", first + 1), explain(report)


# The correct driver under disk faults (keel-sim --disk-faults): the Storage node holds its
# acknowledgement of a final checkpoint until the write is durable, so a power loss or a
# full disk before the write leaves the writer's final checkpoint unflushed until it
# adopts a view that excludes the Storage node (TraceConfigSwitch's Orphaned), and the
# Master resends it in the step that starts that switch (switch.py's `commanding`).
# Every line validates. Witness that the first allowance is no blank cheque: a task
# listed unflushed by a node while the Storage node is up, and its state not stored at
# the node's version, is rejected at that line.
@pytest.mark.parametrize("faults, seed", [
    ("storage-power-loss", 2),
    ("storage-full", 3),
    ("master-power-loss", 4),
])
def test_traces_of_the_driver_under_disk_faults_are_behaviours_of_the_specs(
        tmp_path: Path, faults: str, seed: int) -> None:
    trace = tmp_path / "run.ndjson"
    done = subprocess.run(
        [str(binary("keel-sim")), "run", str(MISSION), "--seed", str(seed), "--disk-faults",
         faults, "--trace", str(trace)],
        capture_output=True, text=True, timeout=120, check=False)
    assert trace.is_file(), done.stdout + done.stderr
    code, report, stderr = validate(trace)
    assert code == 0, explain(report) + stderr
    if faults != "storage-power-loss":
        return
    lines = lines_of(trace)
    loss = next(i for i, line in enumerate(lines) if line["action"] == "PowerLoss")
    at = max(i for i, line in enumerate(lines[:loss])
             if line["node"] == "PN2" and line["fsm"] == "switch" and line["action"] == "Ack"
             and "taskB" not in line["vars"]["active"] and not line["vars"]["unflushed"])
    lines[at] = {**lines[at], "vars": {**lines[at]["vars"], "unflushed": ["taskB"]}}
    code, report, _ = validate(write(tmp_path / "bad.ndjson", lines), fsm=["switch"])
    assert code == 1, explain(report)
    assert first_unexplained(report)["line"] == at + 1, explain(report)


def _take_over_lines_name_the_member_passed_over(tmp_path: Path, seed: int, field: str, taker: str,
                                                bad_switch: dict) -> None:
    """An earth-observation run whose take-over (by `taker`) passes over PN2 for the reason
    `field` names (`newer`, `unprepared`): the trace validates, and both lines name PN2 in
    `passed` and in `field`. Then each line is rejected at itself: the election's without
    `field` (PN2 passed over at the taker's own epoch, not behind), and the switch's with
    `bad_switch`'s arguments (a member passed over for that reason that does not fit it)."""
    eo = ROOT / "config" / "earth_observation.yaml"
    trace, _ = sim_trace(tmp_path, seed, duration="5s", mission=eo)
    lines = lines_of(trace)
    code, report, stderr = validate(trace, mission=eo)
    assert code == 0, explain(report) + stderr
    at = {fsm: next(i for i, line in enumerate(lines) if line["fsm"] == fsm
                    and line["action"] == "BecomeMaster" and line["args"].get(field))
          for fsm in ("election", "switch")}
    election, switch = lines[at["election"]], lines[at["switch"]]
    assert election["node"] == taker and election["args"][field] == ["PN2"]
    assert election["args"]["passed"] == {"PN2": 1}
    assert switch["args"]["passed"] == ["PN2"] and switch["args"][field] == ["PN2"]
    for fsm, args in (("election", {field: []}), ("switch", bad_switch)):
        bad = list(lines)
        bad[at[fsm]] = {**bad[at[fsm]], "args": {**bad[at[fsm]]["args"], **args}}
        code, report, _ = validate(write(tmp_path / f"{fsm}.ndjson", bad), mission=eo, fsm=[fsm])
        assert code == 1, (fsm, explain(report))
        assert first_unexplained(report)["line"] == at[fsm] + 1, (fsm, explain(report))


def test_a_take_over_that_passes_over_a_member_of_a_newer_switch_validates_and_a_false_one_is_caught(
        tmp_path: Path) -> None:
    # earth-observation seed 4503, no loss: a partition hid PN1's phase switch (epoch 1,
    # seq 2) from PN3 and PN4, then PN1 crashed. PN2 took the switch; PN3, behind it in the
    # succession of the view before, passes it over for its Prepared of that newer switch
    # (NodeProtocol::diverged_members) and takes over (TraceConfigSwitch's TakeOverEvidence:
    # PN2's Prepared of a newer switch of PN3's epoch came before). The false one: the
    # switch's line naming PN4 too, which prepared no newer switch (it was on PN3's side of
    # the partition).
    _take_over_lines_name_the_member_passed_over(
        tmp_path, 4503, "newer", "PN3", {"passed": ["PN2", "PN4"], "newer": ["PN2", "PN4"]})


def test_a_take_over_that_passes_over_a_member_that_never_prepared_its_view_validates_and_a_false_one_is_caught(
        tmp_path: Path) -> None:
    # earth-observation seed 8153, no loss: a partition hid the phase switch to downlink
    # from PN2, and the Master crashed. PN4, behind PN2 in the new view's succession, never
    # hears PN2 prepare that view: it passes PN2 over (NodeProtocol::never_prepared) and
    # takes over (TraceConfigSwitch's TakeOverEvidence: no Prepared of PN2 names PN4's
    # view). The false one: the switch's line naming PN1 too, which prepared PN4's view.
    _take_over_lines_name_the_member_passed_over(
        tmp_path, 8153, "unprepared", "PN4", {"passed": ["PN2", "PN1"], "unprepared": ["PN2", "PN1"]})


def test_a_take_over_that_passes_over_a_member_behind_validates_and_one_not_behind_is_caught(
        tmp_path: Path) -> None:
    # earth-observation seed 11501 with 5 % loss: PN3 never took a Command (it says epoch
    # 1), PN2 took over epoch 2 and crashed; PN4, behind PN3 in epoch 2's succession,
    # passes over PN3, heard and behind (NodeProtocol::diverged_members), and takes over.
    # Both lines of the take-over name PN3 (`passed`, the election's with the epoch PN3
    # last said), and validate (TraceElection's PassOver, TraceConfigSwitch's
    # TakeOverEvidence).
    eo = ROOT / "config" / "earth_observation.yaml"
    trace, _ = sim_trace(tmp_path, 11501, duration="5s", mission=eo, loss="5%")
    lines = lines_of(trace)
    code, report, stderr = validate(trace, mission=eo)
    assert code == 0, explain(report) + stderr
    take = next(i for i, line in enumerate(lines) if line["fsm"] == "election"
                and line["action"] == "BecomeMaster" and line["args"].get("passed"))
    assert lines[take]["node"] == "PN4" and lines[take]["args"]["passed"] == {"PN3": 1}

    def passing(at: dict[str, int], took: bool) -> list[dict]:
        """The trace with PN4's line naming `at` as PN3's epoch heard; with `took`, PN3
        took PN2's Command of epoch 2 first (a line inserted after PN2's own, PN3's later
        lines following it)."""
        bad = list(lines)
        bad[take] = {**bad[take], "args": {**bad[take]["args"], "passed": at}}
        if not took:
            return bad
        own = next(i for i, line in enumerate(bad) if line["fsm"] == "election"
                   and line["node"] == "PN2" and line["action"] == "ReceiveCommand"
                   and line["args"]["epoch"] == 2)
        assert not any(line["node"] == "PN3" and line["fsm"] == "election"
                       and line["action"] == "ReceiveCommand" for line in bad[:take])
        command = {**bad[own], "node": "PN3",
                   "args": {"n": "PN3", "from": "PN2", "epoch": 2, "stepDown": False},
                   "vars": {"role": "Observer", "epoch": 2, "leader": "PN2", "suspects": [],
                            "lastCommand": 2}}
        bad = bad[:own + 1] + [command] + bad[own + 1:]
        for i in range(own + 2, take + 1):
            if bad[i]["node"] == "PN3" and bad[i]["fsm"] == "election":
                bad[i] = {**bad[i], "vars": {**bad[i]["vars"], "epoch": 2, "leader": "PN2",
                                             "lastCommand": 2}}
        return bad

    # PN3 took epoch 2 meanwhile, its heartbeats of epoch 1 still the last PN4 heard: the
    # rule as the runtime applies it (a member may move on before its heartbeats say so).
    code, report, _ = validate(write(tmp_path / "moved-on.ndjson", passing({"PN3": 1}, True)),
                               mission=eo, fsm=["election"])
    assert code == 0, explain(report)
    # Passed over at the taker's own epoch (not behind), or at an epoch PN3 never went by:
    # rejected at the take-over's line.
    for name, at, took, line in (("not-behind", {"PN3": 2}, True, take + 2),
                                 ("never-had", {"PN3": 0}, False, take + 1)):
        code, report, _ = validate(write(tmp_path / f"{name}.ndjson", passing(at, took)),
                                   mission=eo, fsm=["election"])
        assert code == 1, (name, explain(report))
        assert first_unexplained(report)["line"] == line, (name, explain(report))

    # The switch's line without PN3 passed over: PN3 is a member of the view taken over,
    # and the take-over's members do not name it.
    at = next(i for i, line in enumerate(lines) if line["fsm"] == "switch"
              and line["action"] == "BecomeMaster" and line["args"].get("passed"))
    unnamed = list(lines)
    unnamed[at] = {**lines[at], "args": {k: v for k, v in lines[at]["args"].items()
                                         if k != "passed"}}
    code, report, _ = validate(write(tmp_path / "unnamed.ndjson", unnamed), mission=eo,
                               fsm=["switch"])
    assert code == 1, explain(report)
    assert first_unexplained(report)["line"] == at + 1, explain(report)
