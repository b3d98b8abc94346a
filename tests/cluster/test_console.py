"""The console without a browser: tailing a run directory, the fold of trace lines into
events and state, the measures, the HTTP API and the command line (keel_cluster/console.py).
Traces come from keel-sim (no cluster) or are written here line by line."""

from __future__ import annotations

import html.parser
import http.client
import json
import os
import random
import re
import shutil
import socket
import subprocess
import sys
import time
import threading
import zipfile
from pathlib import Path
from typing import Any

import pytest
from keel_cluster import analysis, console
from keel_cluster.launcher import EVENTS_FILE, Cluster

sys.path.insert(0, str(Path(__file__).resolve().parent))
import console_runs  # noqa: E402
from console_runs import ROOT, Writer  # noqa: E402

MS = 1_000_000


def line(t_ms: float, node: str | None, fsm: str, action: str, variables: dict[str, Any] | None = None,
         **args: object) -> dict[str, Any]:
    return {"t_ns": int(t_ms * MS), "node": node, "fsm": fsm, "action": action, "args": args,
            "vars": variables or {}}


def poll(feed: console.Feed) -> None:
    """Passes until the feed has read everything there is, and one that finds nothing new."""
    while feed.poll_once():
        pass
    feed.poll_once()


def page_state(feed: console.Feed) -> dict[str, Any]:
    """The state a page builds from the feed's events: their patches applied in time order
    (by index at equal times), as console.js's foldTo does."""
    state: dict[str, Any] = {"nodes": {}, "path": {}, "measures": {}, "faults": {}}
    for event in sorted(feed.fold.events, key=lambda e: (e["t"], e["i"])):
        console.merge_patch(state, json.loads(json.dumps(event.get("p") or {})))
    return state


@pytest.fixture(scope="module")
def sim_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[dict[str, Any]], str]:
    """prototype3, seed 2: PN3 crashes and restarts, then the Master PN1 crashes."""
    folder = tmp_path_factory.mktemp("sim")
    lines, report = console_runs.simulate("config/prototype3.yaml", 2, folder)
    run_dir = console_runs.run_dir_of(lines, folder / "run")
    console_runs.compile_image("config/prototype3.yaml", run_dir)
    return run_dir, lines, report


@pytest.fixture(scope="module")
def folded(sim_run: tuple[Path, list[dict[str, Any]], str]) -> console.Feed:
    feed = console.Feed(sim_run[0])
    poll(feed)
    return feed


# --- Tailing -------------------------------------------------------------------------------


def test_only_whole_lines_are_read_and_a_line_is_read_once_its_newline_is_there(tmp_path: Path) -> None:
    tail = console.Tail(tmp_path, console.TRACE_GLOB)
    assert tail.poll() == ([], False)  # no file yet
    path = tmp_path / "PN1.trace.ndjson"
    path.write_text('{"a":1}\n{"b":')
    assert tail.poll()[0] == [("PN1.trace.ndjson", b'{"a":1}')]
    assert tail.poll()[0] == []  # the half line waits
    with open(path, "a") as handle:
        handle.write('2}\n')
    assert tail.poll()[0] == [("PN1.trace.ndjson", b'{"b":2}')]
    (tmp_path / "PN2.trace.ndjson").write_text('{"c":3}\n')  # a file that appears late
    assert tail.poll()[0] == [("PN2.trace.ndjson", b'{"c":3}')]


def test_a_file_that_shrinks_is_read_again_from_its_start(tmp_path: Path) -> None:
    tail = console.Tail(tmp_path, console.TRACE_GLOB)
    path = tmp_path / "PN1.trace.ndjson"
    path.write_text('{"a":1}\n{"b":2}\n')
    assert len(tail.poll()[0]) == 2
    path.write_text('{"c":3}\n')
    assert tail.poll()[0] == [("PN1.trace.ndjson", b'{"c":3}')]


def test_a_line_past_the_limit_is_skipped_and_counted(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(console, "LINE_BYTES_MAX", 64)
    tail = console.Tail(tmp_path, console.TRACE_GLOB)
    path = tmp_path / "PN1.trace.ndjson"
    path.write_text("x" * 200)  # a line being written, already too long
    lines = []
    for _ in range(5):
        lines += tail.poll()[0]
    with open(path, "a") as handle:
        handle.write('x\n{"after":1}\n' + "y" * 100 + '\n{"last":2}\n')
    for _ in range(5):
        lines += tail.poll()[0]
    assert lines == [("PN1.trace.ndjson", b'{"after":1}'), ("PN1.trace.ndjson", b'{"last":2}')]
    assert tail.oversized == 2


def test_a_line_a_killed_node_left_unfinished_is_counted_and_the_rest_read(tmp_path: Path) -> None:
    # keel-node appends: a restarted node's first line follows its predecessor's half line,
    # on the same line. The half line is counted; the line after it is read.
    writer = Writer(tmp_path)
    writer.write_raw("PN1.trace.ndjson", console_runs.encode(line(10, "PN1", "switch", "Hold", n="PN1"))[:30])
    writer.write([line(20, "PN1", "switch", "Hold", n="PN1"), line(30, "PN1", "switch", "Release", n="PN1")])
    feed = console.Feed(tmp_path)
    poll(feed)
    assert feed.status()["malformed"] == 1
    assert [(e["t"] // MS, e["a"]) for e in feed.fold.events if e.get("d")] == [(20, "Hold"), (30, "Release")]
    # Its heartbeat too: the half line does not pass for a heartbeat.
    writer.write_raw("PN2.trace.ndjson", console_runs.encode(line(40, "PN2", "switch", "Hold", n="PN2"))[:25]
                     + console_runs.encode(line(50, "PN2", "heartbeat", "SendHeartbeat", n="PN2")))
    poll(feed)
    assert feed.status()["malformed"] == 2
    assert [e["t"] // MS for e in feed.fold.events if e["n"] == "PN2"] == [50]


def test_a_line_left_unfinished_at_the_end_of_a_finished_run_is_counted(tmp_path: Path) -> None:
    writer = Writer(tmp_path)
    writer.write([line(20, "PN1", "switch", "Hold", n="PN1")])
    writer.write_raw("PN1.trace.ndjson", console_runs.encode(line(30, "PN1", "switch", "Release", n="PN1"))[:30])
    feed = console.Feed(tmp_path)
    poll(feed)
    assert feed.status()["malformed"] == 0  # a live run: the line is being written
    (tmp_path / "report.json").write_text(json.dumps({"events": []}))
    poll(feed)
    assert feed.status()["finished"] is True and feed.status()["malformed"] == 1


def test_a_pass_folds_the_files_lines_in_time_order_each_file_in_its_own(tmp_path: Path) -> None:
    Writer(tmp_path).write([
        line(10, "PN1", "switch", "Hold", n="PN1"), line(30, "PN1", "switch", "Release", n="PN1"),
        line(20, "PN2", "switch", "Hold", n="PN2"),
        line(40, "PN2", "switch", "Release", n="PN2"), line(35, "PN2", "switch", "Hold", n="PN2"),
    ])
    Writer(tmp_path).write_raw(EVENTS_FILE, json.dumps({"t_ns": 25 * MS, "action": "kill", "argument": "PN3"}) + "\n")
    feed = console.Feed(tmp_path)
    poll(feed)
    said = [(e["t"] // MS, e["d"]) for e in feed.fold.events if e.get("d")]
    # PN2's clock went back: its last line stays after the one it wrote before, at its time.
    assert said == [(10, "PN1 holds its tasks (no lease)"), (20, "PN2 holds its tasks (no lease)"),
                    (25, "kill PN3"), (30, "PN1 releases its tasks"), (40, "PN2 releases its tasks"),
                    (40, "PN2 holds its tasks (no lease)")]
    assert feed.fold.state["nodes"]["PN2"]["held"] is True
    assert page_state(feed) == feed.fold.state  # the page orders by time: the same state


def test_a_file_replaced_by_a_longer_one_is_read_from_its_start(tmp_path: Path) -> None:
    # A run directory used again: the file is another (inode) even when it is already longer.
    tail = console.Tail(tmp_path, console.TRACE_GLOB)
    path = tmp_path / "PN1.trace.ndjson"
    path.write_text('{"a":1}\n')
    assert len(tail.poll()[0]) == 1
    replacement = tmp_path / "new"
    replacement.write_text('{"b":2}\n{"c":3}\n{"d":4}\n')
    replacement.replace(path)
    assert [raw for _, raw in tail.poll()[0]] == [b'{"b":2}', b'{"c":3}', b'{"d":4}']


def test_a_pass_reads_about_its_byte_budget(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(console, "PASS_BYTES_MAX", 400)
    monkeypatch.setattr(console, "LINE_BYTES_MAX", 100)
    for name in ("PN1", "PN2"):
        (tmp_path / f"{name}.trace.ndjson").write_text("".join(f'{{"{name}":{k:04}}}\n' for k in range(100)))
    tail = console.Tail(tmp_path, console.TRACE_GLOB)
    found, more = tail.poll()
    assert more and 0 < sum(len(raw) + 1 for _, raw in found) <= 400 + 101
    while more:
        lines, more = tail.poll()
        found += lines
    assert len(found) == 200


def test_the_report_of_an_earlier_run_in_the_directory_does_not_finish_this_one(tmp_path: Path) -> None:
    report = tmp_path / "report.json"
    report.write_text(json.dumps({"events": [{"t_ns": 1000 * MS, "action": "kill", "argument": "PN3"}]}))
    earlier = time.time_ns() - 3_600 * 10**9
    os.utime(report, ns=(earlier, earlier))
    # run --console: the console started after it.
    feed = console.Feed(tmp_path, not_before_ns=earlier + 10**9)
    Writer(tmp_path).write([line(1300, "PN1", "heartbeat", "DeclareFailed", m="PN1", n="PN3")])
    poll(feed)
    assert feed.status()["finished"] is False and feed.fold.faults == []  # nor are its events this run's
    # console RUN_DIR: the launcher's log says when this run started.
    started = json.dumps({"t_ns": earlier + 60 * 10**9, "action": "start", "argument": "PN1"}) + "\n"
    Writer(tmp_path).write_raw(EVENTS_FILE, started)
    attached = console.Feed(tmp_path)
    poll(attached)
    assert attached.status()["finished"] is False
    report.write_text(json.dumps({"events": []}))  # this run's report
    poll(attached)
    assert attached.status()["finished"] is True


# --- The fold ------------------------------------------------------------------------------


def fold(lines: list[dict[str, Any]]) -> console.Fold:
    result = console.Fold()
    for x in lines:
        result.raw_line(console_runs.encode(x).strip().encode())
    return result


def test_heartbeats_sent_and_received_never_reach_the_page() -> None:
    monitor = {"missed": {"PN2": 0}, "failed": [], "heard": ["PN2"]}
    events = fold([
        line(0, "PN1", "heartbeat", "SendHeartbeat", monitor, n="PN1"),
        *[line(t, "PN1", "heartbeat", "ReceiveHeartbeat", monitor, m="PN1", n="PN2") for t in range(1, 200)],
    ]).events
    # One liveness mark, when the node is first seen, and then one per SEEN_EVERY_NS.
    assert [e["k"] for e in events] == ["seen"]
    # Read in full when their text is not keel-node's (another order of keys): the same.
    reordered = console.Fold()
    for t in range(1, 200):
        received = line(t, "PN1", "heartbeat", "ReceiveHeartbeat", dict(monitor, missed={"PN2": t % 2}),
                        m="PN1", n="PN2")
        reordered.raw_line(json.dumps(dict(reversed(received.items()))).encode())
    assert [e["k"] for e in reordered.events] == ["seen"]


def test_a_tick_is_an_event_only_when_the_missed_counts_change() -> None:
    def tick(t: float, missed: int) -> dict[str, Any]:
        return line(t, "PN1", "heartbeat", "Tick", {"missed": {"PN2": missed}, "failed": []},
                    m="PN1", late=False, silent=False)

    result = fold([tick(100, 0), tick(200, 0), tick(300, 1), tick(400, 2), tick(450, 2), tick(500, 0)])
    links = [e for e in result.events if e["k"] == "link"]
    assert [e["p"]["nodes"]["PN1"].get("missed") for e in links] == [
        {"PN2": 0}, {"PN2": 1}, {"PN2": 2}, {"PN2": 0}]
    assert result.state["nodes"]["PN1"]["missed"] == {"PN2": 0}


def test_the_timeline_says_what_happened() -> None:
    result = fold([
        line(1000, "PN1", "heartbeat", "DeclareFailed", {"missed": {"PN4": 3}, "failed": ["PN4"]},
             m="PN1", n="PN4", reason="missed"),
        line(1001, "PN1", "switch", "Exclude", {"masterConfig": "C5", "epoch": 1, "failed": ["PN4"]},
             m="PN1", f="PN4", c="C5", own=False, ground=False),
        line(1002, "PN2", "switch", "Activate", {"role": "Observer", "config": "C5", "active": ["acca1"]},
             n="PN2", t="acca1", version=12, restored=True, lineage=[1, 2]),
        line(1010, "PN1", "switch", "CompleteSwitch", {"role": "Master", "epoch": 1, "config": "C5",
                                                      "masterConfig": "C5"}, m="PN1", c="C5", seq=2),
        line(1020, "PN1", "switch", "RefuseGroundCommand", {}, m="PN1", c="C9",
             why="the cluster is not in safe mode"),
    ])
    said = [e["d"] for e in result.events if e.get("d")]
    assert said == [
        "PN1 declares PN4 failed (missed)",
        "PN1 excludes PN4 -> C5",
        "acca1 starts on PN2 from checkpoint 12 (lineage 1.2)",
        "switch to C5 complete (PN1)",
        "PN1 refuses the ground's recover C9: the cluster is not in safe mode",
    ]
    assert result.events[-1]["k"] == "ground"
    assert result.state["path"] == {"0": {"t": 1010 * MS, "c": "C5", "m": "PN1", "epoch": 1}}
    assert result.state["nodes"]["PN1"]["declared"] == ["PN4"]
    assert result.state["nodes"]["PN2"]["active"] == ["acca1"]


def test_the_state_is_what_the_patches_add_up_to(folded: console.Feed) -> None:
    rebuilt: dict[str, Any] = {"nodes": {}, "path": {}, "measures": {}, "faults": {}}
    for event in folded.fold.events:
        console.merge_patch(rebuilt, event.get("p") or {})
    assert rebuilt == folded.fold.state
    assert json.loads(json.dumps(rebuilt)) == rebuilt  # what the page receives


def test_events_applied_in_time_order_give_the_state_arrival_order_gives(folded: console.Feed) -> None:
    # The page replays by time; the feed folds as lines arrive, file by file.
    by_time: dict[str, Any] = {"nodes": {}, "path": {}, "measures": {}, "faults": {}}
    for event in sorted(folded.fold.events, key=lambda e: (e["t"], e["i"])):
        console.merge_patch(by_time, event.get("p") or {})
    assert by_time == folded.fold.state


def test_a_patch_touches_only_its_own_node(folded: console.Feed) -> None:
    for event in folded.fold.events:
        touched = set((event.get("p") or {}).get("nodes", {}))
        if event["f"] in ("heartbeat", "election", "switch", "health"):
            assert touched <= {event["n"]}, event


def test_the_fold_follows_the_simulated_run(sim_run: tuple[Path, list[dict[str, Any]], str],
                                            folded: console.Feed) -> None:
    _, lines, _ = sim_run
    path = [step["c"] for _, step in sorted(folded.fold.state["path"].items(), key=lambda kv: int(kv[0]))]
    completed = []
    for x in lines:
        if x["action"] == "CompleteSwitch" and (not completed or completed[-1] != x["args"]["c"]):
            completed.append(x["args"]["c"])
    assert path == completed == ["P1", "P4", "P1", "P2"]
    nodes = folded.fold.state["nodes"]
    assert nodes["PN2"]["role"] == "Master" and nodes["PN2"]["masterConfig"] == "P2"
    assert nodes["PN1"]["down"] is True  # its env Crash, never restarted
    assert "ReceiveHeartbeat" not in {e["a"] for e in folded.fold.events}
    assert len(folded.fold.events) < len(lines) / 3


def test_the_measures_are_the_simulators_own(sim_run: tuple[Path, list[dict[str, Any]], str],
                                           folded: console.Feed) -> None:
    # keel-sim -v: "crash PN3 at 1.532s: detected 330 ms later, reconfigured 387 ms later".
    _, _, report = sim_run
    said = [x.split() for x in report.splitlines() if x.strip().startswith("crash ")]
    measures = [m for _, m in sorted(folded.fold.state["measures"].items(), key=lambda kv: int(kv[0]))]
    kills = [m for m in measures if m["kind"] == "kill"]
    assert [m["target"] for m in kills] == [words[1] for words in said] == ["PN3", "PN1"]
    for m, words in zip(kills, said, strict=True):
        assert abs(m["detection_ms"] - float(words[5])) <= 1, (m, words)
        assert abs(m["total_ms"] - float(words[9])) <= 1, (m, words)
        assert m["decision_ms"] is not None and m["switch_ms"] is not None
    assert [m["config"] for m in kills] == ["P4", "P2"]


def test_the_measures_match_the_reports_read_from_the_whole_run(
        sim_run: tuple[Path, list[dict[str, Any]], str], folded: console.Feed) -> None:
    # The console times each fault over the lines seen so far; at the end that is what the
    # run's report (analysis.fault_metrics over every line) says.
    run_dir, _, _ = sim_run
    lines, _ = analysis.read_traces(run_dir)
    whole = [m.as_dict() for m in analysis.fault_metrics(lines, folded.fold.faults)
             if m.kind in console.TIMED]
    measures = [m for _, m in sorted(folded.fold.state["measures"].items(), key=lambda kv: int(kv[0]))]
    assert measures == [{k: v for k, v in m.items() if v is not None} for m in whole]


def faulty_run(run_dir: Path) -> list[dict[str, Any]]:
    """A run of five faults (kills, a partition, a phase command), each excluded or entered
    and switched; the launcher's events, as it logs them."""
    events = [{"t_ns": 1000 * MS, "action": "kill", "argument": "PN3"},
              {"t_ns": 2000 * MS, "action": "restart", "argument": "PN3"},
              {"t_ns": 3000 * MS, "action": "kill", "argument": "PN2"},
              {"t_ns": 5000 * MS, "action": "partition", "argument": "ST1"},
              {"t_ns": 7000 * MS, "action": "phase", "argument": "science"},
              {"t_ns": 9000 * MS, "action": "kill", "argument": "PN1"}]
    Writer(run_dir).write_raw(EVENTS_FILE, "".join(json.dumps(e) + "\n" for e in events))
    lines = []
    for k, (t0, victim, master, config) in enumerate([(1000, "PN3", "PN1", "P4"), (3000, "PN2", "PN1", "P3"),
                                                      (5000, "ST1", "PN1", "P5")]):
        lines += [line(t0 + 300 + k, "PN1", "heartbeat", "DeclareFailed", m="PN1", n=victim),
                  line(t0 + 280 + k, "PN2" if victim != "PN2" else "PN3", "heartbeat", "DeclareFailed",
                       m="PN2", n=victim),
                  line(t0 + 301 + k, master, "switch", "Exclude", m=master, f=victim, c=config),
                  line(t0 + 306 + k, "PN2", "switch", "Activate", n="PN2", t="taskB", version=3, restored=True),
                  line(t0 + 309 + 2 * k, master, "switch", "CompleteSwitch", m=master, c=config)]
    lines += [line(7010, "PN1", "switch", "RequestPhase", m="PN1", phase="science", c="S3"),
              line(7030, "PN1", "switch", "CompleteSwitch", m="PN1", c="S3"),
              line(9350, "PN2", "heartbeat", "DeclareFailed", m="PN2", n="PN1"),
              line(9400, "PN2", "switch", "BecomeMaster", n="PN2", c="S2"),
              line(9420, "PN2", "switch", "CompleteSwitch", m="PN2", c="S2")]
    Writer(run_dir).write(lines)
    return events


def whole_run_measures(run_dir: Path, events: list[dict[str, Any]]) -> list[dict[str, Any]]:
    lines, _ = analysis.read_traces(run_dir)
    return [{k: v for k, v in m.as_dict().items() if v is not None} for m in analysis.fault_metrics(lines, events)]


def test_a_finished_run_has_every_fault_timed_as_its_report_times_them(tmp_path: Path) -> None:
    # A finished run's log and traces arrive whole in the first pass.
    events = faulty_run(tmp_path)
    feed = console.Feed(tmp_path)
    poll(feed)
    measures = [m for _, m in sorted(feed.fold.state["measures"].items(), key=lambda kv: int(kv[0]))]
    expected = whole_run_measures(tmp_path, events)
    assert len(expected) == 5 and [m["kind"] for m in expected] == ["kill", "kill", "partition", "phase", "kill"]
    assert measures == expected
    assert page_state(feed) == feed.fold.state


def test_a_console_attached_to_a_run_with_faults_behind_it_times_them_all(tmp_path: Path) -> None:
    run = tmp_path / "whole"
    events = faulty_run(run)
    live = tmp_path / "live"
    live.mkdir()
    text = {p.name: p.read_text().splitlines(keepends=True) for p in run.iterdir()}
    feed = console.Feed(live)
    # The first three faults and their lines, then the rest, as a console started late sees them.
    for since_ms, upto_ms in ((0, 6000), (6000, 10_000)):
        for name, rows in text.items():
            mine = [r for r in rows if since_ms <= json.loads(r)["t_ns"] // MS < upto_ms]
            Writer(live).write_raw(name, "".join(mine))
        poll(feed)
    measures = [m for _, m in sorted(feed.fold.state["measures"].items(), key=lambda kv: int(kv[0]))]
    assert measures == whole_run_measures(run, events)


def test_a_revised_measure_never_goes_back_in_time(tmp_path: Path) -> None:
    writer = Writer(tmp_path)
    writer.write_raw(EVENTS_FILE, json.dumps({"t_ns": 1000 * MS, "action": "kill", "argument": "PN3"}) + "\n")
    writer.write([line(1300, "PN1", "heartbeat", "DeclareFailed", m="PN1", n="PN3"),
                  line(1301, "PN1", "switch", "Exclude", m="PN1", f="PN3", c="P4"),
                  line(1500, "PN2", "switch", "Activate", n="PN2", t="taskB", version=3, restored=True)])
    feed = console.Feed(tmp_path)
    poll(feed)
    # Another node's declaration, earlier, arrives late: detection 100 ms, decision 201 ms.
    writer.write([line(1100, "ST1", "heartbeat", "DeclareFailed", m="ST1", n="PN3")])
    poll(feed)
    times = [e["t"] for e in feed.fold.events if e["k"] == "measure"]
    assert len(times) == 2 and times == sorted(times)
    assert feed.fold.state["measures"]["0"]["detection_ms"] == 100
    assert page_state(feed) == feed.fold.state


def test_the_late_flag_follows_every_tick() -> None:
    # core/fsm/heartbeat_monitor.cpp: a self-suspecting Tick has suspect, late and silent; a
    # counting one late and silent.
    result = fold([
        line(100, "PN1", "heartbeat", "Tick", {"missed": {"PN2": 0}}, m="PN1", suspect=True, late=True,
             silent=False),
        line(200, "PN1", "heartbeat", "Tick", {"missed": {"PN2": 0}}, m="PN1", late=False, silent=False),
    ])
    flags = [e["p"]["nodes"]["PN1"].get("late") for e in result.events if "late" in e["p"]["nodes"]["PN1"]]
    assert flags == [True, False]
    assert result.state["nodes"]["PN1"]["late"] is False


def test_fields_of_another_type_than_their_producers_are_dropped() -> None:
    hostile = "<img src=x onerror=alert(1)>"
    result = fold([
        line(100, "PN1", "switch", "Activate", {"role": "Worker", "active": hostile, "epoch": "7",
                                                "config": ["C1"], "stored": {"taskB": "v1"}},
             n="PN1", t="taskB"),
        line(200, "PN1", "heartbeat", "Tick", {"missed": {"PN2": hostile}, "failed": [1, 2]},
             m="PN1", late="yes"),
        line(300, "PN1", "switch", "CompleteSwitch", {"epoch": 2.5}, m="PN1", c={"x": 1}),
        line(400, "PN2", "switch", "Activate", {"active": ["taskB"], "epoch": 3, "stored": {"taskB": 4}},
             n="PN2", t="taskB"),
    ])
    pn1 = result.state["nodes"]["PN1"]
    assert set(pn1) == {"role", "seen"} and pn1["role"] == "Worker"
    assert result.state["path"] == {}
    assert result.state["nodes"]["PN2"]["active"] == ["taskB"] and result.state["nodes"]["PN2"]["epoch"] == 3
    assert result.state["nodes"]["PN2"]["stored"] == {"taskB": 4}


def test_lines_that_break_a_parser_are_counted_and_the_feed_goes_on(tmp_path: Path) -> None:
    writer = Writer(tmp_path)
    head = '{"t_ns":100000000,"node":"PN1","fsm":"switch","action":"Hold","args":'
    writer.write_raw("PN1.trace.ndjson", "".join([
        head + "[" * 100_000 + "]" * 100_000 + "}\n",  # RecursionError in json
        '{"t_ns":1e999,"node":"PN1","fsm":"switch","action":"Hold","args":{}}\n',  # OverflowError in int()
        '{"t_ns":' + "9" * 5000 + ',"node":"PN1","fsm":"switch","action":"Hold","args":{}}\n',
        '{"t_ns":' + "9" * 5000 + ',"node":"PN1","fsm":"heartbeat","action":"SendHeartbeat"}\n',
        '{"t_ns":NaN,"node":"PN1","fsm":"switch","action":"Hold","args":{}}\n',
        console_runs.encode(line(200, "PN1", "switch", "Release", n="PN1")),
    ]))
    writer.write_raw(EVENTS_FILE, '{"t_ns": 1e999, "action": "kill", "argument": "PN3"}\n'
                     '{"t_ns": [[[[1]]]], "action": "kill", "argument": "PN3"}\n'
                     + json.dumps({"t_ns": 300 * MS, "action": "kill", "argument": "PN2"}) + "\n")
    (tmp_path / "gone.image.json").symlink_to(tmp_path / "nowhere")  # find_image's stat fails
    feed = console.Feed(tmp_path)
    poll(feed)
    assert feed.status()["malformed"] == 7 and feed.status()["error"] is None
    assert [e["d"] for e in feed.fold.events if e.get("d")] == ["PN1 releases its tasks", "kill PN2"]
    assert console.find_image(tmp_path) is None
    assert json.loads(json.dumps(feed.fold.events, allow_nan=False)) == feed.fold.events


def test_a_pass_that_fails_is_said_and_the_feed_goes_on(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    feed = console.Feed(tmp_path, poll_s=0.01)
    take = feed.fold.take
    failures = []

    def failing_once(t_ns: int, item: Any) -> None:
        if not failures:
            failures.append(item)
            raise RuntimeError("a fold that fails")
        take(t_ns, item)

    monkeypatch.setattr(feed.fold, "take", failing_once)
    feed.start()
    try:
        Writer(tmp_path).write([line(100, "PN1", "switch", "Hold", n="PN1")])
        with feed.lock:
            assert feed.lock.wait_for(lambda: feed.errors == 1, 60)
            assert feed.status()["error"] == "RuntimeError: a fold that fails"
        Writer(tmp_path).write([line(200, "PN1", "switch", "Release", n="PN1")])
        with feed.lock:
            assert feed.lock.wait_for(lambda: any(e["a"] == "Release" for e in feed.fold.events), 60)
    finally:
        feed.stop()


def test_the_status_never_walks_the_files_the_feed_is_adding_to(tmp_path: Path) -> None:
    # HTTP threads read the status while the feed's thread tails the run directory.
    Writer(tmp_path).write([line(100, "PN1", "switch", "Hold", n="PN1")])
    feed = console.Feed(tmp_path)
    poll(feed)
    other = tmp_path / "PN2.trace.ndjson"

    class Growing(dict):
        def __iter__(self):  # a file appears while the status is being made
            keys = super().__iter__()
            yield next(keys)
            other.write_text(console_runs.encode(line(200, "PN2", "switch", "Hold", n="PN2")))
            feed.traces.poll()
            yield from keys

    files = feed.traces.files
    feed.traces.files = Growing(files)
    assert feed.status()["trace_files"] == ["PN1.trace.ndjson"]
    feed.traces.files = dict(files)
    if not other.exists():
        other.write_text(console_runs.encode(line(200, "PN2", "switch", "Hold", n="PN2")))
    poll(feed)
    assert feed.status()["trace_files"] == ["PN1.trace.ndjson", "PN2.trace.ndjson"]


def test_merge_patch_undoes_diff_patch() -> None:
    generator = random.Random(7)

    def value(depth: int) -> Any:
        kind = generator.randrange(5 if depth < 3 else 3)
        if kind == 0:
            return generator.randrange(4)
        if kind == 1:
            return generator.choice(["C1", "C2", "SAFE"])
        if kind == 2:
            return [generator.randrange(3) for _ in range(generator.randrange(3))]
        return {generator.choice("abcd"): value(depth + 1) for _ in range(generator.randrange(4))}

    for _ in range(500):
        old, new = value(0), value(0)
        if not isinstance(old, dict) or not isinstance(new, dict):
            continue
        patch = console.diff_patch(old, new)
        assert console.merge_patch(json.loads(json.dumps(old)), patch or {}) == new


def busy_lines(start_ms: int, end_ms: int) -> list[dict[str, Any]]:
    """Heartbeats every 10 ms from three nodes, ST1 storing a checkpoint every 20 ms, PN1
    flushing one every 50 ms, and now and then a hold or a release."""
    lines = []
    for t in range(start_ms, end_ms, 10):
        lines += [line(t, n, "heartbeat", "SendHeartbeat", n=n) for n in ("PN1", "PN2", "ST1")]
        if t % 20 == 0:
            lines.append(line(t, "ST1", "switch", "StoreCheckpoint", {"stored": {"taskB": t}}, t="taskB",
                              version=t, **{"from": "PN1"}))
        if t % 50 == 0:
            lines.append(line(t, "PN1", "switch", "FlushCheckpoint", t="taskB", version=t))
        if t % 700 == 0:
            lines.append(line(t, "PN2", "switch", "Hold" if t % 1400 else "Release", n="PN2"))
    return lines


def test_past_its_soft_limit_the_page_builds_the_servers_state(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(console, "EVENT_LIMIT", 10)
    writer = Writer(tmp_path)
    feed = console.Feed(tmp_path)
    for start in range(0, 6000, 1000):
        writer.write(busy_lines(start, start + 1000))
        poll(feed)
        assert page_state(feed) == feed.fold.state, start
    status = feed.status()
    assert status["dropped"] > 400 and not status["truncated"]
    assert feed.fold.state["nodes"]["ST1"]["stored"] == {"taskB": 5980}
    assert page_state(feed)["nodes"]["ST1"]["seen"] >= 5500 * MS  # marked alive to the end
    # Past the limit, the checkpoints and the liveness marks of a node come as one mark per
    # SEEN_EVERY_NS (and one when a pass finds nothing new), not one per line.
    late = [e for e in feed.fold.events[10:] if e["k"] in ("seen", "checkpoint")]
    for node in ("PN1", "PN2", "ST1"):
        assert len([e for e in late if e["n"] == node]) <= 6000 * MS // console.SEEN_EVERY_NS + 6 + 1, node
    assert [e["i"] for e in feed.fold.events] == list(range(len(feed.fold.events)))


def test_past_its_hard_limit_the_feed_reads_no_more_and_the_page_has_what_it_read(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(console, "EVENT_LIMIT", 10)
    monkeypatch.setattr(console, "EVENT_LIMIT_HARD", 14)
    writer = Writer(tmp_path)
    writer.write([line(t, "ST1", "switch", "StoreCheckpoint", {"stored": {"taskB": t}}, t="taskB", version=t,
                       **{"from": "PN3"}) for t in range(1, 21)])
    feed = console.Feed(tmp_path)
    poll(feed)
    writer.write([line(100 + t, "PN1", "heartbeat", "DeclareFailed", {"failed": [f"N{k}" for k in range(t + 1)]},
                       m="PN1", n=f"N{t}") for t in range(8)])
    poll(feed)
    kinds = [e["k"] for e in feed.fold.events]
    # Room for three declarations; the rest's changes kept merged, one event for PN1.
    assert kinds.count("declare") == 3 and feed.truncated
    assert len(kinds) == console.EVENT_LIMIT_HARD + 1
    assert [e["i"] for e in feed.fold.events] == list(range(len(kinds)))
    assert feed.status()["dropped"] > 0 and feed.status()["truncated"] is True
    assert feed.fold.state["nodes"]["ST1"]["stored"] == {"taskB": 20}
    assert page_state(feed) == feed.fold.state
    assert page_state(feed)["nodes"]["PN1"]["declared"] == [f"N{k}" for k in range(8)]
    writer.write([line(200, "PN1", "switch", "Hold", n="PN1")])
    poll(feed)
    assert len(feed.fold.events) == len(kinds) and page_state(feed) == feed.fold.state  # nothing more


def test_the_limits_count_bytes_too(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(console, "EVENT_BYTES_LIMIT", 4000)
    monkeypatch.setattr(console, "EVENT_BYTES_LIMIT_HARD", 20_000)
    writer = Writer(tmp_path)
    feed = console.Feed(tmp_path)
    writer.write(busy_lines(0, 3000))
    poll(feed)
    status = feed.status()
    assert status["dropped"] > 0 and not status["truncated"]
    assert page_state(feed) == feed.fold.state
    writer.write([line(4000 + t, "PN2", "switch", "Hold" if t % 2 else "Release", n="PN2", note="x" * 200)
                  for t in range(200)])
    poll(feed)
    status = feed.status()
    assert status["truncated"] and status["event_bytes"] < 20_000 + 2000
    assert page_state(feed) == feed.fold.state


# --- The launcher's events -----------------------------------------------------------------


def test_the_launcher_logs_what_it_does_in_the_run_directory(tmp_path: Path) -> None:
    cluster = Cluster(ROOT / "config" / "prototype3.yaml", ["PN1"], tmp_path, Path("/bin/true"),
                      echo=False, insecure=True)
    cluster._record("kill", "PN3")
    cluster._record("phase", "science")
    logged = [json.loads(x) for x in (tmp_path / EVENTS_FILE).read_text().splitlines()]
    assert logged == cluster.events


def test_a_ground_command_a_node_refused_at_admission_is_logged_and_shown(tmp_path: Path) -> None:
    # The node's status line counts its refusals by reason (ground.refused); the launcher
    # logs each new one as an event, counting a restarted process from 0 again.
    from keel_cluster.launcher import NodeProcess

    cluster = Cluster(ROOT / "config" / "prototype3.yaml", ["PN1"], tmp_path, Path("/bin/true"),
                      echo=False, insecure=True)
    node = NodeProcess("PN1", [], tmp_path / "PN1.log")

    def status(**refused: int) -> dict[str, Any]:
        return {"ground": {"accepted": 1, "last_seq": 7, "refused": refused}}

    cluster._note_refusals(node, status())
    cluster._note_refusals(node, status(replay=1))
    cluster._note_refusals(node, status(replay=1))  # the same count again: nothing new
    cluster._note_refusals(node, status(replay=3, signature=1, bogus=True))  # type: ignore[arg-type]
    cluster._note_refusals(node, {"ground": "not an object"})
    node.ground_refused = {}  # what start() does for a new process
    cluster._note_refusals(node, status(replay=1))
    refusals = [e["argument"] for e in cluster.events if e["action"] == "refused"]
    assert refusals == ["PN1 replay", "PN1 replay", "PN1 replay", "PN1 signature", "PN1 replay"]
    logged = [json.loads(x) for x in (tmp_path / EVENTS_FILE).read_text().splitlines()]
    assert logged == cluster.events
    # The console shows each on the node's lane, as the ground's; it is no fault to time.
    feed = console.Feed(tmp_path)
    poll(feed)
    said = [(e["n"], e["k"], e["d"]) for e in feed.fold.events if e["a"] == "refused"]
    assert said[0] == ("PN1", "ground", "PN1 refused a ground command at admission (replay)")
    assert ("PN1", "ground", "PN1 refused a ground command at admission (signature)") in said and len(said) == 5
    assert feed.fold.faults == [] and feed.fold.state["faults"] == {}


def test_a_kill_the_launcher_logged_marks_the_node_down_and_is_timed(tmp_path: Path) -> None:
    writer = Writer(tmp_path)
    writer.write_raw(EVENTS_FILE, json.dumps({"t_ns": 1000 * MS, "action": "kill", "argument": "PN3"}) + "\n")
    writer.write([
        line(1300, "PN1", "heartbeat", "DeclareFailed", m="PN1", n="PN3"),
        line(1301, "PN1", "switch", "Exclude", m="PN1", f="PN3", c="P4"),
        line(1306, "PN2", "switch", "Activate", n="PN2", t="taskB", version=3, restored=True),
        line(1309, "PN1", "switch", "CompleteSwitch", m="PN1", c="P4"),
    ])
    feed = console.Feed(tmp_path)
    poll(feed)
    state = feed.fold.state
    assert state["nodes"]["PN3"]["down"] is True
    assert state["faults"]["0"] == {"t": 1000 * MS, "action": "kill", "argument": "PN3"}
    [measure] = state["measures"].values()
    assert (measure["detection_ms"], measure["decision_ms"], measure["switch_ms"], measure["restore_ms"],
            measure["total_ms"]) == (300, 1, 8, 5, 309)
    said = [e["d"] for e in feed.fold.events if e["k"] == "measure" and e.get("d")]
    assert said == [("kill PN3: detected 300 ms, decided 1 ms, switched 8 ms, restored 5 ms, total 309 ms"
                     " -> P4 (Master PN1)")]


def test_a_run_without_the_launchers_log_takes_its_reports_events(tmp_path: Path) -> None:
    Writer(tmp_path).write([line(1300, "PN1", "heartbeat", "DeclareFailed", m="PN1", n="PN3")])
    (tmp_path / "report.json").write_text(json.dumps(
        {"events": [{"t_ns": 1000 * MS, "action": "kill", "argument": "PN3"}]}))
    feed = console.Feed(tmp_path)
    poll(feed)
    assert feed.fold.state["nodes"]["PN3"]["down"] is True
    assert feed.status()["finished"] is True


# --- The mission ---------------------------------------------------------------------------


def test_the_graph_is_read_from_the_image_as_from_the_yaml(sim_run: tuple[Path, list[dict[str, Any]], str]) -> None:
    run_dir, _, _ = sim_run
    from_image = console.read_mission(console.find_image(run_dir))
    from_yaml = console.read_mission(ROOT / "config" / "prototype3.yaml")
    assert from_image["name"] == "prototype3"
    assert [n["name"] for n in from_image["nodes"]] == ["PN1", "PN2", "PN3", "ST1"]
    assert {"from": "P1", "to": "P4", "kind": "failure", "label": "PN3"} in from_image["edges"]
    assert {"from": "P1", "to": "S1", "kind": "phase", "label": "science"} in from_image["edges"]
    assert sorted(map(json.dumps, from_image["edges"])) == sorted(map(json.dumps, from_yaml["edges"]))
    assert (from_image["period_ms"], from_image["miss_limit"]) == (from_yaml["period_ms"], from_yaml["miss_limit"])
    assert from_image["period_ms"] > 0 and from_image["miss_limit"] > 0


def test_a_mission_that_does_not_read_is_said(tmp_path: Path) -> None:
    bad = tmp_path / "bad.image.json"
    bad.write_text('{"content": {}}')
    with pytest.raises(console.ConsoleError, match="not a mission the console can read"):
        console.read_mission(bad)
    feed = console.Feed(tmp_path)
    poll(feed)
    assert "bad.image.json" in feed.status()["mission_error"]


def test_the_mission_follows_the_launchers_updates(sim_run: tuple[Path, list[dict[str, Any]], str],
                                                  tmp_path: Path) -> None:
    image = console.find_image(sim_run[0])
    shutil.copy(image, tmp_path)
    feed = console.Feed(tmp_path)
    poll(feed)
    assert feed.mission["name"] == "prototype3" and feed.mission_version == 1
    # Update 1: the launcher logs it, then compiles the new image in update-1/.
    Writer(tmp_path).write_raw(EVENTS_FILE, json.dumps({"t_ns": 5000 * MS, "action": "update",
                                                        "argument": "missions/next.yaml"}) + "\n")
    poll(feed)
    assert feed.mission["name"] == "prototype3"  # not compiled yet
    updated = json.loads(image.read_text())
    updated["content"]["mission"] = "prototype3-next"
    (tmp_path / "update-1").mkdir()
    (tmp_path / "update-1" / "next.image.json").write_text(json.dumps(updated))
    poll(feed)
    assert feed.mission["name"] == "prototype3-next" and feed.mission_version == 2
    assert feed.status()["mission"] == str(tmp_path / "update-1" / "next.image.json")
    assert console.find_image(tmp_path, updates=1) == tmp_path / "update-1" / "next.image.json"
    # Update 2, an image flown as it is (the launcher does not copy it).
    flown = tmp_path.parent / f"{tmp_path.name}-flown.image.json"
    updated["content"]["mission"] = "prototype3-flown"
    flown.write_text(json.dumps(updated))
    Writer(tmp_path).write_raw(EVENTS_FILE, json.dumps({"t_ns": 6000 * MS, "action": "update",
                                                        "argument": str(flown)}) + "\n")
    poll(feed)
    poll(feed)
    assert feed.mission["name"] == "prototype3-flown" and feed.mission_version == 3
    # An update whose argument names no file: the image flown before it stays, and the feed reads on.
    Writer(tmp_path).write_raw(EVENTS_FILE, json.dumps({"t_ns": 7000 * MS, "action": "update",
                                                        "argument": "no\u0000such"}) + "\n")
    poll(feed)
    assert feed.mission["name"] == "prototype3-flown" and feed.status()["error"] is None


# --- The HTTP API --------------------------------------------------------------------------


@pytest.fixture
def server(sim_run: tuple[Path, list[dict[str, Any]], str]) -> console.ConsoleServer:
    serving = console.serve(sim_run[0])
    yield serving
    serving.close()


def get(server: console.ConsoleServer, path: str, host: str | None = None,
        headers: dict[str, str] | None = None) -> tuple[int, dict[str, str], bytes]:
    connection = http.client.HTTPConnection("127.0.0.1", server.server_address[1], timeout=60)
    sent = dict(headers or {})
    if host:
        sent["Host"] = host
    connection.request("GET", path, headers=sent)
    response = connection.getresponse()
    body = response.read()
    connection.close()
    return response.status, dict(response.getheaders()), body


def wait_for_feed(server: console.ConsoleServer) -> None:
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        answer = json.loads(get(server, "/api/status")[2])
        if answer["events"] and answer["passes"] > 1:
            return
        time.sleep(0.05)
    raise AssertionError("the feed read nothing in 60 s")


def test_the_page_and_its_assets_are_served_from_the_package(server: console.ConsoleServer) -> None:
    assert server.server_address[0] == "127.0.0.1"
    for path, kind in (("/", "text/html"), ("/console.js", "text/javascript"), ("/console.css", "text/css")):
        status, headers, body = get(server, path)
        assert status == 200 and headers["Content-Type"].startswith(kind) and body
    assert get(server, "/../console.py")[0] == 404
    assert get(server, "/console.py")[0] == 404


def test_nothing_the_page_uses_comes_from_the_network() -> None:
    # Every address the page names is a path of the console's own: no scheme, no host.
    class Addresses(html.parser.HTMLParser):
        found: list[str] = []

        def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
            self.found += [value or "" for name, value in attrs if name in ("src", "href", "action")]

    page = Addresses()
    page.feed((console.STATIC_DIR / "index.html").read_text())
    assert sorted(page.found) == ["console.css", "console.js"]
    script = (console.STATIC_DIR / "console.js").read_text()
    assert sorted(set(re.findall(r"(?:EventSource|fetch|import)\(\s*([^,)]*)", script))) == [
        '"api/command"', '"api/stream"']
    style = (console.STATIC_DIR / "console.css").read_text()
    assert "@import" not in style and "url(" not in style
    for asset in console.STATIC_DIR.iterdir():
        assert "//" not in re.sub(r"(?m)^\s*//.*$|\s//\s.*$|/\*.*?\*/", "", asset.read_text(), flags=re.S), asset


def test_a_page_asked_for_by_another_name_is_refused(server: console.ConsoleServer) -> None:
    assert get(server, "/", host="attacker.example:80")[0] == 403
    assert get(server, "/", host=f"localhost:{server.server_address[1]}")[0] == 200


def test_a_request_another_site_makes_is_refused(server: console.ConsoleServer) -> None:
    port = server.server_address[1]
    for headers in ({"Sec-Fetch-Site": "cross-site"}, {"Sec-Fetch-Site": "same-site"},
                    {"Origin": "http://attacker.example"}, {"Origin": f"http://127.0.0.1:{port + 1}"},
                    {"Origin": "null"}):
        for path in ("/", "/api/stream", "/api/state"):
            status, _, body = get(server, path, headers=headers)
            assert status == 403 and b"its own page only" in body, (headers, path)
    for headers in ({"Sec-Fetch-Site": "same-origin", "Origin": f"http://127.0.0.1:{port}"},
                    {"Sec-Fetch-Site": "none"}, {"Origin": f"http://localhost:{port}"}):
        assert get(server, "/api/status", headers=headers)[0] == 200, headers


def post(server: console.ConsoleServer, body: bytes, headers: dict[str, str],
         path: str = "/api/command") -> tuple[int, dict[str, Any] | bytes]:
    connection = http.client.HTTPConnection("127.0.0.1", server.server_address[1], timeout=60)
    connection.request("POST", path, body=body, headers=headers)
    response = connection.getresponse()
    answer = response.read()
    connection.close()
    kind = response.getheader("Content-Type") or ""
    return response.status, json.loads(answer) if kind == "application/json" else answer


def test_a_replay_takes_no_command(server: console.ConsoleServer) -> None:
    assert json.loads(get(server, "/api/command")[2]) == {"enabled": False}
    assert server.command_url == server.url
    own = {"Origin": f"http://127.0.0.1:{server.server_address[1]}", "X-Keel-Token": server.token}
    status, answer = post(server, b'{"line": "kill PN2"}', own)
    assert status == 409 and "no cluster to command" in answer["error"]


def test_the_page_sends_the_runs_ground_console_a_line_with_its_token(
        sim_run: tuple[Path, list[dict[str, Any]], str]) -> None:
    # keel-cluster run --console: the page's lines go where --ground's stdin lines go
    # (cli.run); only the console's own page, with the token it read, may send one.
    taken: list[str] = []

    def take(line: str) -> str | console.Applied | None:
        if line.startswith("bogus"):
            return "stdin:1: unknown action 'bogus'"
        taken.append(line)
        return console.Applied("proven target: S1 (phase science from P1)") if line.startswith("phase") else None

    serving = console.serve(sim_run[0], commands=console.Commands(take, ["phase science"]))
    try:
        port = serving.server_address[1]
        # The key is in the address the run prints, and nowhere the console serves.
        offer = json.loads(get(serving, "/api/command")[2])
        assert offer == {"enabled": True, "examples": ["phase science"]}
        token = serving.token
        assert serving.command_url == f"{serving.url}#k={token}" and len(token) >= 32
        own = {"Origin": f"http://127.0.0.1:{port}", "X-Keel-Token": token}
        assert post(serving, b'{"line": " exclude PN3 "}', own) == (200, {"ok": True, "line": "exclude PN3"})
        assert taken == ["exclude PN3"]
        assert post(serving, b'{"line": "phase science"}', own) == (
            200, {"ok": True, "line": "phase science", "note": "proven target: S1 (phase science from P1)"})
        taken.remove("phase science")
        status, answer = post(serving, b'{"line": "bogus PN3"}', own)
        assert status == 400 and answer == {"ok": False, "error": "stdin:1: unknown action 'bogus'"}
        for body in (b"not json", b'{"line": 3}', b'{"line": ""}', b'{"line": "kill PN2\\nquit"}', b"[]"):
            status, answer = post(serving, body, own)
            assert status == 400 and "one line" in answer["error"], body
        status, answer = post(serving, b'{"line": "' + b"x" * 2000 + b'"}', own)
        assert status == 413 and "1024 bytes" in answer["error"]
        # Another page, no page, the wrong token or none, another path: nothing is taken.
        for headers in ({"X-Keel-Token": token},
                        {"Origin": "http://attacker.example", "X-Keel-Token": token},
                        {"Origin": f"http://127.0.0.1:{port}", "Sec-Fetch-Site": "cross-site",
                         "X-Keel-Token": token}):
            status, answer = post(serving, b'{"line": "kill PN2"}', headers)
            assert status == 403 and b"own page only" in answer, headers
        for headers in ({"Origin": f"http://127.0.0.1:{port}"},
                        {"Origin": f"http://127.0.0.1:{port}", "X-Keel-Token": token[:-1] + "x"}):
            status, answer = post(serving, b'{"line": "kill PN2"}', headers)
            assert status == 403 and "console's key" in answer["error"], headers
        assert post(serving, b'{"line": "kill PN2"}', own, path="/api/state")[0] == 404
        # A page reached through another name (DNS rebinding), or a length that does not read.
        status, answer = post(serving, b'{"line": "kill PN2"}', {**own, "Host": "attacker.example"})
        assert status == 403 and b"127.0.0.1 only" in answer
        assert get(serving, "/api/command", host="attacker.example")[0] == 403
        assert get(serving, "/api/command", headers={"Sec-Fetch-Site": "cross-site"})[0] == 403
        for length in ("\u00b2", "1" * 5000, "-1"):
            connection = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
            connection.putrequest("POST", "/api/command")
            for name, value in {**own, "Content-Length": length}.items():
                connection.putheader(name, value.encode("latin-1") if not value.isascii() else value)
            connection.endheaders()
            response = connection.getresponse()
            assert response.status == 411 and response.getheader("Connection") == "close", length
            connection.close()
        assert taken == ["exclude PN3"]
    finally:
        serving.close()


class FakeCluster:
    def __init__(self) -> None:
        self.applied: list[tuple[str, str]] = []

    def apply(self, event: Any) -> None:
        if event.argument == "PN9":
            raise RuntimeError("PN9 is not running")
        self.applied.append((event.action, event.argument))


def test_the_runs_page_commands_are_applied_by_its_loop_and_answered() -> None:
    # cli.PageCommands, between the page's HTTP thread (take) and the run's loop (apply).
    from keel_cluster.cli import PAGE_ACTIONS, PageCommands
    page = PageCommands({"PN1", "PN2", "PN3", "ST1", "PN9"}, ["PN1", "PN2", "PN3"], {"science", "nominal"},
                        {"P1", "C4"})
    assert page.examples == ["phase nominal", "exclude PN3", "readmit PN3", "kill PN3"]
    assert "not running" in page.take("kill PN2")  # not started yet
    page.running.set()
    cluster = FakeCluster()
    answers: dict[str, str | None] = {}

    def send(line: str) -> threading.Thread:
        thread = threading.Thread(target=lambda: answers.__setitem__(line, page.take(line)))
        thread.start()
        return thread

    for line in ("quit", "", "# a comment", "update other.yaml", "bogus PN2", "kill PN7"):
        answers[line] = page.take(line)
    assert "does not end the run" in answers["quit"] and "does not end the run" in answers[""]
    assert "does not end the run" in answers["# a comment"]
    assert answers["update other.yaml"].startswith("update is not taken from the page")
    assert all(action in answers["update other.yaml"] for action in PAGE_ACTIONS)
    assert "bogus" in answers["bogus PN2"] and "PN7" in answers["kill PN7"]
    waiting = [send("kill PN2  # as on stdin"), send("restart PN9")]
    deadline = time.monotonic() + 10
    while page.queue.qsize() < 2 and time.monotonic() < deadline:
        time.sleep(0.01)
    page.apply(cluster)
    for thread in waiting:
        thread.join(10)
    assert cluster.applied == [("kill", "PN2")]
    assert answers["kill PN2  # as on stdin"] is None
    assert answers["restart PN9"] == "restart PN9: PN9 is not running"
    # The run ends: a request still waiting is told; later ones are refused at once.
    late = send("phase science")
    while page.queue.qsize() < 1 and time.monotonic() < deadline:
        time.sleep(0.01)
    page.end()
    late.join(10)
    assert answers["phase science"] == "the run has ended"
    assert "not running" in page.take("phase science") and cluster.applied == [("kill", "PN2")]


class StatusCluster(FakeCluster):
    """A cluster whose acting Master says its configuration and failed set (status lines)."""

    def __init__(self, config: str, failed: list[str]) -> None:
        super().__init__()
        self.paused: set[str] = set()
        self.nodes = {n: type("Node", (), {"running": True})() for n in ("PN1", "PN2", "PN3", "ST1")}
        self.status = {"PN1": {"role": "Master", "epoch": 1, "config": config, "failed": failed},
                       "PN3": {"role": "Observer", "epoch": 1, "config": config, "failed": failed}}

    def statuses(self) -> dict[str, dict[str, Any]]:
        return self.status


def test_a_ground_command_from_the_page_is_answered_with_its_proven_target() -> None:
    # What the proven graph says a ground command leads to from the acting Master's
    # configuration and failed set, as the Master walks it (common.Graph); a fault, none.
    from keel_cluster.cli import PageCommands
    from keel_cluster.common import summarize

    graph = summarize(ROOT / "config" / "prototype3.yaml").graph
    page = PageCommands({"PN1", "PN2", "PN3", "ST1"}, ["PN1", "PN2", "PN3"], {"science", "nominal"},
                        {"P1", "P3", "S1", "S3"}, graph)

    def answer(line: str, cluster: FakeCluster) -> Any:
        page.running.set()
        got: dict[str, Any] = {}
        thread = threading.Thread(target=lambda: got.setdefault("answer", page.take(line)))
        thread.start()
        deadline = time.monotonic() + 10
        while page.queue.qsize() < 1 and time.monotonic() < deadline:
            time.sleep(0.01)
        page.apply(cluster)
        thread.join(10)
        return got["answer"]

    nominal, one_out = StatusCluster("P1", []), StatusCluster("P3", ["PN2"])
    assert answer("phase science", nominal) == console.Applied("proven target: S1 (phase science from P1)")
    assert answer("exclude PN2", nominal) == console.Applied("proven target: P3 (PN2 out of P1)")
    assert answer("readmit PN2", one_out) == console.Applied("proven target: P1 (PN2 back into P3)")
    assert answer("phase science", one_out) == console.Applied("proven target: S3 (phase science from P3)")
    refused = answer("exclude PN3", one_out)
    assert isinstance(refused, console.Applied) and "leads to SAFE" in refused.note and "withholds" in refused.note
    assert answer("phase nominal", StatusCluster("SAFE", ["PN2", "PN3"])) == console.Applied(
        "no proven edge from SAFE for phase nominal (or it uses a failed node): the Master (PN1) will refuse it")
    assert "checks it" in answer("recover P1", one_out).note
    assert answer("kill PN2", nominal) is None and nominal.applied[-1] == ("kill", "PN2")
    # No acting Master to read: said; a cluster without status lines: nothing to say.
    headless = StatusCluster("P1", [])
    headless.status = {}
    assert "no acting Master" in answer("phase science", headless).note
    assert answer("phase science", FakeCluster()) is None
    page.end()


def test_every_answer_forbids_framing_and_foreign_content(server: console.ConsoleServer) -> None:
    for path in ("/", "/console.js", "/api/status", "/nowhere", "/favicon.ico"):
        status, headers, _ = get(server, path)
        assert headers["Content-Security-Policy"] == "default-src 'self'; frame-ancestors 'none'", path
        assert headers["X-Content-Type-Options"] == "nosniff", path
    assert get(server, "/favicon.ico")[0] == 204
    status, headers, _ = get(server, "/", host="attacker.example")
    assert status == 403 and "frame-ancestors 'none'" in headers["Content-Security-Policy"]


def test_a_request_that_fails_is_one_line_and_a_page_that_goes_away_none(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    static = tmp_path / "page"
    static.mkdir()  # the page's files missing: 500, not a traceback
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    serving = console.ConsoleServer(console.Feed(run_dir, poll_s=0.01), 0, static)
    serving.start()
    try:
        status, _, body = get(serving, "/console.js")
        assert status == 500 and b"cannot read the page's console.js" in body

        def broken() -> dict[str, Any]:
            raise RuntimeError("a status that cannot be made")

        serving.feed.status = broken  # type: ignore[method-assign]
        with pytest.raises((http.client.HTTPException, ConnectionError)):
            get(serving, "/api/status")
        del serving.feed.status
        # A page that goes away while its stream writes.
        stream = Stream(serving, "/api/stream")
        stream.next()
        stream.close()
        Writer(run_dir).write([line(100, "PN1", "switch", "Hold", n="PN1")])
        deadline = time.monotonic() + 60
        while serving.streams and time.monotonic() < deadline:
            Writer(run_dir).write([line(200, "PN1", "switch", "Release", n="PN1")])
            time.sleep(0.05)
        assert serving.streams == 0
    finally:
        serving.close()
    said = capsys.readouterr().err
    assert "Traceback" not in said
    assert said.splitlines() == [
        f"keel-cluster console: a request from 127.0.0.1:{said.split('127.0.0.1:')[1].split()[0]} failed: "
        "RuntimeError: a status that cannot be made"]


def test_the_api_gives_the_events_the_state_and_the_mission(server: console.ConsoleServer) -> None:
    wait_for_feed(server)
    status, _, body = get(server, "/api/events?since=0")
    answer = json.loads(body)
    assert status == 200 and answer["next"] == len(answer["events"]) > 0
    assert [e["i"] for e in answer["events"]] == list(range(answer["next"]))
    later = json.loads(get(server, f"/api/events?since={answer['next'] - 2}")[2])
    assert [e["i"] for e in later["events"]][:2] == [answer["next"] - 2, answer["next"] - 1]
    state = json.loads(get(server, "/api/state")[2])
    assert state["nodes"]["PN2"]["role"] == "Master"
    assert json.loads(get(server, "/api/mission")[2])["mission"]["name"] == "prototype3"
    assert json.loads(get(server, "/api/status")[2])["waiting"] is False


class Stream:
    """A reader of /api/stream, as an EventSource reads it."""

    def __init__(self, server: console.ConsoleServer, path: str):
        self.sock = socket.create_connection(("127.0.0.1", server.server_address[1]), timeout=60)
        self.sock.sendall(f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n".encode())
        self.data = b""
        self.found: list[tuple[str, dict[str, Any]]] = []

    def next(self) -> tuple[str, dict[str, Any]]:
        while not self.found:
            chunk = self.sock.recv(1 << 16)
            assert chunk, "the stream ended"
            self.data += chunk
            *complete, self.data = self.data.split(b"\n\n")
            for block in complete:
                fields = dict(x.split(": ", 1) for x in block.decode().splitlines()
                              if ": " in x and not x.startswith(":"))
                if "data" in fields:
                    self.found.append((fields.get("id", ""), json.loads(fields["data"])))
        return self.found.pop(0)

    def close(self) -> None:
        self.sock.close()


def read_stream(server: console.ConsoleServer, path: str) -> tuple[str, dict[str, Any]]:
    stream = Stream(server, path)
    try:
        return stream.next()
    finally:
        stream.close()


def test_the_stream_sends_the_mission_then_every_event_from_where_the_page_is(server: console.ConsoleServer) -> None:
    wait_for_feed(server)
    total = json.loads(get(server, "/api/status")[2])["events"]
    last_id, message = read_stream(server, "/api/stream")
    assert message["mission"]["name"] == "prototype3"
    assert [e["i"] for e in message["events"]] == list(range(total)) and int(last_id) == total
    # A page that reconnects (EventSource sends Last-Event-ID, or ?since=) gets the rest only.
    _, again = read_stream(server, f"/api/stream?since={total - 3}")
    assert [e["i"] for e in again["events"]] == [total - 3, total - 2, total - 1]


def test_a_live_run_reaches_the_stream_as_it_is_written(tmp_path: Path) -> None:
    serving = console.serve(tmp_path)
    stream = Stream(serving, "/api/stream")
    try:
        _, first = stream.next()
        assert first["status"]["waiting"] is True and first["events"] == []
        Writer(tmp_path).write([line(1300, "PN1", "heartbeat", "DeclareFailed", m="PN1", n="PN3")])
        said: list[str] = []
        while "PN1 declares PN3 failed (missed)" not in said:
            _, message = stream.next()  # the socket's timeout fails the test
            said += [e["d"] for e in message["events"] if "d" in e]
        assert message["status"]["waiting"] is False
    finally:
        stream.close()
        serving.close()


def test_drain_returns_once_every_page_has_what_the_run_wrote(tmp_path: Path) -> None:
    # Passes a second apart: what a run writes just after one is read only by the next.
    serving = console.ConsoleServer(console.Feed(tmp_path, poll_s=1.0), 0)
    serving.start()
    stream = Stream(serving, "/api/stream")
    try:
        stream.next()
        with serving.feed.lock:
            assert serving.feed.lock.wait_for(lambda: serving.feed.passes > 0, 60)
        written = [line(100 + t, "PN1", "switch", "Hold" if t % 2 else "Release", n="PN1") for t in range(50)]
        Writer(tmp_path).write(written)
        (tmp_path / "report.json").write_text(json.dumps({"events": []}))
        assert serving.drain(60)
        with serving.feed.lock:
            total = len(serving.feed.fold.events)
            assert serving.feed.fold.lines == len(written) and serving.feed.finished
        stream.sock.settimeout(5)  # drained: all of it is already on its way
        last_id, message = "", {}
        while not last_id or int(last_id) < total or not message["status"]["finished"]:
            last_id, message = stream.next()
        assert int(last_id) == total
    finally:
        stream.close()
        serving.close()


# --- The command line ----------------------------------------------------------------------


def keel_cluster(*args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "keel_cluster.cli", *args], capture_output=True, text=True,
                          timeout=timeout, check=False)


def test_a_run_directory_that_does_not_exist_is_said_without_a_traceback(tmp_path: Path) -> None:
    done = keel_cluster("console", str(tmp_path / "nowhere"))
    assert done.returncode == 2
    assert "nowhere: no such run directory" in done.stderr and "Traceback" not in done.stderr


def test_a_port_that_is_taken_is_exit_3(tmp_path: Path) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        done = keel_cluster("console", str(tmp_path), "--port", str(taken.getsockname()[1]))
    assert done.returncode == 3 and "cannot listen on 127.0.0.1" in done.stderr
    assert "Traceback" not in done.stderr


def test_run_console_on_a_port_that_is_taken_is_exit_3_before_any_node_starts(tmp_path: Path) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = keel_cluster("run", str(ROOT / "config" / "prototype3.yaml"), "--insecure", "--node-binary",
                            "/bin/true", "--run-dir", str(tmp_path / "run"), "--duration", "1s",
                            "--console", str(port))
    assert done.returncode == 3, done.stderr
    assert f"keel-cluster: --console: cannot listen on 127.0.0.1:{port}: Address already in use" in done.stderr
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "run" / EVENTS_FILE).exists()  # no node started


def test_bad_flags_are_exit_2(tmp_path: Path) -> None:
    assert keel_cluster("console", str(tmp_path), "--port", "http").returncode == 2
    assert keel_cluster("console", str(tmp_path), "--mission", str(tmp_path / "none.yaml")).returncode == 2
    assert keel_cluster("run", "config/prototype3.yaml", "--console", "70000").returncode == 2


def test_the_console_prints_its_address_and_stops_on_sigterm(tmp_path: Path) -> None:
    process = subprocess.Popen([sys.executable, "-m", "keel_cluster.cli", "console", str(tmp_path)],
                               stderr=subprocess.PIPE, text=True)
    try:
        said = process.stderr.readline()
        assert said.startswith(f"keel-cluster: console of {tmp_path} at http://127.0.0.1:"), said
        url = said.split(" at ", 1)[1].split()[0]
        port = int(url.rsplit(":", 1)[1].strip("/"))
        connection = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        connection.request("GET", "/api/status")
        assert json.loads(connection.getresponse().read())["waiting"] is True
        process.terminate()
        assert process.wait(timeout=60) == 0
    finally:
        process.kill()
        process.wait()


def test_an_installed_package_carries_the_page(tmp_path: Path) -> None:
    # Built from a copy: setuptools leaves build/ beside the sources.
    source = tmp_path / "source"
    shutil.copytree(ROOT / "nodes" / "cluster", source,
                    ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                           "-w", str(tmp_path), str(source)],
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    [wheel] = tmp_path.glob("keel_cluster-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    for asset in ("index.html", "console.js", "console.css"):
        assert f"keel_cluster/console/{asset}" in names


# --- console --dds: what keel-observe saw on the domain ----------------------------------

IMAGE = ROOT / "tests" / "missions" / "images" / "good" / "prototype3.json"


def observed(t_ms: float, what: str, **fields: object) -> bytes:
    return json.dumps({"t_ns": int(t_ms * MS), "observed": what, **fields}).encode() + b"\n"


def observation(folder: Path, lines: list[bytes], image: bool = True) -> console.Feed:
    folder.mkdir(parents=True, exist_ok=True)
    if image:
        shutil.copy(IMAGE, folder / "prototype3.image.json")
    (folder / console.OBSERVED_FILE).write_bytes(b"".join(lines))
    feed = console.Feed(folder)
    poll(feed)
    return feed


def test_what_keel_observe_saw_is_folded_with_the_images_names(tmp_path: Path) -> None:
    # prototype3's ids: PN1 0, PN2 1, PN3 2, ST1 3; P1 0, P3 2; taskA 0.
    state = {"role": "observer", "epoch": 1, "configuration_id": 0, "configuration": "P1", "phase": "nominal"}
    feed = observation(tmp_path / "dds", [
        observed(0, "joined", domain=7, secured=True),
        observed(1, "state", node=0, name="PN1", **dict(state, role="master")),
        observed(1, "state", node=1, name="PN2", **state),
        observed(1, "state", node=3, name="ST1", **dict(state, role="storage")),
        observed(2, "heartbeat", **{"from": 2}, epoch=1, incarnation=1, boot=5, excluded=False, waiting=False),
        observed(500, "declare", **{"from": 2}, epoch=1, failed=1),
        observed(501, "command", **{"from": 0}, epoch=1, seq=2, config=2, base=2, master=0, failed=[1], joint=1),
        observed(502, "ack", **{"from": 2}, to=0, epoch=1, seq=2, kind="Prepared"),
        observed(503, "activate", **{"from": 0}, epoch=1, seq=2),
        observed(504, "checkpoint", **{"from": 3}, to=2, epoch=1, task=0, lineage=4, count=9),
        observed(520, "state", node=0, name="PN1", **dict(state, role="master", configuration_id=2)),
        observed(530, "state", node=1, name="PN2", **dict(state, role="resigned")),
    ])
    said = [e["d"] for e in feed.fold.events if "d" in e]
    assert said == ["PN3 declares PN2 failed", "PN1 commands P3 (epoch 1, seq 2; out: PN2)",
                    "PN1 activates its switch (epoch 1, seq 2)", "ST1 holds taskA at version 4.9"]
    nodes = page_state(feed)["nodes"]
    assert nodes["PN1"]["role"] == "Master" and nodes["PN1"]["config"] == "P3"
    assert nodes["PN1"]["masterConfig"] == "P3" and nodes["PN1"]["view"] == ["PN2"]
    assert nodes["ST1"]["role"] == "Worker" and nodes["PN2"]["resigned"] is True
    assert nodes["PN3"]["seen"] == 500 * MS  # its declaration (its ack, 2 ms later, needs no mark of its own)
    assert [step["c"] for step in feed.fold.state["path"].values()] == ["P1", "P3"]
    assert feed.status()["malformed"] == 0 and feed.status()["trace_files"] == [console.OBSERVED_FILE]
    assert page_state(feed) == feed.fold.state


def test_an_observation_that_names_what_the_image_has_not_is_counted_and_the_rest_read(tmp_path: Path) -> None:
    good = observed(3, "heartbeat", **{"from": 0}, epoch=1, incarnation=1, boot=1, excluded=False, waiting=False)
    feed = observation(tmp_path / "dds", [
        b"not json\n",
        observed(1, "heartbeat", **{"from": 99}, epoch=1),  # no such node
        observed(1, "command", **{"from": 0}, epoch=1, seq=2, config=999, failed=[]),  # no such configuration
        observed(1, "command", **{"from": 0}, epoch=1, seq=2, config=2, failed=[42]),  # no such node
        observed(1, "checkpoint", **{"from": 3}, task=77, lineage=1, count=1),  # no such task
        observed(1, "state", node=0, role=5, epoch=1, configuration_id=0, phase="nominal"),  # a role that is no word
        observed(2, "dropped", kind="heartbeat", why="the payload does not decode"),
        observed(2, "gossip"),
        good,
    ])
    assert feed.status()["malformed"] == 8
    assert page_state(feed)["nodes"]["PN1"]["seen"] == 3 * MS


def test_an_observation_is_read_once_the_image_names_its_ids(tmp_path: Path) -> None:
    line = observed(3, "heartbeat", **{"from": 0}, epoch=1, incarnation=1, boot=1, excluded=False, waiting=False)
    feed = observation(tmp_path / "dds", [line], image=False)
    assert feed.fold.events == [] and feed.status()["malformed"] == 0
    shutil.copy(IMAGE, tmp_path / "dds" / "prototype3.image.json")
    poll(feed)
    assert page_state(feed)["nodes"]["PN1"]["seen"] == 3 * MS


def test_console_dds_refuses_what_it_cannot_use(tmp_path: Path) -> None:
    def refused(*args: str) -> str:
        done = keel_cluster("console", *args, timeout=60)
        assert done.returncode == 2, (args, done.stderr)
        assert "Traceback" not in done.stderr
        return done.stderr

    assert "needs --mission IMAGE" in refused("--dds", "7")
    assert "needs --mission IMAGE" in refused("--dds", "7", "--mission", str(ROOT / "config" / "prototype3.yaml"))
    assert "a domain is 0..230" in refused("--dds", "231", "--mission", str(IMAGE))
    assert "no monitor identity" in refused("--dds", "7", "--mission", str(IMAGE), "--security", str(tmp_path))
    (tmp_path / "used").mkdir()
    (tmp_path / "used" / console.OBSERVED_FILE).write_text("")
    assert "already holds an observation" in refused("--dds", "7", "--mission", str(IMAGE), str(tmp_path / "used"))
    assert "give a RUN_DIR, or --dds DOMAIN" in refused()


def test_console_dds_says_why_dds_refused_its_participant(tmp_path: Path) -> None:
    # A credentials folder whose monitor certificate is not one: keel-observe cannot create
    # its participant (exit 3, its reason), and the console says so (exit 4).
    security = tmp_path / "security"
    (security / "tools" / "monitor").mkdir(parents=True)
    for name in ("ca.pem", "governance.p7s"):
        (security / name).write_text("not a certificate\n")
    for name in ("cert.pem", "key.pem", "permissions.p7s"):
        (security / "tools" / "monitor" / name).write_text("not a certificate\n")
    done = keel_cluster("console", "--dds", "7", "--mission", str(IMAGE), "--security", str(security),
                        str(tmp_path / "watch"), timeout=90)
    assert done.returncode == 4, done.stderr
    assert "keel-observe: DDS refused the participant in domain 7" in done.stderr and "(exit 3)" in done.stderr
    assert "Traceback" not in done.stderr


def test_keel_observe_usage_errors_are_exit_2() -> None:
    from keel_cluster.common import find_executable

    binary = find_executable("keel-observe", ["nodes/observe/keel-observe"])
    assert binary is not None, "keel-observe is not built"
    for args in ([], ["--domain", "231"], ["--domain", "7", "--period-ms", "0"], ["--domain", "7", "--bogus"]):
        done = subprocess.run([str(binary), *args], capture_output=True, text=True, timeout=30, check=False)
        assert done.returncode == 2, (args, done.stderr)
    done = subprocess.run([str(binary), "--domain", "7", "--security", "/nonexistent"], capture_output=True,
                          text=True, timeout=30, check=False)
    assert done.returncode == 2 and "/nonexistent/ca.pem: missing" in done.stderr


def test_task_data_rates_come_from_the_nodes_status_lines(tmp_path: Path) -> None:
    # RUN_DIR/NAME.status.jsonl (keel-cluster appends every status line; run --console asks
    # for one a second): each task's executions and samples per second since the counts
    # at least RATE_MIN_NS before; a count that goes back (a new process) starts again.
    def status(t_ms: float, **counts: tuple[int, int, int]) -> str:
        return json.dumps({"t_ns": int(t_ms * MS), "node": "PN2", "role": "Observer", "task_counts": {
            task: {"executions": e, "inputs": i, "outputs": o} for task, (e, i, o) in counts.items()}}) + "\n"

    writer = Writer(tmp_path)
    writer.write_raw("PN2.status.jsonl", status(1000, taskA=(10, 0, 10)))
    writer.write_raw("PN2.status.jsonl", status(1500, taskA=(15, 0, 15)))  # too soon: no rate yet
    writer.write_raw("PN2.status.jsonl", status(2000, taskA=(30, 4, 30), taskB=(1, 1, 0)))
    writer.write_raw("PN2.status.jsonl", "not json\n")
    writer.write_raw("PN2.status.jsonl", status(3000, taskA=(40, 4, 60), taskB=(3, 5, 0)))
    feed = console.Feed(tmp_path)
    poll(feed)
    rates = [e["p"]["nodes"]["PN2"]["rates"] for e in feed.fold.events if e["a"] == "rates"]
    assert rates[0] == {"taskA": {"exec": 20.0, "in": 4.0, "out": 20.0}}  # 1000 -> 2000 ms
    assert page_state(feed)["nodes"]["PN2"]["rates"] == {"taskA": {"exec": 10.0, "in": 0.0, "out": 30.0},
                                                        "taskB": {"exec": 2.0, "in": 4.0, "out": 0.0}}
    assert feed.status()["malformed"] == 1
    # A restarted process counts from 0: no rate from the old counts.
    writer.write_raw("PN2.status.jsonl", status(4000, taskA=(2, 0, 2)))
    poll(feed)
    assert page_state(feed)["nodes"]["PN2"]["rates"] == {}
    writer.write_raw("PN2.status.jsonl", status(5000, taskA=(12, 0, 12)))
    poll(feed)
    assert page_state(feed)["nodes"]["PN2"]["rates"] == {"taskA": {"exec": 10.0, "in": 0.0, "out": 10.0}}
