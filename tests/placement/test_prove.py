"""keel-place IMAGE --prove (core/placement/prove.hpp): the placer run on every failure
sequence of a phase placed online, as the nodes run it. A mission it proves, one where the
placer must give up an essential task within the tolerance (the violation named with its
failure sequence, exit 1), a graph+online graph whose SAFE the placer answers, generated
missions (the counts of failed sets), and inputs it refuses (exit 2, never a crash).
"""

from __future__ import annotations

import contextlib
import io
import json
import subprocess
from math import comb
from pathlib import Path

import pytest
from keel_verify.cli import main
from keel_verify.generate import generate, to_yaml

ROOT = Path(__file__).resolve().parents[2]
ONLINE = ROOT / "tests" / "verify" / "missions" / "online"


def keel_place() -> Path:
    from test_checker_agrees import keel_place as find

    return find()


def compiled(mission: Path, image: Path, *extra: str) -> None:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        code = main(["compile", str(mission), "-o", str(image), *extra])
    assert code == 0, f"compile exit {code} ({mission})"


def unproved(mission: Path, image: Path) -> None:
    """The image keel-verify hands keel-place --prove (check/online.py): the graph proved,
    the placer not yet (compile writes no image of a mission the placer fails)."""
    from keel_verify.check.core import check_file
    from keel_verify.check.online import _image
    from keel_verify.image import encode_file

    result, loaded = check_file(str(mission))
    assert loaded is not None and result.valid, result.violations
    image.write_bytes(encode_file(_image(loaded, result)))


def prove(image: Path, *extra: str) -> tuple[int, dict, str]:
    run = subprocess.run([str(keel_place()), str(image), "--prove", *extra], text=True,
                         capture_output=True, timeout=300, check=False)
    return run.returncode, json.loads(run.stdout) if run.returncode in (0, 1) else {}, run.stderr


def test_the_online_earth_observation_mission_is_proved(tmp_path: Path) -> None:
    image = tmp_path / "eo.json"
    compiled(ONLINE / "earth-observation-online.yaml", image)
    code, proof, err = prove(image)
    assert code == 0, err
    assert proof["result"] == "proved" and proof["failures"] == 1
    assert [(p["phase"], p["placement"]) for p in proof["phases"]] == [
        ("observation", "online"), ("downlink", "online")]
    for phase in proof["phases"]:
        # Each of the four tolerated processing nodes fails alone: every task keeps running.
        assert phase["within_tolerance"] == {"failed_sets": 4, "running_every_task": 4,
                                             "shedding": 0, "shed": {}}
        assert phase["violations"] == []
        # ST1 and IF1 are not tolerated: the checkpointed aocs needs storage (SAFE), the
        # camera or downlink task needs IF1 (shed).
        assert phase["beyond_tolerance"]["failed_sets"] == 2
        assert phase["beyond_tolerance"]["safe"] == 1


def test_beyond_the_tolerance_every_failed_set_is_counted(tmp_path: Path) -> None:
    image = tmp_path / "eo.json"
    compiled(ONLINE / "earth-observation-online.yaml", image)
    code, proof, err = prove(image, "--failures", "3")
    assert code == 0, err
    for phase in proof["phases"]:
        beyond = phase["beyond_tolerance"]
        # Six nodes, at most three failed, less the four single tolerated failures; a set
        # whose every order passes through SAFE first is not reached.
        assert 0 < beyond["failed_sets"] <= comb(6, 1) + comb(6, 2) + comb(6, 3) - 4
        assert beyond["failed_sets"] == (beyond["running_every_task"] + beyond["shedding"]
                                         + beyond["safe"])
        assert beyond["shedding"] > 0 and beyond["safe"] > 0


def test_an_essential_task_the_placer_cannot_keep_is_a_violation(tmp_path: Path) -> None:
    """If the prover passed this mission it would be broken: PN3 alone has room for the
    essential task, and PN3 is a tolerated failure."""
    image = tmp_path / "unplaceable.json"
    unproved(ONLINE / "online-essential-unplaceable.yaml", image)
    code, proof, _ = prove(image)
    assert code == 1
    assert proof["result"] == "violated" and proof["violation_count"] == 1
    (violation,) = proof["phases"][0]["violations"]
    assert violation["kind"] == "safe-mode-within-tolerance"
    assert violation["failures"] == ["PN3"]
    assert "PN3 failed" in violation["message"]


def test_graph_plus_online_proves_where_the_graph_says_safe(tmp_path: Path) -> None:
    """The graph's SAFE for PN3 within the tolerance is a violation of a graph phase; in a
    graph+online phase the placer answers it, and the proof covers its answer."""
    source = (ROOT / "tests" / "verify" / "missions" / "safe-mode-within-tolerance.yaml").read_text()
    mission = tmp_path / "graph-online.yaml"
    mission.write_text(source.replace("    initial: P1", "    placement: graph+online\n    initial: P1"))
    image = tmp_path / "graph-online.json"
    compiled(mission, image)
    code, proof, err = prove(image)
    assert code == 0, err
    (phase,) = proof["phases"]
    assert phase["placement"] == "graph+online"
    assert phase["within_tolerance"]["failed_sets"] == 3
    assert phase["placements"] >= 1  # PN3's failure, answered by the placer


@pytest.mark.parametrize("nodes,failures", [(8, 1), (16, 2)])
def test_generated_online_missions(tmp_path: Path, nodes: int, failures: int) -> None:
    mission = tmp_path / "generated.yaml"
    mission.write_text(to_yaml(generate(nodes, failures, seed=3, placement="online")))
    image = tmp_path / "generated.json"
    compiled(mission, image, "--max-failures", "0")
    code, proof, err = prove(image)
    assert code == 0, err
    within = sum(comb(nodes, size) for size in range(1, failures + 1))
    for phase in proof["phases"]:
        assert phase["within_tolerance"]["failed_sets"] == within
        assert phase["violations"] == [] and phase["transitions"] >= phase["states"] >= 1


def test_a_graph_mission_has_nothing_to_prove(tmp_path: Path) -> None:
    image = tmp_path / "eo.json"
    compiled(ROOT / "config" / "earth_observation.yaml", image)
    code, proof, _ = prove(image)
    assert code == 0 and proof["phases"] == [] and proof["result"] == "proved"


def test_inputs_it_refuses(tmp_path: Path) -> None:
    missing = tmp_path / "missing.json"
    code, _, err = prove(missing)
    assert code == 2 and str(missing) in err
    broken = tmp_path / "broken.json"
    broken.write_text("{not json")
    code, _, err = prove(broken)
    assert code == 2 and str(broken) in err
    image = tmp_path / "eo.json"
    compiled(ONLINE / "earth-observation-online.yaml", image)
    code, _, err = prove(image, "--failures", "9")
    assert code == 2 and "--failures" in err
    code, _, threads = prove(image, "--threads", "65")
    assert code == 2 and "--threads" in threads
    code, _, negative = prove(image, "--threads", "-1")
    assert code == 2 and "--threads" in negative
    # Any number of threads in range proves the same.
    one, two = prove(image, "--threads", "1"), prove(image, "--threads", "2")
    assert one[0] == two[0] == 0
    assert [{k: v for k, v in p.items() if k != "ms"} for p in one[1]["phases"]] == \
        [{k: v for k, v in p.items() if k != "ms"} for p in two[1]["phases"]]
    for text in (err, threads, negative):
        assert "terminate" not in text and "Traceback" not in text
