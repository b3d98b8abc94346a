"""Proved means it runs: a differential fuzz of mission YAML. Every random mission that
``keel-verify compile`` proves and writes an image for is loaded by the C++ side as a node
loads it (``keel-mission IMAGE``: the image loader, then the runtime's topology) and must
be accepted and read the same as the verifier read the YAML (its normalised JSON). A
mission a node would refuse after it was proved is a bug in one of the two.

The missions are ``keel_verify.generate``'s valid ones (2 to 8 processing nodes, one or
two phases), then varied where readers tend to disagree: names of every allowed shape
(63 characters, digits, ``-`` and ``_``), parameters of every type (integers at and beyond
2^53, negative zero, tiny and huge floats, strings with quotes, backslashes, control
characters and non-ASCII text), periods, health bounds, per-phase parameters, the tie
grace (absent, 0 or stated) and the mission's own name. ``KEEL_FUZZ_MISSIONS`` sets how
many (default 30; ``./keel bench`` runs more); each failure names its seed, and the YAML
is kept in the test's directory.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import random
import string
import subprocess
from pathlib import Path
from typing import Any

import pytest
from keel_verify.cli import main
from keel_verify.generate import generate, to_yaml
from keel_verify.mission import load_mission
from test_loaders import cpp_loader

COUNT = int(os.environ.get("KEEL_FUZZ_MISSIONS", "30"))
FIRST = string.ascii_letters
REST = string.ascii_letters + string.digits + "_-"
TEXT = ["", "a\"b", "back\\slash", "tab\there", "new\nline", "bell\x07", "ünïcødé", "日本語",
        "emoji 🛰", "'single'", "#not a comment", "- dash", "{braces}", "null", "true", "1e3"]


def name(rng: random.Random, taken: set[str]) -> str:
    while True:
        size = rng.choice([1, 2, 5, 12, 63])
        text = rng.choice(FIRST) + "".join(rng.choice(REST) for _ in range(size - 1))
        if text not in taken and text.upper() != "SAFE":
            taken.add(text)
            return text


def value(rng: random.Random) -> Any:
    kind = rng.randrange(6)
    if kind == 0:
        return rng.choice([0, 1, -1, 2**31, 2**53, 2**53 + 1, -(2**63), 2**63 - 1,
                           rng.randrange(-10**6, 10**6)])
    if kind == 1:
        return rng.choice([0.5, -0.0, 1e-300, 1.5e300, 3.141592653589793, 0.1 + 0.2,
                           rng.uniform(-1e6, 1e6)])
    if kind == 2:
        return rng.choice([True, False])
    return rng.choice(TEXT) + ("" if rng.random() < 0.5 else str(rng.randrange(100)))


def rename(data: Any, names: dict[str, str]) -> Any:
    """Every key and string value that is a name, renamed (capabilities too: consistent)."""
    if isinstance(data, dict):
        return {names.get(k, k): rename(v, names) for k, v in data.items()}
    if isinstance(data, list):
        return [rename(v, names) for v in data]
    if isinstance(data, str):
        return names.get(data, data)
    return data


def fuzzed(seed: int) -> dict[str, Any]:
    rng = random.Random(seed)
    nodes = rng.randrange(2, 9)
    data = generate(nodes, rng.randrange(1, min(2, nodes - 1) + 1), seed=seed,
                    phases=rng.choice([1, 2]), tasks_per_node=rng.randrange(1, 4))
    taken: set[str] = set()
    names: dict[str, str] = {}
    for old in [*data["nodes"], *data["tasks"], *data["phases"]]:
        names[old] = name(rng, taken)
    for phase in data["phases"].values():
        for config in phase["configurations"]:
            names[config] = name(rng, taken)
    data = rename(data, names)
    data["mission"] = rng.choice(["m", "mission ünïcødé", "x" * 200, "with: colon", "日本"])
    for task in data["tasks"].values():
        if rng.random() < 0.6:
            task["params"] = {name(rng, set(taken)): value(rng) for _ in range(rng.randrange(1, 5))}
        if rng.random() < 0.3:
            task["period_ms"] = rng.choice([1, 20, 1000, 600_000])
        if rng.random() < 0.2:
            low = rng.uniform(-100, 100)
            task["health"] = {"min": low, "max": low + rng.uniform(0, 50),
                              "deadline_ms": rng.choice([1, 500, 600_000])}
    for phase in data["phases"].values():
        if rng.random() < 0.3:
            task = rng.choice(list(data["tasks"]))
            phase["params"] = {task: {name(rng, set(taken)): value(rng)}}
    data["heartbeat"] = {"period_ms": rng.choice([10, 100, 250]),
                         "miss_limit": rng.choice([2, 3, 5])}
    if rng.random() < 0.3:
        data["heartbeat"]["tie_grace"] = rng.choice([0, 1, 3, 1000])
    return data


def compile_quietly(mission: Path, image: Path) -> int:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        return main(["compile", str(mission), "-o", str(image)])


def test_every_mission_compile_proves_loads_in_the_runtime_as_the_verifier_read_it(
        tmp_path: Path) -> None:
    loader = cpp_loader()
    if loader is None:
        pytest.skip("KEEL_BUILD_DIR not set: keel-mission is checked under CTest")
    compiled = refused_by_compile = 0
    for seed in range(COUNT):
        mission = tmp_path / f"fuzz-{seed}.yaml"
        mission.write_text(to_yaml(fuzzed(seed)), encoding="utf-8")
        image = tmp_path / f"fuzz-{seed}.json"
        code = compile_quietly(mission, image)
        assert code in (0, 1), f"seed {seed}: compile exit {code} ({mission})"
        if code != 0:
            assert not image.exists(), f"seed {seed}: an image for an unproved mission"
            refused_by_compile += 1
            continue
        compiled += 1
        done = subprocess.run([str(loader), str(image), "--json"], capture_output=True,
                              text=True, timeout=60, check=False)
        assert done.returncode == 0, f"seed {seed}: proved, then refused: {done.stderr} ({mission})"
        assert json.loads(done.stdout) == load_mission(str(mission)).to_json(), (
            f"seed {seed}: the runtime reads the image otherwise than the verifier read "
            f"{mission}")
    # Not vacuous: most generated missions are proved (the generator writes valid ones;
    # the variations keep them valid but for what the prover refuses on its own).
    assert compiled >= COUNT // 2, (compiled, refused_by_compile)


def test_the_fuzz_catches_an_image_the_runtime_refuses(tmp_path: Path) -> None:
    # The oracle can fail: an image the runtime must refuse (two tasks on one port, with the
    # hash recomputed as a forger would) is refused by keel-mission, naming why.
    loader = cpp_loader()
    if loader is None:
        pytest.skip("KEEL_BUILD_DIR not set: keel-mission is checked under CTest")
    mission = tmp_path / "fuzz.yaml"
    mission.write_text(to_yaml(fuzzed(0)), encoding="utf-8")
    image = tmp_path / "fuzz.json"
    assert compile_quietly(mission, image) == 0
    from keel_verify import image as images

    data = json.loads(image.read_bytes())
    tasks = data["content"]["tasks"]
    tasks[0]["port"] = tasks[1]["port"]
    data["sha256"] = images.content_hash(data)
    image.write_bytes(images.encode_file(data))
    done = subprocess.run([str(loader), str(image), "--json"], capture_output=True, text=True,
                          timeout=60, check=False)
    assert done.returncode != 0 and done.stdout == "", done.stdout
    assert "port" in done.stderr, done.stderr


def test_no_tampered_image_flies(tmp_path: Path) -> None:
    """Random byte edits of compiled images (a flipped bit, a changed, inserted or removed
    byte): keel-mission refuses each, or, if the edit left the canonical content as it was
    (white space the hash does not cover), reads exactly the mission the verifier proved."""
    loader = cpp_loader()
    if loader is None:
        pytest.skip("KEEL_BUILD_DIR not set: keel-mission is checked under CTest")
    rng = random.Random(7)
    refused = accepted = 0
    for seed in range(3):
        mission = tmp_path / f"fuzz-{seed}.yaml"
        mission.write_text(to_yaml(fuzzed(seed)), encoding="utf-8")
        image = tmp_path / f"fuzz-{seed}.json"
        assert compile_quietly(mission, image) == 0
        original = image.read_bytes()
        expected = load_mission(str(mission)).to_json()
        for attempt in range(max(10, COUNT)):
            data = bytearray(original)
            at = rng.randrange(len(data))
            edit = rng.randrange(4)
            if edit == 0:
                data[at] ^= 1 << rng.randrange(8)
            elif edit == 1:
                data[at] = rng.randrange(256)
            elif edit == 2:
                data.insert(at, rng.choice(b' 0"\\{}[],:a\n'))
            else:
                del data[at]
            if bytes(data) == original:
                continue
            tampered = tmp_path / f"tampered-{seed}-{attempt}.json"
            tampered.write_bytes(bytes(data))
            done = subprocess.run([str(loader), str(tampered), "--json"], capture_output=True,
                                  text=True, timeout=60, check=False)
            assert "Traceback" not in done.stderr and done.returncode in (0, 2), done.stderr
            if done.returncode == 0:
                accepted += 1
                assert json.loads(done.stdout) == expected, (
                    f"an edit at byte {at} of {image} flies another mission")
            else:
                refused += 1
                assert done.stdout == "" and done.stderr.strip(), done.stderr
    assert refused > accepted  # not vacuous: most edits change what the image says
