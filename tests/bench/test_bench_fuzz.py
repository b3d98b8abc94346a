"""bench-fuzz's ledger: runs of the same fuzzed sources add up towards the 10^7 goal, a
finding on them spoils it, a change to any fuzzed source (or an uncommitted one) starts
the count again (not a change to a unit test), and a ledger that is not one is refused
with nothing written."""

from __future__ import annotations

import importlib.machinery
import importlib.util
import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _bench_fuzz():
    loader = importlib.machinery.SourceFileLoader("bench_fuzz", str(ROOT / "tests/bench/bench-fuzz"))
    spec = importlib.util.spec_from_loader("bench_fuzz", loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


bench = _bench_fuzz()


def _run(sources: str, executions: int, findings: int = 0) -> dict:
    return {"sources": sources, "commit": "c0ffee", "date": "2026-11-30T00:00:00+00:00",
            "executions": executions, "findings": findings, "seconds": 10.0}


def test_runs_of_the_same_sources_add_up_to_the_goal(tmp_path: Path) -> None:
    ledger = tmp_path / "ledger.json"
    first = bench.add_to_ledger(ledger, _run("a" * 16, 6_000_000))
    assert first["executions"] == 6_000_000 and not first["met"]
    # Another version's run is kept, but counts for its own sources only.
    other = bench.add_to_ledger(ledger, _run("b" * 16, 9_000_000))
    assert other["runs"] == 1 and not other["met"]
    second = bench.add_to_ledger(ledger, _run("a" * 16, 4_000_000))
    assert (second["runs"], second["executions"], second["findings"]) == (2, 10_000_000, 0)
    assert second["met"]
    assert len(json.loads(ledger.read_text())["runs"]) == 3


def test_a_finding_on_the_sources_means_the_goal_is_not_met(tmp_path: Path) -> None:
    ledger = tmp_path / "ledger.json"
    bench.add_to_ledger(ledger, _run("a" * 16, 9_000_000, findings=1))
    total = bench.add_to_ledger(ledger, _run("a" * 16, 9_000_000))
    assert total["executions"] == 18_000_000 and total["findings"] == 1 and not total["met"]


def test_a_file_that_is_not_a_ledger_is_refused_and_left_alone(tmp_path: Path) -> None:
    ledger = tmp_path / "ledger.json"
    ledger.write_text('{"runs": 3}\n')
    with pytest.raises(SystemExit, match="not a fuzz ledger"):
        bench.add_to_ledger(ledger, _run("a" * 16, 1))
    assert ledger.read_text() == '{"runs": 3}\n'


@pytest.mark.skipif(shutil.which("git") is None, reason="needs git")
def test_the_sources_are_named_by_their_trees_and_unnamed_when_changed(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    repo = tmp_path / "repo"
    for path in bench.FUZZED_PATHS:
        target = repo / path
        if Path(path).suffix:
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(f"{path}\n")
        else:
            target.mkdir(parents=True, exist_ok=True)
            (target / "file.cpp").write_text(f"{path}\n")
    (repo / "README.md").write_text("not fuzzed\n")
    (repo / "core/fsm/tests").mkdir()
    (repo / "core/fsm/tests/unit_test.cpp").write_text("a unit test\n")

    def git(*args: str) -> None:
        subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True)

    git("init", "-q")
    git("add", "-A")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "one")
    monkeypatch.setattr(bench, "ROOT", repo)
    sources, head = bench.fuzzed_sources()
    assert sources is not None and len(sources) == 16 and head != "unknown"

    # A file outside the fuzzed sources changes nothing, nor does a unit test of theirs,
    # committed or not.
    (repo / "README.md").write_text("changed\n")
    (repo / "core/fsm/tests/unit_test.cpp").write_text("another unit test\n")
    assert bench.fuzzed_sources()[0] == sources
    git("add", "-A")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "tests")
    assert bench.fuzzed_sources()[0] == sources
    # An uncommitted change to a fuzzed source: no name, so the run is not added.
    (repo / "core/fsm/file.cpp").write_text("changed\n")
    assert bench.fuzzed_sources()[0] is None
    # Committed, it is another version of the sources.
    git("add", "-A")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "two")
    changed = bench.fuzzed_sources()[0]
    assert changed is not None and changed != sources


def test_a_fuzzer_older_than_its_sources_is_not_counted(tmp_path: Path,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    repo = tmp_path / "repo"
    (repo / "core/fsm").mkdir(parents=True)
    source = repo / "core/fsm/node_protocol.cpp"
    source.write_text("code\n")
    subprocess.run(["git", "-C", str(repo), "init", "-q"], check=True)
    subprocess.run(["git", "-C", str(repo), "add", "-A"], check=True)
    monkeypatch.setattr(bench, "ROOT", repo)
    fuzzer = tmp_path / "keel-protocol-fuzz"
    fuzzer.write_text("binary\n")
    os.utime(source, (1_000_000, 1_000_000))
    os.utime(fuzzer, (2_000_000, 2_000_000))
    assert bench.built_after_sources(fuzzer)
    os.utime(source, (3_000_000, 3_000_000))
    assert not bench.built_after_sources(fuzzer)
