"""The launcher's compile step: nodes fly the image keel-verify compile writes for a mission
YAML, no node starts when the mission is not proved, and an image is flown as it is."""

from __future__ import annotations

import subprocess
import time
from pathlib import Path
from typing import Any

import pytest
from keel_cluster import launcher
from keel_cluster.launcher import Cluster, LaunchError, flight_image, is_image

ROOT = Path(__file__).resolve().parents[2]
PROTOTYPE3 = ROOT / "config" / "prototype3.yaml"
PROTOTYPE3_IMAGE = ROOT / "tests" / "missions" / "images" / "good" / "prototype3.json"
# Loads, but is not proved (its decision graph has violations): compile exits 1.
UNPROVED = ROOT / "tests" / "missions" / "good" / "everything.yaml"


@pytest.fixture(autouse=True)
def _unsigned(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("KEEL_SIGNING_KEY", raising=False)
    monkeypatch.setattr(launcher, "_compiled", {})


def test_images_and_yaml_are_told_apart(tmp_path: Path) -> None:
    assert is_image(PROTOTYPE3_IMAGE)
    assert not is_image(PROTOTYPE3)
    spaced = tmp_path / "spaced.json"
    spaced.write_bytes(b"\xef\xbb\xbf \n\t{}")
    assert is_image(spaced)
    assert not is_image(tmp_path / "missing.json")


def test_an_image_is_flown_as_it_is(tmp_path: Path) -> None:
    assert flight_image(PROTOTYPE3_IMAGE, tmp_path) == PROTOTYPE3_IMAGE
    assert list(tmp_path.iterdir()) == []


def test_a_yaml_is_compiled_once_into_the_run_directory(tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    first = flight_image(PROTOTYPE3, tmp_path / "run1")
    assert first == tmp_path / "run1" / "prototype3.image.json"
    # What keel-verify compile writes for the shipped mission (a committed fixture).
    assert first.read_bytes() == PROTOTYPE3_IMAGE.read_bytes()

    def no_second_compile(*args: Any, **kwargs: Any) -> None:
        raise AssertionError("compiled twice")

    monkeypatch.setattr(subprocess, "run", no_second_compile)
    second = flight_image(PROTOTYPE3, tmp_path / "run2")
    assert second.read_bytes() == first.read_bytes()


def test_no_node_starts_when_the_mission_is_not_proved(tmp_path: Path) -> None:
    cluster = Cluster(UNPROVED, ["PN1", "PN2"], tmp_path / "run", Path("/bin/true"), echo=False)
    with pytest.raises(LaunchError) as refused, cluster:
        pass
    message = str(refused.value)
    assert "keel-verify compile" in message and "(exit 1)" in message
    assert "no node started" in message and "violation" in message
    assert cluster.nodes == {}
    assert not (tmp_path / "run" / "everything.image.json").exists()


def test_every_node_is_started_with_the_image(tmp_path: Path) -> None:
    names = ["PN1", "PN2", "PN3", "ST1"]
    with Cluster(PROTOTYPE3, names, tmp_path / "run", Path("/bin/true"), echo=False) as cluster:
        image = tmp_path / "run" / "prototype3.image.json"
        for name in names:
            argv = cluster.nodes[name].argv
            assert argv[argv.index("--mission") + 1] == str(image.resolve())


def test_an_image_gives_the_same_summary_as_its_yaml(tmp_path: Path) -> None:
    # keel-cluster run, bench and campaign take an image as well as a YAML: what they read
    # of it (nodes, phases, the decision graph) is the same.
    from keel_cluster.cli import _mission_summary
    from keel_cluster.common import summarize

    for name in ("prototype3", "earth_observation"):
        source = ROOT / "config" / f"{name}.yaml"
        image = flight_image(source, tmp_path)
        assert is_image(image)
        assert summarize(image) == summarize(source), name
        assert _mission_summary(image) == _mission_summary(source), name


def test_a_tampered_image_is_refused_before_a_cluster_starts(tmp_path: Path) -> None:
    from keel_cluster.common import summarize

    image = tmp_path / "tampered.json"
    image.write_bytes(PROTOTYPE3_IMAGE.read_bytes().replace(b'"PN1"', b'"PX1"', 1))
    with pytest.raises(LaunchError, match="tampered"):
        summarize(image)


def test_no_node_starts_when_the_node_binary_lacks_a_component(tmp_path: Path) -> None:
    # A node binary with `producer` only: prototype3's taskB needs `consumer`, which every
    # node would refuse at boot; compile (with the binary's components) refuses it first.
    binary = tmp_path / "node"
    binary.write_text("#!/bin/sh\n[ \"$1\" = --list-components ] && echo producer && exit 0\n"
                      "exit 2\n")
    binary.chmod(0o755)
    assert launcher.node_components(binary) == ["producer"]
    with pytest.raises(LaunchError) as refused:
        flight_image(PROTOTYPE3, tmp_path / "run", binary)
    assert "component-missing" in str(refused.value) and "consumer" in str(refused.value)
    # The real keel-node has every shipped component: the same mission compiles.
    node = launcher.find_node_binary(None)
    assert is_image(flight_image(PROTOTYPE3, tmp_path / "run2", node))


def test_a_node_binary_that_cannot_be_started_is_said_not_raised(tmp_path: Path) -> None:
    # A restart while the binary is being rebuilt (the file busy, or not executable yet)
    # is a LaunchError naming the node and the file, never an OSError's traceback.
    names = ["PN1", "PN2", "PN3", "ST1"]
    blocked = tmp_path / "keel-node"
    blocked.write_text("#!/bin/sh\n")  # not executable
    with Cluster(PROTOTYPE3, names, tmp_path / "run", Path("/bin/true"), echo=False) as cluster:
        node = cluster.nodes["PN1"]
        for _ in range(100):
            if not node.running:
                break
            time.sleep(0.05)
        node.argv[0] = str(blocked)
        with pytest.raises(LaunchError, match=r"PN1: cannot start .*keel-node: Permission denied"):
            cluster.start("PN1")
