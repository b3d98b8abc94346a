"""keel-node as a command: --help, input errors naming the mission file, clean SIGTERM."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time
from pathlib import Path

from keel_cluster.launcher import find_node_binary

ROOT = Path(os.environ.get("KEEL_ROOT", Path(__file__).resolve().parents[2]))


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(find_node_binary(None)), *args], capture_output=True, text=True,
                          timeout=30)


def test_help() -> None:
    done = run("--help")
    assert done.returncode == 0
    assert "--mission" in done.stdout and "--control-stdin" in done.stdout


def test_missing_flags_are_input_errors() -> None:
    assert run().returncode == 2


def test_mission_errors_name_the_file_location(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text((ROOT / "config/prototype3.yaml").read_text().replace("miss_limit: 3",
                                                                         "miss_limit: 3, bogus: 1"))
    done = run("--mission", str(bad), "--node", "PN1")
    assert done.returncode == 2
    assert f"{bad}:9:" in done.stderr


def test_unknown_node_and_unregistered_component(tmp_path: Path) -> None:
    done = run("--mission", str(ROOT / "config/prototype3.yaml"), "--node", "PN9")
    assert done.returncode == 2 and "no node 'PN9'" in done.stderr
    mission = tmp_path / "m.yaml"
    mission.write_text((ROOT / "config/prototype3.yaml").read_text().replace(
        "component: consumer", "component: kalman"))
    done = run("--mission", str(mission), "--node", "PN1")
    assert done.returncode == 2
    assert f"{mission}:20: task 'taskB': unknown component 'kalman'" in done.stderr


def test_sigterm_is_a_clean_stop(tmp_path: Path) -> None:
    process = subprocess.Popen(
        [str(find_node_binary(None)), "--mission", str(ROOT / "config/prototype3.yaml"),
         "--node", "PN2", "--domain", str(1 + os.getpid() % 200), "--trace",
         str(tmp_path / "PN2.trace.ndjson"), "--storage-db", str(tmp_path / "PN2.sqlite")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stdout is not None
    status = json.loads(process.stdout.readline())
    # A first boot runs nothing until the initial Master's boot switch; alone, PN2 declares
    # the others failed after the start-up grace, which it traces: a node at work.
    assert status["node"] == "PN2" and status["config"] == "P1" and status["tasks"] == []
    trace = tmp_path / "PN2.trace.ndjson"
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and not (trace.exists() and trace.read_text().strip()):
        time.sleep(0.1)
    process.send_signal(signal.SIGTERM)
    _, log = process.communicate(timeout=10)
    assert process.returncode == 0, log
    assert "stopping" in log
    lines = (tmp_path / "PN2.trace.ndjson").read_text().splitlines()
    assert lines and all(json.loads(line)["node"] == "PN2" for line in lines)
