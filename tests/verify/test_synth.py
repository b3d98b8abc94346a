"""Synthesis: its output passes check (and the explicit oracle) on the paper's missions
and on generated ones; an intolerable mission is refused; --suggest proposes
configurations that are valid under the counterexample's failures; graph draws the
violations."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest
from explicit import explore, invalidities
from keel_verify.check.core import check_mission
from keel_verify.generate import generate, to_mission, to_yaml
from keel_verify.mission import load_mission, loads_mission
from keel_verify.synth.core import synthesize
from test_fixtures import ROOT, run


@pytest.mark.parametrize("mission", ["config/earth_observation.yaml", "config/prototype3.yaml"])
def test_synth_of_the_paper_missions_is_proved(mission: str, tmp_path: Path) -> None:
    out = tmp_path / "synth.yaml"
    code, text, err = run("synth", str(ROOT / mission), "-o", str(out))
    assert code == 0, err
    assert "check: PROVED" in text
    synthesised = load_mission(out)
    original = load_mission(ROOT / mission)
    for key in ("nodes", "tasks", "tolerance", "heartbeat"):
        assert synthesised.to_json()[key] == original.to_json()[key]


def test_synth_keeps_the_file_and_the_names_it_can(tmp_path: Path) -> None:
    # Everything but the phases is the file as written (comments, block style, key
    # order); a synthesised configuration that is one of the file's keeps its name (C2:
    # PN2 the master, t1 on PN2), a new one gets a name of its own.
    source = ROOT / "tests" / "missions" / "good" / "minimal.yaml"
    out = tmp_path / "synth.yaml"
    code, _, err = run("synth", str(source), "-o", str(out))
    assert code == 0, err
    text, written = source.read_text(), out.read_text()
    head = text[: text.index("phases:")]
    assert head.startswith("# The smallest useful mission") and written.startswith(head)
    mission = load_mission(out)
    configs = mission.phases["main"].configurations
    assert set(configs) == {"C1", "C2", "C1_PN2"}
    assert (configs["C2"].master, configs["C2"].placement) == ("PN2", {"t1": "PN2"})
    assert mission.phases["main"].on_failure["C1"] == {"PN1": "C2", "PN2": "C1_PN2"}


def test_synth_keeps_the_comments_of_the_phases_where_their_keys_stay(tmp_path: Path) -> None:
    # A comment above a phase or a configuration stays above it, a trailing one on its
    # line; one about a part of the graph the synthesised one writes otherwise (an edge of
    # a block-style edge list: synth writes one line per configuration) is named, with its
    # line, on stderr.
    text = (ROOT / "tests" / "missions" / "good" / "minimal.yaml").read_text()
    text = text.replace("phases:\n  main:\n", "phases:\n  # the only phase\n  main:\n")
    text = text.replace("      C1:\n        master: PN1",
                        "      # nominal: PN1 commands\n      C1:\n        master: PN1")
    text = text.replace("      C2:\n", "      C2:  # PN2 alone\n")
    text = text.replace("        PN1: C2\n        PN2: SAFE\n",
                        "        PN1: C2  # PN1 lost\n        # a second failure\n"
                        "        PN2: SAFE\n")
    # A trailing comment on a line with quotes is not parsed here: named too.
    text = text.replace("    initial: C1\n", "    initial: \"C1\"  # quoted\n")
    source = tmp_path / "commented.yaml"
    source.write_text(text)
    out = tmp_path / "synth.yaml"
    code, _, err = run("synth", str(source), "-o", str(out))
    assert code == 0, err
    written = out.read_text().splitlines()
    assert written[written.index("  # the only phase") + 1] == "  main:"
    nominal = written.index("      # nominal: PN1 commands")
    assert written[nominal + 1].startswith("      C1: {master: PN1")
    assert any(line.startswith("      C2: {master: PN2") and line.endswith("  # PN2 alone")
               for line in written)
    lines = text.splitlines()
    for comment in ("PN1: C2  # PN1 lost", "# a second failure", 'initial: "C1"  # quoted'):
        number = next(i for i, line in enumerate(lines, 1) if line.strip() == comment)
        assert f"{source}:{number}: synth: this comment was about a part of the graph" in err
    assert err.count("not carried over") == 3
    assert load_mission(out).phases["main"].configurations.keys() == {"C1", "C2", "C1_PN2"}


def test_synth_keeps_the_name_of_the_configuration_whose_place_it_takes(tmp_path: Path) -> None:
    # earth-observation's D2 is where its graph goes when PN1 fails in D1; the synthesised
    # configuration for that failure differs (another node hosts aocs) but keeps the name.
    out = tmp_path / "synth.yaml"
    code, _, err = run("synth", str(ROOT / "config" / "earth_observation.yaml"), "-o", str(out))
    assert code == 0, err
    original = load_mission(ROOT / "config" / "earth_observation.yaml").phases
    synthesised = load_mission(out).phases
    for phase in ("observation", "downlink"):
        assert set(synthesised[phase].configurations) == set(original[phase].configurations)
        assert synthesised[phase].on_failure[synthesised[phase].initial] == \
            original[phase].on_failure[original[phase].initial]
    assert synthesised["downlink"].configurations["D2"] != original["downlink"].configurations["D2"]


@pytest.mark.parametrize("nodes,k,phases", [(3, 1, 1), (4, 2, 2), (5, 1, 2), (6, 2, 1)])
def test_synth_of_generated_missions_passes_both_checkers(nodes: int, k: int, phases: int) -> None:
    data = generate(nodes, k, seed=nodes * 10 + k, phases=phases)
    result = synthesize(to_mission(data))
    mission = loads_mission(to_yaml(result.data), "synth.yaml")
    assert check_mission(mission).valid
    assert explore(mission).valid
    # Fewest moves: a single failure moves only the tasks of the failed node here
    # (capacity is generous in generated missions).
    assert max(result.moves) <= max(
        sum(1 for n in c.placement.values() if n == c.master) + len(c.placement)
        for c in mission.phases[next(iter(mission.phases))].configurations.values())


def test_synth_refuses_a_mission_that_cannot_tolerate_its_failures(tmp_path: Path) -> None:
    text = (ROOT / "config" / "earth_observation.yaml").read_text()
    text = text.replace("nodes: [PN1, PN2, PN3, PN4]}", "nodes: [PN1, PN2, PN3, PN4, IF1]}")
    source = tmp_path / "camera-may-fail.yaml"
    source.write_text(text)
    code, _, err = run("synth", str(source), "-o", str(tmp_path / "out.yaml"))
    assert code == 1
    assert "no valid configuration when IF1 failed" in err


SUGGESTED = re.compile(r"(?:replace with|configuration|add) ([A-Za-z0-9_]+): (\{.*\}) \(valid")
# An edge to a configuration the mission has (the smallest fix for a missing edge).
EDGE_TO_EXISTING = re.compile(
    r"add on_failure ([A-Za-z0-9_]+): \{([A-Za-z0-9_]+): ([A-Za-z0-9_]+)\} "
    r"\(configuration \3 is valid")


@pytest.mark.parametrize("fixture", ["missing-transition", "task-on-failed-node", "capacity",
                                     "capability", "task-missing", "master-invalid",
                                     "observer-invalid", "master-mismatch",
                                     "safe-mode-within-tolerance", "phase-transition-invalid"])
def test_suggestions_are_valid_under_the_counterexample(fixture: str) -> None:
    path = ROOT / "tests" / "verify" / "missions" / f"{fixture}.yaml"
    code, out, _ = run("check", str(path), "--suggest", "--json")
    assert code == 1
    report = json.loads(out)
    for v in report["violations"]:
        if edge := EDGE_TO_EXISTING.search(v["suggestion"]):
            source, node, target = edge.groups()
            assert (source, node) == (v["config"], v["node"]), v
            assert invalidities(load_mission(path), target, frozenset(v["failures"])) == []
            continue
        match = SUGGESTED.search(v["suggestion"])
        assert match, v["suggestion"]
        name, body = match.groups()
        phase = v["target"] if v["kind"] == "phase-transition-invalid" else v["phase"]
        text = path.read_text()
        original = load_mission(path)
        # Put the suggested configuration into its phase (replacing one of that name).
        lines = [ln for ln in text.splitlines() if not ln.strip().startswith(f"{name}: {{master")]
        anchor = next(i for i, ln in enumerate(lines)
                      if ln.strip() == "configurations:" and _phase_of_line(lines, i) == phase)
        lines.insert(anchor + 1, f"      {name}: {body}")
        mission = loads_mission("\n".join(lines) + "\n", "suggested.yaml")
        assert mission.to_json()["tasks"] == original.to_json()["tasks"]
        assert invalidities(mission, name, frozenset(v["failures"])) == []


def test_a_missing_edge_is_suggested_to_a_configuration_the_mission_has(tmp_path: Path) -> None:
    # The minimal mission without its edge for PN1's failure in C1: C2 (PN2 the master,
    # t1 on PN2) is valid there, so the suggestion is the edge to it, not a new
    # configuration that repeats C2. Where no configuration fits (PN2's failure: t1 must
    # move to PN1, the master), a new one is offered, with its edge.
    text = (ROOT / "tests" / "missions" / "good" / "minimal.yaml").read_text()
    edge = "      C1:\n        PN1: C2\n        PN2: SAFE"
    assert edge in text
    path = tmp_path / "minimal-without-an-edge.yaml"
    path.write_text(text.replace(edge, "      C1:\n        PN2: SAFE"))
    code, out, _ = run("check", str(path), "--suggest", "--json")
    assert code == 1
    suggestions = {(v["kind"], v["node"]): v["suggestion"] for v in json.loads(out)["violations"]}
    assert suggestions[("missing-transition", "PN1")] == (
        "add on_failure C1: {PN1: C2} (configuration C2 is valid under failures PN1)")
    path.write_text(text.replace(edge, "      C1:\n        PN1: C2"))
    code, out, _ = run("check", str(path), "--suggest", "--json")
    (v,) = [v for v in json.loads(out)["violations"]
            if (v["kind"], v["config"], v["node"]) == ("missing-transition", "C1", "PN2")]
    assert v["suggestion"].startswith(
        "add on_failure C1: {PN2: C1_PN2} and configuration C1_PN2:"), v


def test_a_missing_edge_is_never_suggested_to_a_configuration_of_another_master(
        tmp_path: Path) -> None:
    # P1 has no edge for PN3's failure (an Observer: PN1 stays the Master). P4 (PN1, the
    # consumer moved to PN1) is the fix. P0 moves as few tasks and is valid there too, but
    # names PN2 its master: the runtime would go to safe mode instead, so it is not offered
    # (and it would be, by name, without the master's filter).
    path = ROOT / "tests" / "verify" / "missions" / "missing-transition.yaml"
    text = path.read_text()
    p4 = "      P4: {master: PN1, observers: [PN2], tasks: {producer: PN2, consumer: PN1}}\n"
    assert p4 in text
    p0 = "      P0: {master: PN2, observers: [PN1], tasks: {producer: PN2, consumer: PN1}}\n"
    variant = tmp_path / "missing-transition-two-candidates.yaml"
    variant.write_text(text.replace(p4, p4 + p0))
    code, out, _ = run("check", str(variant), "--suggest", "--json")
    (v,) = [v for v in json.loads(out)["violations"]
            if (v["kind"], v["config"], v["node"]) == ("missing-transition", "P1", "PN3")]
    assert v["suggestion"] == (
        "add on_failure P1: {PN3: P4} (configuration P4 is valid under failures PN3)")


def _phase_of_line(lines: list[str], index: int) -> str:
    for ln in reversed(lines[:index]):
        if re.match(r"^  [A-Za-z]", ln):
            return ln.strip().rstrip(":")
    return ""


def test_graph_draws_violations(tmp_path: Path) -> None:
    mission = ROOT / "tests" / "verify" / "missions" / "missing-transition.yaml"
    code, _, _ = run("graph", str(mission), "-o", str(tmp_path / "g.dot"))
    assert code == 1
    dot = (tmp_path / "g.dot").read_text()
    assert '"P1" -> missing0 [label="PN3", color="#c62828"' in dot
    code, _, _ = run("graph", str(ROOT / "config" / "prototype3.yaml"), "-o", str(tmp_path / "p.dot"))
    assert code == 0 and "#c62828" not in (tmp_path / "p.dot").read_text()


def test_graph_names_the_formats_it_writes(tmp_path: Path,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    def proved(*_args: object) -> None:
        raise AssertionError("the mission was proved before the bad argument was said")

    monkeypatch.setattr("keel_verify.graph.check_file", proved)
    code, _, err = run("graph", str(ROOT / "config" / "prototype3.yaml"), "-o",
                       str(tmp_path / "g.out"))
    assert code == 2 and "no output format 'out'" in err and ".svg, .png, .pdf, .dot" in err
    assert not (tmp_path / "g.out").exists()


@pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz is not installed")
def test_graph_renders_svg(tmp_path: Path) -> None:
    code, out, _ = run("graph", str(ROOT / "config" / "earth_observation.yaml"), "-o",
                       str(tmp_path / "g.svg"))
    assert code == 0 and "proved valid" in out
    assert (tmp_path / "g.svg").read_text().lstrip().startswith("<?xml")


def test_graph_without_graphviz_is_a_clear_error(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(shutil, "which", lambda _name: None)
    code, _, err = run("graph", str(ROOT / "config" / "prototype3.yaml"), "-o",
                       str(tmp_path / "g.svg"))
    assert code == 2 and "Graphviz 'dot' is not installed" in err
