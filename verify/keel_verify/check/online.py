"""The proof of a mission's online phases (docs/missions.md, "Placement modes and what is
proved"): ``keel-place IMAGE --prove`` runs the runtime's placer (core/placement) on every
failure sequence within the tolerance, and its violations become the verifier's.

A phase placed ``online`` has its initial configuration alone, and a ``graph+online`` one
leaves the placer to answer where its graph says SAFE, has no edge or names another Master
than the election: the decision graph's own proof does not report those
(:func:`answered_by_placer`); ``keel-place --prove`` proves what the placer answers there.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
from dataclasses import replace
from pathlib import Path
from typing import Any

from keel_verify.check.model import KINDS
from keel_verify.check.result import PROVED, CheckResult, Step, Violation
from keel_verify.image import encode_file, seal
from keel_verify.mission import Mission

# What the decision graph of a phase placed online leaves to the placer: a failure with no
# edge, an edge to SAFE, a Master other than the election's.
PLACER_ANSWERS = frozenset({"missing-transition", "safe-mode-within-tolerance", "master-mismatch"})
# Failure sequences keel-place --prove explores at most (core/placement/prove.hpp).
MAX_PROVE_FAILURES = 8
# keel-place --prove on a large mission takes seconds; this bounds a runaway one.
PROVE_TIMEOUT_S = 600
PLACE_ENV = "KEEL_PLACE"


class ProverUnavailable(Exception):
    """keel-place is not built or found (exit 2: a missing tool)."""


class ProverFailed(Exception):
    """keel-place refused the image keel-verify wrote, or crashed (exit 4: internal)."""


def online_phases(mission: Mission) -> list[str]:
    """The phases whose placement is not graph, in file order."""
    return [name for name, phase in mission.phases.items() if phase.placement != "graph"]


def answered_by_placer(mission: Mission, violations: list[Violation]) -> list[Violation]:
    """The graph's violations without those the placer answers in a phase placed online."""
    online = set(online_phases(mission))
    return [v for v in violations if not (v.phase in online and v.kind in PLACER_ANSWERS)]


def find_keel_place() -> Path:
    """$KEEL_PLACE, else keel-place in $KEEL_BUILD_DIR (default build/default), else on
    PATH. Raises :class:`ProverUnavailable` naming how to build it."""
    explicit = os.environ.get(PLACE_ENV)
    if explicit:
        path = Path(explicit)
        if path.is_file() and os.access(path, os.X_OK):
            return path
        raise ProverUnavailable(f"${PLACE_ENV} names {explicit}, which is not an executable")
    root = Path(os.environ.get("KEEL_ROOT", Path(__file__).resolve().parents[3]))
    build = Path(os.environ.get("KEEL_BUILD_DIR", root / "build" / "default"))
    candidate = build / "core" / "placement" / "keel-place"
    if candidate.is_file() and os.access(candidate, os.X_OK):
        return candidate
    on_path = shutil.which("keel-place")
    if on_path:
        return Path(on_path)
    raise ProverUnavailable(
        f"proving a phase placed online runs keel-place, which is not built ({candidate} "
        f"does not exist): build it with `cmake --build {build} --target keel-place`, or name "
        f"it with ${PLACE_ENV} or $KEEL_BUILD_DIR")


def _image(mission: Mission, result: CheckResult) -> dict[str, Any]:
    """An image of the mission for keel-place (the graph's own verdict is reported apart)."""
    from keel_verify.compile import build_image  # compile imports check: not at the top

    proved = replace(result, status=PROVED, violations=[])
    source = Path(mission.path).read_bytes() if Path(mission.path).is_file() else b""
    return seal(build_image(mission, proved, Path(mission.path).name, source, None), None)


def _keel_place(mission: Mission, result: CheckResult, mode: str, extra: list[str],
                stdin: str | None = None) -> tuple[Path, subprocess.CompletedProcess[str]]:
    """keel-place IMAGE `mode` `extra` on the mission compiled (written to a temporary
    directory): the binary and its run. Raises :class:`ProverUnavailable` (not found, or
    not runnable) and :class:`ProverFailed` (it ran past PROVE_TIMEOUT_S)."""
    keel_place = find_keel_place()
    with tempfile.TemporaryDirectory(prefix="keel-place-") as directory:
        image = Path(directory) / "mission.json"
        image.write_bytes(encode_file(_image(mission, result)))
        try:
            run = subprocess.run([str(keel_place), str(image), mode, *extra], input=stdin,
                                 capture_output=True, text=True, timeout=PROVE_TIMEOUT_S, check=False)
        except subprocess.TimeoutExpired:
            raise ProverFailed(f"keel-place {mode} took more than {PROVE_TIMEOUT_S} s") from None
        except OSError as error:
            raise ProverUnavailable(f"cannot run {keel_place}: {error.strerror or error}") from None
    return keel_place, run


def placer_answers(mission: Mission, queries: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """keel-place --batch's answers to ``queries`` (core/placement/main.cpp), one each, on
    the mission compiled for the placer alone (its graph is not proved here). Raises
    :class:`ProverUnavailable` and :class:`ProverFailed`."""
    from keel_verify.compile import PROOF_STATS  # compile imports check: not at the top

    if not queries:
        return []
    result = CheckResult(mission=mission.name, file=str(mission.path), status=PROVED,
                         violations=[], stats={name: 0 for name in PROOF_STATS})
    _, run = _keel_place(mission, result, "--batch", [],
                         "".join(json.dumps(q) + "\n" for q in queries))
    if run.returncode != 0:
        why = " ".join(run.stderr.split()) or f"exit {run.returncode}"
        raise ProverFailed(f"keel-place --batch refused the compiled mission: {why}")
    try:
        answers = [json.loads(line) for line in run.stdout.splitlines() if line.strip()]
    except json.JSONDecodeError as error:
        raise ProverFailed(f"keel-place --batch answered no JSON: {error}") from None
    if len(answers) != len(queries) or any("error" in a for a in answers):
        raise ProverFailed(f"keel-place --batch answered {answers[:3]} to {queries[:3]}")
    return answers


def run_prover(mission: Mission, result: CheckResult, failures: int | None) -> dict[str, Any]:
    """keel-place --prove's answer on the compiled mission (written to a temporary
    directory). ``failures``: the longest sequence (default: tolerance.node_failures)."""
    extra = [] if failures is None else ["--failures", str(min(failures, MAX_PROVE_FAILURES))]
    keel_place, run = _keel_place(mission, result, "--prove", extra)
    if run.returncode == 2 and "--prove" in run.stderr and "not expected" in run.stderr:
        raise ProverUnavailable(
            f"{keel_place} was built before it could prove (no --prove): rebuild it with "
            f"`cmake --build {keel_place.parents[2]} --target keel-place`")
    if run.returncode not in (0, 1, 3):
        why = " ".join(run.stderr.split()) or f"exit {run.returncode}"
        raise ProverFailed(f"keel-place --prove refused the compiled image: {why}")
    try:
        proof = json.loads(run.stdout)
    except json.JSONDecodeError as error:
        raise ProverFailed(f"keel-place --prove answered no JSON: {error}") from None
    proof.pop("image", None)  # the temporary file, gone
    return proof


def violations_of(mission: Mission, proof: dict[str, Any]) -> list[Violation]:
    """keel-place's violations as the verifier's, each at its phase's line, its path the
    failure sequence (``online`` where the placer answers)."""
    from keel_verify.check.core import column_of  # core imports this module

    out = []
    for phase_proof in proof["phases"]:
        phase = mission.phases[phase_proof["phase"]]
        col = column_of(mission.path, phase.line, phase.name)
        for v in phase_proof["violations"]:
            failures = list(v["failures"])
            kind = v["kind"] if v["kind"] in KINDS else "task-missing"
            start = mission.phases[v.get("start", phase.name)]
            steps = [Step("start", start.initial, phase=start.name)]
            for event in v.get("path", [{"failure": n} for n in failures]):
                if "failure" in event:
                    steps.append(Step("failure", "online", node=event["failure"]))
                else:
                    steps.append(Step("phase", "online", phase=event["phase"]))
            if kind in ("safe-mode-within-tolerance", "master-mismatch") and steps[-1].event == "failure":
                steps[-1] = Step("failure", "SAFE", node=failures[-1])
            out.append(Violation(kind=kind, phase=phase.name, config="online", task=None,
                                 node=failures[-1] if failures else None,
                                 message=f"{v['message']} (placement {phase.placement})",
                                 failures=failures, steps=steps, file=mission.path,
                                 line=phase.line, col=col))
        hidden = phase_proof["violation_count"] - len(phase_proof["violations"])
        if hidden > 0 and out:
            out[-1].message += f" ({hidden} more violations of phase {phase.name} not listed)"
    return out


def incomplete(proof: dict[str, Any]) -> str:
    """Why the proof is undecided (a phase not fully explored), or ""."""
    phases = [p["phase"] for p in proof["phases"] if not p.get("complete", True)]
    if not phases:
        return ""
    return (f"keel-place --prove gave up on phase {', '.join(phases)} before exploring every "
            f"failure sequence (its bound on failures applied)")


def summary_lines(proof: dict[str, Any]) -> list[str]:
    """One line per phase: what was proved within the tolerance and counted beyond it."""
    lines = []
    for p in proof["phases"]:
        within = p["within_tolerance"]
        beyond = p["beyond_tolerance"]
        text = (f"phase {p['phase']} ({p['placement']}): keel-place proved "
                f"{within['failed_sets']} failed sets within tolerance"
                if p["violation_count"] == 0 else
                f"phase {p['phase']} ({p['placement']}): {p['violation_count']} violation(s) "
                f"over {within['failed_sets']} failed sets within tolerance")
        if within["shedding"]:
            text += f" ({within['shedding']} shed non-essential tasks: {_shed(within)})"
        if beyond["failed_sets"]:
            text += (f"; beyond tolerance, up to {p['failures']} failures: "
                     f"{beyond['running_every_task']} run every task, {beyond['shedding']} shed "
                     f"({_shed(beyond)}), {beyond['safe']} reach SAFE")
        text += f" ({p['states']} states, {p['ms']:.0f} ms)"
        lines.append(text)
    return lines


def _shed(outcomes: dict[str, Any]) -> str:
    return ", ".join(f"{task} {n}" for task, n in outcomes["shed"].items()) or "none"
