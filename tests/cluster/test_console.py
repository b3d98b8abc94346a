"""The console without a browser: tailing a run directory, the fold of trace lines into
events and state, the measures, the HTTP API and the command line (keel_cluster/console.py).
Traces come from keel-sim (no cluster) or are written here line by line."""

from __future__ import annotations

import http.client
import json
import random
import shutil
import socket
import subprocess
import sys
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
    while feed.poll_once():
        pass


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
    # keel-node appends: a restarted node's first line follows its predecessor's half line.
    writer = Writer(tmp_path)
    writer.write_raw("PN1.trace.ndjson", json.dumps(line(10, "PN1", "switch", "Hold", n="PN1"))[:30])
    writer.write([line(20, "PN1", "switch", "Hold", n="PN1"), line(30, "PN1", "switch", "Release", n="PN1")])
    feed = console.Feed(tmp_path)
    poll(feed)
    assert feed.status()["malformed"] == 1
    assert [e["a"] for e in feed.fold.events if e.get("d")] == ["Release"]


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
    # PN2's clock went back: its last line stays after the one it wrote before.
    assert said == [(10, "PN1 holds its tasks (no lease)"), (20, "PN2 holds its tasks (no lease)"),
                    (25, "kill PN3"), (30, "PN1 releases its tasks"), (40, "PN2 releases its tasks"),
                    (35, "PN2 holds its tasks (no lease)")]
    assert feed.fold.state["nodes"]["PN2"]["held"] is True


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
    ])
    said = [e["d"] for e in result.events if e.get("d")]
    assert said == [
        "PN1 declares PN4 failed (missed)",
        "PN1 excludes PN4 -> C5",
        "acca1 starts on PN2 from checkpoint 12 (lineage 1.2)",
        "switch to C5 complete (PN1)",
    ]
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


def test_past_its_limit_the_feed_counts_checkpoints_and_keeps_the_rest(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(console, "EVENT_LIMIT", 10)
    monkeypatch.setattr(console, "EVENT_LIMIT_HARD", 14)
    writer = Writer(tmp_path)
    writer.write([line(t, "ST1", "switch", "StoreCheckpoint", {"stored": {"taskB": t}}, t="taskB", version=t,
                       **{"from": "PN3"}) for t in range(1, 21)])
    feed = console.Feed(tmp_path)
    poll(feed)
    writer.write([line(100 + t, "PN1", "heartbeat", "DeclareFailed", m="PN1", n=f"N{t}") for t in range(8)])
    poll(feed)
    kinds = [e["k"] for e in feed.fold.events]
    assert kinds.count("declare") == 4 and feed.truncated  # the hard limit: nothing more
    assert [e["i"] for e in feed.fold.events] == list(range(len(kinds)))
    assert feed.status()["dropped"] > 0 and feed.status()["truncated"] is True
    assert feed.fold.state["nodes"]["ST1"]["stored"] == {"taskB": 20}  # the state saw them all


# --- The launcher's events -----------------------------------------------------------------


def test_the_launcher_logs_what_it_does_in_the_run_directory(tmp_path: Path) -> None:
    cluster = Cluster(ROOT / "config" / "prototype3.yaml", ["PN1"], tmp_path, Path("/bin/true"),
                      echo=False, insecure=True)
    cluster._record("kill", "PN3")
    cluster._record("phase", "science")
    logged = [json.loads(x) for x in (tmp_path / EVENTS_FILE).read_text().splitlines()]
    assert logged == cluster.events


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


# --- The HTTP API --------------------------------------------------------------------------


@pytest.fixture
def server(sim_run: tuple[Path, list[dict[str, Any]], str]) -> console.ConsoleServer:
    serving = console.serve(sim_run[0])
    yield serving
    serving.close()


def get(server: console.ConsoleServer, path: str, host: str | None = None) -> tuple[int, dict[str, str], bytes]:
    connection = http.client.HTTPConnection("127.0.0.1", server.server_address[1], timeout=10)
    connection.request("GET", path, headers={"Host": host} if host else {})
    response = connection.getresponse()
    body = response.read()
    connection.close()
    return response.status, dict(response.getheaders()), body


def wait_for_feed(server: console.ConsoleServer) -> None:
    for _ in range(200):
        answer = json.loads(get(server, "/api/status")[2])
        if answer["events"] and answer["passes"] > 1:
            return
        __import__("time").sleep(0.05)
    raise AssertionError("the feed read nothing")


def test_the_page_and_its_assets_are_served_from_the_package(server: console.ConsoleServer) -> None:
    assert server.server_address[0] == "127.0.0.1"
    for path, kind in (("/", "text/html"), ("/console.js", "text/javascript"), ("/console.css", "text/css")):
        status, headers, body = get(server, path)
        assert status == 200 and headers["Content-Type"].startswith(kind) and body
    assert get(server, "/../console.py")[0] == 404
    assert get(server, "/console.py")[0] == 404


def test_nothing_the_page_uses_comes_from_the_network() -> None:
    for asset in console.STATIC_DIR.iterdir():
        text = asset.read_text()
        assert "http://" not in text and "https://" not in text and "//cdn" not in text, asset.name
        assert "@import" not in text and "url(http" not in text, asset.name


def test_a_page_asked_for_by_another_name_is_refused(server: console.ConsoleServer) -> None:
    assert get(server, "/", host="attacker.example:80")[0] == 403
    assert get(server, "/", host=f"localhost:{server.server_address[1]}")[0] == 200


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
        self.sock = socket.create_connection(("127.0.0.1", server.server_address[1]), timeout=10)
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


# --- The command line ----------------------------------------------------------------------


def keel_cluster(*args: str, timeout: float = 30) -> subprocess.CompletedProcess[str]:
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
        connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
        connection.request("GET", "/api/status")
        assert json.loads(connection.getresponse().read())["waiting"] is True
        process.terminate()
        assert process.wait(timeout=10) == 0
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
