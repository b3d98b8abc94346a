"""One fixture set, one reader: every good mission loads, every bad one is rejected with
the rule and position its first line names. Only the verifier reads YAML; a node reads the
mission image compiled from it, so the C++ side is checked on images: the image of every
mission the reader accepts (good fixtures and seeded mutants of them) must load in
``keel-mission`` (the image loader and the runtime's topology, as keel-node boots) and read
back as the JSON the reader built, and a YAML given to ``keel-mission`` is refused, saying
how to compile it.

A bad fixture's first line reads ``# expect: LINE:COL RULE | why`` (or ``# expect: RULE |
why`` for YAML syntax errors, whose exact position depends on the parser). The C++ side is
``keel-mission`` from the CMake build (``KEEL_BUILD_DIR``); when the tests run under CTest
it must exist.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import random
import re
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest
from keel_verify.mission import MissionError, load_mission

ROOT = Path(__file__).resolve().parents[2]
GOOD = sorted((ROOT / "tests" / "missions" / "good").glob("*.yaml")) + sorted(
    (ROOT / "config").glob("*.yaml")
)
BAD = sorted((ROOT / "tests" / "missions" / "bad").glob("*.yaml"))
EXPECT = re.compile(r"^# expect: (?:(\d+):(\d+) )?([a-z-]+) \| .+$")
ERROR_LINE = re.compile(r"^(.*):(\d+):(\d+): ([a-z-]+): (.+)$")


def expectation(path: Path) -> tuple[int | None, int | None, str]:
    first = path.read_text(encoding="utf-8").split("\n", 1)[0]
    match = EXPECT.match(first)
    assert match, f"{path}: first line must be '# expect: LINE:COL RULE | why'"
    line, col, rule = match.groups()
    return (int(line) if line else None, int(col) if col else None, rule)


def cpp_loader() -> Path | None:
    build = os.environ.get("KEEL_BUILD_DIR")
    if not build:
        return None
    candidates = list(Path(build).rglob("keel-mission"))
    candidates = [c for c in candidates if c.is_file() and os.access(c, os.X_OK)]
    assert candidates, f"keel-mission is not built in {build}"
    return candidates[0]


def run_cpp(path: Path) -> subprocess.CompletedProcess[str]:
    binary = cpp_loader()
    if binary is None:
        pytest.skip(
            "KEEL_BUILD_DIR not set: keel-mission (the C++ image loader) is checked under CTest"
        )
    return subprocess.run(
        [str(binary), str(path), "--json"],
        check=False,
        capture_output=True,
        text=True,
        timeout=30,
    )


def test_every_rule_has_a_fixture() -> None:
    rules = {expectation(p)[2] for p in BAD}
    documented = set(
        re.findall(
            r"^\| `([a-z-]+)` \|",
            # The mission rules; the image's own reasons follow under their heading.
            (ROOT / "config/schema/README.md").read_text().split("## The mission image")[0],
            re.MULTILINE,
        )
    )
    assert documented, "config/schema/README.md lists no rules"
    # unreadable needs no file: test_a_file_that_cannot_be_read_is_unreadable_not_bad_yaml.
    assert "unreadable" in documented
    missing = documented - rules - {"unreadable"}
    assert not missing, f"rules without a bad fixture: {sorted(missing)}"


@pytest.mark.parametrize("path", GOOD, ids=lambda p: p.name)
def test_python_accepts_good(path: Path) -> None:
    mission = load_mission(path)
    assert mission.to_json()["schema"] == 1


@pytest.mark.parametrize("path", BAD, ids=lambda p: p.name)
def test_python_rejects_bad(path: Path) -> None:
    line, col, rule = expectation(path)
    with pytest.raises(MissionError) as caught:
        load_mission(path)
    errors = caught.value.errors
    assert len(errors) == 1, [str(e) for e in errors]
    error = errors[0]
    assert error.rule == rule, str(error)
    if line is not None:
        assert (error.line, error.col) == (line, col), str(error)
    assert error.file == str(path)


def image_of(path: Path, out: Path) -> Path | None:
    """The image ``keel-verify compile`` writes for the mission at ``path`` once proved: its
    content is what the reader built, which is what these tests compare. The proof section
    is a shipped image's (the loaders check its shape, not the proof: a good fixture need not
    be a valid mission). None when compile would refuse the mission an image (a number JSON
    cannot write, over the runtime's capacity: ``image_errors``)."""
    from keel_verify.compile import image_content, image_errors
    from keel_verify.image import encode_file, seal

    mission = load_mission(path)
    if image_errors(mission, path.read_text(encoding="utf-8-sig")):
        return None
    shipped = json.loads((ROOT / "tests/missions/images/good/prototype3.json").read_text())
    image = {key: shipped[key] for key in ("keel_image", "verifier", "proof", "capacity")}
    image["mission"] = mission.name
    image["source"] = {"file": path.name, "sha256": hashlib.sha256(path.read_bytes()).hexdigest()}
    image["content"] = image_content(mission)
    out.write_bytes(encode_file(seal(image)))
    return out


@pytest.mark.parametrize("path", GOOD, ids=lambda p: p.name)
def test_cpp_reads_the_image_as_the_reader_read_the_yaml(path: Path, tmp_path: Path) -> None:
    image = image_of(path, tmp_path / "mission.json")
    if image is None:
        # Read, but no image: compile refuses it, so no node is ever given it.
        assert path.name == "tricky-scalars.yaml", "only this fixture holds .inf and .nan"
        return
    result = run_cpp(image)
    assert result.returncode == 0, result.stderr
    assert _same_json(json.loads(result.stdout), load_mission(path).to_json())


@pytest.mark.parametrize("path", [*GOOD[:1], *BAD[:1]], ids=lambda p: p.name)
def test_cpp_refuses_yaml_saying_how_to_compile(path: Path) -> None:
    result = run_cpp(path)
    assert result.returncode == 2 and result.stdout == "", result
    assert result.stderr == (
        f"{path}:1:1: not-an-image: a mission YAML is read by keel-verify only; "
        f"compile it: keel-verify compile {path} -o IMAGE.json\n"
    )


def test_python_cli_exit_codes(tmp_path: Path) -> None:
    from keel_verify.cli import main

    assert main(["load", str(ROOT / "config" / "earth_observation.yaml")]) == 0
    assert main(["load", str(ROOT / "tests/missions/bad/wrong-type-root.yaml")]) == 2
    assert main(["load", str(ROOT / "tests/missions/bad/port-conflict.yaml")]) == 1
    assert main(["load", str(tmp_path / "missing.yaml")]) == 2
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"mission: \xff\xfe\n")
    assert main(["load", str(binary)]) == 2


def test_cpp_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    binary = cpp_loader()
    if binary is None:
        pytest.skip(
            "KEEL_BUILD_DIR not set: keel-mission (the C++ image loader) is checked under CTest"
        )
    from keel_verify.cli import main

    def cpp(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [str(binary), *args], check=False, capture_output=True, text=True, timeout=30
        )

    mission = ROOT / "config" / "earth_observation.yaml"
    image = image_of(mission, tmp_path / "eo.json")
    assert image is not None
    assert main(["load", str(mission)]) == 0
    said = capsys.readouterr().out
    read = cpp(str(image))
    assert read.returncode == 0 and read.stdout == said.replace(str(mission), str(image))
    for path in (tmp_path / "missing.json", tmp_path):
        refused = cpp(str(path))
        assert refused.returncode == 2 and refused.stdout == "", refused
        assert refused.stderr.startswith(f"{path}:1:1: unreadable: "), refused.stderr
    help_text = cpp("--help")
    assert help_text.returncode == 0 and "--json" in help_text.stdout
    usage = cpp()
    assert usage.returncode == 2 and usage.stdout == ""


def test_a_file_that_cannot_be_read_is_unreadable_not_bad_yaml(tmp_path: Path) -> None:
    # Missing, a directory: the system's reason, kind schema (exit 2), never yaml-syntax.
    for path, reason in ((tmp_path / "missing.yaml", "No such file or directory"),
                         (tmp_path, "Is a directory")):
        with pytest.raises(MissionError) as caught:
            load_mission(path)
        error = caught.value.errors[0]
        assert (error.rule, error.kind, error.message) == ("unreadable", "schema",
                                                           f"cannot read: {reason}")


def test_alias_bomb_is_refused(tmp_path: Path) -> None:
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    for i in range(1, 9):
        prev = f"*a{i - 1}"
        lines.append(f"a{i}: &a{i} [{', '.join([prev] * 10)}]")
    bomb = tmp_path / "bomb.yaml"
    bomb.write_text("\n".join(lines) + "\n")
    with pytest.raises(MissionError) as caught:
        load_mission(bomb)
    assert caught.value.errors[0].rule == "yaml-syntax"


# --------------------------------------------------------------------------------------
# Mutated good missions (seeded, so a failure names its seed): the reader ends every one in
# a verdict, a Mission or a MissionError, and every mutant it accepts that keel-verify
# compiles has an image keel-mission (the C++ image loader) loads and prints as the same
# JSON the reader built from the YAML.

_PIECES = [
    b":",
    b"- ",
    b"[",
    b"]",
    b"{",
    b"}",
    b",",
    b"&a ",
    b"*a",
    b"!",
    b"\t",
    b'"',
    b"'",
    b"#",
    b"|",
    b">",
    b"\n",
    b"\xc3\xa9",
    b"? ",
    b"~",
    b"SAFE",
    b"-",
    b"  ",
    b" ",
    b"null",
    b"1.0",
    b"true",
    b"yes",
    b"''",
    b": ",
    b"\n  ",
    b"\n- ",
    b" #",
    b"|\n",
]


def _mutate(text: bytes, rng: random.Random) -> bytes:
    lines = text.split(b"\n")
    kind = rng.randrange(8)
    if kind == 0 and lines:
        del lines[rng.randrange(len(lines))]
    elif kind == 1 and lines:
        i = rng.randrange(len(lines))
        lines.insert(i, lines[i])
    elif kind == 2 and len(lines) > 1:
        i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
    elif kind == 3 and text:
        i = rng.randrange(len(text))
        return (
            text[:i]
            + bytes([rng.choice(b" :-[]{},#&*!|>'\"\tabcXYZ0123456789.\n")])
            + text[i + 1 :]
        )
    elif kind == 4:
        i = rng.randrange(len(text) + 1)
        return text[:i] + rng.choice(_PIECES) + text[i:]
    elif kind == 5:
        return text[: rng.randrange(len(text) + 1)]
    elif kind == 6 and lines:
        i = rng.randrange(len(lines))
        lines[i] = b"  " + lines[i] if rng.random() < 0.5 else lines[i].removeprefix(b"  ")
    elif text:
        i = rng.randrange(len(text))
        return text[:i] + text[i + rng.randrange(1, 30) :]
    return b"\n".join(lines)


def _same_json(a: object, b: object) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same_json(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same_json(x, y) for x, y in zip(a, b, strict=True))
    return (
        type(a) is type(b)
        and a == b
        or (
            isinstance(a, int | float)
            and isinstance(b, int | float)
            and not isinstance(a, bool)
            and not isinstance(b, bool)
            and a == b
        )
    )


@pytest.mark.parametrize("first_seed", range(0, 400, 100))
def test_mutated_missions_end_in_a_verdict_and_fly_as_read(first_seed: int, tmp_path: Path) -> None:
    """The reader never fails but with a MissionError, and every mutant it accepts has an
    image the C++ loader reads back as the reader read the YAML."""
    if cpp_loader() is None:
        pytest.skip(
            "KEEL_BUILD_DIR not set: keel-mission (the C++ image loader) is checked under CTest"
        )
    missions = [p.read_bytes() for p in GOOD]
    accepted = 0
    disagreements = []
    for seed in range(first_seed, first_seed + 100):
        rng = random.Random(seed)
        text = missions[seed % len(missions)]
        for _ in range(1 + rng.randrange(3)):
            text = _mutate(text, rng)
        path = tmp_path / f"mutant-{seed}.yaml"
        path.write_bytes(text)
        try:
            read = load_mission(path).to_json()
        except MissionError:
            continue
        image = image_of(path, tmp_path / f"mutant-{seed}.json")
        if image is None:
            continue
        accepted += 1
        result = run_cpp(image)
        if result.returncode != 0:
            disagreements.append((seed, result.stderr))
        elif not _same_json(json.loads(result.stdout), read):
            disagreements.append((seed, "different JSON"))
    assert not disagreements, disagreements[:3]
    # About 1 in 15 mutants is still a mission the reader accepts: enough to compare.
    assert accepted >= 3, f"only {accepted} of 100 mutants were missions: the test reads too few"


@pytest.mark.parametrize("path", GOOD, ids=lambda p: p.name)
def test_fast_and_reference_readers_build_the_same_mission(path: Path) -> None:
    """libyaml's parser, under the composer or straight from its events, is only a faster
    route to the reference reader's result."""
    from keel_verify import mission as module

    text = path.read_bytes().decode("utf-8-sig" if path.name.startswith("bom") else "utf-8")
    reference = module._load(text, str(path), module._Loader)
    assert module._load(text, str(path), module._FastLoader) == reference
    if "&" not in text:  # anchors are left to the composers
        assert module._load(text, str(path), module._read_plain) == reference


def _verdict(read: Callable[..., object], *args: object) -> object:
    try:
        return read(*args)
    except MissionError as error:
        return error.errors


@pytest.mark.parametrize("first_seed", range(0, 400, 100))
def test_every_route_reaches_the_reference_verdict(first_seed: int) -> None:
    """What load_mission returns (events read straight, shape checked by jsonschema_rs
    first, falling back to the composers) is what the pure-Python reader returns, on
    mutants too: the same Mission, or the same errors at the same positions."""
    from keel_verify import mission as module

    missions = [p.read_bytes() for p in GOOD]
    plain = 0
    for seed in range(first_seed, first_seed + 100):
        rng = random.Random(seed)
        raw = missions[seed % len(missions)]
        for _ in range(1 + rng.randrange(3)):
            raw = _mutate(raw, rng)
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            continue
        reference = _verdict(module._load, text, "m.yaml", module._Loader)
        assert _verdict(module.loads_mission, text, "m.yaml") == reference, seed
        try:
            module._read_plain(text, "m.yaml")
            plain += 1
        except (module._Unusual, MissionError):
            pass
    # About 1 in 5 mutants is still read straight from the events: that route is exercised.
    assert plain >= 10, f"only {plain} of 100 mutants took the event route"


def test_an_integral_float_is_judged_by_jsonschema(tmp_path: Path) -> None:
    """jsonschema_rs takes 100.0 for an integer; the mission schema does not. The event
    route says when a document has such a number, and the shape is then judged by
    jsonschema, which refuses it (the bad fixture wrong-type-integer-as-float is the
    same case end to end)."""
    from keel_verify import mission as module

    text = (ROOT / "config" / "prototype3.yaml").read_text()
    text = re.sub(r"cpu: (\d+)", r"cpu: \1.0", text, count=1)
    data, doc = module._read_plain(text, "m.yaml")
    assert not doc.fast_shape
    assert module._fast_validator().is_valid(data)  # the disagreement this guards against
    with pytest.raises(MissionError) as caught:
        module.loads_mission(text, "m.yaml")
    assert caught.value.errors[0].rule == "wrong-type"


def test_aliases_may_add_a_bounded_number_of_nodes(monkeypatch: pytest.MonkeyPatch) -> None:
    """What is written is bounded by the file size limit alone; aliases may add at most
    MAX_YAML_NODES nodes to it."""
    from keel_verify import mission as module

    monkeypatch.setattr(module, "MAX_YAML_NODES", 100)
    written = "big: [" + ", ".join(["1"] * 500) + "]\n"
    for loader in (module._read_plain, module._FastLoader, module._Loader):
        data, _ = module._parse(written, "m.yaml", loader)
        assert len(data["big"]) == 500
    within = "a: &a [1, 2, 3, 4, 5, 6, 7, 8, 9]\nb: [" + ", ".join(["*a"] * 9) + "]\n"
    beyond = "a: &a [1, 2, 3, 4, 5, 6, 7, 8, 9]\nb: [" + ", ".join(["*a"] * 11) + "]\n"
    for loader in (module._FastLoader, module._Loader):
        module._parse(within, "m.yaml", loader)
        with pytest.raises(MissionError) as caught:
            module._parse(beyond, "m.yaml", loader)
        error = caught.value.errors[0]
        assert error.message == "aliases expand the document by more than 100 YAML nodes"
