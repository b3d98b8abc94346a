"""keel-node as a command: --help, input errors naming the mission file, credentials refused
with the file and the reason (exit 4), clean SIGTERM."""

from __future__ import annotations

import datetime as dt
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from keel_cluster.launcher import find_node_binary
from keel_cluster.security import make_credentials, node_kit

ROOT = Path(os.environ.get("KEEL_ROOT", Path(__file__).resolve().parents[2]))


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(find_node_binary(None)), *args], check=False, capture_output=True, text=True,
                          timeout=30)


def test_help() -> None:
    done = run("--help")
    assert done.returncode == 0
    assert "--mission" in done.stdout and "--control-stdin" in done.stdout


def test_missing_flags_are_input_errors() -> None:
    assert run().returncode == 2


def test_a_node_runs_secured_unless_told_insecure() -> None:
    done = run("--mission", str(ROOT / "config/prototype3.yaml"), "--node", "PN1")
    assert done.returncode == 2
    assert "a node runs secured: give --security DIR" in done.stderr
    done = run("--mission", str(ROOT / "config/prototype3.yaml"), "--node", "PN1", "--insecure",
               "--security", "/nonexistent")
    assert done.returncode == 2 and "exclude each other" in done.stderr


def test_domains_are_checked() -> None:
    base = ["--mission", str(ROOT / "config/prototype3.yaml"), "--node", "PN1", "--insecure"]
    for flag, value in (("--domain", "233"), ("--data-domain", "-1"), ("--data-domain", "x")):
        done = run(*base, flag, value)
        assert done.returncode == 2 and f"{flag} {value}: not a DDS domain id" in done.stderr, done
    done = run(*base, "--domain", "7", "--data-domain", "7")
    assert done.returncode == 2 and "needs a DDS domain of its own" in done.stderr, done.stderr


@pytest.fixture(scope="module")
def credentials(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("creds") / "security"
    make_credentials(ROOT / "config/prototype3.yaml", out)
    return out


def refused(tmp_path: Path, security: Path, node: str = "PN1") -> subprocess.CompletedProcess[str]:
    # The credentials are judged before the mission is read.
    return run("--mission", str(ROOT / "config/prototype3.yaml"), "--node", node,
               "--security", str(security), "--domain", str(1 + os.getpid() % 200),
               "--storage-db", str(tmp_path / "n.sqlite"))


def test_missing_credentials_are_refused_naming_the_file(tmp_path: Path) -> None:
    done = refused(tmp_path, tmp_path / "nowhere")
    assert done.returncode == 4, done.stderr
    assert f"credentials refused: {tmp_path / 'nowhere' / 'ca.pem'}: missing or unreadable" in done.stderr


def test_another_nodes_credentials_are_refused(tmp_path: Path, credentials: Path) -> None:
    # PN2's identity placed where PN1's belongs: a node given another node's credentials.
    swapped = tmp_path / "swapped"
    shutil.copytree(credentials, swapped)
    shutil.rmtree(swapped / "nodes" / "PN1")
    shutil.copytree(credentials / "nodes" / "PN2", swapped / "nodes" / "PN1")
    done = refused(tmp_path, swapped)
    assert done.returncode == 4, done.stderr
    assert "nodes/PN1/cert.pem: is the identity of 'PN2', not of node 'PN1'" in done.stderr


def test_an_expired_certificate_is_named_as_such(tmp_path: Path) -> None:
    out = tmp_path / "old"
    make_credentials(ROOT / "config/prototype3.yaml", out, days=1,
                     not_before=dt.datetime.now(dt.UTC) - dt.timedelta(days=3))
    done = refused(tmp_path, out)
    assert done.returncode == 4, done.stderr
    assert "the identity CA certificate expired on" in done.stderr or \
        "the identity certificate expired on" in done.stderr, done.stderr


def test_a_node_never_holds_the_cas_key_the_operators_or_another_nodes(tmp_path: Path,
                                                                       credentials: Path,
                                                                       image: Path) -> None:
    # The set's folder holds the CA's key, the operator's and every node's: a node given it
    # refuses to start (exit 4), naming the key; its kit (keel-cluster credentials --kit)
    # holds only public material and its own key.
    kit = node_kit(credentials, "PN2")
    assert not (kit / "ca.key").exists() and not (kit / "operator" / "key.pem").exists()
    assert sorted(p.name for p in (kit / "nodes").iterdir()) == ["PN2"]
    done = run("--mission", str(image), "--node", "PN2", "--security", str(credentials),
               "--domain", str(1 + os.getpid() % 200))
    assert done.returncode == 4, done.stderr
    assert f"credentials refused: {credentials / 'ca.key'}: a node never holds this key" in done.stderr
    for secret in ("operator/key.pem", "mission/signing.key", "nodes/PN1/key.pem"):
        leaky = tmp_path / secret.replace("/", "-")
        shutil.copytree(kit, leaky)
        (leaky / secret).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(credentials / secret, leaky / secret)
        done = run("--mission", str(image), "--node", "PN2", "--security", str(leaky),
                   "--domain", str(1 + os.getpid() % 200))
        assert done.returncode == 4 and f"{leaky / secret}: a node never holds this key" in done.stderr, done.stderr


def test_a_revoked_node_is_refused(tmp_path: Path, credentials: Path) -> None:
    from keel_cluster.security import revoke
    copy = tmp_path / "revoked"
    shutil.copytree(credentials, copy)
    revoke(copy, "PN3")
    done = refused(tmp_path, copy, "PN3")
    assert done.returncode == 4, done.stderr
    assert "nodes/PN3/cert.pem: was revoked on" in done.stderr


def keel_verify(*args: str) -> subprocess.CompletedProcess[str]:
    # The verifier of the Python that runs the tests (the project's venv, wherever
    # KEEL_CACHE put it).
    return subprocess.run([sys.executable, "-m", "keel_verify.cli", *args], check=False, capture_output=True,
                          text=True, timeout=120)


def compile_image(mission: Path, out: Path) -> Path:
    done = keel_verify("compile", str(mission), "-o", str(out))
    assert done.returncode == 0, done.stdout + done.stderr
    return out


@pytest.fixture(scope="module")
def image(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return compile_image(ROOT / "config/prototype3.yaml",
                         tmp_path_factory.mktemp("image") / "prototype3.json")


def test_a_mission_yaml_is_refused_saying_how_to_compile(tmp_path: Path) -> None:
    done = run("--mission", str(ROOT / "config/prototype3.yaml"), "--node", "PN1", "--insecure")
    assert done.returncode == 2
    assert "is not a mission image: a node flies only what keel-verify proved; compile it: " \
        "keel-verify compile" in done.stderr, done.stderr
    # A mission error is the verifier's to name (file:line:col), before any image exists.
    bad = tmp_path / "bad.yaml"
    bad.write_text((ROOT / "config/prototype3.yaml").read_text().replace("miss_limit: 3",
                                                                         "miss_limit: 3, bogus: 1"))
    done = keel_verify("compile", str(bad), "-o", str(tmp_path / "bad.json"))
    assert done.returncode == 2 and f"{bad}:9:" in done.stdout + done.stderr
    assert not (tmp_path / "bad.json").exists()


def test_a_tampered_image_is_refused(tmp_path: Path, image: Path) -> None:
    tampered = tmp_path / "tampered.json"
    tampered.write_text(image.read_text().replace('"PN3"', '"PN9"', 1))
    done = run("--mission", str(tampered), "--node", "PN1", "--insecure")
    assert done.returncode == 2, done.stderr
    assert "compile the mission again" in done.stderr


def test_unknown_node_and_unregistered_component(tmp_path: Path, image: Path) -> None:
    done = run("--mission", str(image), "--node", "PN9", "--insecure")
    assert done.returncode == 2 and "no node 'PN9'" in done.stderr, done.stderr
    mission = tmp_path / "m.yaml"
    mission.write_text((ROOT / "config/prototype3.yaml").read_text().replace(
        "component: consumer", "component: kalman"))
    other = compile_image(mission, tmp_path / "m.json")
    done = run("--mission", str(other), "--node", "PN1", "--insecure")
    assert done.returncode == 2
    assert "task 'taskB': unknown component 'kalman'" in done.stderr, done.stderr


def test_sigterm_is_a_clean_stop(tmp_path: Path, credentials: Path, image: Path) -> None:
    process = subprocess.Popen(
        [str(find_node_binary(None)), "--mission", str(image),
         "--node", "PN2", "--security", str(node_kit(credentials, "PN2")), "--domain", str(1 + os.getpid() % 200),
         "--trace",
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


def test_an_older_mission_revision_is_refused(tmp_path: Path) -> None:
    # PN2 flies revision 2 and saves it with its state; booted on revision 1 it refuses
    # (exit 2, both revisions and the state file named), even with --cold-start; revision
    # 3 (a rollback is a new revision) flies, and so does revision 2 again on a fresh file.
    def image_of(revision: int) -> Path:
        mission = tmp_path / f"r{revision}.yaml"
        mission.write_text((ROOT / "config/prototype3.yaml").read_text().replace(
            "schema: 1\n", f"schema: 1\nrevision: {revision}\n", 1))
        return compile_image(mission, tmp_path / f"r{revision}.json")

    database = tmp_path / "PN2.sqlite"

    def fly(image: Path, *extra: str) -> subprocess.CompletedProcess[str]:
        process = subprocess.Popen(
            [str(find_node_binary(None)), "--mission", str(image), "--node", "PN2", "--insecure",
             "--domain", str(1 + os.getpid() % 200), "--storage-db", str(database), *extra],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        assert process.stdout is not None
        line = process.stdout.readline()  # a first status line: it flies
        if line:
            process.send_signal(signal.SIGTERM)
        out, err = process.communicate(timeout=20)
        return subprocess.CompletedProcess(process.args, process.returncode, line + out, err)

    assert json.loads(fly(image_of(2)).stdout.splitlines()[0])["node"] == "PN2"
    for extra in ((), ("--cold-start",)):
        done = fly(image_of(1), *extra)
        assert done.returncode == 2, done.stderr
        assert "revision 1, older than revision 2 this node flew" in done.stderr, done.stderr
        assert str(database) in done.stderr
    assert fly(image_of(3)).returncode == 0
    assert fly(image_of(2)).returncode == 2
    for leftover in (database, Path(f"{database}-wal"), Path(f"{database}-shm"), Path(f"{database}.state")):
        leftover.unlink(missing_ok=True)
    assert fly(image_of(2)).returncode == 0


def test_a_node_warns_well_before_its_credentials_expire(tmp_path: Path, credentials: Path,
                                                        image: Path) -> None:
    # A node names the first of its credentials to expire in its status line, and warns
    # once it is within a tenth of that credential's validity (at least a day): a set valid
    # for 1 day warns at start; the 30-day set does not.
    short = tmp_path / "short"
    make_credentials(ROOT / "config/prototype3.yaml", short, days=1)
    for folder, warns in ((short, True), (credentials, False)):
        process = subprocess.Popen(
            [str(find_node_binary(None)), "--mission", str(image), "--node", "PN2", "--security",
             str(node_kit(folder, "PN2")), "--domain", str(1 + (os.getpid() + 7) % 200)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        assert process.stdout is not None
        status = json.loads(process.stdout.readline())
        time.sleep(0.5)
        process.send_signal(signal.SIGTERM)
        _, log = process.communicate(timeout=10)
        assert process.returncode == 0, log
        first = status["credentials"]
        assert first["warning"] is warns, first
        assert 0 < first["in_s"] <= (86_400 if warns else 31 * 86_400), first
        assert str(folder / "kits" / "PN2") in first["file"] and first["first_expiry"].endswith("Z"), first
        assert ("expires on" in log and "renew the credentials" in log) is warns, log


def test_a_node_takes_a_ground_command_only_where_it_can_save_it_and_flies_without_an_operator(
        tmp_path: Path, credentials: Path, image: Path) -> None:
    # docs/operations.md: a secured node without a state database admits no ground
    # command (it could not refuse the command replayed after a restart): `unsaved`. A
    # node whose operator files fail their check (here: gone from its kit) still flies,
    # logs why, and refuses every ground command, naming the problem.
    from keel_cluster.security import ground_line

    sha = json.loads(image.read_text())["sha256"]
    line = ground_line(credentials, sha, 1, "phase", "science")
    kit = node_kit(credentials, "PN2")
    orphan = tmp_path / "orphan"
    shutil.copytree(kit, orphan)
    shutil.rmtree(orphan / "operator")
    for folder, db, why in ((kit, False, "ground command refused (unsaved)"),
                            (orphan, True, "ground command refused (signature): this node has no valid operator")):
        argv = [str(find_node_binary(None)), "--mission", str(image), "--node", "PN2", "--security",
                str(folder), "--domain", str(1 + (os.getpid() + 11) % 200), "--control-stdin"]
        if db:
            argv += ["--storage-db", str(tmp_path / f"{folder.name}.sqlite")]
        process = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                   text=True)
        assert process.stdout is not None and process.stdin is not None
        json.loads(process.stdout.readline())
        process.stdin.write(line + "\nstatus\n")
        process.stdin.flush()
        time.sleep(0.5)
        process.stdin.write("quit\n")
        process.stdin.flush()
        out, log = process.communicate(timeout=10)
        assert process.returncode == 0, log
        assert why in log, log
        if folder == orphan:
            assert "the ground's operator:" in log and "takes no ground command" in log, log


def realtime_permitted() -> bool:
    """Whether this process's children may use SCHED_FIFO at keel-node's default loop
    priority (root, CAP_SYS_NICE or RLIMIT_RTPRIO of at least 50)."""
    probe = subprocess.run([sys.executable, "-c", "import os; os.sched_setscheduler(0, os.SCHED_FIFO, "
                            "os.sched_param(50))"], check=False, capture_output=True)
    return probe.returncode == 0


def memory_lock_permitted() -> bool:
    import resource
    return os.geteuid() == 0 or resource.getrlimit(resource.RLIMIT_MEMLOCK)[0] == resource.RLIM_INFINITY


def test_realtime_flags_are_checked() -> None:
    base = ["--mission", str(ROOT / "config/prototype3.yaml"), "--node", "PN1", "--insecure", "--realtime"]
    for flags, says in ((["--realtime-priority", "0"], "--realtime-priority 0: a SCHED_FIFO priority, 1..99"),
                        (["--task-priority", "50"], "--task-priority 50: 0 (normal scheduling) or a SCHED_FIFO "
                                                    "priority below the loop's (50)"),
                        (["--realtime-priority", "30", "--task-priority", "30"], "below the loop's (30)"),
                        (["--loop-budget", "101"], "--loop-budget 101: a percentage"),
                        (["--loop-budget", "5000"], "--loop-budget 5000: out of range"),
                        (["--loop-budget", "x"], "--loop-budget x: not a number")):
        done = run(*base, *flags)
        assert done.returncode == 2 and says in done.stderr, (flags, done.stderr)
    done = run(*base[:-1], "--loop-budget", "10")
    assert done.returncode == 2 and "--loop-budget need --realtime" in done.stderr, done.stderr


# A thread's scheduling in /proc/PID/task/TID/stat (proc(5)): fields 40 and 41 after the
# pid and the name, rt_priority and policy.
SCHED_FIFO_POLICY = 1


def thread_scheduling(pid: int) -> list[tuple[str, int, int]]:
    """(name, policy, rt_priority) of every thread of process `pid`."""
    threads = []
    for stat in Path(f"/proc/{pid}/task").glob("*/stat"):
        try:
            text = stat.read_text()
        except OSError:
            continue  # the thread ended
        name = text[text.index("(") + 1:text.rindex(")")]
        fields = text[text.rindex(")") + 2:].split()
        threads.append((name, int(fields[38]), int(fields[37])))
    return threads


def scheduling_status(image: Path, *flags: str, wrapper: tuple[str, ...] = (), burst: int = 0,
                      index: int = 13) -> tuple[dict[str, Any], str, list[tuple[str, int, int]]]:
    """Runs PN1 alone with `flags`, sends `burst` status requests at once, and returns the
    last status line's `scheduling`, the log and its threads' scheduling while it ran."""
    process = subprocess.Popen(
        [*wrapper, str(find_node_binary(None)), "--mission", str(image), "--node", "PN1", "--insecure",
         "--domain", str(1 + (os.getpid() + index) % 200), "--control-stdin", *flags],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stdout is not None and process.stdin is not None
    json.loads(process.stdout.readline())
    process.stdin.write("status\n" * burst)
    process.stdin.flush()
    time.sleep(1.0)
    threads = thread_scheduling(process.pid)
    process.stdin.write("status\nquit\n")
    process.stdin.flush()
    out, log = process.communicate(timeout=15)
    assert process.returncode == 0, log
    return json.loads(out.strip().splitlines()[-1])["scheduling"], log, threads


def test_a_realtime_node_runs_its_loop_above_its_tasks_within_its_budget(image: Path) -> None:
    # docs/clusters.md, "Real-time scheduling": the node says at boot and in every status
    # line what it got. A burst of status requests makes the loop run past a 1 % budget:
    # it sleeps rather than starve the machine, and counts it (100 lines: 1-3 ms of CPU).
    if not realtime_permitted():
        pytest.skip("SCHED_FIFO is not permitted to this user")
    scheduling, log, threads = scheduling_status(image, "--realtime", "--task-priority", "30",
                                                 "--loop-budget", "1", burst=100)
    assert scheduling["realtime"] is True and scheduling["loop_priority"] == 50, scheduling
    assert scheduling["task_priority"] == 30 and scheduling["budget_percent"] == 1, scheduling
    assert scheduling["memory_locked"] is memory_lock_permitted() and scheduling["fallback"] == "", scheduling
    assert scheduling["throttled"] >= 1, scheduling
    assert "scheduling: protocol loop SCHED_FIFO 50, tasks SCHED_FIFO 30, memory " in log, log
    assert "loop budget 1% of every 10 ms" in log, log
    # The threads as they ran: the loop and the protocol participant's DDS threads (recv,
    # tev, dq.*) at 50; the executor's workers and the data plane's (and its participant's)
    # at 30; the rest (the main thread, the stdin reader) at normal scheduling.
    fifo = {}
    for name, policy, priority in threads:
        if policy == SCHED_FIFO_POLICY:
            fifo.setdefault(priority, []).append(name)
    assert set(fifo) == {50, 30}, threads
    for priority in (50, 30):
        assert "keel-node" in fifo[priority] and "recv" in fifo[priority], (priority, threads)
    assert len(fifo[30]) > len(fifo[50]), threads  # the workers, the timer, the data plane
    assert any(policy != SCHED_FIFO_POLICY for _, policy, _ in threads), threads
    # The default: the tasks at normal scheduling, a 50 % budget the same burst stays in;
    # and nothing of it without --realtime.
    scheduling, log, threads = scheduling_status(image, "--realtime", burst=100)
    assert scheduling["throttled"] == 0 and scheduling["budget_percent"] == 50, scheduling
    assert scheduling["task_priority"] == 0 and "tasks normal scheduling" in log, (scheduling, log)
    assert {priority for _, policy, priority in threads if policy == SCHED_FIFO_POLICY} == {50}, threads
    scheduling, log, threads = scheduling_status(image, burst=100)
    assert scheduling["realtime"] is False and scheduling["fallback"] == "not asked (--realtime)", scheduling
    assert "protocol loop and tasks at normal scheduling" in log, log
    assert all(policy != SCHED_FIFO_POLICY for _, policy, _ in threads), threads


def test_where_realtime_is_not_permitted_the_node_says_so_and_flies(image: Path) -> None:
    setpriv = shutil.which("setpriv")
    if setpriv is None or os.geteuid() != 0:
        pytest.skip("needs setpriv (util-linux) and root, to take the capabilities away")
    # Without CAP_SYS_NICE (and RLIMIT_RTPRIO 0) SCHED_FIFO is refused; without
    # CAP_IPC_LOCK and with a small RLIMIT_MEMLOCK, memory is not locked.
    drop = (setpriv, "--inh-caps", "-sys_nice,-ipc_lock", "--bounding-set", "-sys_nice,-ipc_lock")
    scheduling, log, _ = scheduling_status(image, "--realtime", wrapper=drop)
    assert scheduling["realtime"] is False and scheduling["budget_percent"] == 100, scheduling
    assert scheduling["fallback"] == "SCHED_FIFO priority 50: Operation not permitted", scheduling
    assert "warning PN1: scheduling: protocol loop and tasks at normal scheduling (real-time scheduling " \
           "unavailable: SCHED_FIFO priority 50: Operation not permitted); memory not locked" in log, log
    prlimit = shutil.which("prlimit")
    if prlimit is None:
        return
    scheduling, log, _ = scheduling_status(
        image, "--realtime", wrapper=(setpriv, "--inh-caps", "-ipc_lock", "--bounding-set", "-ipc_lock",
                                      prlimit, "--memlock=65536"))
    assert scheduling["realtime"] is True and scheduling["memory_locked"] is False, scheduling
    assert scheduling["lock_error"] == "RLIMIT_MEMLOCK is 64 KiB and no CAP_IPC_LOCK: a locked node could " \
                                       "not grow", scheduling
    assert "memory not locked: RLIMIT_MEMLOCK is 64 KiB" in log, log
