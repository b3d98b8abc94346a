"""The demo's analysis on a synthetic run directory: what counts as lost, as classified
twice, the image period windows and the AOCS jump. No cluster needed."""

from __future__ import annotations

import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "nodes" / "demo"))

import demo

S = 1_000_000_000
T0 = 1_000 * S
PLAN = {"worker_node": "PN4", "worker_task": "acca1", "master": "PN1",
        "kill_worker_at_s": 10, "kill_master_at_s": 20, "duration_s": 25}


def write_run(tmp: Path, *, lose: set[int] = frozenset(), twice: set[int] = frozenset(),
              after_master: str = "online") -> Path:
    run = tmp / "run"
    eo = run / "eo"
    eo.mkdir(parents=True)
    events = [{"t_ns": T0, "action": "start", "argument": n} for n in ("PN1", "PN2", "PN3", "PN4")]
    events += [{"t_ns": T0 + 10 * S, "action": "kill", "argument": "PN4"},
               {"t_ns": T0 + 20 * S, "action": "kill", "argument": "PN1"}]
    faults = [{"kind": "kill", "target": "PN4", "detection_ms": 300.0, "total_ms": 310.0, "config": "C5",
               "new_master": "PN1"},
              {"kind": "kill", "target": "PN1", "detection_ms": 300.0, "decision_ms": 2.0, "total_ms": 320.0,
               "config": after_master, "new_master": "PN2"}]
    (run / "report.json").write_text(json.dumps({"events": events, "faults": faults, "reliability": {}}))
    camera, stats, duplicates = [], [], []
    # Until 25 s; past the Master's failure at 20 s only where the mission goes on.
    last = 250 if after_master != "SAFE" else 200
    for sequence in range(1, last):
        emitted = T0 + sequence * S // 10
        camera.append({"sequence": sequence, "resend": 0, "t_ns": emitted})
        if sequence in lose or T0 + 20 * S < emitted < T0 + 20 * S + S // 2:
            continue
        worker = "acca0" if sequence % 2 == 0 else "acca1"
        pid = 10 if worker == "acca0" else (11 if emitted < T0 + 10 * S else 12)
        row = {"sequence": sequence, "worker": worker, "worker_pid": pid, "t_ns": emitted + 40_000_000,
               "compute_ms": 2.0, "accuracy": 0.96, "width": 64}
        stats.append(row)
        if sequence in twice:
            duplicates.append({"sequence": sequence, "worker": worker, "worker_pid": 99, "kind": "classified-again"})
    for name, rows in (("camera", camera), ("stats", stats), ("duplicates", duplicates)):
        (eo / f"{name}.ndjson").write_text("".join(json.dumps(r) + "\n" for r in rows))
    aocs = []
    for step in range(1, 2001):  # the original instance until step 2000 (20 s)
        aocs.append({"step": step, "time_s": step / 100, "error_rad": 1e-5 * (1 + step % 3), "pid": 1,
                     "mode": "live", "restored": False})
    for step in range(1995, 2100):  # restored from step 1994: replays to 2030, then live
        aocs.append({"step": step, "time_s": step / 100, "error_rad": 1e-5 * (1 + step % 3), "pid": 2,
                     "mode": "replay" if step <= 2030 else "live", "restored": True})
    (eo / "aocs.ndjson").write_text("".join(json.dumps(r) + "\n" for r in aocs))
    return run


def test_a_clean_run_passes_every_check(tmp_path: Path) -> None:
    run = write_run(tmp_path)
    analysis = demo.analyse(run, json.loads((run / "report.json").read_text()), PLAN)
    results = {name: ok for name, ok, _ in demo.checks(analysis, PLAN)}
    assert all(results.values()), results
    assert analysis["period"]["two_workers_p50_ms"] == 100.0
    assert analysis["period"]["ratio"] == 1.0
    aocs = analysis["aocs"]
    assert aocs["migrated"] and aocs["replayed_same_as_original"] == 6 and aocs["replayed_differing"] == 0
    assert aocs["jump_rad"] <= aocs["nominal_step_rad"]


def test_an_unrecorded_image_is_lost_unless_safe_mode_cut_it_off(tmp_path: Path) -> None:
    # 120 was emitted at 12 s (failover window); 195 at 19.5 s, in flight when the Master died.
    run = write_run(tmp_path, lose={120, 195})
    analysis = demo.analyse(run, json.loads((run / "report.json").read_text()), PLAN)
    assert analysis["accounting"]["lost"] == [120]
    assert analysis["accounting"]["in_flight_at_master_failure"] == [195]
    failed = [name for name, ok, _ in demo.checks(analysis, PLAN) if not ok]
    assert failed == ["no image lost across the failover"]


def test_the_mission_goes_on_after_the_masters_failure(tmp_path: Path) -> None:
    # Beyond the graph: the placer's configuration after the Master's failure, the images
    # recorded after it, and the image period once it settled (from 21.3 s).
    run = write_run(tmp_path)
    analysis = demo.analyse(run, json.loads((run / "report.json").read_text()), PLAN)
    assert analysis["beyond_graph"]["config"] == "online"
    assert analysis["beyond_graph"]["decide_ms"] == 2.0
    assert analysis["period"]["recorded_after_master_failure"] == 46
    assert analysis["period"]["after_both_p50_ms"] == 100.0
    # The graph alone: safe mode stops the camera, and the demo fails.
    safe = write_run(tmp_path / "safe", after_master="SAFE")
    analysis = demo.analyse(safe, json.loads((safe / "report.json").read_text()), PLAN)
    failed = [name for name, ok, _ in demo.checks(analysis, PLAN) if not ok]
    assert failed == ["the mission goes on after the Master's failure (beyond the graph)"]


def test_a_second_classification_fails_the_demo(tmp_path: Path) -> None:
    run = write_run(tmp_path, twice={33})
    analysis = demo.analyse(run, json.loads((run / "report.json").read_text()), PLAN)
    assert analysis["accounting"]["classified_twice"] == [33]
    failed = [name for name, ok, _ in demo.checks(analysis, PLAN) if not ok]
    assert failed == ["no image classified twice"]
