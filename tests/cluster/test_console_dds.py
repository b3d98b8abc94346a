"""`keel-cluster console --dds`: the console joins a real secured cluster's DDS domain read
only (keel-observe, as the subscribe-only keel-monitor identity) instead of reading its
files. prototype3 on loopback, PN2 killed: the console's state shows PN1 Master in P1, then
PN2's exclusion into P3 within a second of the Master's command, and the folder it recorded
plays back to the same state."""

from __future__ import annotations

import http.client
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from keel_cluster import analysis, console

sys.path.insert(0, str(Path(__file__).resolve().parent))
from console_runs import ROOT  # noqa: E402

WITHIN_S = 1.0  # from the Master's command (its trace's t_ns) to the console's state
WAIT_S = 60.0  # any other wait: generous, it is not a measure


def keel_cluster(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "keel_cluster.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=ROOT,
                            env=dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path)))


def said(process: subprocess.Popen[str], pattern: str) -> re.Match[str]:
    assert process.stderr is not None
    for line in process.stderr:
        found = re.search(pattern, line)
        if found:
            return found
    raise AssertionError(f"never said {pattern!r} (exit {process.poll()})")


def state_of(port: int) -> dict[str, Any]:
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    connection.request("GET", "/api/state")
    return json.loads(connection.getresponse().read())


def wait_for(port: int, what: str, check: Any) -> tuple[float, dict[str, Any]]:
    """The wall time (ns) at which the console's state first passed `check`, and the state."""
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        state = state_of(port)
        if check(state):
            return time.time_ns(), state
        time.sleep(0.02)
    raise AssertionError(f"the console never showed {what}: {json.dumps(state)[:2000]}")


def master(state: dict[str, Any]) -> tuple[str, str | None, list[str]] | None:
    masters = [(name, n) for name, n in state["nodes"].items() if n.get("role") == "Master" and not n.get("resigned")]
    if len(masters) != 1:
        return None
    name, node = masters[0]
    return name, node.get("masterConfig") or node.get("config"), node.get("view") or []


def test_the_console_follows_a_secured_cluster_on_its_dds_domain(tmp_path: Path) -> None:
    text = (ROOT / "config" / "prototype3.yaml").read_text()
    mission = tmp_path / "prototype3.yaml"
    mission.write_text(text.replace("miss_limit: 3}", "miss_limit: 4}"))  # a loaded machine: no false declaration
    scenario = tmp_path / "scenario.yaml"
    scenario.write_text("duration: 18s\nevents:\n  - at 8s kill PN2\n")
    run_dir = tmp_path / "run"
    run = keel_cluster("run", str(mission), "--scenario", str(scenario), "--run-dir", str(run_dir), "--quiet")
    watching: subprocess.Popen[str] | None = None
    try:
        domain = said(run, r"keel-cluster: DDS domain (\d+) .*secured").group(1)
        image = next(run_dir.glob("*.image.json"))
        folder = tmp_path / "watch"
        watching = keel_cluster("console", "--dds", domain, "--security", str(run_dir / "security"),
                                "--mission", str(image), str(folder))
        port = int(said(watching, r"console of DDS domain \d+ \(as keel-monitor; recorded in .*\) at "
                                  r"http://127\.0\.0\.1:(\d+)/").group(1))
        _, before = wait_for(port, "PN1 Master of P1, and every node's role", lambda s: master(s) == ("PN1", "P1", [])
                             and {name for name, n in s["nodes"].items() if "role" in n} == {"PN1", "PN2", "PN3", "ST1"})
        assert before["nodes"]["ST1"]["role"] == "Worker" and before["nodes"]["PN2"]["role"] == "Observer"
        shown_ns, after = wait_for(port, "PN2 out, P3", lambda s: master(s) == ("PN1", "P3", ["PN2"]))
        assert after["nodes"]["PN1"]["view"] == ["PN2"]
        # Its own state says P3 once the switch completed: the path's next step.
        wait_for(port, "the path P1, P3", lambda s: [step["c"] for step in s["path"].values()] == ["P1", "P3"])
        run.communicate(timeout=120)
        assert run.returncode == 0
        watching.send_signal(signal.SIGTERM)
        _, stderr = watching.communicate(timeout=60)
        assert watching.returncode == 0, stderr
        assert f"replay the observation with: keel-cluster console {folder}" in stderr
    finally:
        for process in (run, watching):
            if process is not None and process.poll() is None:
                process.kill()
                process.wait()
    # The Master's command, stamped in its own trace, against when the console showed it.
    commands = [json.loads(line) for line in (run_dir / "PN1.trace.ndjson").read_text().splitlines()
                if '"BroadcastCommand"' in line]
    [exclusion] = [c for c in commands if c["args"]["c"] == "P3" and c["vars"]["failed"] == ["PN2"]][:1]
    delay_ms = (shown_ns - exclusion["t_ns"]) / 1e6
    observed = [json.loads(line) for line in (folder / console.OBSERVED_FILE).read_text().splitlines()]
    assert observed[0]["observed"] == "joined" and observed[0]["secured"] is True
    seen = {line["observed"] for line in observed}
    assert {"state", "heartbeat", "command", "activate", "ack", "declare"} <= seen, seen
    print(f"the exclusion's command reached the console's state {delay_ms:.0f} ms after PN1 stamped it; "
          f"{len(observed)} lines observed")
    assert delay_ms <= WITHIN_S * 1000, delay_ms
    # The folder plays back alone (its copy of the image, its observation) to the same state.
    replay = console.Feed(folder)
    while replay.poll_once():
        pass
    replay.poll_once()
    assert master(replay.fold.state) == ("PN1", "P3", ["PN2"])
    assert replay.status()["malformed"] == 0
    # The files' console and the wire's agree on the path through the graph.
    files = console.Feed(run_dir)
    while files.poll_once():
        pass
    assert [s["c"] for s in files.fold.state["path"].values()] == ["P1", "P3"]
    assert analysis  # the same package's analysis module is what the files' console times faults with
