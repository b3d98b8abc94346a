"""``keel-cluster``: run an emulated cluster of keel-node processes.

    keel-cluster run MISSION.yaml [--scenario S.yaml] [--netns] [--json] [--duration 10s]
                                  [--run-dir DIR] [--node-binary PATH] [--domain ID] [--ground]
                                  [--console [PORT]] [--vote-span PERIODS]
                                  [--insecure | --security-profile encrypt|full|sign]
    keel-cluster console RUN_DIR [--port PORT] [--mission FILE]
    keel-cluster console --dds DOMAIN --mission IMAGE [--security DIR] [FOLDER] [--port PORT]
    keel-cluster bench MISSION.yaml [--quick] [--netns] [--out DIR] [--figures 9,10,11,13] [--seed S]
    keel-cluster campaign MISSION.yaml [--failures 200] [--phase-switches 200] [--netns] [--seed S]
    keel-cluster credentials MISSION --out DIR [--days N] [--profile encrypt|full|sign] [--revoke NAME]
                                [--renew NAME] [--kit NAME]
                                [--operator-verbs VERB,...]

Clusters are secured with DDS Security unless --insecure: credentials for the mission are
made in RUN_DIR/security (keel_cluster/security.py; docs/security.md). `run` prints the DDS
domain it uses (--domain ID to choose it; by default 100 + pid % 100). Ground commands
(phase, recover, exclude, readmit, pause-task, resume-task, designate) are signed with the
run's operator key (docs/operations.md);
`run --ground` reads them, and faults, on stdin while the cluster runs. `designate NODE` (a
mission with heartbeat.tie_grace; not with --insecure, whose nodes take it only signed)
reads NODE's latest heartbeat number from its status line and sends `designate NODE WAIT
SPAN ECHO`, WAIT the periods left of the latest span given another node, SPAN WAIT +
--vote-span (keel_cluster/designation.py).

Exit codes: 0 the run completed and every reliability check held; 1 a reliability check
failed (lost task, double activation, split master, lost checkpoint; and fault model 2's:
time with two running Masters or a task on two nodes across epochs, an activation below a
version the cluster had, an exclusion of a node no fault touched) or a node crashed on its
own; 2 bad input (mission, scenario, flags); 3 the cluster could not be started (or, with
--console, its console). `console`: 0 ended by Ctrl-C; 2 bad input (no such run directory,
a --mission it cannot read; --dds without the image, or credentials without the monitor's
identity); 3 it could not listen on the port; 4 (--dds) keel-observe could not join the
domain, or stopped (docs/clusters.md, "Watching a cluster live: the console").
"""

from __future__ import annotations

import argparse
import json
import queue
import sys
import threading
import time
from pathlib import Path
from typing import Any, Callable

from keel_cluster import __version__, analysis, console, security
from keel_cluster.common import SAFE, Graph, master_status, summarize
from keel_cluster.designation import VOTE_SPAN_PERIODS, VOTE_SPAN_PERIODS_MAX, Designation
from keel_cluster.launcher import Cluster, LaunchError, find_node_binary, is_image
from keel_cluster.scenario import Event, Scenario, ScenarioError, load_scenario, parse_duration_s, parse_event


def _mission_summary(path: Path) -> tuple[list[str], list[str], set[str], set[str], set[str]]:
    """Node names (file order), processing nodes, phases, configurations, tasks — through the
    verifier's loader,
    so a bad mission gets the same file:line:col errors as everywhere else."""
    from keel_verify.mission import MissionError, load_mission

    from keel_cluster.common import read_mission
    from keel_cluster.launcher import is_image

    if is_image(path):
        raw = read_mission(path)
        configs = {c for phase in raw["phases"].values() for c in phase["configurations"]}
        processing = [n for n, node in raw["nodes"].items() if node.get("kind") == "processing"]
        return list(raw["nodes"]), processing, set(raw["phases"]), configs, set(raw["tasks"])
    try:
        mission = load_mission(path)
    except MissionError as error:
        raise ScenarioError(str(error)) from None
    configs = {c for phase in mission.phases.values() for c in phase.configurations}
    return list(mission.nodes), mission.processing_nodes, set(mission.phases), configs, set(mission.tasks)


def _operator_input(nodes: set[str], processing: list[str], phases: set[str],
                    configs: set[str], tasks: set[str] | None) -> Callable[[], list[Event | None]]:
    """The operator's console of `keel-cluster run --ground`: a thread reads stdin, one
    command per line (a scenario action without its time: `phase science`, `exclude PN3`),
    and the run applies each at once; `quit` or the end of stdin ends the run's console
    (`quit` the run too). A line that does not parse is said and skipped."""
    typed: queue.Queue[Event | None] = queue.Queue()

    def read() -> None:
        for number, text in enumerate(sys.stdin, 1):
            line = text.split("#", 1)[0].strip()
            if not line:
                continue
            if line == "quit":
                typed.put(None)
                return
            try:
                typed.put(parse_event(f"at 0s {line}", f"stdin:{number}", nodes, phases, configs, tasks))
            except ScenarioError as error:
                print(f"keel-cluster: {error}", file=sys.stderr)

    threading.Thread(target=read, name="ground-console", daemon=True).start()

    def drain() -> list[Event | None]:
        events: list[Event | None] = []
        while not typed.empty():
            events.append(typed.get_nowait())
        return events

    return drain


# What the console's page may send the run (`run --console`): the ground's commands and the
# emulator's faults, as on --ground's stdin; not `update` (a file path, which compiles and
# flies a mission: stdin's only) nor `quit`.
PAGE_ACTIONS = ("phase", "recover", "exclude", "readmit", "pause-task", "resume-task", "designate", "kill",
                "restart", "partition", "heal", "deaf", "pause", "resume")
PAGE_ANSWER_S = 10.0
STATUS_EVERY_S = 1.0  # run --console: every node's status line, for the page's task data rates


class PageCommands:
    """The console page's commands (console.Commands): `take` (the page's HTTP thread)
    parses a line and waits for the run's loop to apply it (`apply`, called by the loop);
    it answers why a line was not applied, None once it was. Lines come only while the run
    runs (`running`)."""

    def __init__(self, nodes: set[str], processing: list[str], phases: set[str], configs: set[str],
                 graph: Graph | None = None, tasks: set[str] | None = None):
        self.nodes, self.phases, self.configs, self.tasks = nodes, phases, configs, tasks
        self.graph = graph  # the mission's graph: a ground command's proven target (note)
        self.running = threading.Event()
        self.queue: queue.Queue[tuple[Event, queue.Queue[str | None]]] = queue.Queue()
        # take() checks `running` and queues under it, end() clears and drains under it: a
        # request never waits in a queue nothing reads any more.
        self.lock = threading.Lock()
        worker = processing[-1] if processing else sorted(nodes)[-1] if nodes else "PN1"
        self.examples = ([f"phase {sorted(phases)[0]}"] if phases else []) + [
            f"exclude {worker}", f"readmit {worker}", f"kill {worker}"]

    def take(self, line: str) -> str | None:
        line = line.split("#", 1)[0].strip()
        if not line or line == "quit":
            return f"a command: {', '.join(PAGE_ACTIONS)} and its argument (the page does not end the run)"
        action = line.split()[0]
        if action not in PAGE_ACTIONS:
            return f"{action} is not taken from the page ({', '.join(PAGE_ACTIONS)} are)"
        try:
            event = parse_event(f"at 0s {line}", "console", self.nodes, self.phases, self.configs, self.tasks)
        except ScenarioError as error:
            return str(error)
        answer: queue.Queue[str | None] = queue.Queue(maxsize=1)
        with self.lock:
            if not self.running.is_set():
                return "the cluster is not running (not started yet, or the run has ended)"
            self.queue.put((event, answer))
        try:
            return answer.get(timeout=PAGE_ANSWER_S)
        except queue.Empty:
            return f"not applied within {PAGE_ANSWER_S:g} s (the run is busy); it may still be"

    def apply(self, cluster: Cluster) -> None:
        """Applies what the page sent (the run's loop), answering each request."""
        while True:
            try:
                event, answer = self.queue.get_nowait()
            except queue.Empty:
                return
            try:
                note = self.note(event, cluster)
                done = cluster.apply(event)
                if isinstance(done, Designation):
                    note = designation_note(done)
                answer.put(console.Applied(note) if note else None)
            except Exception as error:  # noqa: BLE001 - the page is told, the run goes on
                print(f"keel-cluster: {event.action} {event.argument} (console): {error}", file=sys.stderr)
                answer.put(f"{event.action} {event.argument}: {error}")

    def note(self, event: Event, cluster: Cluster) -> str | None:
        """For a ground command, what the proven graph says it leads to from the acting
        Master's configuration and failed set (its status line), as the Master walks it
        (common.Graph, Topology's walk), or why the nodes will refuse it; None for a fault,
        or with no graph or no Master to read."""
        if self.graph is None or event.action not in ("phase", "recover", "exclude", "readmit"):
            return None
        try:
            found = master_status(cluster)
        except AttributeError:  # a cluster without statuses (tests)
            return None
        if found is None:
            return "no acting Master to read the configuration from (the nodes decide)"
        master, status = found
        config = str(status.get("config"))
        failed = {str(n) for n in status.get("failed") or []}
        graph, argument = self.graph, event.argument
        if event.action == "phase":
            target = graph.after_phase(config, argument, failed)
            if target is None:
                return (f"no proven edge from {config} for phase {argument} (or it uses a failed node): "
                        f"the Master ({master}) will refuse it")
            return f"proven target: {target} (phase {argument} from {config})"
        if event.action == "exclude":
            if argument in failed:
                return f"{argument} is already out of {config}"
            target = graph.after_failure(config, argument, failed | {argument})
            if target == config:
                return f"proven target: {config} ({argument} hosts nothing {config} needs: it stays)"
            if target == SAFE:
                return (f"the proven edge for {argument} out of {config} leads to SAFE: the Master ({master}) "
                        "holds it out and withholds the exclusion (docs/operations.md)")
            return f"proven target: {target} ({argument} out of {config})"
        if event.action == "readmit":
            if argument not in failed:
                return f"{argument} is not out of {config}: the hold, if any, is lifted"
            target = graph.after_recovery(config, failed - {argument}, config, argument)
            return f"proven target: {target} ({argument} back into {config})"
        return (f"proven target: {argument}, if it is valid with {', '.join(sorted(failed)) or 'no node'} out "
                f"(the Master ({master}) checks it, and says why not)")

    def end(self) -> None:
        """The run ended: nothing more is applied; waiting requests are told."""
        with self.lock:
            self.running.clear()
        while True:
            try:
                _, answer = self.queue.get_nowait()
            except queue.Empty:
                return
            answer.put("the run has ended")


def designation_note(designation: Designation) -> str:
    """What the page is told of a designation sent (its terms, which the launcher chose)."""
    node, wait, span, echo = designation.arguments()
    return (f"sent designate {node} {wait} {span} {echo}: the ground's vote for {node} from {wait} periods "
            f"after {node} takes it until {span} periods after its heartbeat {echo}")


def run(args: argparse.Namespace) -> int:
    mission_path = Path(args.mission)
    try:
        nodes, processing, phases, configs, tasks = _mission_summary(mission_path)
        if args.scenario:
            scenario = load_scenario(args.scenario, set(nodes), processing, phases, configs, tasks)
        else:
            scenario = Scenario()
        if args.duration:
            scenario.duration_s = parse_duration_s(args.duration, "--duration")
        binary = find_node_binary(args.node_binary)
    except (ScenarioError, LaunchError) as error:
        print(f"keel-cluster: {error}", file=sys.stderr)
        return 2
    run_dir = Path(args.run_dir or f"runs/{time.strftime('%Y%m%d-%H%M%S')}-{mission_path.stem}")
    echo = not args.quiet
    mode = "network namespaces" if args.netns else "loopback"
    if echo:
        print(
            f"keel-cluster: {len(nodes)} nodes of {mission_path} on {mode}, "
            f"{len(scenario.events)} events over {scenario.duration_s:g}s; run directory {run_dir}",
            file=sys.stderr,
        )
    security_note = ("insecure (--insecure: no DDS Security)" if args.insecure
                     else f"secured, profile {args.security_profile}")
    watching: console.ConsoleServer | None = None
    try:
        graph = summarize(mission_path).graph
    except Exception:  # noqa: BLE001 - the notes are a help; keel-node validates the mission
        graph = None
    page = PageCommands(set(nodes), processing, phases, configs, graph, tasks)
    if args.console is not None:
        try:
            # An image given as the mission is not copied into the run directory.
            watching = console.serve(run_dir, args.console, mission_path if is_image(mission_path) else None,
                                     not_before_ns=time.time_ns(),
                                     commands=console.Commands(page.take, page.examples))
        except OSError as error:
            print(f"keel-cluster: --console: cannot listen on 127.0.0.1:{args.console}: {error.strerror}",
                  file=sys.stderr)
            return 3
        # The address carries the key that lets its page command the run (#k=): the
        # console gives it to no one else.
        print(f"keel-cluster: console at {watching.command_url} (open it in a browser; it follows {run_dir}; "
              "its page may send the run commands: keep the address to yourself)", file=sys.stderr, flush=True)
    try:
        return _run_cluster(args, mission_path, nodes, processing, phases, configs, scenario, binary,
                            run_dir, echo, security_note, page if watching is not None else None, tasks)
    finally:
        if watching is not None:
            # The run's last lines, and that it finished, reach every open page.
            if not watching.drain(console.DRAIN_S):
                print(f"keel-cluster: the console had not sent the whole run within {console.DRAIN_S:g} s "
                      "(a page that does not read?)", file=sys.stderr)
            watching.close()
            print(f"keel-cluster: console closed; replay the run with: keel-cluster console {run_dir}",
                  file=sys.stderr)


def _run_cluster(args: argparse.Namespace, mission_path: Path, nodes: list[str], processing: list[str],
                 phases: set[str], configs: set[str], scenario: Scenario, binary: Path, run_dir: Path,
                 echo: bool, security_note: str, page: PageCommands | None = None,
                 tasks: set[str] | None = None) -> int:
    dds_tool: Path | None = None
    launched = Cluster(mission_path, nodes, run_dir, binary, use_netns=args.netns, echo=echo,
                       insecure=args.insecure, security_profile=args.security_profile, domain_id=args.domain,
                       extra_args=["--realtime"] if args.realtime else None,
                       vote_span_periods=args.vote_span)
    if page is not None:
        launched.status_every_s = STATUS_EVERY_S  # the console's task data rates
    try:
        with launched as cluster:
            # keel-node's data plane domain (core/net/README.md, "Two domains per node").
            data_domain = (cluster.domain_id + 116) % 231
            print(f"keel-cluster: DDS domain {cluster.domain_id} (samples: {data_domain}), "
                  f"{security_note}", file=sys.stderr)
            if cluster.security_dir is not None:
                dds_tool = cluster.security_dir / "dds-tool.xml"
                where = "" if not args.netns else " (loopback only: with --netns the nodes are not on lo)"
                # Runnable as printed from a Keel checkout (`./keel dds` runs the tool that
                # `./keel setup --dds-tools` installed); the file is for any other tool.
                print(f"keel-cluster: DDS tools join as keel-monitor{where} with {dds_tool}; watch it: "
                      f"./keel dds --security {cluster.security_dir} -- ps -i {cluster.domain_id}",
                      file=sys.stderr)
            else:
                print(f"keel-cluster: watch it: ./keel dds -- ps -i {cluster.domain_id}", file=sys.stderr)
            stdin = _operator_input(set(nodes), processing, phases, configs, tasks) if args.ground else None

            def typed() -> list[Event | None]:
                # The operator's lines (stdin), and the console page's, applied here: each
                # page's request waits for its own answer.
                if page is not None:
                    page.apply(cluster)
                return stdin() if stdin is not None else []

            if page is not None:
                page.running.set()
            try:
                cluster.run(scenario, typed=typed if stdin is not None or page is not None else None)
            finally:
                if page is not None:
                    page.end()
            final = cluster.statuses()
            crashed = [
                n for n, p in cluster.nodes.items()
                if p.process is not None and p.process.poll() not in (None, -9)
                and not any(e["action"] == "kill" and e["argument"] == n for e in cluster.events)
            ]
            events = list(cluster.events)
    except LaunchError as error:
        print(f"keel-cluster: {error}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print("keel-cluster: interrupted; all nodes stopped", file=sys.stderr)
        return 130
    lines, malformed = analysis.read_traces(run_dir)
    faults = analysis.fault_metrics(lines, events)
    checks = analysis.reliability(lines, events, final)
    report: dict[str, Any] = {
        "mission": str(mission_path),
        "run_dir": str(run_dir),
        "mode": "netns" if args.netns else "loopback",
        "security": "insecure" if args.insecure else args.security_profile,
        "dds_tool_config": str(dds_tool) if dds_tool else None,
        "duration_s": scenario.duration_s,
        "events": events,
        "faults": [f.as_dict() for f in faults],
        "moves": [m.as_dict() for m in analysis.task_moves(lines)],
        "reliability": checks.as_dict(),
        "final_status": final,
        "crashed_nodes": crashed,
        "trace_lines": len(lines),
        "malformed_trace_lines": [m.__dict__ for m in malformed],
    }
    (run_dir / "report.json").write_text(json.dumps(report, indent=2) + "\n")
    if args.json:
        json.dump(report, sys.stdout, indent=2)
        print()
    else:
        print_report(report)
    failed = any(report["reliability"][k] for k in
                 ("double_activations", "split_masters", "lost_checkpoints", "lost_tasks",
                  "activations_below_known", "false_exclusions", "two_masters_ms", "double_run_ms"))
    return 1 if failed or crashed else 0


def credentials(args: argparse.Namespace) -> int:
    """`keel-cluster credentials`: make (or re-issue) a mission's DDS Security credentials,
    or revoke one node's."""
    out = Path(args.out)
    try:
        if args.kit:
            print(security.node_kit(out, args.kit))
            return 0
        if args.renew:
            manifest = security.renew(out, args.renew, days=args.days)
            folder = "operator" if args.renew in ("operator", "keel-operator") else f"nodes/{args.renew}"
            until = (manifest.tools.get("operator", {}) if folder == "operator"
                     else manifest.nodes[args.renew]).get("not_after")
            if folder == "operator":
                # A node loads the operator's certificate and grant at start
                # (docs/operations.md): until it restarts with the new ones, it checks
                # commands against the old ones, and refuses what the new key signs.
                print(f"renewed the operator: a new key, certificate and grant in {manifest.directory / folder}, "
                      f"valid until {until}; the ground signs with the new key.pem; give every node "
                      f"the new cert.pem and grant (its kit: --kit NAME) and restart it: until then it "
                      f"refuses what the new key signs (signature)")
            else:
                print(f"renewed {args.renew}: a new key, certificate and grant in {manifest.directory / folder}, "
                      f"valid until {until}; give them to the node and restart it (its peers accept them now)")
            return 0
        if args.revoke:
            manifest = security.revoke(out, args.revoke)
            print(f"revoked {args.revoke}: its certificate is in {manifest.directory / 'crl.pem'} "
                  f"(revoked: {', '.join(manifest.revoked)}); give every node the new crl.pem")
            return 0
        manifest = security.make_credentials(Path(args.mission), out, days=args.days, profile=args.profile,
                                             operator_verbs=[v for v in args.operator_verbs.split(",") if v])
    except security.CredentialsError as error:
        print(f"keel-cluster credentials: {error}", file=sys.stderr)
        return 2
    try:
        for line in security.describe(manifest):
            print(line)
    except BrokenPipeError:  # | head
        sys.stdout = None  # type: ignore[assignment] - nothing more to write
    return 0


def print_report(report: dict[str, Any]) -> None:
    print(f"run directory: {report['run_dir']}  ({report['trace_lines']} trace lines)")
    print("timeline:")
    t0 = report["events"][0]["t_ns"] if report["events"] else 0
    for event in report["events"]:
        print(f"  {(event['t_ns'] - t0) / 1e9:8.3f}s  {event['action']:<9} {event['argument']}")
    if report["faults"]:
        print("reconfigurations (ms):")
        print(f"  {'event':<18}{'detect':>9}{'decide':>9}{'switch':>9}{'restore':>9}{'total':>9}  master/config")
        for f in report["faults"]:
            cells = [f.get(k) for k in ("detection_ms", "decision_ms", "switch_ms", "restore_ms", "total_ms")]
            shown = "".join(f"{c:9.2f}" if c is not None else f"{'-':>9}" for c in cells)
            print(f"  {f['kind'] + ' ' + f['target']:<18}{shown}  {f.get('new_master') or '-'}/{f.get('config') or '-'}")
    if report.get("moves"):
        print("tasks moved:")
        for move in report["moves"]:
            shown = analysis.TaskMove(move["t_ns"], move["task"], move["from"], move["to"],
                                      move["version"], tuple(move["lineage"]), move["restored"])
            print(f"  {(move['t_ns'] - t0) / 1e9:8.3f}s  {shown.describe()}")
    r = report["reliability"]
    print(
        f"reliability: lost tasks {r['lost_tasks']}, double activations {r['double_activations']}, "
        f"split masters {r['split_masters']}, lost checkpoints {r['lost_checkpoints']}"
    )
    print(
        f"fault model 2: two running Masters {r['two_masters_ms']} ms, a task on two nodes "
        f"{r['double_run_ms']} ms, activations below a known version {r['activations_below_known']}, "
        f"starts with the state out of reach {r.get('unrecoverable_starts', 0)}, "
        f"exclusions of nodes no fault touched {r['false_exclusions']}"
    )
    for detail in r["details"]:
        print(f"  {detail}")
    if report["crashed_nodes"]:
        print(f"nodes that exited on their own: {', '.join(report['crashed_nodes'])} (see their .log)")


def _security_flags(parser: argparse.ArgumentParser) -> None:
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--insecure", action="store_true",
                       help="no DDS Security (nodes get --insecure); for tests that need it")
    group.add_argument("--security-profile", choices=list(security.PROFILES), default=security.DEFAULT_PROFILE,
                       help="governance profile of the cluster's credentials (default encrypt)")


def _domain_id(text: str) -> int:
    """A DDS domain id as keel-node takes it (0..232)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a DDS domain id (0..232)") from None
    if not 0 <= value <= 232:
        raise argparse.ArgumentTypeError(f"{value} is not a DDS domain id (0..232)")
    return value


def _vote_span(text: str) -> int:
    """The vote's span past its wait, in heartbeat periods (1..VOTE_SPAN_PERIODS_MAX)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of periods") from None
    if not 1 <= value <= VOTE_SPAN_PERIODS_MAX:
        raise argparse.ArgumentTypeError(f"{value} periods: the vote span is 1..{VOTE_SPAN_PERIODS_MAX}")
    return value


def _port(text: str) -> int:
    """A TCP port, 0 for any free one."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number (0..65535)") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"{value} is not a port number (0..65535)")
    return value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="keel-cluster", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="version", version=f"keel-cluster {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    p = sub.add_parser("run", help="run one keel-node per node of a mission")
    p.add_argument("mission")
    p.add_argument("--scenario", help="scenario file (timed faults and commands)")
    p.add_argument("--netns", action="store_true", help="each node in its own network namespace")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.add_argument("--duration", help="run length, e.g. 10s (overrides the scenario's)")
    p.add_argument("--run-dir", help="where traces, logs and report.json go (default runs/...)")
    p.add_argument("--node-binary",
                   help="node binary to run: keel-node, or one of your own built with keel_add_node "
                        "(docs/components.md; default: the CMake build's keel-node)")
    p.add_argument("--quiet", action="store_true", help="no live status")
    p.add_argument("--realtime", action="store_true",
                   help="every node's protocol loop under SCHED_FIFO above its tasks, memory locked "
                        "(keel-node --realtime; each node's log and status say what it got)")
    p.add_argument("--domain", type=_domain_id, metavar="ID",
                   help="DDS domain id, 0..232 (default 100 + pid %% 100; printed at start)")
    p.add_argument("--ground", action="store_true",
                   help="read commands on stdin while the cluster runs, one per line: the ground's "
                        "(phase NAME, recover CONFIG, exclude NODE, readmit NODE, pause-task TASK, "
                        "resume-task TASK, designate NODE; signed with the run's "
                        "operator key) and the scenario's faults (kill NODE, ...); quit ends the run "
                        "(docs/operations.md)")
    p.add_argument("--console", nargs="?", const=0, type=_port, metavar="PORT",
                   help="serve the run's live console on 127.0.0.1 (PORT, or any free port) and print "
                        "its URL; its page may send the run commands, as --ground's stdin; it closes "
                        "with the run (keel-cluster console RUN_DIR replays it)")
    p.add_argument("--vote-span", type=_vote_span, default=VOTE_SPAN_PERIODS, metavar="PERIODS",
                   help="designate NODE: the ground's vote lasts this many heartbeat periods past its wait "
                        f"(default {VOTE_SPAN_PERIODS}); WAIT is the periods left of the latest span given "
                        "another node, ECHO NODE's latest heartbeat number. A mission with "
                        "heartbeat.tie_grace only, and not with --insecure: nodes take designate only signed")
    _security_flags(p)
    p.set_defaults(func=run)

    w = sub.add_parser("console", help="a live console of a run directory in the browser (a live run or a "
                                       "finished one, played back)")
    w.add_argument("run_dir", metavar="RUN_DIR", nargs="?",
                   help="the run directory to follow; with --dds, the folder the observation is recorded in "
                        "(default: a new one in the system's temporary folder, printed)")
    w.add_argument("--port", type=_port, default=0, help="port on 127.0.0.1 (default: any free port, printed)")
    w.add_argument("--mission", help="the mission (image or YAML) when RUN_DIR holds no *.image.json; with "
                                     "--dds, the image the nodes fly (required)")
    w.add_argument("--dds", type=int, metavar="DOMAIN",
                   help="join the cluster's protocol DDS domain read only (keel-observe) instead of reading "
                        "its files: a cluster on another machine, or one that writes no traces")
    w.add_argument("--security", metavar="DIR",
                   help="with --dds: the mission's credentials (RUN_DIR/security, or keel-cluster credentials' "
                        "folder); the console joins as their subscribe-only monitor identity. Without it, "
                        "--dds joins an --insecure cluster")
    w.add_argument("--interface", default="lo", help="with --dds: the network interface DDS uses (default lo)")
    w.add_argument("--peer", action="append", default=None, metavar="ADDRESS",
                   help="with --dds: a node's unicast address (repeatable; default 127.0.0.1): DDS discovers "
                        "peers by unicast only, so the nodes must list this machine among theirs too")
    w.set_defaults(func=console.main_console)

    b = sub.add_parser("bench", help="the paper's figures 9, 10, 11, 13 measured on a real cluster")
    b.add_argument("mission")
    b.add_argument("--quick", action="store_true", help="few samples of each figure (a smoke test)")
    b.add_argument("--netns", action="store_true", help="each node in its own network namespace")
    b.add_argument("--out", default="bench-results", help="folder for cluster.json and cluster/ (plots)")
    b.add_argument("--figures", default="9,10,11,13", help="which figures, e.g. 9,10")
    b.add_argument("--periods", help="Fig. 10 heartbeat periods in ms (default 100,...,4000)")
    b.add_argument("--samples", type=int, help="Fig. 10 samples per period (default: per period)")
    b.add_argument("--seed", type=int, default=1, help="seed for the failed node and the failure time")
    b.add_argument("--realtime", action="store_true",
                   help="every node with keel-node --realtime (the report's `scheduling`)")
    b.add_argument("--replot", action="store_true",
                   help="measure nothing: summaries, simulator comparison and plots from the last report")
    b.add_argument("--node-binary",
                   help="node binary to run: keel-node, or one of your own built with keel_add_node "
                        "(docs/components.md; default: the CMake build's keel-node)")
    _security_flags(b)
    b.set_defaults(func=lambda a: __import__("keel_cluster.bench", fromlist=["main_bench"]).main_bench(a))

    c = sub.add_parser("campaign", help="reliability campaign: many short clusters with faults")
    c.add_argument("mission")
    c.add_argument("--failures", type=int, default=200, help="node failures to inject in total")
    c.add_argument("--phase-switches", type=int, default=200, help="phase switches in total")
    c.add_argument("--netns", action="store_true", help="each node in its own network namespace")
    c.add_argument("--seed", type=int, default=1)
    c.add_argument("--max-minutes", type=float, default=30.0, help="stop after this long")
    c.add_argument("--kinds", default="worker,master,double,storage,partition",
                   help="scenarios to draw from, in turn (also: deaf, pause — fault model 2)")
    c.add_argument("--out", default="bench-results/campaign.json",
                   help="report file (a folder gets campaign.json inside it)")
    c.add_argument("--node-binary",
                   help="node binary to run: keel-node, or one of your own built with keel_add_node "
                        "(docs/components.md; default: the CMake build's keel-node)")
    c.add_argument("--validate-traces", action=argparse.BooleanOptionalAction, default=True,
                   help="validate every run's traces against the specs (keel-verify trace; "
                        "on by default); report coverage per protocol; a rejected trace, or "
                        "one with lines left unvalidated, is a problem")
    _security_flags(c)
    c.set_defaults(func=lambda a: __import__("keel_cluster.campaign", fromlist=["main_campaign"]).main_campaign(a))

    k = sub.add_parser("credentials", help="DDS Security credentials for a mission (CA, identities, permissions)")
    k.add_argument("mission", help="mission YAML or compiled image")
    k.add_argument("--out", required=True, help="folder for the credentials (replaced as a whole)")
    k.add_argument("--days", type=int, default=security.DEFAULT_DAYS,
                   help=f"validity of the certificates and permissions (default {security.DEFAULT_DAYS})")
    k.add_argument("--profile", choices=list(security.PROFILES), default=security.DEFAULT_PROFILE,
                   help="governance: encrypt (data encrypted, submessages signed; default), "
                        "full (every RTPS message encrypted), sign (signed only)")
    k.add_argument("--revoke", metavar="NAME",
                   help="make nothing: add node NAME's certificate to the CRL of the set in --out")
    k.add_argument("--kit", metavar="NAME",
                   help="make nothing else: copy what node NAME is given (its --security DIR: public "
                        "material and its own key, never the CA's) to DIR/kits/NAME and print the path")
    k.add_argument("--renew", metavar="NAME",
                   help="make nothing else: issue node NAME (or the operator) a new key, certificate and "
                        "grant, valid for --days from now, in the set in --out (its CA's key is needed)")
    k.add_argument("--operator-verbs", default=",".join(security.GROUND_VERBS), metavar="VERB,...",
                   help="the ground commands the operator may send (docs/operations.md; default "
                        f"{','.join(security.GROUND_VERBS)})")
    k.set_defaults(func=credentials)
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return 2
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
