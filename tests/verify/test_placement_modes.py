"""A phase's `placement` (docs/missions.md, "Placement modes and what is proved"): bad
values and online phases with edges are input errors at their line; compile writes the
field only when it is not graph (graph images keep their bytes); keel-verify check proves
the online phases with keel-place --prove and reports its violations as its own (exit 1,
the failure sequence named), and says how to build keel-place when it is missing (exit 2).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import sys
from pathlib import Path

import pytest
from keel_verify.cli import main

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))
from docblocks import differs, text_block

MISSIONS = ROOT / "tests" / "verify" / "missions"
ONLINE = MISSIONS / "online"
THREE = MISSIONS / "valid-three-nodes.yaml"


def run(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(argv))
    return code, out.getvalue(), err.getvalue()


def with_placement(tmp_path: Path, value: str, source: Path = THREE) -> Path:
    mission = tmp_path / f"{source.stem}.yaml"
    mission.write_text(source.read_text().replace("    initial: P1",
                                                  f"    placement: {value}\n    initial: P1"))
    return mission


def keel_place_built() -> None:
    build = os.environ.get("KEEL_BUILD_DIR")
    if not build or not (Path(build) / "core" / "placement" / "keel-place").is_file():
        pytest.skip("keel-place is not built (KEEL_BUILD_DIR): checked under CTest")


def test_an_unknown_placement_is_an_input_error_at_its_line(tmp_path: Path) -> None:
    mission = with_placement(tmp_path, "anywhere")
    code, _, err = run("check", str(mission))
    assert code == 2
    line = next(i for i, text in enumerate(mission.read_text().splitlines(), 1)
                if "placement:" in text)
    assert f"{mission}:{line}:" in err and "placement" in err and "graph+online" in err


def test_an_online_phase_with_edges_is_an_input_error_naming_the_phase(tmp_path: Path) -> None:
    mission = with_placement(tmp_path, "online")
    code, _, err = run("check", str(mission))
    assert code == 2
    lines = mission.read_text().splitlines()
    configuration = next(i for i, t in enumerate(lines, 1) if t.strip().startswith("P2:"))
    edges = next(i for i, t in enumerate(lines, 1) if t.strip() == "on_failure:")
    assert f"{mission}:{configuration}:" in err and "phase nominal" in err
    assert f"{mission}:{edges}:" in err and "on_failure" in err


def test_compile_writes_placement_only_when_not_graph(tmp_path: Path) -> None:
    graph = tmp_path / "graph.json"
    assert run("compile", str(THREE), "-o", str(graph))[0] == 0
    assert all("placement" not in p for p in json.loads(graph.read_text())["content"]["phases"])
    explicit = tmp_path / "explicit.json"
    assert run("compile", str(with_placement(tmp_path, "graph")), "-o", str(explicit))[0] == 0
    # `placement: graph` stated or not: the same content, the same bytes but the source's hash.
    assert (json.loads(explicit.read_text())["content"]
            == json.loads(graph.read_text())["content"])
    online = tmp_path / "online.json"
    assert run("compile", str(ONLINE / "earth-observation-online.yaml"), "-o", str(online))[0] == 0
    assert [p.get("placement") for p in json.loads(online.read_text())["content"]["phases"]] == [
        "online", "online"]


def test_check_proves_the_online_phases(monkeypatch: pytest.MonkeyPatch) -> None:
    keel_place_built()
    monkeypatch.chdir(ROOT)
    mission = "tests/verify/missions/online/earth-observation-online.yaml"
    code, out, err = run("check", mission)
    assert code == 0, out + err
    assert ": PROVED valid under every sequence" in out.splitlines()[-1]
    assert "phase observation (online): keel-place proved 4 failed sets within tolerance" in out
    shown = text_block("docs/missions.md",
                       "tests/verify/missions/online/earth-observation-online.yaml: phase")
    problem = differs(shown, out.splitlines())
    assert problem is None, problem
    code, out, _ = run("check", mission, "--json")
    report = json.loads(out)
    assert report["valid"] is True
    assert [p["phase"] for p in report["stats"]["online"]["phases"]] == ["observation", "downlink"]


def test_check_proves_a_graph_plus_online_phase_where_its_graph_says_safe(tmp_path: Path) -> None:
    keel_place_built()
    source = MISSIONS / "safe-mode-within-tolerance.yaml"
    assert run("check", str(source))[0] == 1
    code, out, err = run("check", str(with_placement(tmp_path, "graph+online", source)))
    assert code == 0, out + err
    assert "phase nominal (graph+online): keel-place proved 3 failed sets" in out


def test_check_reports_the_placers_violation_with_its_failures(
        monkeypatch: pytest.MonkeyPatch) -> None:
    keel_place_built()
    monkeypatch.chdir(ROOT)
    mission = "tests/verify/missions/online/online-essential-unplaceable.yaml"
    code, out, _ = run("check", mission)
    assert code == 1
    lines = (ROOT / mission).read_text().splitlines()
    phase_line = next(i for i, t in enumerate(lines, 1) if t.startswith("  nominal:"))
    assert f"{mission}:{phase_line}:3: safe-mode-within-tolerance: " in out
    assert "path: P1 --PN3--> SAFE" in out
    code, out, _ = run("check", mission, "--json")
    assert code == 1
    (violation,) = json.loads(out)["violations"]
    assert violation["kind"] == "safe-mode-within-tolerance"
    assert violation["failures"] == ["PN3"] and violation["phase"] == "nominal"
    code, out, _ = run("check", mission, "--format", "github")
    assert code == 1 and f"::error file={mission},line={phase_line}," in out


def test_check_without_keel_place_says_how_to_build_it(tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("KEEL_BUILD_DIR", str(tmp_path / "no-build"))
    monkeypatch.delenv("KEEL_PLACE", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))
    code, _, err = run("check", str(ONLINE / "earth-observation-online.yaml"))
    assert code == 2
    assert "keel-place" in err and "--target keel-place" in err and "Traceback" not in err
    # A graph mission needs no keel-place.
    assert run("check", str(THREE))[0] == 0


def test_a_proof_that_gives_up_is_undecided(tmp_path: Path,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    """keel-place --prove bounds the failures it applies; a phase not fully explored is
    undecided (exit 3), never a pass."""
    keel_place_built()
    real = Path(os.environ["KEEL_BUILD_DIR"]) / "core" / "placement" / "keel-place"
    bounded = tmp_path / "keel-place"
    bounded.write_text(f'#!/bin/sh\nexec "{real}" "$@" --max-transitions 2\n')
    bounded.chmod(0o755)
    monkeypatch.setenv("KEEL_PLACE", str(bounded))
    code, out, _ = run("check", str(ONLINE / "earth-observation-online.yaml"))
    assert code == 3, out
    assert "UNDECIDED: keel-place --prove gave up on phase observation, downlink" in out


def test_check_with_a_keel_place_built_before_prove_says_to_rebuild_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    old = tmp_path / "keel-place"
    old.write_text("#!/bin/sh\necho 'The following argument was not expected: --prove' >&2\n"
                   "exit 2\n")
    old.chmod(0o755)
    monkeypatch.setenv("KEEL_PLACE", str(old))
    code, _, err = run("check", str(ONLINE / "earth-observation-online.yaml"))
    assert code == 2
    assert "built before it could prove" in err and "--target keel-place" in err


def _downlink_to_d1(tmp_path: Path, placement: str) -> Path:
    """The earth-observation mission with every phase change into downlink leading to D1
    (master PN1, aocs on PN1): after PN1 fails, that entry uses a failed node. With
    downlink placed `placement` (graph: its own graph kept)."""
    import yaml

    data = yaml.safe_load((ROOT / "config" / "earth_observation.yaml").read_text())
    data["phases"]["observation"]["on_phase"]["downlink"] = {
        c: "D1" for c in data["phases"]["observation"]["configurations"]}
    downlink = data["phases"]["downlink"]
    if placement == "online":
        downlink["placement"] = "online"
        downlink["configurations"] = {"D1": downlink["configurations"]["D1"]}
        downlink.pop("on_failure", None)
        downlink["on_phase"] = {"observation": {"D1": "C1"}}
    path = tmp_path / f"downlink-{placement}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def test_a_phase_change_into_an_online_phase_after_a_failure_is_the_placers(tmp_path: Path) -> None:
    # The runtime takes the on_phase entry where it is usable and asks the placer where it
    # is not (core/fsm/online.hpp, phase_target): after PN1's failure, D1 (master PN1) is
    # not usable, so the graph's proof holds no phase change into an online phase to its
    # entry after a failure. Into a phase placed by its graph alone it still does.
    keel_place_built()
    code, out, err = run("check", str(_downlink_to_d1(tmp_path, "online")))
    assert code == 0, out + err
    code, out, err = run("check", str(_downlink_to_d1(tmp_path, "graph")))
    assert code == 1 and "phase-transition-invalid" in out + err, out + err


def _downlink_pn3_first(tmp_path: Path) -> Path:
    """config/earth_observation.yaml with downlink placed online, its D1's observers PN3
    first: when PN1 fails in downlink the election makes PN3 Master, and observation's
    graph has C2 (master PN2) for PN1's failure."""
    path = _downlink_to_d1(tmp_path, "online")
    path.write_text(path.read_text().replace("observers:\n        - PN2\n        - PN3\n        - PN4",
                                             "observers:\n        - PN3\n        - PN2\n        - PN4"))
    assert "- PN3\n        - PN2\n        - PN4" in path.read_text()
    return path


def test_a_phase_change_the_runtime_refuses_within_the_tolerance_is_a_violation(
        tmp_path: Path) -> None:
    # keel-place --prove explores every phase change from every state it reaches, as the
    # Master makes it (core/fsm/online.hpp, phase_target): PN1 fails in downlink, PN3
    # becomes Master, and the change back to observation (placed by its graph, whose
    # configuration of PN1's failure is C2, PN2's) is refused: the mission can never return
    # to observation. Not vacuous: the shipped mission's changes are proved and counted.
    keel_place_built()
    code, out, err = run("check", str(_downlink_pn3_first(tmp_path)), "--json")
    assert code == 1, out + err
    found = [v for v in json.loads(out)["violations"] if v["kind"] == "phase-transition-invalid"]
    assert len(found) == 1, out
    violation = found[0]
    assert violation["phase"] == "downlink" and violation["failures"] == ["PN1"]
    assert "the change to phase observation is refused" in violation["message"]
    assert [(s["event"], s.get("node"), s.get("phase")) for s in violation["steps"]] == [
        ("start", None, "observation"), ("phase", None, "downlink"), ("failure", "PN1", None),
        ("phase", None, "observation")]
    code, out, err = run("check", str(ROOT / "config" / "earth_observation_online.yaml"), "--json")
    assert code == 0, out + err
    phases = json.loads(out)["stats"]["online"]["phases"]
    assert all(p["phase_changes"] > 0 for p in phases)


def test_compile_proves_the_online_phases_and_writes_no_image_when_the_placer_fails(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    keel_place_built()
    image = tmp_path / "image.json"
    code, out, err = run("compile", str(ONLINE / "online-essential-unplaceable.yaml"), "-o", str(image))
    assert code == 1 and "safe-mode-within-tolerance" in out + err and not image.exists()
    code, out, err = run("compile", str(_downlink_pn3_first(tmp_path)), "-o", str(image))
    assert code == 1 and "phase-transition-invalid" in out + err and not image.exists()
    code, out, err = run("compile", str(ONLINE / "earth-observation-online.yaml"), "-o", str(image))
    assert code == 0 and image.exists(), out + err
    assert "keel-place proved" in out
    # Without keel-place an online mission gets no image, and is told how to build it.
    image.unlink()
    monkeypatch.setenv("KEEL_BUILD_DIR", str(tmp_path / "no-build"))
    monkeypatch.delenv("KEEL_PLACE", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))
    code, _, err = run("compile", str(ONLINE / "earth-observation-online.yaml"), "-o", str(image))
    assert code == 2 and "--target keel-place" in err and not image.exists()
    assert run("compile", str(THREE), "-o", str(image))[0] == 0  # a graph mission needs none
