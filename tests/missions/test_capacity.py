"""A mission at the capacity (core/fsm/types.hpp: 256 nodes, 1,024 tasks), end to end:
``keel-verify compile`` proves it and writes its image, the C++ loader (``keel-mission``)
builds the whole mission from it, and ``keel-node`` flies it: the Master, which runs all
1,024 tasks, and node 255 (the broadcast address when addresses were one byte) boot, print
their status and stop cleanly. One node more, or one task more, and compile refuses.

The C++ half runs under CTest (``KEEL_BUILD_DIR`` names the build); without it only the
verifier's half runs.
"""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from keel_verify import limits

ROOT = Path(__file__).resolve().parents[2]


def mission_at(nodes: int, tasks: int) -> str:
    """One phase, one configuration: every task (a built-in producer) on the Master N0,
    N1 its Observer, nothing tolerated."""
    lines = ["mission: capacity", "schema: 1", "heartbeat: {period_ms: 100, miss_limit: 3}",
             "tolerance: {node_failures: 0, nodes: []}", "nodes:"]
    lines += [f"  N{i}: {{kind: processing}}" for i in range(nodes)]
    lines += ["tasks:"]
    lines += [f"  T{i}: {{port: {i + 1}, component: producer, period_ms: 1000}}"
              for i in range(tasks)]
    lines += ["phases:", "  main:", "    initial: C1", "    configurations:", "      C1:",
              "        master: N0", "        observers: [N1]", "        tasks:"]
    lines += [f"          T{i}: N0" for i in range(tasks)]
    return "\n".join(lines) + "\n"


def compile_mission(source: Path) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k != "KEEL_SIGNING_KEY"}
    env["PYTHONPATH"] = str(ROOT / "verify")
    return subprocess.run([sys.executable, "-m", "keel_verify.cli", "compile", str(source)],
                          capture_output=True, text=True, env=env, timeout=300, check=False)


def built(name: str) -> Path | None:
    build = os.environ.get("KEEL_BUILD_DIR")
    if not build:
        return None
    candidates = [c for c in Path(build).rglob(name) if c.is_file() and os.access(c, os.X_OK)]
    assert candidates, f"{name} is not built in {build}"
    return candidates[0]


@pytest.fixture(scope="module")
def image(tmp_path_factory: pytest.TempPathFactory) -> Path:
    assert (limits.MAX_NODES, limits.MAX_TASKS) == (256, 1024)
    source = tmp_path_factory.mktemp("capacity") / "capacity.yaml"
    source.write_text(mission_at(limits.MAX_NODES, limits.MAX_TASKS))
    done = compile_mission(source)
    assert done.returncode == 0, done.stdout + done.stderr
    return source.with_suffix(".json")


def test_a_mission_at_the_capacity_compiles(image: Path) -> None:
    data = json.loads(image.read_bytes())
    assert data["capacity"] == {"max_nodes": 256, "max_tasks": 1024}
    assert len(data["content"]["nodes"]) == 256
    assert len(data["content"]["tasks"]) == 1024


@pytest.mark.parametrize(("nodes", "tasks", "what"),
                         [(257, 1, "257 nodes"), (2, 1025, "1025 tasks")], ids=["nodes", "tasks"])
def test_one_more_is_refused(tmp_path: Path, nodes: int, tasks: int, what: str) -> None:
    source = tmp_path / "over.yaml"
    source.write_text(mission_at(nodes, tasks))
    done = compile_mission(source)
    assert done.returncode == 2, done.stdout + done.stderr
    assert "out-of-range" in done.stderr and what in done.stderr
    assert not source.with_suffix(".json").exists()


def test_the_cpp_loader_builds_the_whole_mission(image: Path) -> None:
    binary = built("keel-mission")
    if binary is None:
        pytest.skip("KEEL_BUILD_DIR not set: the C++ loader is checked under CTest")
    done = subprocess.run([str(binary), str(image), "--json"], capture_output=True, text=True,
                          timeout=60, check=False)
    assert done.returncode == 0, done.stderr
    held = json.loads(done.stdout)
    assert [n["name"] for n in held["nodes"]] == [f"N{i}" for i in range(256)]
    assert [t["name"] for t in held["tasks"]] == [f"T{i}" for i in range(1024)]


def first_status(process: subprocess.Popen[str], timeout_s: float) -> dict:
    """The first JSON status line the node prints on stdout."""
    assert process.stdout is not None
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        ready, _, _ = select.select([process.stdout], [], [], 0.2)
        if ready:
            line = process.stdout.readline()
            if not line:
                break
            if line.startswith("{"):
                status: dict = json.loads(line)
                return status
        if process.poll() is not None:
            break
    raise AssertionError(f"no status line within {timeout_s} s (exit {process.poll()})")


@pytest.mark.parametrize("node", ["N0", "N255"])
def test_keel_node_flies_the_image(image: Path, tmp_path: Path, node: str) -> None:
    binary = built("keel-node")
    if binary is None:
        pytest.skip("KEEL_BUILD_DIR not set: keel-node is checked under CTest")
    stderr = tmp_path / f"{node}.log"
    with stderr.open("w") as log:
        process = subprocess.Popen(
            [str(binary), "--mission", str(image), "--node", node, "--insecure",
             "--domain", str(1 + os.getpid() % 200),
             "--storage-db", str(tmp_path / f"{node}.sqlite")],
            stdout=subprocess.PIPE, stderr=log, text=True)
        try:
            status = first_status(process, 60)
            assert status["node"] == node
            assert status["config"] == "C1" and status["phase"] == "main"
            assert status["role"] == ("Master" if node == "N0" else "Worker")
            process.send_signal(signal.SIGTERM)
            assert process.wait(timeout=30) == 0, stderr.read_text()[-3000:]
        finally:
            if process.poll() is None:
                process.kill()
                process.wait()
    text = stderr.read_text()
    assert "configured 1024 components" in text
    assert f"node address {node[1:]}" in text
