"""The campaign's reading of the mission graph and its split of timeouts into expected and
unexpected: synthetic runs whose answers are known."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from keel_cluster.campaign import build_report, failure_timeout, phase_timeout, summary_lines
from keel_cluster.common import ONLINE, SAFE, Graph, summarize

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def graph() -> Graph:
    found = summarize(ROOT / "config" / "prototype3.yaml").graph
    assert found is not None
    return found


def test_graph_follows_prototype3(graph: Graph) -> None:
    # One failure: the edge of the configuration; a second one: SAFE; the storage node
    # matters everywhere and has no edge: SAFE.
    assert graph.after_failure("P1", "PN1", {"PN1"}) == "P2"
    assert graph.after_failure("P1", "PN2", {"PN2"}) == "P3"
    assert graph.after_failure("P3", "PN3", {"PN2", "PN3"}) == SAFE
    assert graph.after_failure("P1", "ST1", {"ST1"}) == SAFE
    # A node that does not matter to the configuration changes nothing; SAFE is terminal.
    assert graph.after_failure("P3", "PN2", {"PN2"}) == "P3"
    assert graph.after_failure(SAFE, "PN1", {"PN1"}) == SAFE
    assert graph.after_phase("P3", "science", {"PN2"}) == "S3"
    assert graph.after_phase(SAFE, "science", set()) is None


def test_beyond_the_graph_the_campaign_prescribes_an_online_configuration() -> None:
    # config/earth_observation_online.yaml (graph+online): the graph's edge for one
    # failure, the placer where the graph says SAFE; once online, online; a phase command
    # from online goes to the target phase's configuration of the failed set where that is
    # not SAFE, else to its placer; a readmission back to the graph where it answers.
    online = summarize(ROOT / "config" / "earth_observation_online.yaml").graph
    assert online is not None
    assert online.after_failure("C1", "PN4", {"PN4"}) == "C5"
    assert online.after_failure("C5", "PN1", {"PN4", "PN1"}) == ONLINE
    assert online.after_failure(ONLINE, "PN2", {"PN4", "PN1", "PN2"}) == ONLINE
    assert online.after_phase(ONLINE, "downlink", {"PN4", "PN1"}) == ONLINE
    assert online.after_phase(ONLINE, "downlink", {"PN4"}) == "D5"
    assert online.after_recovery("C5", {"PN4"}, ONLINE, "PN1") == "C5"
    assert online.after_recovery("C5", {"PN4", "PN2"}, ONLINE, "PN1") == ONLINE
    # The graph alone: SAFE there.
    graph_only = summarize(ROOT / "config" / "earth_observation.yaml").graph
    assert graph_only is not None
    assert graph_only.after_failure("C5", "PN1", {"PN4", "PN1"}) == SAFE


def test_recovery_returns_to_the_configuration_of_the_smaller_failed_set(graph: Graph) -> None:
    # Topology::recovery_target: the walk from the phase's initial configuration.
    assert graph.after_recovery("P2", set()) == "P1"  # the old Master is back
    assert graph.after_recovery("S4", set()) == "S1"  # the phase is the base's
    # Out of SAFE (P3, then PN3): PN3 back leaves PN2 failed, which is P3.
    assert graph.after_recovery("P3", {"PN2"}) == "P3"
    # Two nodes still failed is beyond the graph: still SAFE.
    assert graph.after_recovery("P1", {"PN2", "PN3"}) == SAFE


def test_recovery_follows_the_missions_edge(graph: Graph) -> None:
    # An on_recovery edge from the current configuration wins over the walk; from SAFE,
    # or for another node, the walk.
    edged = dataclasses.replace(graph, on_recovery={"P4": {"PN3": "P3"}})
    assert edged.after_recovery("P4", set(), "P4", "PN3") == "P3"
    assert edged.after_recovery("P4", set(), "P4", "PN2") == "P1"
    assert edged.after_recovery("P4", set(), SAFE, "PN3") == "P1"
    assert graph.after_recovery("P4", set(), "P4", "PN3") == "P1"


def test_phase_edge_into_a_failed_host_is_refused() -> None:
    graph = Graph(matters={"A": {"N1", "N2"}, "B": {"N1", "N2"}}, uses={"A": {"N1"}, "B": {"N1", "N2"}},
                  hosts={"A": {"N1"}, "B": {"N2"}}, on_failure={}, on_phase={"A": {"p2": "B"}},
                  initial_of={"A": "A", "B": "A"}, order=["N1", "N2"])
    assert graph.after_phase("A", "p2", set()) == "B"
    assert graph.after_phase("A", "p2", {"N2"}) is None
    expected, why = phase_timeout(graph, "A", "p2", {"N2"}, "A", "A -kill N2-> A")
    assert expected and why.startswith("refused, as specified")


def test_phase_refused_in_prescribed_safe_mode_is_expected(graph: Graph) -> None:
    expected, why = phase_timeout(graph, SAFE, "science", {"ST1"}, SAFE, "P1 -kill ST1-> SAFE")
    assert expected and why.startswith("safe mode is terminal") and "kill ST1" in why


def test_safe_mode_the_graph_does_not_prescribe_is_unexpected(graph: Graph) -> None:
    # A partitioned and healed node: the graph leads to P3, the cluster ended in SAFE.
    expected, why = phase_timeout(graph, "P3", "science", {"PN2"}, SAFE, "P1 -partition PN2-> P3")
    assert not expected and "runs SAFE" in why and "prescribes P3" in why
    # Where the graph leads and still not switched: unexpected too.
    expected, why = phase_timeout(graph, "P3", "science", {"PN2"}, "P3", "P1 -partition PN2-> P3")
    assert not expected and "not carried out" in why


def test_failure_timeouts() -> None:
    assert failure_timeout("PN1", "timeout", SAFE, SAFE, SAFE, 5.5)[0]
    assert failure_timeout("PN2", "timeout", "P3", "P3", "P3", 5.5)[0]
    expected, why = failure_timeout("PN2", "timeout", "P1", "P3", "P1", 5.5)
    assert not expected and "P1 -> P3" in why
    assert not failure_timeout("PN2", "gone", "P1", "P3", "P1", 5.5)[0]


def run_row(index: int, timeouts: list[dict[str, object]], ended: str, prescribed: str) -> dict[str, object]:
    return {"index": index, "kind": "storage", "failures": 1, "phase_switches": 2, "timeouts": timeouts,
            "victims": ["kill ST1"], "lost_tasks": 0, "double_activations": 0, "split_masters": 0,
            "lost_checkpoints": 0, "activations_below_known": 0, "unrecoverable_starts": 0, "false_exclusions": 0,
            "two_masters_ms": 0.0, "double_run_ms": 0.0, "crashed_nodes": [], "ended": ended, "prescribed": prescribed,
            "ended_as_prescribed": ended == prescribed, "graph_steps": [f"P1 -kill ST1-> {prescribed}"]}


def report_of(rows: list[dict[str, object]]) -> dict[str, object]:
    totals = {"failures": 1, "phase_switches": 2, "lost_tasks": 0, "double_activations": 0, "split_masters": 0,
              "lost_checkpoints": 0, "activations_below_known": 0, "unrecoverable_starts": 0, "false_exclusions": 0, "two_masters_ms": 0.0,
              "double_run_ms": 0.0}
    return build_report(rows, totals, mission=Path("m.yaml"), use_netns=False, seed=1, kinds=["storage"],
                        period_ms=100, miss_limit=3, complete=True, seconds=1.0, run_root=Path("/tmp/x"))


def test_only_unexpected_timeouts_are_problems() -> None:
    ok = {"what": "phase science", "expected": True, "why": "safe mode is terminal: refused"}
    report = report_of([run_row(0, [ok], SAFE, SAFE)])
    assert report["timeouts"] == {"total": 1, "expected": 1, "expected_by_reason": {"safe mode is terminal": 1},
                                  "unexpected": 0, "unexpected_list": []}
    assert report["problems"] == 0
    # The same timeout, unexpected: one problem, listed with its run, and printed.
    bad = dict(ok, expected=False, why="the cluster runs SAFE, the graph prescribes P3")
    report = report_of([run_row(4, [bad], "P3", "P3")])
    assert report["problems"] == 1 and report["timeouts"]["unexpected_list"][0]["run"] == 4
    assert any("run 4 (storage): phase science" in line for line in summary_lines(report))


def test_an_ending_the_graph_does_not_prescribe_is_a_problem() -> None:
    report = report_of([run_row(7, [], SAFE, "P3")])
    assert report["problems"] == 1 and report["runs_astray"] == [7]
    # With the phase command it then times out on: still one run astray.
    bad = {"what": "phase science", "expected": False, "why": "the cluster runs SAFE, the graph prescribes P3"}
    assert report_of([run_row(7, [bad], SAFE, "P3")])["problems"] == 1
    assert report["unprescribed_endings"][0]["run"] == 7
    assert any("ended in SAFE, prescribed P3" in line for line in summary_lines(report))


def test_out_names_a_file_or_a_folder_and_is_checked_before_any_cluster(tmp_path: Path) -> None:
    from keel_cluster.campaign import OutputError, resolve_out

    assert resolve_out(tmp_path) == tmp_path / "campaign.json"
    assert resolve_out(tmp_path / "new" / "c.json") == tmp_path / "new" / "c.json"
    (tmp_path / "taken").mkdir()
    (tmp_path / "taken" / "campaign.json").mkdir()
    with pytest.raises(OutputError, match="not a regular file"):
        resolve_out(tmp_path / "taken")
    (tmp_path / "file").write_text("")
    with pytest.raises(OutputError, match="not a writable folder"):
        resolve_out(tmp_path / "file" / "c.json")


def test_campaign_cli_refuses_an_unusable_out_without_starting(tmp_path: Path) -> None:
    import subprocess
    import sys

    (tmp_path / "file").write_text("")
    done = subprocess.run(
        [sys.executable, "-m", "keel_cluster.cli", "campaign", str(ROOT / "config" / "prototype3.yaml"),
         "--out", str(tmp_path / "file" / "c.json")],
        capture_output=True, text=True, timeout=60, check=False,
        env={"PYTHONPATH": str(ROOT / "nodes" / "cluster") + ":" + str(ROOT / "verify"), "PATH": "/usr/bin:/bin"})
    assert done.returncode == 2, done.stderr
    assert "not a writable folder" in done.stderr and "Traceback" not in done.stderr


def test_plot_writes_a_png_per_measured_figure(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    from keel_cluster.bench import plot

    report = {
        "mode": "loopback",
        "load_average_end": [0.5, 0.5, 0.5],
        "figures": {
            "9": {"samples_total_ms": [2.0, 2.5, 3.1, 4.4], "completed": 4},
            "11": {"min_ms": 5.0, "p50_ms": 15.0, "mean_ms": 15.1, "p99_ms": 24.6, "max_ms": 25.0,
                   "switches": 150},
        },
    }
    assert plot(report, tmp_path / "out") == ["fig9.png", "fig11.png"]
    for name in ("fig9.png", "fig11.png"):
        assert (tmp_path / "out" / name).read_bytes().startswith(b"\x89PNG")
    assert not (tmp_path / "out" / "fig10.png").exists()


def test_trace_validation_is_summed_per_protocol_over_the_runs() -> None:
    from keel_cluster.campaign import trace_summary

    rows = [
        {"trace": {"exit_code": 0, "coverage": {"switch": {"validated": 10, "total": 10}}}},
        {"trace": {"exit_code": 3, "coverage": {"switch": {"validated": 4, "total": 9}}}},
        {"trace": {"exit_code": 1, "coverage": {}}},
        {},
    ]
    summary = trace_summary(rows)
    assert summary["per_protocol"] == {"switch": {"validated": 14, "total": 19}}
    assert summary["runs_by_exit_code"] == {"0": 1, "3": 1, "1": 1}
    # A rejected trace (1) and one with lines left unvalidated (3) are problems.
    assert summary["runs_rejected"] == 1 and summary["runs_not_validated"] == 2
