"""Starts one keel-node per node of a mission, drives a scenario, and cleans up.

The launcher talks to each node through the keel-node contract (nodes/cluster/README.md):
command-line flags, control lines on stdin (`phase NAME`, `partition NODE...`, `heal`,
`quit`), status lines (JSON) on stdout, and an NDJSON protocol trace per node. It never
leaves a process or a namespace behind: everything it starts is stopped in `close()`,
which also runs on SIGINT/SIGTERM.

Nodes fly a mission image. Given a mission YAML, the launcher first compiles it into the
run directory with `keel-verify compile` (once per mission per process: a campaign's runs
share the result) and starts no node unless the mission is proved; given an image, it
passes it on as it is.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, Callable

from keel_cluster import netns
from keel_cluster.designation import (
    DESIGNATIONS_FILE,
    VOTE_SPAN_PERIODS,
    Designation,
    Designations,
)
from keel_cluster.scenario import Event, Scenario

HISTORY_LIMIT = 100_000
# What the launcher did and when (kill, restart, partition, phase, ...), one JSON object a
# line in the run directory, appended as it happens: the console (console.py) follows a run
# from it, live or afterwards. Not `.ndjson`: keel-verify trace reads every *.ndjson of a
# run directory as a trace.
EVENTS_FILE = "events.jsonl"
# keel-verify compile proves the mission; large missions take a while.
COMPILE_TIMEOUT_S = 600
# How long `designate` waits for the designee's status line (its latest heartbeat number).
STATUS_ANSWER_S = 1.0


class LaunchError(Exception):
    pass


def find_node_binary(explicit: str | None) -> Path:
    if explicit:
        path = Path(explicit)
        if not (path.is_file() and os.access(path, os.X_OK)):
            raise LaunchError(f"--node-binary {explicit}: not an executable file")
        return path
    root = Path(os.environ.get("KEEL_ROOT", Path(__file__).resolve().parents[3]))
    build = Path(os.environ.get("KEEL_BUILD_DIR", root / "build" / "default"))
    for candidate in [build / "nodes" / "keel-node" / "keel-node", *build.rglob("keel-node")]:
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return candidate
    on_path = shutil.which("keel-node")
    if on_path:
        return Path(on_path)
    raise LaunchError(f"keel-node is not built (looked in {build}); run ./keel setup")


def node_components(node_binary: Path) -> list[str]:
    """The components `node_binary --list-components` names; none for a binary that lists
    none (a stand-in in tests): compile then checks no component."""
    try:
        done = subprocess.run([str(node_binary), "--list-components"], capture_output=True,
                              text=True, timeout=30, check=False)
    except (OSError, subprocess.TimeoutExpired):
        return []
    return done.stdout.split() if done.returncode == 0 else []


def is_image(path: Path) -> bool:
    """A mission image opens with `{` after optional whitespace; keel-node tells a YAML
    from an image the same way."""
    try:
        with open(path, "rb") as stream:
            start = stream.read(64 * 1024)
    except OSError:
        return False
    return start.removeprefix(b"\xef\xbb\xbf").lstrip(b" \t\r\n")[:1] == b"{"


# Images compiled by this process: (SHA-256 of the YAML, signing key, node binary) -> the
# image's bytes.
_compiled: dict[tuple[str, str, str], bytes] = {}


def flight_image(mission: Path, run_dir: Path, node_binary: Path | None = None,
                 signing_key: Path | None = None) -> Path:
    """The image the nodes fly: `mission` itself when it is an image, else what
    `keel-verify compile` writes for it, in `run_dir`, checked against the components of
    `node_binary` when given (a task whose component the nodes lack is a violation, not a
    refusal at boot), signed with `signing_key` when given (else with KEEL_SIGNING_KEY when
    set). Raises LaunchError, naming compile's exit code and message, when the mission is
    not proved (compile writes no image)."""
    if is_image(mission):
        return mission
    try:
        source = mission.read_bytes()
    except OSError as error:
        raise LaunchError(f"{mission}: cannot read: {error.strerror}") from None
    run_dir.mkdir(parents=True, exist_ok=True)
    image = run_dir / f"{mission.stem}.image.json"
    key = (hashlib.sha256(source).hexdigest(), str(signing_key or os.environ.get("KEEL_SIGNING_KEY", "")),
           str(node_binary or ""))
    if key in _compiled:
        image.write_bytes(_compiled[key])
        return image
    command = [sys.executable, "-m", "keel_verify.cli", "compile", str(mission), "-o", str(image)]
    if signing_key is not None:
        command += ["--sign-key", str(signing_key)]
    components = node_components(node_binary) if node_binary is not None else []
    if components:
        command += ["--components", ",".join(components)]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=COMPILE_TIMEOUT_S,
                              check=False)
    except subprocess.TimeoutExpired:
        raise LaunchError(f"keel-verify compile {mission}: no result in {COMPILE_TIMEOUT_S} s; "
                          "no node started") from None
    except OSError as error:
        raise LaunchError(f"keel-verify compile {mission}: cannot run: {error}") from None
    if done.returncode != 0:
        # compile reports the proof (violations, with counterexamples) on stdout and why
        # it wrote nothing on stderr.
        report = done.stdout.strip().splitlines()
        shown = "\n".join([*report[:20], *(["..."] if len(report) > 20 else []),
                           *done.stderr.strip().splitlines()])
        raise LaunchError(f"keel-verify compile {mission} wrote no image (exit {done.returncode}); "
                          f"no node started:\n{shown}")
    _compiled[key] = image.read_bytes()
    return image


@dataclass
class NodeProcess:
    name: str
    argv: list[str]
    log_path: Path
    process: subprocess.Popen[str] | None = None
    log: IO[str] | None = None
    status: dict[str, Any] = field(default_factory=dict)
    starts: int = 0
    reader: threading.Thread | None = None
    # Every status line in arrival order (a node prints one only when something changes),
    # at most HISTORY_LIMIT of them: benchmarks read when a configuration became active.
    history: list[dict[str, Any]] = field(default_factory=list)
    # The ground commands this process refused at admission, by reason (its status line's
    # ground.refused): each new refusal is logged as a `refused` event.
    ground_refused: dict[str, int] = field(default_factory=dict)
    # Status lines read from the node's processes so far (fresh_status waits for the next).
    lines: int = 0

    @property
    def running(self) -> bool:
        return self.process is not None and self.process.poll() is None


class Cluster:
    """A running emulated cluster. Use as a context manager."""

    def __init__(
        self,
        mission_path: Path,
        node_names: list[str],
        run_dir: Path,
        node_binary: Path,
        *,
        use_netns: bool = False,
        domain_id: int | None = None,
        extra_args: list[str] | None = None,
        echo: bool = True,
        insecure: bool = False,
        security_profile: str = "encrypt",
        security_dir: Path | None = None,
        vote_span_periods: int = VOTE_SPAN_PERIODS,
        clock_ns: Callable[[], int] = time.time_ns,
    ):
        self.mission_path = mission_path.resolve()
        # What the nodes fly (flight_image), chosen when the cluster starts.
        self.image_path: Path | None = None
        self.node_names = node_names
        self.run_dir = run_dir
        self.node_binary = node_binary
        self.use_netns = use_netns
        self.domain_id = domain_id if domain_id is not None else 100 + os.getpid() % 100
        self.extra_args = extra_args or []
        self.echo = echo
        # DDS Security (nodes/cluster/README.md, "Security"): unless insecure, credentials
        # for the mission are made (or reused) in security_dir, run_dir/security by default,
        # when the cluster starts, and every node is given them with --security.
        self.insecure = insecure
        self.security_profile = security_profile
        self.security_dir: Path | None = None if insecure else (security_dir or run_dir / "security")
        self.credentials: Any = None  # security.Manifest, once made
        self.events: list[dict[str, Any]] = []
        self.paused: set[str] = set()  # stopped (SIGSTOP): their last status is stale
        self.nodes: dict[str, NodeProcess] = {}
        self.fabric: netns.Fabric | None = None
        self._lock = threading.Lock()
        # Lines to a node's stdin come from the scenario's thread and the status poller.
        self._send_lock = threading.Lock()
        # Every status_every_s seconds each running node is asked for its status line (the
        # console's task data rates come from their counts); None: only when they change.
        self.status_every_s: float | None = None
        self._polling = threading.Event()
        self._poller: threading.Thread | None = None
        # Events are recorded from the scenario's thread and the nodes' status readers (a
        # refusal): the list and events.jsonl keep one order.
        self._events_lock = threading.Lock()
        self._previous_handlers: dict[int, Any] = {}
        # Released at the end of close() (keel_cluster.common.DomainLease), if given.
        self.lease: Any = None
        self._image_sha256 = ""
        self.public_key: str | None = None  # what nodes check the image with (_public_key)
        self._updates = 0  # update(): each new image in run_dir/update-N
        self._ground_seq = 0  # the last ground command's seq (ground_line)
        # `designate` (designation.py): the vote's span past its wait, the designations sent
        # (also those an earlier launcher recorded in the run directory), and the ground's
        # clock they are timed with (the wall clock: the record outlives this process).
        self.vote_span_periods = vote_span_periods
        self.designations = Designations(run_dir / DESIGNATIONS_FILE)
        self.clock_ns = clock_ns
        self._flown: dict[str, Any] | None = None  # the flown image, as read_mission reads it

    # -- lifecycle ---------------------------------------------------------------------

    def __enter__(self) -> Cluster:
        self.run_dir.mkdir(parents=True, exist_ok=True)
        for sig in (signal.SIGINT, signal.SIGTERM):
            self._previous_handlers[sig] = signal.signal(sig, self._on_signal)
        try:
            if self.security_dir is not None:
                from keel_cluster.security import ensure_credentials

                try:
                    self.credentials = ensure_credentials(self.mission_path, self.security_dir,
                                                          profile=self.security_profile)
                except LaunchError:
                    # A mission that is not proved says so first: its proof is the more
                    # basic problem (flight_image raises the compile's report).
                    flight_image(self.mission_path, self.run_dir, self.node_binary)
                    raise
                self.security_dir = self.credentials.directory
            self.image_path = flight_image(self.mission_path, self.run_dir, self.node_binary,
                                           self._signing_key()).resolve()
            self.public_key = self._public_key()
            if self.use_netns:
                reason = netns.probe()
                if reason:
                    raise LaunchError(f"--netns: {reason}")
                self.fabric = netns.Fabric(self._free_run_id(), self.node_names)
                self.fabric.create()
            for name in self.node_names:
                self.nodes[name] = NodeProcess(name, self._argv(name), self.run_dir / f"{name}.log")
            for name in self.node_names:
                self.start(name)
            if self.status_every_s:
                self._polling.set()
                self._poller = threading.Thread(target=self._poll_status, name="status-poller", daemon=True)
                self._poller.start()
        except BaseException:
            self.close()
            raise
        return self

    def _poll_status(self) -> None:
        assert self.status_every_s
        while self._polling.is_set():
            for name, node in list(self.nodes.items()):
                if node.running and name not in self.paused:
                    self.send(name, "status")
            time.sleep(self.status_every_s)

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _on_signal(self, signum: int, frame: object) -> None:
        self.close()
        raise KeyboardInterrupt

    def _free_run_id(self) -> int:
        existing = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True).stdout
        for candidate in range(1 + os.getpid() % 200, 255):
            if f"kc-{candidate}-" not in existing:
                return candidate
        raise LaunchError("no free network-namespace run id (stale kc-* namespaces?)")

    def _argv(self, name: str) -> list[str]:
        assert self.image_path is not None, "the cluster has not started"
        argv = [
            str(self.node_binary),
            "--mission", str(self.image_path),
            "--node", name,
            "--trace", str(self.run_dir / f"{name}.trace.ndjson"),
            "--domain", str(self.domain_id),
            "--storage-db", str(self.run_dir / f"{name}.checkpoints.sqlite"),
            "--control-stdin",
        ]
        if self.fabric is not None:
            argv += ["--interface", "eth0", "--peers", ",".join(self.fabric.peers())]
            argv = self.fabric.command(name, argv)
        else:
            argv += ["--interface", "lo", "--peers", "127.0.0.1"]
        if self.security_dir is None:
            argv += ["--insecure"]
        else:
            # Its kit: never the CA's key, the operator's or another node's (docs/security.md).
            argv += ["--security", str((self.security_dir / "kits" / name).resolve())]
        if self.public_key is not None:
            # Signed images are the default: a node flies only an image signed with the
            # mission's key (the set's, in its kit, or KEEL_SIGNING_KEY's).
            argv += ["--public-key", str(self.security_dir / "kits" / name / "mission" / "signing.pub"
                                         if self.public_key == "kit" else self.public_key)]
        return argv + self.extra_args

    def _signing_key(self) -> Path | None:
        """The key mission images are signed with: KEEL_SIGNING_KEY when set, else the
        credentials set's (secured runs); none for an insecure run."""
        if os.environ.get("KEEL_SIGNING_KEY"):
            return Path(os.environ["KEEL_SIGNING_KEY"]).resolve()
        if self.credentials is not None:
            from keel_cluster.security import MISSION_KEY

            return self.credentials.directory / MISSION_KEY
        return None

    def _public_key(self) -> str | None:
        """What nodes check the image's signature with: "kit" (the set's public key, in
        each node's kit), the public key of KEEL_SIGNING_KEY (written to the run
        directory), or none: no signing key, or an image given already compiled that is
        not signed with it (it flies as it is, its hash checked)."""
        key = self._signing_key()
        if key is None or self.image_path is None:
            return None
        from keel_verify.image import KeyFileError, key_id, load_signing_key

        try:
            wanted = key_id(load_signing_key(key).public_key())
            signature = json.loads(self.image_path.read_text(encoding="utf-8")).get("signature") or {}
        except KeyFileError as error:
            raise LaunchError(str(error)) from None
        except (OSError, ValueError) as error:
            raise LaunchError(f"{self.image_path}: cannot read the image's signature: {error}") from None
        if signature.get("key_id") != wanted:
            return None
        if self.credentials is not None and key == self.credentials.directory / "mission" / "signing.key":
            return "kit"
        public = self.run_dir / "mission-signing.pub"
        done = subprocess.run(["openssl", "pkey", "-in", str(key), "-pubout", "-out", str(public)],
                              capture_output=True, text=True, check=False)
        if done.returncode != 0:
            raise LaunchError(f"{key}: openssl pkey -pubout failed: {done.stderr.strip()[:200]}")
        return str(public)

    def start(self, name: str) -> None:
        node = self.nodes[name]
        if node.running:
            raise LaunchError(f"{name} is already running")
        if self.credentials is not None:
            from keel_cluster.security import node_kit

            node_kit(self.credentials.directory, name)  # made again: a renewal reaches it
        node.log = open(node.log_path, "a", encoding="utf-8")  # noqa: SIM115 - closed in close()
        try:
            node.process = subprocess.Popen(
                node.argv,
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=node.log,
                text=True,
                bufsize=1,
                start_new_session=True,
                env=self._environment(),
            )
        except OSError as error:
            # The binary replaced or removed meanwhile (a rebuild while a run restarts a
            # node), or not executable: said with the node and the file, no traceback.
            node.log.close()
            node.process = None
            raise LaunchError(f"{name}: cannot start {node.argv[0]}: {error.strerror}") from None
        node.starts += 1
        node.ground_refused = {}  # a new process counts from 0
        node.reader = threading.Thread(target=self._read_status, args=(node, node.process), daemon=True)
        node.reader.start()
        self._record("start" if node.starts == 1 else "restart", name)

    def _environment(self) -> dict[str, str]:
        # Components that write files (the earth-observation sink, camera and AOCS) write
        # them into the run directory unless the caller chose a place.
        env = dict(os.environ)
        env.setdefault("KEEL_EO_OUT_DIR", str((self.run_dir / "eo").resolve()))
        return env

    def _read_status(self, node: NodeProcess, process: subprocess.Popen[str]) -> None:
        assert process.stdout is not None
        history = self._status_history(node.name)
        for line in process.stdout:
            line = line.strip()
            if not line:
                continue
            try:
                status = json.loads(line)
            except json.JSONDecodeError:
                continue
            if history is not None and isinstance(status, dict):
                try:
                    history.write(line + "\n")
                    history.flush()
                except OSError:
                    history = None
            if isinstance(status, dict):
                with self._lock:
                    node.status = status
                    node.lines += 1
                    if len(node.history) < HISTORY_LIMIT:
                        node.history.append(status)
                self._note_refusals(node, status)
        if history is not None:
            history.close()

    def _status_history(self, name: str) -> IO[str] | None:
        """RUN_DIR/NAME.status.jsonl, where every status line of the node is appended as
        it comes (its processes' in turn): the run's status history (the console's task data
        rates); None when it cannot be written (said once)."""
        try:
            return open(self.run_dir / f"{name}.status.jsonl", "a", encoding="utf-8")  # noqa: SIM115
        except OSError as error:
            print(f"keel-cluster: {self.run_dir / name}.status.jsonl: cannot write: {error.strerror}",
                  file=sys.stderr)
            return None

    def _note_refusals(self, node: NodeProcess, status: dict[str, Any]) -> None:
        """A ground command a node refused at admission (signature, verb, expiry, replay,
        ...: its status line's `ground.refused` counts, core/node/ground.hpp) is logged as a
        `refused` event, `NAME REASON`, once per refusal: the console's timeline and the
        run's events show it, not only the node's log."""
        ground = status.get("ground")
        refused = ground.get("refused") if isinstance(ground, dict) else None
        if not isinstance(refused, dict):
            return
        for kind, count in sorted(refused.items()):
            if not isinstance(count, int) or isinstance(count, bool):
                continue
            for _ in range(max(0, count - node.ground_refused.get(kind, 0))):
                self._record("refused", f"{node.name} {kind}")
            node.ground_refused[kind] = max(count, node.ground_refused.get(kind, 0))

    def kill(self, name: str) -> None:
        node = self.nodes[name]
        if not node.running:
            raise LaunchError(f"{name} is not running")
        assert node.process is not None
        self._record("kill", name)
        os.killpg(node.process.pid, signal.SIGKILL)
        node.process.wait(timeout=10)
        with self._lock:
            node.status = {}

    def send(self, name: str, line: str) -> bool:
        node = self.nodes[name]
        if not node.running or node.process is None or node.process.stdin is None:
            return False
        try:
            with self._send_lock:
                node.process.stdin.write(line + "\n")
                node.process.stdin.flush()
            return True
        except (BrokenPipeError, OSError, ValueError):  # ValueError: its stdin was closed
            return False

    def partition(self, name: str) -> None:
        self._record("partition", name)
        if self.fabric is not None:
            self.fabric.set_link(name, up=False)
            return
        for other in self.node_names:
            self.send(other, f"partition {name}" if other != name else "partition " + " ".join(
                n for n in self.node_names if n != name))

    def heal(self, name: str) -> None:
        self._record("heal", name)
        if self.fabric is not None:
            self.fabric.set_link(name, up=True)
            return
        for other in self.node_names:
            self.send(other, "heal")

    def deaf(self, name: str) -> None:
        """Receive omission: `name` hears no one (it still sends) until `heal`."""
        self._record("deaf", name)
        self.send(name, "deaf")

    def pause(self, name: str) -> None:
        """Stops the node's process (SIGSTOP), as a long stall would, until `resume`."""
        self._signal(name, "pause", signal.SIGSTOP)

    def resume(self, name: str) -> None:
        self._signal(name, "resume", signal.SIGCONT)

    def _signal(self, name: str, action: str, signum: signal.Signals) -> None:
        node = self.nodes[name]
        if not node.running or node.process is None:
            raise LaunchError(f"{name} is not running")
        self._record(action, name)
        os.killpg(node.process.pid, signum)
        (self.paused.add if signum == signal.SIGSTOP else self.paused.discard)(name)

    # The ground's commands (docs/operations.md): each recorded, signed and sent to every node.
    def phase(self, phase: str) -> None:
        """Enter `phase` (only the Master acts on it)."""
        self.ground("phase", phase)

    def recover(self, config: str) -> None:
        """Leave safe mode for `config` (only the Master acts on it)."""
        self.ground("recover", config)

    def exclude(self, name: str) -> None:
        """Hold node `name` out (it resigns; no Master readmits it)."""
        self.ground("exclude", name)

    def readmit(self, name: str) -> None:
        """Let node `name`, held out, be readmitted again."""
        self.ground("readmit", name)

    def pause_task(self, task: str) -> None:
        """Pause `task` where it runs (it stays placed; never an essential task)."""
        self.ground("pause-task", task)

    def resume_task(self, task: str) -> None:
        """Let `task`, paused, run again from its last state."""
        self.ground("resume-task", task)

    def designate(self, name: str) -> Designation:
        """The ground's vote for node `name` to take over a cluster left headless by a tie
        (spec/Designate.tla; docs/operations.md, `designate`): `designate NAME WAIT SPAN
        ECHO`, ECHO the heartbeat number of `name`'s status line read just before, WAIT and
        SPAN by the ground's rule (designation.py). Raises LaunchError, sending nothing,
        for a node not in the mission or not a processing node, a mission without
        heartbeat.tie_grace, an insecure cluster (a node takes designate only signed), or a
        designee down, stopped or silent (its heartbeat number unknown)."""
        if name not in self.nodes:
            raise LaunchError(f"no node {name} in the mission (its nodes: {', '.join(self.node_names)})")
        flown = self.flown_mission()
        kind = (flown["nodes"].get(name) or {}).get("kind")
        if kind != "processing":
            raise LaunchError(f"{name} is no processing node ({kind}): only a monitor, a processing node, takes over")
        heartbeat = flown["heartbeat"]
        period_ms = heartbeat.get("period_ms")
        if not int(heartbeat.get("tie_grace") or 0) > 0:
            raise LaunchError("the mission sets no heartbeat.tie_grace: the ground is no voter of its leases, "
                              "and every node refuses a designation")
        if self.credentials is None:
            raise LaunchError("an --insecure cluster cannot designate: a node takes designate only signed "
                              "by the operator")
        granted = (self.credentials.tools.get("operator") or {}).get("verbs")
        if isinstance(granted, list) and "designate" not in granted:
            raise LaunchError(f"the operator's grant in {self.credentials.directory} does not "
                              f"name designate ({', '.join(map(str, granted))}): every node would refuse it; "
                              "make the credentials again (keel-cluster credentials)")
        assert isinstance(period_ms, int) and period_ms > 0, heartbeat
        echo = self._heartbeat_seq(name)
        designation = self.designations.designate(name, echo, self.clock_ns(), period_ms * 1_000_000,
                                                  self.vote_span_periods)
        # Remembered before it is sent: a designation recorded and never sent only delays
        # a later one; one sent and not recorded could let two votes overlap.
        problem = self.designations.record(designation)
        if problem is not None:
            print(f"keel-cluster: {problem} (the designation is remembered in this run only)", file=sys.stderr)
        self.ground("designate", *designation.arguments())
        return designation

    def flown_mission(self) -> dict[str, Any]:
        """The image the nodes fly, in the mission YAML's shape (common.read_mission)."""
        if self._flown is None:
            assert self.image_path is not None, "the cluster has not started"
            from keel_cluster.common import read_mission

            self._flown = read_mission(self.image_path)
        return self._flown

    def _heartbeat_seq(self, name: str) -> int:
        """The number of `name`'s latest heartbeat, from a status line it prints on request."""
        node = self.nodes[name]
        if not node.running:
            raise LaunchError(f"{name} is down: the ground echoes its latest heartbeat number, read from "
                              "its status line")
        if name in self.paused:
            raise LaunchError(f"{name} is stopped (pause): its status, and the heartbeat number the ground "
                              "echoes, are unknown")
        status = self.fresh_status(name, STATUS_ANSWER_S)
        if status is None:
            raise LaunchError(f"{name} printed no status line within {STATUS_ANSWER_S:g} s: the heartbeat "
                              "number the ground echoes is unknown")
        seq = status.get("heartbeat_seq")
        if not isinstance(seq, int) or isinstance(seq, bool) or seq < 0:
            raise LaunchError(f"{name}'s status line has no heartbeat_seq (a node binary that does not "
                              "take designate?)")
        return seq

    def fresh_status(self, name: str, timeout_s: float) -> dict[str, Any] | None:
        """A status line of `name` printed after this call asked for it; None when none
        came within timeout_s (the node is down, stopped or busy)."""
        node = self.nodes[name]
        with self._lock:
            before = node.lines
        if not self.send(name, "status"):
            return None
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            with self._lock:
                if node.lines > before:
                    return dict(node.status)
            time.sleep(0.005)
        return None

    def update(self, mission: str) -> None:
        """An update (docs/operations.md, "Updating the mission image"): `mission` (a YAML,
        compiled and signed as at start, or an image) becomes the image every node flies.
        Every node stops (quit, one after the other), then each starts on it; a node that
        finds its state saved on another image discards its protocol state, as a cold start
        does, and keeps its checkpoints, its revision and the ground's seq, so the new
        image's initial Master boots its initial configuration and the tasks resume from
        the Storage node's checkpoints. A revision below the one the nodes flew is refused
        by every node (exit 2)."""
        self._record("update", mission)
        self._updates += 1
        image = flight_image(Path(mission).resolve(), self.run_dir / f"update-{self._updates}",
                             self.node_binary, self._signing_key()).resolve()
        running = [name for name, node in self.nodes.items() if node.running]
        for name in running:
            self.stop(name)
        self.image_path = image
        self.public_key = self._public_key()
        self._image_sha256 = ""
        self._flown = None
        for name, node in self.nodes.items():
            node.argv = self._argv(name)
        for name in running:
            self.start(name)

    def stop(self, name: str) -> None:
        """A clean stop of node `name` (quit; SIGKILL after 5 s)."""
        node = self.nodes[name]
        if not node.running or node.process is None:
            return
        # Its last counts in NODE.status.jsonl (a status line is printed on a change only).
        self.send(name, "status")
        self.send(name, "quit")
        try:
            node.process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            os.killpg(node.process.pid, signal.SIGKILL)
            node.process.wait(timeout=5)
        with self._lock:
            node.status = {}

    def ground_line(self, verb: str, *arguments: str) -> str:
        """The control line of a ground command (docs/operations.md): signed by the
        operator of the run's credentials, its seq the time in microseconds (above every
        earlier one); unsigned on an insecure cluster, whose nodes take it as it is (a
        verb of one argument only)."""
        if self.credentials is None:
            return " ".join([verb, *arguments])
        from keel_cluster.security import ground_line

        assert self.image_path is not None, "the cluster has not started"
        if not self._image_sha256:
            self._image_sha256 = str(json.loads(self.image_path.read_text(encoding="utf-8"))["sha256"])
        self._ground_seq = max(self._ground_seq + 1, time.time_ns() // 1000)
        return ground_line(self.credentials.directory, self._image_sha256, self._ground_seq, verb, *arguments)

    def ground(self, verb: str, *arguments: str) -> None:
        """Records a ground command and sends it to every node, as the ground's uplink would."""
        self._record(verb, " ".join(arguments))
        line = self.ground_line(verb, *arguments)
        for other in self.node_names:
            self.send(other, line)
            # Its status line at once: a refusal at admission changes nothing else it
            # shows, and is logged from the line's counts (_note_refusals).
            self.send(other, "status")

    def close(self) -> None:
        self._polling.clear()
        if self._poller is not None:
            self._poller.join(timeout=5)
            self._poller = None
        for node in self.nodes.values():
            if node.running and node.process is not None:
                try:
                    os.killpg(node.process.pid, signal.SIGCONT)  # a paused node must hear it
                except ProcessLookupError:
                    pass
                self.send(node.name, "status")  # its last counts, in NODE.status.jsonl
                self.send(node.name, "quit")
                try:
                    os.killpg(node.process.pid, signal.SIGTERM)
                except ProcessLookupError:
                    pass
        deadline = time.monotonic() + 5
        for node in self.nodes.values():
            if node.process is None:
                continue
            try:
                node.process.wait(timeout=max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                try:
                    os.killpg(node.process.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                node.process.wait(timeout=5)
            if node.log is not None:
                node.log.close()
                node.log = None
        if self.fabric is not None:
            self.fabric.destroy()
            self.fabric = None
        for sig, handler in self._previous_handlers.items():
            signal.signal(sig, handler)
        self._previous_handlers.clear()
        if self.lease is not None:
            self.lease.release()
            self.lease = None

    # -- scenario ----------------------------------------------------------------------

    def _record(self, action: str, argument: str) -> None:
        with self._events_lock:
            event = {"t_ns": time.time_ns(), "action": action, "argument": argument}
            self.events.append(event)
            try:
                with open(self.run_dir / EVENTS_FILE, "a", encoding="utf-8") as log:
                    log.write(json.dumps(event) + "\n")
            except OSError as error:
                print(f"keel-cluster: {self.run_dir / EVENTS_FILE}: cannot write: {error.strerror}", file=sys.stderr)
        if self.echo and action not in ("start",):
            print(f"keel-cluster: {action} {argument}", file=sys.stderr)

    def apply(self, event: Event) -> Any:
        """Applies a scenario's (or the operator's) event; what its action gives (designate:
        the Designation sent), else None."""
        actions = {"kill": self.kill, "restart": self.start, "partition": self.partition,
                   "heal": self.heal, "phase": self.phase, "deaf": self.deaf,
                   "pause": self.pause, "resume": self.resume, "recover": self.recover,
                   "exclude": self.exclude, "readmit": self.readmit, "update": self.update,
                   "pause-task": self.pause_task, "resume-task": self.resume_task,
                   "designate": self.designate}
        if event.action not in actions:  # pragma: no cover - scenario.py accepts only these
            raise LaunchError(f"unknown action {event.action}")
        return actions[event.action](event.argument)

    def history(self, name: str) -> list[dict[str, Any]]:
        with self._lock:
            return list(self.nodes[name].history)

    def statuses(self) -> dict[str, dict[str, Any]]:
        with self._lock:
            return {name: dict(node.status) for name, node in self.nodes.items()}

    def run(self, scenario: Scenario, status_every_s: float = 1.0,
            typed: Callable[[], list[Event | None]] | None = None) -> None:
        """Applies the scenario's events at their times until its duration; `typed` (the
        operator's console, `keel-cluster run --ground`) gives events to apply now, None
        to end the run."""
        start = time.monotonic()
        pending = list(scenario.events)
        next_status = start + status_every_s
        while True:
            now = time.monotonic() - start
            while pending and pending[0].at_s <= now:
                self.apply(pending.pop(0))
            for event in typed() if typed is not None else []:
                if event is None:
                    return
                try:
                    self.apply(event)
                except LaunchError as error:
                    print(f"keel-cluster: {event.action} {event.argument}: {error}", file=sys.stderr)
            if now >= scenario.duration_s:
                break
            if self.echo and time.monotonic() >= next_status:
                print(format_status(self.statuses(), now), file=sys.stderr)
                next_status += status_every_s
            wake = min([scenario.duration_s] + [e.at_s for e in pending[:1]]) - now
            time.sleep(max(0.0, min(0.05, wake)))


def format_status(statuses: dict[str, dict[str, Any]], now_s: float) -> str:
    parts = []
    for name, status in statuses.items():
        if not status:
            parts.append(f"{name}:down")
            continue
        role = str(status.get("role", "?"))[:3]
        config = status.get("config", "?")
        tasks = ",".join(status.get("tasks", []))
        parts.append(f"{name}:{role}/{config}" + (f"[{tasks}]" if tasks else ""))
    return f"  t={now_s:5.1f}s  " + "  ".join(parts)
