"""Metrics and reliability checks from traces: synthetic runs whose answers are known."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from keel_cluster import analysis

MS = 1_000_000


def line(t_ms: float, node: str, fsm: str, action: str, **args: object) -> str:
    return json.dumps(
        {"t_ns": int(t_ms * MS), "node": node, "fsm": fsm, "action": action, "args": args, "vars": {}}
    )


def write_run(tmp_path: Path, lines: dict[str, list[str]]) -> Path:
    for node, content in lines.items():
        (tmp_path / f"{node}.trace.ndjson").write_text("\n".join(content) + "\n")
    return tmp_path


def test_failure_breakdown(tmp_path: Path) -> None:
    run = write_run(
        tmp_path,
        {
            "PN1": [
                line(1300, "PN1", "heartbeat", "DeclareFailed", m="PN1", n="PN3"),
                line(1301, "PN1", "switch", "Exclude", m="PN1", f="PN3"),
                line(1309, "PN1", "switch", "CompleteSwitch", m="PN1", c="C4"),
            ],
            "PN2": [line(1306, "PN2", "switch", "Activate", n="PN2", t="acca0", version=12)],
        },
    )
    lines, bad = analysis.read_traces(run)
    assert not bad
    events = [{"t_ns": 1000 * MS, "action": "kill", "argument": "PN3"}]
    [fault] = analysis.fault_metrics(lines, events)
    assert fault.detection_ms == 300
    assert fault.decision_ms == 1
    assert fault.switch_ms == 8
    assert fault.restore_ms == 5
    assert fault.total_ms == 309
    assert fault.decider_detection_ms == 300
    assert (fault.new_master, fault.config) == ("PN1", "C4")


def test_master_failure_detected_first_by_another_observer(tmp_path: Path) -> None:
    # PN3 declares the Master first; PN2, first in the succession, only a period later, then
    # takes over: the detection is PN3's, the decider's own detection PN2's.
    run = write_run(
        tmp_path,
        {
            "PN3": [line(1250, "PN3", "heartbeat", "DeclareFailed", m="PN3", n="PN1")],
            "PN2": [
                line(1350, "PN2", "heartbeat", "DeclareFailed", m="PN2", n="PN1"),
                line(1351, "PN2", "switch", "BecomeMaster", n="PN2", c="P2"),
                line(1356, "PN2", "switch", "CompleteSwitch", m="PN2", c="P2"),
            ],
        },
    )
    lines, _ = analysis.read_traces(run)
    [fault] = analysis.fault_metrics(lines, [{"t_ns": 1000 * MS, "action": "kill", "argument": "PN1"}])
    assert fault.detection_ms == 250
    assert fault.decider_detection_ms == 350
    assert fault.total_ms == 356
    assert fault.new_master == "PN2"


def test_phase_switch(tmp_path: Path) -> None:
    run = write_run(
        tmp_path,
        {"PN1": [line(2000.5, "PN1", "switch", "RequestPhase", m="PN1", c="S1"),
                 line(2003, "PN1", "switch", "CompleteSwitch", m="PN1", c="S1")]},
    )
    lines, _ = analysis.read_traces(run)
    [fault] = analysis.fault_metrics(lines, [{"t_ns": 2000 * MS, "action": "phase", "argument": "science"}])
    assert fault.detection_ms is None
    assert fault.switch_ms == 2.5
    assert fault.total_ms == 3


def test_truncated_line_is_reported_not_fatal(tmp_path: Path) -> None:
    (tmp_path / "PN1.trace.ndjson").write_text(line(1, "PN1", "switch", "Ack", n="PN1") + '\n{"t_ns": 5, "no')
    lines, bad = analysis.read_traces(tmp_path)
    assert len(lines) == 1 and len(bad) == 1 and bad[0].line == 2



def test_a_run_traced_before_one_name_per_meaning_reads_under_todays_names(tmp_path: Path) -> None:
    # The election's Suspect and the Master's Exclude were both logged as DeclareFailed;
    # a monitor's declaration still is.
    old = write_run(tmp_path, {"PN1": [
        line(1300, "PN1", "heartbeat", "DeclareFailed", m="PN1", n="PN3"),
        line(1301, "PN1", "election", "DeclareFailed", n="PN1", m="PN3"),
        line(1302, "PN1", "switch", "DeclareFailed", m="PN1", f="PN3")]})
    lines, bad = analysis.read_traces(old)
    assert not bad
    assert [(x.fsm, x.action) for x in lines] == [
        ("heartbeat", "DeclareFailed"), ("election", "Suspect"), ("switch", "Exclude")]
    # keel-cluster does not depend on keel-verify, so it keeps its own copy of the map;
    # the two must stay one.
    load = pytest.importorskip("keel_verify.trace.load")
    assert analysis.LEGACY_ACTIONS == load.LEGACY_ACTIONS

def test_reliability_catches_double_activation_split_master_lost_checkpoint(tmp_path: Path) -> None:
    run = write_run(
        tmp_path,
        {
            "PN1": [
                line(10, "PN1", "switch", "FlushCheckpoint", n="PN1", t="aocs", version=7),
                line(11, "PN1", "switch", "Activate", n="PN1", t="acca0", version=0),
                line(12, "PN1", "election", "BecomeMaster", n="PN1", e=2),
            ],
            "PN2": [
                line(13, "PN2", "switch", "Activate", n="PN2", t="acca0", version=0),
                line(14, "PN2", "election", "BecomeMaster", n="PN2", e=2),
                line(15, "PN2", "switch", "Activate", n="PN2", t="aocs", version=5),
            ],
        },
    )
    lines, _ = analysis.read_traces(run)
    final = {"PN1": {"tasks": ["acca0"], "expected_tasks": ["acca0", "aocs", "sink"]},
             "PN2": {"tasks": ["acca0", "aocs"]}}
    result = analysis.reliability(lines, [], final).as_dict()
    assert result["double_activations"] == 1
    assert result["split_masters"] == 1
    assert result["lost_checkpoints"] == 1
    assert result["lost_tasks"] == 2  # acca0 twice, sink nowhere


def test_reliability_clean_run_with_kill(tmp_path: Path) -> None:
    run = write_run(
        tmp_path,
        {
            "PN3": [line(10, "PN3", "switch", "Activate", n="PN3", t="acca0", version=0),
                    line(20, "PN3", "switch", "FlushCheckpoint", n="PN3", t="acca0", version=4)],
            "PN2": [line(60, "PN2", "switch", "Activate", n="PN2", t="acca0", version=4)],
        },
    )
    lines, _ = analysis.read_traces(run)
    events = [{"t_ns": 50 * MS, "action": "kill", "argument": "PN3"}]
    final = {"PN3": {}, "PN2": {"tasks": ["acca0"], "expected_tasks": ["acca0"]}}
    assert analysis.reliability(lines, events, final).as_dict()["details"] == []


def test_distribution() -> None:
    d = analysis.distribution([5.0, 1.0, 3.0])
    assert d["n"] == 3 and d["p50"] == 3.0 and d["min"] == 1.0 and d["max"] == 5.0
    assert analysis.distribution([])["n"] == 0


def test_reliability_follows_the_specs_exemptions(tmp_path: Path) -> None:
    """A partitioned node runs its task until it hears it was declared failed, a flush sent
    into a partition is not stored, and a task restarted while the storage node is down
    starts afresh: none of these is a violation."""

    def viewed(t_ms: float, node: str, action: str, failed: list[str], **args: object) -> str:
        raw = json.loads(line(t_ms, node, "switch", action, **args))
        raw["vars"] = {"failed": failed}
        return json.dumps(raw)

    run = write_run(
        tmp_path,
        {
            "PN3": [line(10, "PN3", "switch", "Activate", n="PN3", t="taskB", version=0),
                    line(20, "PN3", "switch", "FlushCheckpoint", n="PN3", t="taskB", version=4),
                    # Sent into the partition: never stored, so version 4 is the latest.
                    line(30, "PN3", "switch", "FlushCheckpoint", n="PN3", t="taskB", version=5)],
            "ST1": [line(15, "ST1", "switch", "StoreCheckpoint", t="taskB", version=0),
                    line(21, "ST1", "switch", "StoreCheckpoint", t="taskB", version=4)],
            # PN3 partitioned: PN1's view holds it failed when it takes over taskB.
            "PN1": [viewed(60, "PN1", "Activate", ["PN3"], n="PN1", t="taskB", version=4),
                    # ST1 killed at 70: a fresh start from version 0 is all there is.
                    viewed(90, "PN1", "Activate", ["PN3", "ST1"], n="PN1", t="taskA", version=0)],
            "PN2": [line(91, "PN2", "switch", "Activate", n="PN2", t="taskB", version=0)],
        },
    )
    lines, _ = analysis.read_traces(run)
    events = [{"t_ns": 70 * MS, "action": "kill", "argument": "ST1"}]
    result = analysis.reliability(lines, events, {}).as_dict()
    # PN2 does not hold PN1 failed: taskB on both is a double activation; its version 0 is
    # not a lost checkpoint because the storage node is down.
    assert result["double_activations"] == 1, result["details"]
    assert result["lost_checkpoints"] == 0, result["details"]
    events.append({"t_ns": 80 * MS, "action": "restart", "argument": "ST1"})
    result = analysis.reliability(lines, events, {}).as_dict()
    assert result["lost_checkpoints"] == 1, result["details"]  # ST1 back: version 0 < 4


def test_fig10_summary_states_detection_against_its_window() -> None:
    from keel_cluster.bench import TARGETS, Bench, verdicts

    # miss_limit 3, period 100 ms: [200, 400] out of phase, [300, 400] in phase. 250 is in
    # the first only; 410 in neither (10 ms of scheduling late); 20 ms added is on target.
    rows = [
        {"detection_ms": 250.0, "decider_detection_ms": 250.0, "total_ms": 255.0, "master_killed": False},
        {"detection_ms": 350.0, "decider_detection_ms": 350.0, "total_ms": 370.0, "master_killed": False},
        {"detection_ms": 410.0, "decider_detection_ms": 480.0, "total_ms": 490.0, "master_killed": True},
        {"error": "initial configuration not active"},
    ]
    summary = Bench._summarize_failures(100, 3, rows)
    assert summary["detection_window_ms"] == [200, 400]
    assert summary["detection_window_in_phase_ms"] == [300, 400]
    assert (summary["detection_in_window"], summary["detection_in_window_in_phase"]) == (2, 1)
    assert summary["detection_beyond_window_ms"] == 10.0 and summary["detection_below_window_ms"] == 0.0
    assert summary["added_ms_worker_failure"]["max"] == 20.0
    assert summary["added_ms_master_failure"]["max"] == 80.0
    assert summary["added_ms_master_failure_after_own_detection"]["max"] == 10.0
    assert summary["errors"] == ["initial configuration not active"]
    verdict = verdicts({"figures": {"10": {"periods": [summary]}}})["10"]["100"]
    assert verdict["added_p99_worker_ok"] and not verdict["added_p99_ok"]
    assert verdict["detection_in_window"] == "2/3"
    assert TARGETS["10"]["added_ms_p99"] == 20 and "adds <= 20 ms to detection" in TARGETS["10"]["statement"]


def test_fault_model_2_counters_each_read_non_zero_when_broken(tmp_path: Path) -> None:
    # An isolated Master (PN1) keeps commanding after PN2 took over: two Masters for 40 ms.
    # It excludes PN3, which no fault touched, and restarts aocs from version 0 while PN2
    # already ran it at version 30 (the spec exempts it: PN1's view excludes the storage
    # node; an operator does not). aocs runs on both for 20 ms.
    run = write_run(
        tmp_path,
        {
            "PN1": [
                line(0, "PN1", "switch", "BroadcastCommand", m="PN1", c="C1", epoch=1, seq=1),
                line(100, "PN1", "switch", "Exclude", m="PN1", f="PN3", c="SAFE"),
                line(110, "PN1", "switch", "Activate", n="PN1", t="aocs", version=0),
                line(130, "PN1", "switch", "Deactivate", n="PN1", t="aocs"),
                line(140, "PN1", "election", "ReceiveCommand", n="PN1", stepDown=True),
            ],
            "PN2": [
                line(50, "PN2", "switch", "Activate", n="PN2", t="aocs", version=30),
                line(100, "PN2", "election", "BecomeMaster", n="PN2", e=2),
            ],
        },
    )
    lines, _ = analysis.read_traces(run)
    events = [{"t_ns": 60 * MS, "action": "partition", "argument": "PN1"}]
    result = analysis.reliability(lines, events, {}).as_dict()
    assert result["two_masters_ms"] == 40.0
    assert result["double_run_ms"] == 20.0
    assert result["activations_below_known"] == 1
    assert result["false_exclusions"] == 1


def test_a_start_with_the_state_out_of_reach_is_counted_apart(tmp_path: Path) -> None:
    # PN3 (aocs at version 7) and the Storage node die together: PN1 says it starts aocs
    # afresh (StateOutOfReach). That is counted as unrecoverable, not as an avoidable
    # activation below a known version; a later restart from 0 without the word is.
    run = write_run(
        tmp_path,
        {
            "PN3": [line(10, "PN3", "switch", "Activate", n="PN3", t="aocs", version=7)],
            "PN1": [
                line(400, "PN1", "switch", "StateOutOfReach", n="PN1", t="aocs"),
                line(401, "PN1", "switch", "Activate", n="PN1", t="aocs", version=0),
                line(450, "PN1", "switch", "FlushCheckpoint", n="PN1", t="aocs", version=4),
                line(500, "PN1", "switch", "Activate", n="PN1", t="aocs", version=0),
            ],
        },
    )
    lines, _ = analysis.read_traces(run)
    events = [{"t_ns": 50 * MS, "action": "kill", "argument": "PN3"}]
    result = analysis.reliability(lines, events, {}).as_dict()
    assert result["unrecoverable_starts"] == 1
    assert result["activations_below_known"] == 1  # the second start, at 0 below 4


def test_versions_compare_lineage_first(tmp_path: Path) -> None:
    # PN3 ran aocs to 107 in the initial lineage (stored); the Storage node was excluded, PN3
    # crashed, and PN1 started aocs without them from PN2's older hand-off at 5 (reported:
    # StateOutOfReach), opening lineage 1.3. Its checkpoints (lineage 1.3, 6..9) are newer
    # than 107 of the initial lineage: a start at 9 of lineage 1.3 is not below what the
    # cluster had; a start from the abandoned 107 is.
    run = write_run(
        tmp_path,
        {
            "ST1": [line(10, "ST1", "switch", "StoreCheckpoint", t="aocs", version=107)],
            "PN1": [
                line(399, "PN1", "switch", "StateOutOfReach", n="PN1", t="aocs", version=5),
                line(400, "PN1", "switch", "Activate", n="PN1", t="aocs", version=5,
                     opened=[1, 3]),
                line(450, "PN1", "switch", "FlushCheckpoint", n="PN1", t="aocs", version=9,
                     lineage=[1, 3], final=True),
                line(451, "PN1", "switch", "Ack", n="PN1", kind="Prepared"),
                line(452, "PN1", "switch", "Deactivate", n="PN1", t="aocs"),
            ],
            "PN2": [
                line(500, "PN2", "switch", "Activate", n="PN2", t="aocs", version=9,
                     lineage=[1, 3]),
                line(550, "PN2", "switch", "Deactivate", n="PN2", t="aocs"),
                line(600, "PN2", "switch", "Activate", n="PN2", t="aocs", version=107),
            ],
        },
    )
    lines, _ = analysis.read_traces(run)
    result = analysis.reliability(lines, [], {}).as_dict()
    assert result["unrecoverable_starts"] == 1
    assert result["activations_below_known"] == 1  # only the restore of the abandoned 107
    assert "107, below version 9 (lineage 1.3)" in " ".join(
        analysis.reliability(lines, [], {}).activations_below_known)


def test_a_resumed_master_counts_only_once_it_acts(tmp_path: Path) -> None:
    # PN1 (Master, running aocs) is stopped; PN2 takes over and runs aocs. On resume,
    # PN1's first act decides: stepping down overlaps nothing; commanding as Master, or
    # its task running on, is an overlap until it stops.
    def run_with(first: list[dict[str, object]], where: Path) -> dict[str, object]:
        where.mkdir()
        run = write_run(where, {
            "PN1": [
                line(0, "PN1", "switch", "BroadcastCommand", m="PN1", c="C1", epoch=1, seq=1),
                line(10, "PN1", "switch", "Activate", n="PN1", t="aocs", version=0),
                *first,
            ],
            "PN2": [
                line(400, "PN2", "election", "BecomeMaster", n="PN2", e=2),
                line(410, "PN2", "switch", "Activate", n="PN2", t="aocs", version=0),
            ],
        })
        lines, _ = analysis.read_traces(run)
        events = [{"t_ns": 50 * MS, "action": "pause", "argument": "PN1"},
                  {"t_ns": 600 * MS, "action": "resume", "argument": "PN1"}]
        return analysis.reliability(lines, events, {}).as_dict()

    steps_down = run_with([line(602, "PN1", "switch", "Resign", n="PN1"),
                           line(603, "PN1", "switch", "Deactivate", n="PN1", t="aocs")],
                          tmp_path / "a")
    assert (steps_down["two_masters_ms"], steps_down["double_run_ms"]) == (0.0, 0.0)
    acts = run_with([line(602, "PN1", "switch", "BroadcastCommand", m="PN1", c="C1", epoch=1, seq=2),
                     line(610, "PN1", "switch", "Resign", n="PN1"),
                     line(612, "PN1", "switch", "Deactivate", n="PN1", t="aocs")],
                    tmp_path / "b")
    assert acts["two_masters_ms"] == 8.0 and acts["double_run_ms"] == 10.0


def test_a_periodic_write_lost_in_a_partition_is_not_a_version_the_cluster_had(tmp_path: Path) -> None:
    # PN3, partitioned, sends aocs' write of version 6 that never arrives (the Storage node
    # stored 5): the cluster moves aocs from version 5, which is all it had. A final flush
    # counts once its host acks Prepared (it waits for the flush's acknowledgement, or keeps
    # the state as a hand-off); one its host gave up on (it resigned unflushed, cut off)
    # never arrived either.
    def run_with(final: bool, after: list[Any], where: Path) -> dict[str, object]:
        where.mkdir()
        run = write_run(where, {
            "PN3": [line(0, "PN3", "switch", "FlushCheckpoint", n="PN3", t="aocs", version=5),
                    line(20, "PN3", "switch", "FlushCheckpoint", n="PN3", t="aocs", version=6,
                         final=final), *after],
            "ST1": [line(1, "ST1", "switch", "StoreCheckpoint", **{"from": "PN3"}, t="aocs", version=5)],
            "PN1": [line(400, "PN1", "switch", "Activate", n="PN1", t="aocs", version=5)],
        })
        lines, _ = analysis.read_traces(run)
        events = [{"t_ns": 10 * MS, "action": "partition", "argument": "PN3"}]
        return analysis.reliability(lines, events, {}).as_dict()

    acked = [line(30, "PN3", "switch", "Ack", n="PN3", kind="Prepared")]
    abandoned = [line(300, "PN3", "switch", "Resigned", n="PN3", flushed=False)]
    assert run_with(False, [], tmp_path / "periodic")["activations_below_known"] == 0
    assert run_with(True, acked, tmp_path / "acked")["activations_below_known"] == 1
    assert run_with(True, abandoned, tmp_path / "abandoned")["activations_below_known"] == 0


def test_fault_model_2_counters_read_zero_on_a_clean_failover(tmp_path: Path) -> None:
    # PN1 is killed; PN2 takes over and resumes aocs from the version PN1 flushed.
    run = write_run(
        tmp_path,
        {
            "PN1": [
                line(0, "PN1", "switch", "BroadcastCommand", m="PN1", c="C1", epoch=1, seq=1),
                line(10, "PN1", "switch", "Activate", n="PN1", t="aocs", version=0),
                line(40, "PN1", "switch", "FlushCheckpoint", n="PN1", t="aocs", version=3),
            ],
            "PN2": [
                line(400, "PN2", "election", "BecomeMaster", n="PN2", e=2),
                line(401, "PN2", "switch", "Exclude", m="PN2", f="PN1", c="C2"),
                line(410, "PN2", "switch", "Activate", n="PN2", t="aocs", version=3),
            ],
        },
    )
    lines, _ = analysis.read_traces(run)
    events = [{"t_ns": 50 * MS, "action": "kill", "argument": "PN1"}]
    result = analysis.reliability(lines, events, {}).as_dict()
    assert (result["two_masters_ms"], result["double_run_ms"]) == (0.0, 0.0)
    assert result["activations_below_known"] == 0 and result["false_exclusions"] == 0


def test_a_held_task_does_not_run_until_it_is_released(tmp_path: Path) -> None:
    # The lease (spec/Lease.tla): PN2, cut off, holds taskA (its Hold line stops it)
    # before the Master moves it to PN1; readmitted later, it runs taskA again only from
    # its Release. No overlap; without the Hold line, 50 ms of taskA on both.
    def traces(with_hold: bool) -> dict[str, list[str]]:
        pn2 = [line(0, "PN2", "switch", "Activate", n="PN2", t="taskA", version=0)]
        if with_hold:
            pn2.append(line(40, "PN2", "switch", "Hold", n="PN2"))
        pn2 += [line(100, "PN2", "switch", "Deactivate", n="PN2", t="taskA"),
                line(300, "PN2", "switch", "Activate", n="PN2", t="taskA", version=0),
                line(310, "PN2", "switch", "Release", n="PN2")]
        return {
            "PN1": [line(50, "PN1", "switch", "Activate", n="PN1", t="taskA", version=0),
                    line(290, "PN1", "switch", "Deactivate", n="PN1", t="taskA")],
            "PN2": pn2,
        }

    for with_hold, overlap in ((True, 0.0), (False, 50.0)):
        folder = tmp_path / str(with_hold)
        folder.mkdir()
        lines, _ = analysis.read_traces(write_run(folder, traces(with_hold)))
        result = analysis.reliability(lines, [], {}).as_dict()
        assert result["double_run_ms"] == overlap


def test_task_moves_name_where_from_where_to_and_the_state(tmp_path: Path, capsys: Any) -> None:
    # Boot: acca0 on PN3, sink on ST1 (first activations are no moves). PN3 is killed:
    # acca0 starts on PN2 from checkpoint 12 of lineage 4.1; later back on PN3 from its
    # initial state (a task without checkpoints); sink starts again on ST1 (no move).
    run = write_run(
        tmp_path,
        {
            "PN3": [line(100, "PN3", "switch", "Activate", n="PN3", t="acca0", version=0, restored=False),
                    line(2500, "PN3", "switch", "Activate", n="PN3", t="acca0", version=0,
                         restored=False)],
            "PN2": [line(1306, "PN2", "switch", "Activate", n="PN2", t="acca0", version=12,
                         lineage=[4, 1], restored=True)],
            "ST1": [line(101, "ST1", "switch", "Activate", n="ST1", t="sink", version=0, restored=False),
                    line(1400, "ST1", "switch", "Activate", n="ST1", t="sink", version=3, restored=True)],
        },
    )
    lines, _ = analysis.read_traces(run)
    moves = analysis.task_moves(lines)
    assert [m.describe() for m in moves] == [
        "acca0 PN3 -> PN2 from checkpoint version 12 (lineage 4.1)",
        "acca0 PN2 -> PN3 from its initial state (no checkpoint)",
    ]
    assert moves[0].as_dict() == {"t_ns": 1306 * MS, "task": "acca0", "from": "PN3", "to": "PN2",
                                  "version": 12, "lineage": [4, 1], "restored": True}
    # keel-cluster run's summary prints them under the timeline.
    from keel_cluster.cli import print_report

    print_report({"run_dir": str(run), "trace_lines": len(lines),
                  "events": [{"t_ns": 0, "action": "start", "argument": ""}], "faults": [],
                  "moves": [m.as_dict() for m in moves],
                  "reliability": analysis.reliability(lines, [], {}).as_dict(), "crashed_nodes": []})
    out = capsys.readouterr().out
    assert "tasks moved:\n     1.306s  acca0 PN3 -> PN2 from checkpoint version 12 (lineage 4.1)" in out


def test_a_task_activated_while_its_node_holds_moves_only_at_its_release(tmp_path: Path) -> None:
    # PN2 holds (its lease lapsed) when it activates acca0: the move counts at its Release.
    # PN4 activates it while holding and is excluded before releasing: no move to PN4.
    run = write_run(
        tmp_path,
        {
            "PN3": [line(100, "PN3", "switch", "Activate", n="PN3", t="acca0", version=0, restored=False)],
            "PN2": [line(1000, "PN2", "switch", "Hold", n="PN2"),
                    line(1100, "PN2", "switch", "Activate", n="PN2", t="acca0", version=5, restored=True),
                    line(1300, "PN2", "switch", "Release", n="PN2")],
            "PN4": [line(2000, "PN4", "switch", "Hold", n="PN4"),
                    line(2100, "PN4", "switch", "Activate", n="PN4", t="acca0", version=9, restored=True),
                    line(2200, "PN4", "switch", "ReceiveCommand", n="PN4", c="C3", epoch=5, seq=1,
                         out=["PN4"])],
        },
    )
    lines, _ = analysis.read_traces(run)
    moves = analysis.task_moves(lines)
    assert [(m.t_ns, m.source, m.target) for m in moves] == [(1300 * MS, "PN3", "PN2")]


@pytest.mark.parametrize("held", [True, False])
def test_an_exclusion_on_the_grounds_hold_is_no_false_exclusion(tmp_path: Path, held: bool) -> None:
    # The ground's `exclude PN3`: PN1 holds PN3 out (its GroundExclude line), then excludes
    # it by its own switch (Exclude with `ground`): the ground's doing, not a false
    # exclusion. The same Exclude without PN1's hold is one.
    pn1 = [line(0, "PN1", "switch", "BroadcastCommand", m="PN1", c="C1", epoch=1, seq=1)]
    if held:
        pn1.append(line(50, "PN1", "switch", "GroundExclude", f="PN3"))
    pn1.append(line(60, "PN1", "switch", "Exclude", m="PN1", f="PN3", c="C2", own=False,
                    ground=True))
    run = write_run(tmp_path, {"PN1": pn1})
    lines, _ = analysis.read_traces(run)
    events = [{"t_ns": 50 * MS, "action": "exclude", "argument": "PN3"}]
    result = analysis.reliability(lines, events, {}).as_dict()
    assert result["false_exclusions"] == (0 if held else 1)


def test_a_switchs_time_is_broken_down_by_milestone() -> None:
    # Fig. 9's stages (analysis.switch_stages): from the Master's RequestPhase to the first
    # line of each milestone after it, up to its CompleteSwitch; a switch that never
    # completes counts for nothing.
    def line(t_ms: float, node: str, action: str, **args: object) -> analysis.TraceLine:
        return analysis.TraceLine(int(t_ms * 1_000_000), node, "switch", action, dict(args), {})

    lines = [
        line(0, "PN1", "RequestPhase"), line(0.1, "PN1", "BroadcastCommand"),
        line(0.2, "PN1", "ReceiveCommand"), line(1.0, "PN2", "ReceiveCommand"),
        line(1.5, "PN3", "ReceiveCommand"), line(2.0, "PN2", "Ack", kind="Prepared"),
        line(2.5, "PN3", "Ack", kind="Prepared"), line(3.0, "PN1", "BroadcastActivate"),
        line(3.5, "PN2", "ReceiveActivate"), line(4.0, "PN3", "ReceiveActivate"),
        line(4.2, "PN2", "Activate", t="taskA"), line(4.5, "PN3", "Ack", kind="Activated"),
        line(5.0, "PN1", "CompleteSwitch"),
        line(10, "PN1", "RequestPhase"), line(10.5, "PN1", "BroadcastCommand"),  # never completes
    ]
    stages = analysis.switch_stages(lines)
    assert [stages[name]["p50"] for name, _ in analysis.SWITCH_MILESTONES] == [0.1, 1.0, 1.5, 2.5, 3.0, 4.0, 4.2, 5.0]
    assert all(stages[name]["n"] == 1 for name, _ in analysis.SWITCH_MILESTONES)


def test_the_hops_of_a_planned_switch_are_timed_from_both_ends() -> None:
    # analysis.switch_hops: the Command's hop from the Master's BroadcastCommand to each
    # member's ReceiveCommand of that switch, the Activate's likewise, a member's first final
    # checkpoint (a resend does not restart it) to its Prepared; only planned switches (a
    # RequestPhase to its CompleteSwitch) count.
    def line(t_ms: float, node: str, action: str, **args: object) -> analysis.TraceLine:
        return analysis.TraceLine(int(t_ms * 1_000_000), node, "switch", action, dict(args), {})

    lines = [
        line(0, "PN1", "BroadcastCommand", epoch=1, seq=1),  # the boot switch: not planned
        line(5, "PN2", "ReceiveCommand", epoch=1, seq=1, **{"from": "PN1"}),
        line(10, "PN1", "RequestPhase"), line(10.1, "PN1", "BroadcastCommand", epoch=1, seq=2),
        line(10.2, "PN1", "ReceiveCommand", epoch=1, seq=2, **{"from": "PN1"}),  # its own
        line(11.1, "PN2", "ReceiveCommand", epoch=1, seq=2, **{"from": "PN1"}),
        line(11.6, "PN3", "ReceiveCommand", epoch=1, seq=2, **{"from": "PN1"}),
        line(11.7, "PN3", "FlushCheckpoint", t="taskB", version=7, final=True),
        line(12.2, "PN3", "FlushCheckpoint", t="taskB", version=7, final=True),  # resent
        line(12.7, "ST1", "StoreCheckpoint", t="taskB", version=7, **{"from": "PN3"}),
        line(12.9, "PN3", "Ack", kind="Prepared"),
        line(13.0, "PN1", "BroadcastActivate"), line(13.3, "PN2", "ReceiveActivate"),
        line(13.5, "PN3", "ReceiveActivate"), line(14.0, "PN1", "CompleteSwitch"),
    ]
    hops = analysis.switch_hops(lines)
    assert hops["command"]["n"] == 2 and hops["command"]["max"] == pytest.approx(1.5)
    assert hops["command"]["min"] == pytest.approx(1.0)
    assert hops["activate"]["n"] == 2 and hops["activate"]["max"] == pytest.approx(0.5)
    assert hops["flush"]["n"] == 1 and hops["flush"]["p50"] == pytest.approx(1.2)
