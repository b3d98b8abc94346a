"""``keel-cluster campaign``: the reliability campaign on a real cluster.

Many short clusters, one scenario each, drawn in turn from:

- ``worker``: a worker (a processing node that is not the master) is killed;
- ``master``: the master is killed (election, then failover);
- ``double``: two processing nodes killed in a row, the second once the first failure's
  reconfiguration has completed;
- ``storage``: the storage node is killed and restarted;
- ``partition``: a processing node is partitioned, then healed;

each preceded and followed by phase switches (the master commanded between the initial
phase and the first phase it can switch to). After each cluster the traces are checked
with ``analysis.reliability``: lost tasks, double activations, split masters and lost
checkpoints must all be 0. The victims and the moment within the heartbeat period come
from the seed, so a failing cluster is replayed by its seed.
"""

from __future__ import annotations

import datetime
import json
import random
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from keel_cluster import analysis, netns
from keel_cluster.common import (
    MissionSummary,
    leased_cluster,
    load_average,
    master_status,
    settled,
    summarize,
    wait_for,
)
from keel_cluster.launcher import Cluster, LaunchError, find_node_binary

KINDS = ["worker", "master", "double", "storage", "partition"]
COUNTERS = ["lost_tasks", "double_activations", "split_masters", "lost_checkpoints"]


def log(message: str) -> None:
    print(f"keel-cluster campaign: {message}", file=sys.stderr, flush=True)


class Campaign:
    def __init__(self, mission: Path, *, use_netns: bool, seed: int, node_binary: Path, run_root: Path):
        self.mission = mission.resolve()
        self.summary: MissionSummary = summarize(self.mission)
        self.use_netns = use_netns
        self.seed = seed
        self.node_binary = node_binary
        self.run_root = run_root
        self.period_s = self.summary.period_ms / 1000.0
        # Long enough for detection (miss_limit periods, plus one for where in the period
        # the node died), the decision and the switch on a loaded machine.
        self.reconfigure_timeout_s = (self.summary.miss_limit + 2) * self.period_s + 5.0

    def phase_switch(self, cluster: Cluster, target: str) -> bool:
        cluster.phase(target)

        def switched() -> bool:
            status = settled(cluster)
            return status is not None and status.get("phase") == target

        done = wait_for(switched, 5.0) is not None
        time.sleep(0.05)
        return done

    def fail(self, cluster: Cluster, action: str, victim: str) -> bool:
        """Injects one failure and waits until the master's view has moved on (another
        configuration, or another master)."""
        before = master_status(cluster)
        before_key = (before[0], before[1].get("config"), before[1].get("epoch")) if before else None
        if action == "kill":
            if not cluster.nodes[victim].running:
                # It exited on its own before: reported under crashed_nodes.
                return False
            cluster.kill(victim)
        else:
            cluster.partition(victim)

        def moved() -> bool:
            now = master_status(cluster)
            if now is None:
                return False
            return (now[0], now[1].get("config"), now[1].get("epoch")) != before_key

        done = wait_for(moved, self.reconfigure_timeout_s) is not None
        wait_for(lambda: settled(cluster), 2.0)
        return done

    def run_one(self, index: int, kind: str, rng: random.Random) -> dict[str, Any]:
        run_dir = self.run_root / f"{index:04d}-{kind}"
        cycle = self.summary.phase_cycle
        processing = self.summary.processing
        row: dict[str, Any] = {"index": index, "kind": kind, "failures": 0, "phase_switches": 0,
                               "timeouts": [], "run_dir": str(run_dir)}
        with leased_cluster(self.mission, self.summary.nodes, run_dir, self.node_binary,
                            use_netns=self.use_netns, seed=self.seed) as cluster:
            # A node whose first heartbeats are late on a loaded machine can be declared
            # failed during start-up: the cluster then runs another configuration, which
            # the faults below exercise just as well. Go on after 10 s.
            if wait_for(lambda: settled(cluster, self.summary.initial_config), 10.0) is None:
                row["timeouts"].append("initial configuration")
            current = 0

            def switch_twice() -> None:
                nonlocal current
                if len(cycle) < 2:
                    return
                for _ in range(2):
                    target = cycle[1 - current]
                    if self.phase_switch(cluster, target):
                        # Counted when the cluster runs the new phase; after safe mode (a
                        # terminal configuration) a phase command is refused, as specified.
                        row["phase_switches"] += 1
                        current = 1 - current
                    else:
                        row["timeouts"].append(f"phase {target}")
                        return

            def inject(action: str, victim: str) -> None:
                time.sleep(rng.uniform(0, self.period_s))
                row["failures"] += 1
                row.setdefault("victims", []).append(f"{action} {victim}")
                if not self.fail(cluster, action, victim):
                    row["timeouts"].append(f"{action} {victim}")

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
            elif kind == "partition":
                victim = rng.choice(processing)
                inject("partition", victim)
                time.sleep(rng.uniform(0.2, 1.0))
                cluster.heal(victim)
                # After the heal the node rejoins (or is told it was declared failed): give
                # the cluster miss_limit periods to agree again before the next command.
                time.sleep((self.summary.miss_limit + 1) * self.period_s)
            if kind != "double":
                switch_twice()
            time.sleep(0.2)
            events = list(cluster.events)
            final = cluster.statuses()
            crashed = [
                n for n, p in cluster.nodes.items()
                if p.process is not None and p.process.poll() not in (None, -9)
            ]
        lines, malformed = analysis.read_traces(run_dir)
        checks = analysis.reliability(lines, events, final, set(self.summary.storage)).as_dict()
        row.update({k: checks[k] for k in COUNTERS})
        row["details"] = checks["details"]
        row["crashed_nodes"] = crashed
        row["malformed_trace_lines"] = len(malformed)
        row["final"] = {n: (s.get("role"), s.get("config")) for n, s in final.items() if s}
        row["events"] = events
        return row


def run_campaign(mission: Path, *, failures: int, phase_switches: int, use_netns: bool, seed: int,
                 node_binary: str | None, max_minutes: float, out: Path,
                 kinds: list[str] | None = None) -> dict[str, Any]:
    kinds = kinds or KINDS
    if use_netns:
        reason = netns.probe()
        if reason:
            raise LaunchError(f"--netns: {reason}")
    run_root = Path(tempfile.mkdtemp(prefix="keel-campaign-"))
    campaign = Campaign(mission, use_netns=use_netns, seed=seed, node_binary=find_node_binary(node_binary),
                        run_root=run_root)
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
        rows.append(row)
        for key in totals:
            totals[key] += row[key]
        bad = [f"{k} {row[k]}" for k in COUNTERS if row[k]]
        if row["crashed_nodes"]:
            bad.append(f"exited on their own: {', '.join(row['crashed_nodes'])}")
        log(f"[{index + 1}] {kind:<9} {', '.join(row.get('victims', []))}: "
            f"{'; '.join(bad) if bad else 'ok'}{'  timeouts: ' + ', '.join(row['timeouts']) if row['timeouts'] else ''}"
            f"  (total {totals['failures']} failures, {totals['phase_switches']} switches, load {load_average()[0]})")
        for detail in row["details"]:
            log(f"    {detail}")
    report = {
        "benchmark": "campaign",
        "mission": str(mission),
        "mode": "netns" if use_netns else "loopback",
        "seed": seed,
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "heartbeat_ms": campaign.summary.period_ms,
        "miss_limit": campaign.summary.miss_limit,
        "clusters": len(rows),
        "by_kind": {k: sum(1 for r in rows if r["kind"] == k) for k in KINDS},
        "kinds": kinds,
        "totals": totals,
        "all_zero": all(totals[k] == 0 for k in COUNTERS),
        "complete": totals["failures"] >= failures and totals["phase_switches"] >= phase_switches,
        "timeouts": sum(len(r["timeouts"]) for r in rows),
        "crashed_nodes": sum(len(r["crashed_nodes"]) for r in rows),
        "load_average_end": load_average(),
        "seconds": round(time.monotonic() - started, 1),
        "run_root": str(run_root),
        "runs": rows,
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    log(f"{len(rows)} clusters, {totals['failures']} failures, {totals['phase_switches']} phase switches: "
        + ", ".join(f"{k} {totals[k]}" for k in COUNTERS) + f"; wrote {out}")
    return report


def main_campaign(args: Any) -> int:
    unknown = [k for k in args.kinds.split(",") if k.strip() and k.strip() not in KINDS]
    if unknown:
        print(f"keel-cluster campaign: --kinds: unknown {', '.join(unknown)} (known: {', '.join(KINDS)})",
              file=sys.stderr)
        return 2
    try:
        report = run_campaign(Path(args.mission), failures=args.failures, phase_switches=args.phase_switches,
                              use_netns=args.netns, seed=args.seed, node_binary=args.node_binary,
                              max_minutes=args.max_minutes, out=Path(args.out),
                              kinds=[k.strip() for k in args.kinds.split(",") if k.strip()])
    except LaunchError as error:
        print(f"keel-cluster campaign: {error}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print("keel-cluster campaign: interrupted; all nodes stopped", file=sys.stderr)
        return 130
    return 0 if report["all_zero"] and report["crashed_nodes"] == 0 else 1
