"""``keel-cluster campaign``: the reliability campaign on a real cluster.

Many short clusters, one scenario each, drawn in turn from:

- ``worker``: a worker (a processing node that is not the master) is killed;
- ``master``: the master is killed (election, then failover);
- ``double``: two processing nodes killed in a row, the second once the first failure's
  reconfiguration has completed;
- ``storage``: the storage node is killed and restarted;
- ``partition``: a processing node is partitioned, then healed;
- ``deaf``: a processing node cannot receive for twice the detection time;
- ``pause``: a processing node or the Storage node is stopped (SIGSTOP) past the
  detection time, then resumed;
- ``restart``: a processing node is killed and restarted, readmitted, then another one
  is killed;
- ``hog``: four busy processes compete with the cluster for the machine's cores for four
  detection times (CPU starvation): nothing may change;

each preceded and followed by phase switches (the master commanded between the initial
phase and the first phase it can switch to). After each cluster the traces are checked
with ``analysis.reliability``: lost tasks, double activations, split masters and lost
checkpoints must all be 0. The victims and the moment within the heartbeat period come
from the seed, so a failing cluster is replayed by its seed.

The campaign follows the mission's graph beside the cluster (``common.Graph``): after each
failure and phase command it knows the configuration the graph prescribes; beyond the
graph of a phase placed graph+online or online (docs/missions.md, "Placement modes"), an
online configuration (any the placer computes: every node checks it). A wait that
times out is then *expected* when the graph explains it — safe mode is terminal, so a phase
command there is refused as specified (prototype3 goes to SAFE on a second failure and on
a storage failure), a phase edge into a configuration that uses a failed node is refused,
and a failure that does not matter to the configuration changes nothing — and
*unexpected* otherwise (the cluster is not where the graph says, or did not get there in
time). Only unexpected timeouts, and runs that end in a configuration the graph does not
prescribe, count as problems, beside the four counters.
"""

from __future__ import annotations

import datetime
import json
import os
import random
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from keel_cluster import analysis, netns
from keel_cluster.common import (
    ONLINE,
    SAFE,
    Graph,
    MissionSummary,
    leased_cluster,
    load_average,
    master_status,
    settled,
    summarize,
    wait_for,
)
from keel_cluster.launcher import Cluster, LaunchError, find_node_binary

KINDS = ["worker", "master", "double", "storage", "partition", "deaf", "pause", "restart", "hog"]
# The hog fault: busy processes (as many as ./keel bench detector's worst case).
HOGS = 4
COUNTERS = ["lost_tasks", "double_activations", "split_masters", "lost_checkpoints",
            "activations_below_known", "unrecoverable_starts", "false_exclusions",
            "two_masters_ms", "double_run_ms"]


def log(message: str) -> None:
    print(f"keel-cluster campaign: {message}", file=sys.stderr, flush=True)


def phase_timeout(graph: Graph, prescribed: str, target: str, failed: set[str], now: str | None,
                  history: str) -> tuple[bool, str]:
    """Whether a phase command that was not carried out is expected, and why. `now` is the
    configuration the cluster's master runs, `prescribed` the one the graph leads to."""
    nxt = graph.after_phase(prescribed, target, failed)
    if now != prescribed:
        return False, f"the cluster runs {now}, the graph prescribes {prescribed} after {history}"
    if nxt is None and prescribed == SAFE:
        return True, (f"safe mode is terminal: the phase command is refused, as specified (the graph "
                      f"prescribes SAFE after {history})")
    if nxt is None:
        return True, f"refused, as specified: no edge from {prescribed} to phase {target} avoids the failed nodes"
    return False, f"{prescribed} -> {nxt} not carried out within 5 s"


def failure_timeout(victim: str, outcome: str, before: str, prescribed: str, now: str | None,
                    timeout_s: float) -> tuple[bool, str]:
    """Whether a failure after which the master's view did not move is expected, and why."""
    if outcome == "gone":
        return False, f"{victim} had exited on its own"
    if prescribed == before and now == before:
        return True, (f"nothing to switch: {victim}'s failure does not change {before}"
                      + (" (safe mode is terminal)" if before == SAFE else ""))
    return False, (f"the master's view did not move within {timeout_s:g} s (the graph prescribes "
                   f"{before} -> {prescribed}; the cluster runs {now})")


class Campaign:
    def __init__(self, mission: Path, *, use_netns: bool, seed: int, node_binary: Path, run_root: Path,
                 insecure: bool = False, security_profile: str = "encrypt"):
        self.mission = mission.resolve()
        self.summary: MissionSummary = summarize(self.mission)
        self.use_netns = use_netns
        self.seed = seed
        self.node_binary = node_binary
        self.run_root = run_root
        self.insecure = insecure
        self.security_profile = security_profile
        self.period_s = self.summary.period_ms / 1000.0
        # Long enough for detection (miss_limit periods, plus one for where in the period
        # the node died), the decision and the switch on a loaded machine.
        self.reconfigure_timeout_s = (self.summary.miss_limit + 2) * self.period_s + 5.0

    def phase_switch(self, cluster: Cluster, target: str) -> bool:
        """Commands the phase `target` and waits up to 5 s for the cluster to run it. The
        command is sent again each second it is not carried out, as the ground would: one
        that reaches a Master that is resigning (its lease lapsed on a loaded machine) or
        a node that is not Master yet is refused, and a phase command is idempotent (the
        Master refuses a change into the phase it runs)."""
        def switched() -> bool:
            status = settled(cluster)
            return status is not None and status.get("phase") == target

        deadline = time.monotonic() + 5.0
        done = False
        while not done and time.monotonic() < deadline:
            cluster.phase(target)
            done = wait_for(switched, min(1.0, max(0.0, deadline - time.monotonic()))) is not None
        time.sleep(0.05)
        return done

    def fail(self, cluster: Cluster, action: str, victim: str) -> str:
        """Injects one failure and waits until the master's view has moved on (another
        configuration, or another master): "moved", "timeout", or "gone" (the victim had
        exited on its own before)."""
        before = master_status(cluster)
        before_key = (before[0], before[1].get("config"), before[1].get("epoch")) if before else None
        if action == "kill":
            if not cluster.nodes[victim].running:
                # It exited on its own before: reported under crashed_nodes.
                return "gone"
            cluster.kill(victim)
        elif action == "pause":
            cluster.pause(victim)
        else:
            cluster.partition(victim)

        def moved() -> bool:
            now = master_status(cluster)
            if now is None:
                return False
            return (now[0], now[1].get("config"), now[1].get("epoch")) != before_key

        done = wait_for(moved, self.reconfigure_timeout_s) is not None
        wait_for(lambda: settled(cluster), 2.0)
        return "moved" if done else "timeout"

    def run_one(self, index: int, kind: str, rng: random.Random) -> dict[str, Any]:
        run_dir = self.run_root / f"{index:04d}-{kind}"
        cycle = self.summary.phase_cycle
        processing = self.summary.processing
        graph = self.summary.graph
        assert graph is not None
        row: dict[str, Any] = {"index": index, "kind": kind, "failures": 0, "phase_switches": 0,
                               "timeouts": [], "run_dir": str(run_dir)}
        # What the graph prescribes, followed beside the cluster.
        prescribed = self.summary.initial_config
        base = prescribed  # the last prescribed configuration but safe mode (its phase)
        failed: set[str] = set()
        steps: list[str] = []

        def history() -> str:
            return ", ".join(steps) if steps else "no failure injected"

        with leased_cluster(self.mission, self.summary.nodes, run_dir, self.node_binary,
                            use_netns=self.use_netns, seed=self.seed, insecure=self.insecure,
                            security_profile=self.security_profile,
                            security_dir=self.run_root / "security") as cluster:

            def actual() -> str | None:
                found = master_status(cluster)
                return str(found[1].get("config")) if found else None

            def timed_out(what: str, expected: bool, why: str) -> None:
                row["timeouts"].append({"what": what, "expected": expected, "why": why,
                                        "config": actual(), "prescribed": prescribed})

            # A node whose first heartbeats are late on a loaded machine can be declared
            # failed during start-up: the cluster then runs another configuration, which
            # the faults below exercise just as well. Go on after 10 s.
            if wait_for(lambda: settled(cluster, self.summary.initial_config), 10.0) is None:
                timed_out("initial configuration", False,
                          f"{self.summary.initial_config} not running after 10 s (a node declared failed "
                          f"during start-up?)")
            current = 0

            def switch_twice() -> None:
                nonlocal current, prescribed, base
                if len(cycle) < 2:
                    return
                for _ in range(2):
                    target = cycle[1 - current]
                    if self.phase_switch(cluster, target):
                        row["phase_switches"] += 1
                        current = 1 - current
                        nxt = graph.after_phase(prescribed, target, failed)
                        prescribed = nxt if nxt is not None else prescribed
                        base = prescribed if prescribed not in (SAFE, ONLINE) else base
                        continue
                    timed_out(f"phase {target}",
                              *phase_timeout(graph, prescribed, target, failed, actual(), history()))
                    return

            def recover(victim: str) -> None:
                """The victim is back (healed, resumed, restarted): heard for two miss
                limits, the Master readmits it and moves where the mission's on_recovery
                edge says, or to the configuration of the smaller failed set
                (spec/Rejoin.tla), unless that is still safe mode."""
                nonlocal prescribed, base
                if victim not in failed:
                    return
                target = graph.after_recovery(base, failed - {victim}, prescribed, victim)
                if target == SAFE:
                    return
                before = prescribed
                failed.discard(victim)
                prescribed = target
                base = target if target != ONLINE else base
                steps.append(f"{before} -readmit {victim}-> {prescribed}")
                window = (2 * self.summary.miss_limit + 4) * self.period_s + self.reconfigure_timeout_s
                if wait_for(lambda: actual() == prescribed and settled(cluster), window) is None:
                    timed_out(f"readmit {victim}", False,
                              f"{prescribed} not reached {window:.1f} s after {victim} came back "
                              f"({history()})")

            def inject(action: str, victim: str) -> None:
                nonlocal prescribed, base
                time.sleep(rng.uniform(0, self.period_s))
                row["failures"] += 1
                row.setdefault("victims", []).append(f"{action} {victim}")
                before = prescribed
                failed.add(victim)
                prescribed = graph.after_failure(prescribed, victim, failed)
                base = prescribed if prescribed not in (SAFE, ONLINE) else base
                steps.append(f"{before} -{action} {victim}-> {prescribed}")
                outcome = self.fail(cluster, action, victim)
                if outcome == "moved":
                    return
                timed_out(f"{action} {victim}",
                          *failure_timeout(victim, outcome, before, prescribed, actual(), self.reconfigure_timeout_s))

            switch_twice()
            found = master_status(cluster)
            master = found[0] if found else processing[0]
            workers = [n for n in processing if n != master]
            if kind == "worker":
                inject("kill", rng.choice(workers))
            elif kind == "master":
                inject("kill", master)
            elif kind == "double":
                first, second = rng.sample(processing, 2)
                inject("kill", first)
                switch_twice()
                inject("kill", second)
            elif kind == "storage" and self.summary.storage:
                victim = self.summary.storage[0]
                inject("kill", victim)
                time.sleep(self.period_s)
                if not cluster.nodes[victim].running:
                    cluster.start(victim)
                wait_for(lambda: cluster.statuses().get(victim), 10.0)
                wait_for(lambda: settled(cluster), 3.0)
                recover(victim)
            elif kind == "partition":
                victim = rng.choice(processing)
                inject("partition", victim)
                time.sleep(rng.uniform(0.2, 1.0))
                cluster.heal(victim)
                # After the heal the node is told it was declared failed, then readmitted.
                time.sleep((self.summary.miss_limit + 1) * self.period_s)
                recover(victim)
            elif kind == "deaf":
                # Fault model 2: a processing node that cannot receive for twice the
                # detection time. Nothing may change: it suspects itself, and its word alone
                # is not evidence.
                victim = rng.choice(processing)
                row["failures"] += 1
                row.setdefault("victims", []).append(f"deaf {victim}")
                before = prescribed
                if victim == master:
                    # A deaf Master hears no one: it is cut off and steps down, and its
                    # successor takes over along the master-failure edge.
                    failed.add(victim)
                    prescribed = graph.after_failure(prescribed, victim, failed)
                steps.append(f"{before} -deaf {victim}-> {prescribed}")
                cluster.deaf(victim)
                time.sleep(2 * self.summary.miss_limit * self.period_s)
                cluster.heal(victim)
                time.sleep((self.summary.miss_limit + 1) * self.period_s)
                recover(victim)
            elif kind == "pause":
                # Fault model 2: a process stopped past the detection time, then resumed: the
                # cluster moves on as for a failure, and the resumed node stops.
                victim = rng.choice(processing + list(self.summary.storage))
                inject("pause", victim)
                cluster.resume(victim)
                time.sleep((self.summary.miss_limit + 1) * self.period_s)
                recover(victim)
            elif kind == "hog":
                # Fault model 2: CPU starvation. The monitors' loops run late and suspect
                # themselves rather than others; nothing may change.
                row["failures"] += 1
                row.setdefault("victims", []).append(f"hog x{HOGS}")
                steps.append(f"{prescribed} -hog-> {prescribed}")
                hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
                        for _ in range(HOGS)]
                try:
                    time.sleep(4 * self.summary.miss_limit * self.period_s)
                finally:
                    for hog in hogs:
                        hog.kill()
                    for hog in hogs:
                        hog.wait()
                wait_for(lambda: actual() == prescribed and settled(cluster), self.reconfigure_timeout_s)
            elif kind == "restart":
                # Fault model 2's reintegration: a processing node restarts (a failure),
                # is readmitted, and the cluster then tolerates another failure.
                victim = rng.choice(processing)
                inject("kill", victim)
                cluster.start(victim)
                wait_for(lambda: cluster.statuses().get(victim), 10.0)
                recover(victim)
                inject("kill", rng.choice([n for n in processing if n != victim]))
            if kind != "double":
                switch_twice()
            time.sleep(0.2)
            events = list(cluster.events)
            final = cluster.statuses()
            ended = actual()
            crashed = [
                n for n, p in cluster.nodes.items()
                if p.process is not None and p.process.poll() not in (None, -9)
            ]
        write_env_lines(run_dir, events)
        lines, malformed = analysis.read_traces(run_dir)
        checks = analysis.reliability(lines, events, final, set(self.summary.storage)).as_dict()
        row.update({k: checks[k] for k in COUNTERS})
        row["details"] = checks["details"]
        row["crashed_nodes"] = crashed
        row["malformed_trace_lines"] = len(malformed)
        row["final"] = {n: (s.get("role"), s.get("config")) for n, s in final.items() if s}
        row["prescribed"] = prescribed
        row["graph_steps"] = steps
        row["ended"] = ended
        row["ended_as_prescribed"] = ended == prescribed
        row["events"] = events
        return row


# The launcher's process and network events as the traces' environment lines (keel-sim
# writes the same), so that keel-verify trace knows where a node crashed or restarted and
# where a link was faulty (the heartbeat spec's loss bound is lifted there): env.ndjson in
# the run directory, merged with the nodes' traces by t_ns (wall clock, as theirs).
ENV_ACTIONS = {"kill": "Crash", "restart": "Restart", "partition": "Partition", "heal": "Heal",
               "deaf": "Deaf", "pause": "Pause", "resume": "Resume"}


def write_env_lines(run_dir: Path, events: list[dict[str, Any]]) -> None:
    lines = [json.dumps({"t_ns": int(e["t_ns"]), "node": None, "fsm": "env",
                         "action": ENV_ACTIONS[e["action"]], "args": {"n": e["argument"]},
                         "vars": {}})
             for e in events if e.get("action") in ENV_ACTIONS]
    if lines:
        (run_dir / "env.ndjson").write_text("\n".join(lines) + "\n", encoding="utf-8")


def validate_traces(run_dir: Path, mission: Path) -> dict[str, Any]:
    """keel-verify trace over a run's traces: its exit code (0 every protocol line
    validated, 1 a line no spec explains, 3 undecided: some lines not validated yet) and the
    coverage per protocol."""
    command = [sys.executable, "-m", "keel_verify.cli", "trace", str(run_dir), "--mission",
               str(mission), "--json"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=1800, check=False)
    try:
        report = json.loads(done.stdout)
    except json.JSONDecodeError:
        return {"exit_code": done.returncode, "coverage": {}, "error": done.stderr[-500:]}
    return {"exit_code": done.returncode, "coverage": report.get("coverage", {})}


def trace_summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per protocol, lines validated out of the runs' lines; runs by exit code; runs whose
    traces were rejected (exit 1), and runs not validated in full (any exit but 0: a
    rejected trace, lines no trace spec explained yet, an unreadable trace)."""
    per: dict[str, dict[str, int]] = {}
    exits: dict[str, int] = {}
    for row in rows:
        trace = row.get("trace")
        if not trace:
            continue
        exits[str(trace["exit_code"])] = exits.get(str(trace["exit_code"]), 0) + 1
        for protocol, counted in trace["coverage"].items():
            into = per.setdefault(protocol, {"validated": 0, "total": 0})
            into["validated"] += int(counted["validated"])
            into["total"] += int(counted["total"])
    rejected = exits.get("1", 0)
    return {"runs_by_exit_code": exits, "per_protocol": per, "runs_rejected": rejected,
            "runs_not_validated": sum(n for code, n in exits.items() if code != "0")}


def run_campaign(mission: Path, *, failures: int, phase_switches: int, use_netns: bool, seed: int,
                 node_binary: str | None, max_minutes: float, out: Path,
                 kinds: list[str] | None = None, validate: bool = False, insecure: bool = False,
                 security_profile: str = "encrypt") -> dict[str, Any]:
    kinds = kinds or KINDS
    if use_netns:
        reason = netns.probe()
        if reason:
            raise LaunchError(f"--netns: {reason}")
    run_root = Path(tempfile.mkdtemp(prefix="keel-campaign-"))
    campaign = Campaign(mission, use_netns=use_netns, seed=seed, node_binary=find_node_binary(node_binary),
                        run_root=run_root, insecure=insecure, security_profile=security_profile)
    rng = random.Random(seed)
    started = time.monotonic()
    deadline = started + max_minutes * 60
    rows: list[dict[str, Any]] = []
    totals = {"failures": 0, "phase_switches": 0, **{k: 0 for k in COUNTERS}}
    log(f"{campaign.summary.name} ({'netns' if use_netns else 'loopback'}): until {failures} failures and "
        f"{phase_switches} phase switches (at most {max_minutes:g} min), runs in {run_root}")
    # Bounded: each cluster adds at least one failure, so failures + a margin clusters suffice.
    for index in range(failures + phase_switches + 10):
        if totals["failures"] >= failures and totals["phase_switches"] >= phase_switches:
            break
        if time.monotonic() > deadline:
            log("time limit reached")
            break
        kind = kinds[index % len(kinds)]
        if kind == "storage" and not campaign.summary.storage:
            kind = "worker"
        try:
            row = campaign.run_one(index, kind, rng)
        except LaunchError as error:
            log(f"[{index + 1}] {kind}: {error}")
            raise
        if validate:
            row["trace"] = validate_traces(Path(row["run_dir"]), mission)
        rows.append(row)
        for key in totals:
            totals[key] += row[key]
        bad = [f"{k} {row[k]}" for k in COUNTERS if row[k]]
        if validate and row["trace"]["exit_code"] != 0:
            bad.append(f"keel-verify trace exit {row['trace']['exit_code']}")
        if row["crashed_nodes"]:
            bad.append(f"exited on their own: {', '.join(row['crashed_nodes'])}")
        if not row["ended_as_prescribed"]:
            bad.append(f"ended in {row['ended']}, the graph prescribes {row['prescribed']}")
        bad += [f"unexpected timeout: {t['what']} ({t['why']})" for t in row["timeouts"] if not t["expected"]]
        expected = [t["what"] for t in row["timeouts"] if t["expected"]]
        log(f"[{index + 1}] {kind:<9} {', '.join(row.get('victims', []))}: "
            f"{'; '.join(bad) if bad else 'ok'}{'  expected timeouts: ' + ', '.join(expected) if expected else ''}"
            f"  (total {totals['failures']} failures, {totals['phase_switches']} switches, load {load_average()[0]})")
        for detail in row["details"]:
            log(f"    {detail}")
    report = build_report(rows, totals, mission=mission, use_netns=use_netns, seed=seed, kinds=kinds,
                          period_ms=campaign.summary.period_ms, miss_limit=campaign.summary.miss_limit,
                          complete=totals["failures"] >= failures and totals["phase_switches"] >= phase_switches,
                          seconds=round(time.monotonic() - started, 1), run_root=run_root)
    report["security"] = "insecure" if insecure else security_profile
    if validate:
        # A run whose traces are not a behaviour of the specs, or not validated in full
        # (lines no trace spec explained yet, an unreadable trace), is a problem.
        report["trace_validation"] = trace_summary(rows)
        report["problems"] += report["trace_validation"]["runs_not_validated"]
        log("trace validation: " + ", ".join(
            f"{p} {c['validated']}/{c['total']} lines"
            for p, c in report["trace_validation"]["per_protocol"].items())
            + f"; runs by exit code {report['trace_validation']['runs_by_exit_code']}")
    for line in summary_lines(report):
        log(line)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    except OSError as error:
        # The summary above and the run directories keep what the campaign found.
        raise OutputError(f"cannot write {out}: {error.strerror or error}; the runs are in {run_root}") from None
    log(f"wrote {out}")
    return report


class OutputError(Exception):
    """The report cannot be written where --out says."""


def resolve_out(out: Path) -> Path:
    """--out names the report file; a folder (existing, or written with a trailing slash)
    gets campaign.json inside it. Checked before any cluster starts, so an unusable path
    costs nothing."""
    if out.is_dir() or str(out).endswith(("/", "\\")):
        out = out / "campaign.json"
    if out.exists() and not out.is_file():
        raise OutputError(f"--out {out}: not a regular file")
    parent = out.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir() or not os.access(parent, os.W_OK):
        raise OutputError(f"--out {out}: {parent} is not a writable folder")
    return out


def build_report(rows: list[dict[str, Any]], totals: dict[str, int], *, mission: Path, use_netns: bool, seed: int,
                 kinds: list[str], period_ms: int, miss_limit: int, complete: bool, seconds: float,
                 run_root: Path) -> dict[str, Any]:
    """The campaign's JSON: totals, the timeouts split into expected (the graph explains
    them) and unexpected, the runs that ended where the graph does not lead, and `problems`
    (the counters, crashed nodes, and runs with an unexpected timeout or ending, each run
    once), the one number the exit status follows."""
    timeouts = [dict(t, run=r["index"], kind=r["kind"]) for r in rows for t in r["timeouts"]]
    unexpected = [t for t in timeouts if not t["expected"]]
    reasons: dict[str, int] = {}
    for t in timeouts:
        if t["expected"]:
            key = t["why"].split(":")[0]
            reasons[key] = reasons.get(key, 0) + 1
    unprescribed = [{"run": r["index"], "kind": r["kind"], "victims": r.get("victims", []), "ended": r["ended"],
                     "prescribed": r["prescribed"], "graph_steps": r["graph_steps"]}
                    for r in rows if not r["ended_as_prescribed"]]
    crashed = sum(len(r["crashed_nodes"]) for r in rows)
    # A run that ends where the graph does not lead usually also times out on the next
    # phase command: such a run counts once.
    astray = sorted({t["run"] for t in unexpected} | {e["run"] for e in unprescribed})
    problems = sum(totals[k] for k in COUNTERS) + crashed + len(astray)
    return {
        "benchmark": "campaign",
        "mission": str(mission),
        "mode": "netns" if use_netns else "loopback",
        "seed": seed,
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "heartbeat_ms": period_ms,
        "miss_limit": miss_limit,
        "clusters": len(rows),
        "by_kind": {k: sum(1 for r in rows if r["kind"] == k) for k in KINDS},
        # Per fault kind: runs, and each counter summed over them (fault model 2 asks for
        # every counter per kind).
        "counters_by_kind": {
            k: {"runs": sum(1 for r in rows if r["kind"] == k),
                **{c: sum(r.get(c, 0) for r in rows if r["kind"] == k) for c in COUNTERS}}
            for k in KINDS if any(r["kind"] == k for r in rows)},
        "kinds": kinds,
        "totals": totals,
        "all_zero": all(totals[k] == 0 for k in COUNTERS),
        "complete": complete,
        "timeouts": {
            "total": len(timeouts),
            "expected": len(timeouts) - len(unexpected),
            "expected_by_reason": reasons,
            "unexpected": len(unexpected),
            "unexpected_list": unexpected,
        },
        "unprescribed_endings": unprescribed,
        "runs_astray": astray,
        "crashed_nodes": crashed,
        "problems": problems,
        "load_average_end": load_average(),
        "seconds": seconds,
        "run_root": str(run_root),
        "runs": rows,
    }


def summary_lines(report: dict[str, Any]) -> list[str]:
    totals, timeouts = report["totals"], report["timeouts"]
    lines = [
        f"{report['clusters']} clusters, {totals['failures']} failures, {totals['phase_switches']} phase switches: "
        + ", ".join(f"{k} {totals[k]}" for k in COUNTERS) + f"; crashed nodes {report['crashed_nodes']}",
        f"timeouts {timeouts['total']}: expected {timeouts['expected']} ("
        + (", ".join(f"{k} {v}" for k, v in timeouts["expected_by_reason"].items()) or "none")
        + f"), unexpected {timeouts['unexpected']}",
    ]
    for t in timeouts["unexpected_list"]:
        lines.append(f"    run {t['run']} ({t['kind']}): {t['what']}: {t['why']}")
    for kind, counts in report.get("counters_by_kind", {}).items():
        bad = ", ".join(f"{c} {counts[c]}" for c in COUNTERS if counts[c])
        lines.append(f"    {kind}: {counts['runs']} runs, {bad or 'every counter 0'}")
    lines.append(f"runs ended where the graph does not lead: {len(report['unprescribed_endings'])}")
    for e in report["unprescribed_endings"]:
        lines.append(f"    run {e['run']} ({e['kind']}, {', '.join(e['victims'])}): ended in {e['ended']}, "
                     f"prescribed {e['prescribed']} ({', '.join(e['graph_steps']) or 'no failure'})")
    lines.append(f"problems {report['problems']}: the counters, crashed nodes, and {len(report['runs_astray'])} runs "
                 f"with an unexpected timeout or ending (load average at the end {report['load_average_end']})")
    return lines


def main_campaign(args: Any) -> int:
    unknown = [k for k in args.kinds.split(",") if k.strip() and k.strip() not in KINDS]
    if unknown:
        print(f"keel-cluster campaign: --kinds: unknown {', '.join(unknown)} (known: {', '.join(KINDS)})",
              file=sys.stderr)
        return 2
    try:
        out = resolve_out(Path(args.out))
    except OutputError as error:
        print(f"keel-cluster campaign: {error}", file=sys.stderr)
        return 2
    try:
        report = run_campaign(Path(args.mission), failures=args.failures, phase_switches=args.phase_switches,
                              use_netns=args.netns, seed=args.seed, node_binary=args.node_binary,
                              max_minutes=args.max_minutes, out=out,
                              kinds=[k.strip() for k in args.kinds.split(",") if k.strip()],
                              validate=args.validate_traces, insecure=getattr(args, "insecure", False),
                              security_profile=getattr(args, "security_profile", "encrypt"))
    except LaunchError as error:
        print(f"keel-cluster campaign: {error}", file=sys.stderr)
        return 3
    except OutputError as error:
        print(f"keel-cluster campaign: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("keel-cluster campaign: interrupted; all nodes stopped", file=sys.stderr)
        return 130
    return 0 if report["problems"] == 0 else 1
