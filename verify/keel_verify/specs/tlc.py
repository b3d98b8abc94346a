"""Run TLC on one model and read its verdict.

TLC is run in a scratch copy of ``spec/`` (so that neither its state directory nor the
trace-explorer modules it writes on an error ever land in the repository), with
``-workers auto`` and the throughput (parallel) garbage collector. The verdict comes
from two sources that must agree: TLC's exit code and its final lines
("Model checking completed. No error has been found.", "Invariant X is violated.", ...).

Progress: TLC 2.18 reports how far it got ("Progress(D) at ...: X states generated, Y
distinct states found, Z states left on queue") a few seconds after it starts and then
once a minute, and has no option to report more often. To report every few seconds,
TLC runs inside ``KeelTlcProgress`` (a small Java class beside this module, compiled
once with javac into the cache), which starts TLC unchanged and prints the model
checker's live counts every ``progress_s`` seconds; without javac TLC runs alone and its
own reports are the progress. Either way the counts reach ``on_progress`` as
:class:`Progress` while TLC runs.

Simulation mode (``-simulate num=N -depth D -seed S``, a manifest model's "simulate"): TLC
draws N random behaviours and checks the invariants in each; it reports the states it
checked ("Progress: X states checked.") and no distinct-state count, and ends with
"Finished in ..." where an exhaustive run says "No error has been found". A violation
reads as in an exhaustive run.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

from .. import resources
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
# A full progress report: depth, generated, distinct, on queue.
_PROGRESS_REPORT = re.compile(
    r"^Progress\((\d+)\) at .*: ([\d,]+) states generated.*?, ([\d,]+) distinct states "
    r"found.*?, ([\d,]+) states left on queue"
)
# KeelTlcProgress's live counts (same order).
_PROBE = re.compile(r"^@keel-progress (\d+) (\d+) (\d+) (\d+)$")
_DEPTH = re.compile(r"^The depth of the complete state graph search is (\d+)\.")
_INVARIANT = re.compile(r"^Error: Invariant (\w+) is violated")
_ACTION_PROPERTY = re.compile(r"^Error: Action property (\w+) is violated")
_ASSUMPTION = re.compile(r"^Error: Assumption (.*) is false")
_SIMULATED = re.compile(r"^Progress: ([\d,]+) states checked")
_FINISHED = re.compile(r"^Finished in ")
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
    # Simulation mode: the states TLC checked in its random behaviours (no distinct count),
    # and the run's depth, traces and seed.
    states_checked: int | None = None
    simulation: dict[str, int] | None = None

    def as_json(self) -> dict[str, object]:
        data: dict[str, object] = {
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
        if self.simulation is not None:
            data["simulation"] = self.simulation
            data["states_checked"] = self.states_checked
        return data


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
    simulate: bool = False,
) -> TlcResult:
    """Read TLC's output: statistics, the violated property, the error trace.

    The exit code and the final lines are cross-checked: an exit code of 0 without the
    success line, or a violation code without its error line, is undecided. In
    simulation mode (``simulate``) the success line is TLC's "Finished in" after a count
    of the states it checked.
    """
    verdict, text = meaning(exit_code)
    result = TlcResult(exit_code=exit_code, verdict=verdict, meaning=text, seconds=0.0)
    lines = output.splitlines()
    saw_success = False
    saw_error_line = False
    saw_finished = False
    partial: tuple[int, int, int] | None = None
    for line in lines:
        stripped = line.strip()
        if simulated := _SIMULATED.match(stripped):
            result.states_checked = int(simulated.group(1).replace(",", ""))
        elif _FINISHED.match(stripped):
            saw_finished = True
        elif stats := _STATS.match(stripped):
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
    if simulate:
        saw_success = saw_finished and result.states_checked is not None
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


@dataclass(frozen=True)
class Progress:
    """How far a running TLC got, ``seconds`` after it started."""

    seconds: float
    depth: int
    states_generated: int
    distinct_states: int
    queue: int


def progress_of(line: str, seconds: float) -> Progress | None:
    """The counts of a progress line of TLC's or of KeelTlcProgress's, else None."""
    stripped = line.strip()
    match = _PROBE.match(stripped) or _PROGRESS_REPORT.match(stripped)
    if match is None:
        return None
    depth, generated, distinct, queue = (int(g.replace(",", "")) for g in match.groups())
    return Progress(seconds, depth, generated, distinct, queue)


PROGRESS_CLASS = "KeelTlcProgress"
PROGRESS_SOURCE = Path(__file__).with_name(f"{PROGRESS_CLASS}.java")


def _javac() -> str | None:
    """javac: $KEEL_JAVAC, beside the java that runs TLC, or on the PATH."""
    explicit = os.environ.get("KEEL_JAVAC")
    if explicit:
        return shutil.which(explicit)
    java = shutil.which(resources.java_command())
    if java:
        beside = Path(java).resolve().parent / "javac"
        if beside.is_file() and os.access(beside, os.X_OK):
            return str(beside)
    return shutil.which("javac")


@lru_cache(maxsize=4)
def progress_classpath(jar: Path) -> Path | None:
    """The folder holding the compiled KeelTlcProgress class, compiled on first use into
    the cache (the checkout's .cache/, or ~/.cache/keel); None when it cannot be."""
    try:
        source = PROGRESS_SOURCE.read_bytes()
    except OSError:
        return None
    digest = hashlib.sha256(source + jar.name.encode()).hexdigest()[:12]
    target = resources.cache_dir() / "tlc" / f"progress-{digest}"
    if (target / f"{PROGRESS_CLASS}.class").is_file():
        return target
    javac = _javac()
    if javac is None:
        return None
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        building = Path(tempfile.mkdtemp(prefix=".progress-", dir=target.parent))
        try:
            completed = subprocess.run(
                [javac, "-nowarn", "-cp", str(jar), "-d", str(building),
                 str(PROGRESS_SOURCE)],
                capture_output=True, timeout=300, check=False)
            if completed.returncode != 0:
                return None
            try:
                os.rename(building, target)  # atomic: a concurrent run may have won
            except OSError:
                pass
        finally:
            shutil.rmtree(building, ignore_errors=True)
    except (OSError, subprocess.SubprocessError):
        return None
    return target if (target / f"{PROGRESS_CLASS}.class").is_file() else None


def java_command(jar: Path, workers: str, heap: str | None,
                 scratch: Path | None = None, progress_s: float = 0.0,
                 quick: bool = False) -> list[str]:
    """The command that runs TLC; with ``progress_s`` > 0, inside KeelTlcProgress when it
    is available. ``quick``: the JVM compiles with its quick compiler only (C1), which
    halves a short run (most of it is spent compiling with C2) and slows a long one by a
    third or more."""
    command = [resources.java_command(), "-XX:+UseParallelGC"]
    if quick:
        command.append("-XX:TieredStopAtLevel=1")
    if scratch is not None:
        # TLC unpacks its standard modules (TLC.tla, Sequences.tla...) into java.io.tmpdir:
        # concurrent runs sharing /tmp raced on them ("Module-Table lookup failure").
        command.append(f"-Djava.io.tmpdir={scratch}")
    if heap:
        command.append(f"-Xmx{heap}")
    helper = progress_classpath(jar) if progress_s > 0 else None
    classpath = f"{jar}{os.pathsep}{helper}" if helper is not None else str(jar)
    command += resources.class_archive_options(command[0], classpath)
    if helper is not None:
        command += [f"-Dkeel.progress.ms={int(progress_s * 1000)}",
                    "-cp", classpath, PROGRESS_CLASS]
    else:
        command += ["-cp", classpath, "tlc2.TLC"]
    return command + ["-workers", workers]


# The TLC processes running now, in every thread: stop_all() kills them (keel-verify specs
# runs several at once and is stopped in its main thread).
_RUNNING: set[subprocess.Popen[str]] = set()
_RUNNING_LOCK = threading.Lock()


def stop_all() -> None:
    """Kill every TLC process a run_tlc of this process started and that still runs."""
    with _RUNNING_LOCK:
        running = list(_RUNNING)
    for process in running:
        if process.poll() is None:
            process.kill()


def _wait(process: subprocess.Popen[str], timeout_s: float | None) -> tuple[int | None, float]:
    """Wait for ``process``, killed after ``timeout_s``: (its exit code, None on a time-out;
    the CPU seconds it used). The CPU time is the process's own (wait4), right also when
    other threads run and reap other model checkers meanwhile."""
    expired = threading.Event()

    def expire() -> None:
        expired.set()
        process.kill()

    timer = threading.Timer(timeout_s, expire) if timeout_s is not None else None
    if timer is not None:
        timer.daemon = True
        timer.start()
    try:
        _, status, usage = os.wait4(process.pid, 0)
        process.returncode = os.waitstatus_to_exitcode(status)
        cpu_s = usage.ru_utime + usage.ru_stime
    except ChildProcessError:  # reaped elsewhere: the exit code without the CPU time
        process.wait()
        cpu_s = 0.0
    finally:
        if timer is not None:
            timer.cancel()
    return (None if expired.is_set() else process.returncode), cpu_s


def _run_streaming(command: list[str], cwd: Path, timeout_s: float | None,
                   on_progress: Callable[[Progress], None] | None
                   ) -> tuple[str, int | None, float]:
    """Run TLC, reading its output as it comes; (output, exit code or None on time-out,
    CPU seconds). KeelTlcProgress's lines go to ``on_progress`` and are left out of the
    output."""
    started = time.monotonic()
    process = subprocess.Popen(command, cwd=cwd, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, errors="replace")
    with _RUNNING_LOCK:
        _RUNNING.add(process)
    lines: list[str] = []

    def read() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            progress = progress_of(line, time.monotonic() - started)
            if not line.startswith("@keel-progress"):
                lines.append(line)
            if progress is not None and on_progress is not None:
                on_progress(progress)

    reader = threading.Thread(target=read, name="tlc-output", daemon=True)
    reader.start()
    exit_code: int | None = None
    cpu_s = 0.0
    try:
        exit_code, cpu_s = _wait(process, timeout_s)
    finally:
        # On a time-out, and when this process is stopped (SIGTERM, Ctrl-C): no model
        # checker is left running.
        if process.poll() is None:
            process.kill()
            process.wait()
        with _RUNNING_LOCK:
            _RUNNING.discard(process)
        reader.join()
        if process.stdout is not None:
            process.stdout.close()
    return "".join(lines), exit_code, cpu_s


def run_tlc(
    jar: Path,
    spec_dir: Path,
    module: str,
    cfg_text: str,
    extra_files: dict[str, str] | None = None,
    workers: str = "auto",
    timeout_s: float | None = None,
    heap: str | None = None,
    progress_s: float = 0.0,
    on_progress: Callable[[Progress], None] | None = None,
    quick: bool = False,
    simulate: list[str] | None = None,
) -> TlcResult:
    """Model-check ``module`` (a file of ``spec_dir`` or of ``extra_files``) with cfg_text.

    Every ``.tla`` file of ``spec_dir`` and of its ``mutants/`` folder is copied into a
    scratch directory together with ``extra_files`` (name -> text), and TLC runs there.
    Deadlock checking is the cfg's business (CHECK_DEADLOCK). With ``progress_s`` > 0,
    ``on_progress`` hears how far TLC got about every ``progress_s`` seconds. ``quick``:
    see :func:`java_command`. ``simulate``: TLC's simulation-mode arguments
    (``-simulate num=N -depth D -seed S``), which run it in that mode.
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
        command = java_command(jar, workers, heap, scratch,
                               progress_s if on_progress is not None else 0.0, quick) + [
            "-config", cfg_path.name,
            "-metadir", str(scratch / "states"),
            "-cleanup",
        ]
        command += simulate or []
        command.append(f"{module}.tla")
        started = time.monotonic()
        try:
            output, exit_code, cpu_seconds = _run_streaming(command, scratch, timeout_s,
                                                            on_progress)
        except FileNotFoundError as error:
            return TlcResult(None, INPUT_ERROR, f"cannot run java: {error}", 0.0)
        seconds = time.monotonic() - started
        sources = {path.stem: path.read_text() for path in scratch.glob("*.tla")}
    result = parse_output(output, exit_code, cfg_text, sources, simulate=bool(simulate))
    result.seconds = seconds
    result.cpu_seconds = cpu_seconds
    result.output = output
    return result


def find_jar(explicit: str | None = None) -> Path | None:
    """The TLC jar: --tlc-jar, $KEEL_TLC_JAR, a checkout's .cache/tlc, ~/.cache/keel/tlc
    (:func:`keel_verify.resources.find_tlc_jar`)."""
    return resources.find_tlc_jar(explicit)
