"""Mission image fixtures (tests/missions/images/), and both image loaders on them.

The good images are what ``keel-verify compile`` writes for the shipped missions and for
the sources in ``images/sources/``; the bad ones are good images with one thing changed
(most of them sealed again with a correct hash, so that the check under test is the one
that fails). Every fixture is derived here from its source, so a fixture that no longer
matches what compile writes fails ``test_fixtures_are_current``; regenerate them with
``KEEL_UPDATE_GOLDEN=1``.

The C++ loader (``core/mission/image.cpp``) is checked in two places: here, through
``keel-mission`` (which loads only images, as keel-node does) from the CMake build, and in
``core/mission/tests/image_test.cpp`` (signatures, the Mission built, the canonical
encoding).
"""

from __future__ import annotations

import copy
import json
import os
import random
import re
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from keel_verify import image

ROOT = Path(__file__).resolve().parents[2]
IMAGES = ROOT / "tests" / "missions" / "images"
KEYS = IMAGES / "keys"
SOURCES = {
    "prototype3": ROOT / "config" / "prototype3.yaml",
    "earth_observation": ROOT / "config" / "earth_observation.yaml",
    "earth_observation_online": ROOT / "config" / "earth_observation_online.yaml",
    "floats": IMAGES / "sources" / "floats.yaml",
    "over-limit-nodes": IMAGES / "sources" / "over-limit-nodes.yaml",
    "over-limit-tasks": IMAGES / "sources" / "over-limit-tasks.yaml",
}


# A verifier built for a runtime of a larger capacity (512 nodes, 2048 tasks) than this
# one's (256, 1024: core/fsm/types.hpp): the images it writes for the over-limit sources
# (257 nodes, 1025 tasks) are what a node of this runtime must refuse.
LARGER = (512, 2048)


def compile_image(source: Path, sign: bool = False,
                  capacity: tuple[int, int] | None = None) -> bytes:
    """What ``keel-verify compile`` writes for `source` (with `capacity`: what a verifier
    with that capacity writes)."""
    env = {k: v for k, v in os.environ.items() if k != "KEEL_SIGNING_KEY"}
    out = Path(os.environ.get("TMPDIR", "/tmp")) / f"keel-image-{os.getpid()}-{source.stem}.json"
    command = [sys.executable, "-m", "keel_verify.cli", "compile", str(source), "-o", str(out)]
    if capacity is not None:
        command = [sys.executable, "-c",
                   "import sys; from keel_verify import limits, cli; "
                   f"limits.MAX_NODES, limits.MAX_TASKS = {capacity}; "
                   "sys.exit(cli.main(sys.argv[1:]))", *command[3:]]
    if sign:
        command += ["--sign-key", str(KEYS / "test.key")]
    result = subprocess.run(command, capture_output=True, text=True, env=env, timeout=120,
                            check=False)
    assert result.returncode == 0, result.stderr
    try:
        return out.read_bytes()
    finally:
        out.unlink()


def loads(data: bytes) -> dict[str, Any]:
    value: dict[str, Any] = json.loads(data)
    return value


def resealed(data: bytes, change: Callable[[dict[str, Any]], None]) -> bytes:
    """The image with `change` applied and a correct hash (no signature)."""
    value = loads(data)
    change(value)
    return image.encode_file(image.seal(value))


def resealed_keeping_signature(data: bytes, change: Callable[[dict[str, Any]], None]) -> bytes:
    """A signed image changed and given a correct hash, its signature kept: a forgery that
    only the signature check can catch."""
    value = loads(data)
    signature = value["signature"]
    change(value)
    sealed = image.seal(value)
    sealed["signature"] = signature
    return image.encode_file(sealed)


def set_period(value: dict[str, Any]) -> None:
    value["content"]["heartbeat"]["period_ms"] = 900


@dataclass(frozen=True)
class Fixture:
    path: str                      # under tests/missions/images/
    build: Callable[[dict[str, bytes]], bytes]
    python: str                    # image.py's verdict: "ok" or the reason id
    cpp: str                       # the C++ loader's verdict (capacity 256 nodes, 1024 tasks)
    public_key: str | None = None  # under keys/


def _without(key: str) -> Callable[[dict[str, bytes]], bytes]:
    def build(good: dict[str, bytes]) -> bytes:
        value = loads(good["prototype3"])
        del value[key]
        return image.encode_file(value if key == "sha256" else image.seal(value))

    return build


def _edit(change: Callable[[dict[str, Any]], None]) -> Callable[[dict[str, bytes]], bytes]:
    return lambda good: resealed(good["prototype3"], change)


FIXTURES = [
    Fixture("good/prototype3.json", lambda g: g["prototype3"], "ok", "ok"),
    Fixture("good/earth_observation.json", lambda g: g["earth_observation"], "ok", "ok"),
    Fixture("good/earth_observation_online.json", lambda g: g["earth_observation_online"], "ok", "ok"),
    Fixture("good/floats.json", lambda g: g["floats"], "ok", "ok"),
    Fixture(
        "good/prototype3.signed.json", lambda g: g["prototype3.signed"], "ok", "ok", "test.pub"
    ),
    # One byte of the content changed after compile: "period_ms":100 -> 900.
    Fixture("bad/tampered.json",
            lambda g: g["prototype3"].replace(b'"period_ms":100', b'"period_ms":900', 1),
            "tampered", "tampered"),
    Fixture("bad/tampered-no-sha256.json", _without("sha256"), "tampered", "tampered"),
    Fixture("bad/format-version.json", _edit(lambda v: v.update(keel_image=2)),
            "format-version", "format-version"),
    Fixture("bad/format-version-missing.json", _without("keel_image"),
            "format-version", "format-version"),
    Fixture("bad/not-json.json", lambda g: b'{"keel_image": 1, "mission": prototype3}\n',
            "not-json", "not-json"),
    Fixture("bad/not-json-duplicate-key.json",
            lambda g: g["prototype3"].replace(b'{"capacity":', b'{"keel_image":1,"capacity":', 1),
            "not-json", "not-json"),
    Fixture("bad/not-json-nan.json",
            lambda g: g["prototype3"].replace(b'"period_ms":100', b'"period_ms":NaN', 1),
            "not-json", "not-json"),
    Fixture("bad/schema-float-port.json",
            _edit(lambda v: v["content"]["tasks"][0].update(port=100.0)), "schema", "schema"),
    Fixture("bad/schema-unknown-key.json", _edit(lambda v: v.update(uploaded="today")),
            "schema", "schema"),
    # A sample bound beyond what the network carries (64 MiB less the sample header).
    Fixture("bad/schema-max-sample-bytes.json",
            _edit(lambda v: v["content"]["tasks"][0].update(max_sample_bytes=67108845)),
            "schema", "schema"),
    # A checkpoint state bound beyond the capacity's (16 MiB less the snapshot header).
    Fixture("bad/schema-max-state-bytes.json",
            _edit(lambda v: v["content"]["tasks"][1].update(max_state_bytes=16777205)),
            "schema", "schema"),
    # The online placer's fields (core/placement): a priority out of its range and a group
    # that is no name are refused by both loaders.
    Fixture("bad/schema-priority.json",
            _edit(lambda v: v["content"]["tasks"][0].update(priority=-1)), "schema", "schema"),
    Fixture("bad/schema-group.json",
            _edit(lambda v: v["content"]["tasks"][0].update(group="two words")), "schema", "schema"),
    # A checkpoint state bound on taskA, which is not checkpointed: image.py leaves that rule
    # to the verifier that wrote the image; a node checks it.
    Fixture("bad/inconsistent-max-state-bytes.json",
            _edit(lambda v: v["content"]["tasks"][0].update(max_state_bytes=64)),
            "ok", "inconsistent"),
    Fixture("bad/inconsistent-id.json",
            _edit(lambda v: v["content"]["nodes"][1].update(id=7)), "inconsistent", "inconsistent"),
    Fixture("bad/over-limit-own-capacity.json",
            _edit(lambda v: v["capacity"].update(max_nodes=3)), "over-limit", "over-limit"),
    # Written by a verifier of a larger capacity (LARGER), over this runtime's (256, 1024),
    # which keel-verify compile refuses to write.
    Fixture("bad/over-limit-nodes.json", lambda g: g["over-limit-nodes"], "over-limit",
            "over-limit"),
    Fixture("bad/over-limit-tasks.json", lambda g: g["over-limit-tasks"], "over-limit",
            "over-limit"),
    # A hash recomputed over a dangling reference: image.py leaves references to the reader
    # that wrote the image; a node checks them.
    Fixture("bad/inconsistent-reference.json",
            _edit(lambda v: v["content"]["phases"][0]["configurations"][0].update(master="PN9")),
            "ok", "inconsistent"),
    # A recovery edge to a configuration of no phase: the same, for on_recovery.
    Fixture("bad/inconsistent-recovery.json",
            _edit(lambda v: v["content"]["phases"][0].update(
                on_recovery=[{"config": "P4", "node": "PN3", "next": "P9"}])),
            "ok", "inconsistent"),
    # A phase's placement mode: a value of no mode is refused by both loaders; an online
    # phase with the failure edges of a graph is the same kind of reference rule as above,
    # left by image.py to the writer and checked by a node.
    Fixture("bad/schema-placement.json",
            _edit(lambda v: v["content"]["phases"][0].update(placement="anywhere")),
            "schema", "schema"),
    Fixture("bad/inconsistent-online.json",
            _edit(lambda v: v["content"]["phases"][0].update(placement="online")),
            "ok", "inconsistent"),
    Fixture("bad/unsigned.json", lambda g: g["prototype3"], "unsigned", "unsigned", "test.pub"),
    Fixture("bad/wrong-key.json", lambda g: g["prototype3.signed"], "wrong-key", "wrong-key",
            "other.pub"),
    Fixture("bad/bad-signature.json",
            lambda g: resealed_keeping_signature(g["prototype3.signed"], set_period),
            "bad-signature", "bad-signature", "test.pub"),
]


@pytest.fixture(scope="module")
def compiled() -> dict[str, bytes]:
    good = {name: compile_image(source, capacity=LARGER if name.startswith("over-limit") else None)
            for name, source in SOURCES.items()}
    good["prototype3.signed"] = compile_image(SOURCES["prototype3"], sign=True)
    return good


def test_fixtures_are_current(compiled: dict[str, bytes]) -> None:
    update = os.environ.get("KEEL_UPDATE_GOLDEN") == "1"
    stale = []
    for fixture in FIXTURES:
        path = IMAGES / fixture.path
        data = fixture.build(compiled)
        if update:
            path.write_bytes(data)
        elif not path.exists() or path.read_bytes() != data:
            stale.append(fixture.path)
    assert not stale, f"stale image fixtures (regenerate with KEEL_UPDATE_GOLDEN=1): {stale}"


def test_every_reason_has_a_fixture() -> None:
    readme = (ROOT / "config/schema/README.md").read_text()
    section = readme.split("## The mission image")[1].split("**What a loader checks**")[1]
    reasons = set(re.findall(r"^\| `([a-z-]+)` \|", section, re.MULTILINE))
    covered = {f.cpp for f in FIXTURES} | {f.python for f in FIXTURES}
    # unreadable needs no file; the gtest covers it.
    assert reasons - covered <= {"unreadable"}, sorted(reasons - covered - {"unreadable"})


@pytest.mark.parametrize("fixture", FIXTURES, ids=lambda f: f.path)
def test_python_verdict(fixture: Fixture) -> None:
    key = str(KEYS / fixture.public_key) if fixture.public_key else None
    try:
        image.load_image(IMAGES / fixture.path, key)
        verdict = "ok"
    except image.ImageError as error:
        verdict = error.reason
    assert verdict == fixture.python


def keel_mission() -> Path | None:
    build = os.environ.get("KEEL_BUILD_DIR")
    if not build:
        return None
    candidates = [
        c for c in Path(build).rglob("keel-mission") if c.is_file() and os.access(c, os.X_OK)
    ]
    assert candidates, f"keel-mission is not built in {build}"
    return candidates[0]


@pytest.mark.parametrize("fixture", [f for f in FIXTURES if f.public_key is None],
                         ids=lambda f: f.path)
def test_cpp_verdict(fixture: Fixture) -> None:
    binary = keel_mission()
    if binary is None:
        pytest.skip("KEEL_BUILD_DIR not set: the C++ loader is checked under CTest")
    path = IMAGES / fixture.path
    result = subprocess.run([str(binary), str(path), "--json"], capture_output=True, text=True,
                            timeout=60, check=False)
    if fixture.cpp == "ok":
        assert result.returncode == 0, result.stderr
        return
    assert result.returncode == 2, (result.returncode, result.stdout, result.stderr)
    assert result.stdout == ""
    first = result.stderr.splitlines()[0]
    assert first.startswith(f"{path}:"), first
    assert f": {fixture.cpp}: " in first, first


@pytest.mark.parametrize("name", ["prototype3", "earth_observation", "earth_observation_online", "floats"])
def test_cpp_builds_the_mission_the_verifier_proved(name: str) -> None:
    """keel-mission IMAGE --json prints the mission the C++ runtime holds; it is the
    image's content (without ids), which is `keel-verify load --json` of the source."""
    binary = keel_mission()
    if binary is None:
        pytest.skip("KEEL_BUILD_DIR not set: the C++ loader is checked under CTest")
    result = subprocess.run([str(binary), str(IMAGES / "good" / f"{name}.json"), "--json"],
                            capture_output=True, text=True, timeout=60, check=False)
    assert result.returncode == 0, result.stderr
    content = loads((IMAGES / "good" / f"{name}.json").read_bytes())["content"]
    for what in ("nodes", "tasks"):
        for item in content[what]:
            del item["id"]
    held = json.loads(result.stdout)
    assert held == content
    # Floats stay floats and integers integers (== would take 3.0 for 3).
    assert json.dumps(held, sort_keys=True) == json.dumps(content, sort_keys=True)


# Values a mutation puts in place of another: wrong types, edges of the ranges, integers
# beyond 64 bits, floats where integers belong, names defined and not.
MUTANT_VALUES: list[Any] = [0, 1, -1, 7, 65535, 65536, 2**63, 10**30, 0.5, 3.0, -0.0, 1e300, "",
                            "PN1", "PN9", "SAFE", "x y", "é", None, True, False, [], {},
                            ["PN1"], {"a": 1}]


def _paths(value: Any, path: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    found = [path]
    if isinstance(value, dict):
        for key, item in value.items():
            found += _paths(item, (*path, key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            found += _paths(item, (*path, index))
    return found


def _mutate(value: dict[str, Any], rng: random.Random) -> None:
    paths = [p for p in _paths(value) if p]
    path = rng.choice(paths)
    parent: Any = value
    for step in path[:-1]:
        parent = parent[step]
    last = path[-1]
    kind = rng.randrange(4)
    if kind == 0:
        del parent[last]
    elif kind == 1:
        parent[last] = copy.deepcopy(rng.choice(MUTANT_VALUES))
    elif kind == 2:
        target: Any = value
        for step in rng.choice(paths):
            target = target[step]
        parent[last] = copy.deepcopy(target)
    elif isinstance(parent, list):
        parent.insert(last, copy.deepcopy(parent[last]))
    else:
        parent["extra"] = 1


def _verdicts(path: Path, binary: Path) -> tuple[str, str, str]:
    try:
        image.load_image(path)
        python = "ok"
    except image.ImageError as error:
        python = error.reason
    done = subprocess.run([str(binary), str(path)], capture_output=True, text=True, timeout=60,
                          check=False)
    first = done.stderr.splitlines()[0] if done.stderr else ""
    cpp = "ok" if done.returncode == 0 else first.split(": ")[1]
    return python, cpp, first


@pytest.mark.parametrize("first_seed", range(0, 300, 100))
def test_loaders_agree_on_mutated_images(first_seed: int, tmp_path: Path) -> None:
    """Seeded mutations of the good images, most sealed again with a correct hash: both
    loaders give the same verdict, except where the C++ loader refuses more (a reference
    image.py does not check, an integer beyond the 64 bits a node holds); never the other
    way round."""
    binary = keel_mission()
    if binary is None:
        pytest.skip("KEEL_BUILD_DIR not set: the C++ loader is checked under CTest")
    goods = [loads((IMAGES / "good" / f"{n}.json").read_bytes())
             for n in ("prototype3", "earth_observation", "floats")]
    disagreements = []
    for seed in range(first_seed, first_seed + 100):
        rng = random.Random(seed)
        value = copy.deepcopy(goods[seed % len(goods)])
        for _ in range(1 + rng.randrange(2)):
            _mutate(value, rng)
        data = image.encode_file(image.seal(value) if rng.random() < 0.9 else value)
        path = tmp_path / f"mutant-{seed}.json"
        path.write_bytes(data)
        python, cpp, message = _verdicts(path, binary)
        refuses_more = python == "ok" and (
            cpp == "inconsistent" or (cpp == "schema" and "beyond the 64-bit" in message))
        if python != cpp and not refuses_more:
            disagreements.append((seed, python, cpp, message))
    assert not disagreements, disagreements[:3]
