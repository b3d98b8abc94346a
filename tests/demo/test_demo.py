"""`nodes/demo/run-demo --short` end to end: stages, report, accounting, failover, AOCS.

Needs keel-node in $KEEL_BUILD_DIR (CTest sets it) and TLC (./keel setup). Runs in about a
minute: 256 px scenes, a 24 s cluster run.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(os.environ.get("KEEL_ROOT", Path(__file__).resolve().parents[2]))
BUILD = Path(os.environ.get("KEEL_BUILD_DIR", ROOT / "build" / "default"))
sys.path.insert(0, str(ROOT / "tests"))
from docblocks import differs, text_block  # noqa: E402


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory) -> tuple[subprocess.CompletedProcess[str], Path]:
    if not (BUILD / "nodes" / "keel-node" / "keel-node").exists():
        pytest.fail(f"keel-node is not built in {BUILD}")
    out = tmp_path_factory.mktemp("demo")
    env = dict(os.environ, KEEL_DEMO_PYTHON=sys.executable, KEEL_BUILD_DIR=str(BUILD))
    result = subprocess.run([str(ROOT / "nodes" / "demo" / "run-demo"), "--short", "--out", str(out)],
                            capture_output=True, text=True, env=env, timeout=280, cwd=ROOT, check=False)
    return result, out


def test_demo_succeeds_and_announces_every_stage(demo: tuple[subprocess.CompletedProcess[str], Path]) -> None:
    result, _ = demo
    assert result.returncode == 0, result.stdout[-4000:] + result.stderr[-2000:]
    for number in range(1, 5):
        assert f"[{number}/4]" in result.stdout
    assert "PROVED" in result.stdout


def test_the_summary_reads_as_docs_clusters_md_shows(
        demo: tuple[subprocess.CompletedProcess[str], Path]) -> None:
    # The doc shows a --short run's summary, numbers aside (docblocks.py); the mission's
    # path as from the checkout.
    _, out = demo
    printed = (out / "summary.txt").read_text().replace(f"{ROOT}/", "").splitlines()
    problem = differs(text_block("docs/clusters.md", "Keel earth-observation demo"), printed)
    assert problem is None, "docs/clusters.md's demo summary: " + problem


def test_report_exists(demo: tuple[subprocess.CompletedProcess[str], Path]) -> None:
    _, out = demo
    for name in ("index.html", "summary.txt", "summary.json", "image_period.png", "timeline.png", "aocs.png"):
        assert (out / name).stat().st_size > 0, name
    assert list((out / "run" / "eo").glob("overlay-*.png"))
    assert "image period" in (out / "summary.txt").read_text()


def test_every_image_accounted_for(demo: tuple[subprocess.CompletedProcess[str], Path]) -> None:
    _, out = demo
    summary = json.loads((out / "summary.json").read_text())
    accounting = summary["accounting"]
    assert accounting["recorded"] > 50
    assert accounting["lost"] == []
    assert accounting["classified_twice"] == []
    assert accounting["recorded_never_emitted"] == []
    # Both workers' images were recorded, before and after the relocation.
    workers = {key.split()[0] for key in summary["acca"]["by_worker"]}
    assert workers == {"acca0", "acca1"}
    assert len(summary["acca"]["by_worker"]) == 3, "acca1 should run in two processes across the failover"


def test_reconfiguration_happened(demo: tuple[subprocess.CompletedProcess[str], Path]) -> None:
    _, out = demo
    summary = json.loads((out / "summary.json").read_text())
    plan = summary["plan"]
    switched = {f["target"]: f for f in summary["faults"] if f.get("total_ms") is not None}
    assert plan["worker_node"] in switched, summary["faults"]
    assert plan["master"] in switched, summary["faults"]
    reliability = summary["reliability"]
    assert reliability["double_activations"] == 0
    assert reliability["split_masters"] == 0


def test_image_period_and_aocs_continuity(demo: tuple[subprocess.CompletedProcess[str], Path]) -> None:
    _, out = demo
    summary = json.loads((out / "summary.json").read_text())
    assert summary["period"]["two_workers_p50_ms"] <= 150
    assert summary["period"]["ratio"] <= 2.0
    aocs = summary["aocs"]
    assert aocs["migrated"]
    assert aocs["jump_rad"] <= aocs["nominal_step_rad"]
