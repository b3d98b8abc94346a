"""keel-verify compile and image-check: a proved mission becomes an image a node can check;
anything else writes nothing. Tampered, re-versioned, wrongly signed and over-capacity
images are refused, each naming why."""

from __future__ import annotations

import base64
import contextlib
import hashlib
import io
import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric import ed25519
from keel_verify import __version__, image, limits
from keel_verify.check.prover import Prover, Undecided
from keel_verify.cli import main
from keel_verify.mission import load_mission

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = [ROOT / "config" / "prototype3.yaml", ROOT / "config" / "earth_observation.yaml"]
VIOLATED = ROOT / "tests" / "verify" / "missions" / "capacity.yaml"


def run(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def copy(mission: Path, directory: Path) -> Path:
    target = directory / mission.name
    shutil.copyfile(mission, target)
    return target


def compiled(tmp_path: Path, mission: Path = SHIPPED[0], *extra: str) -> Path:
    source = copy(mission, tmp_path)
    code, out, err = run("compile", source, *extra)
    assert code == 0, out + err
    return source.with_suffix(".json")


def rewrite(path: Path, edit, rehash: bool = True) -> None:
    """Edit an image's object and write it back canonically (its hash recomputed, as a
    forger would, unless ``rehash`` is false); the signature is kept as it was."""
    data = json.loads(path.read_bytes())
    edit(data)
    if rehash:
        data["sha256"] = image.content_hash(data)
    path.write_bytes(image.encode_file(data))


def refused(path: Path, *extra: str) -> str:
    code, out, err = run("image-check", path, *extra)
    assert code == 2, out + err
    assert out == "" and "Traceback" not in err
    return err


def write_key(directory: Path, name: str) -> tuple[Path, Path]:
    key = ed25519.Ed25519PrivateKey.generate()
    private = directory / f"{name}.key"
    public = directory / f"{name}.pub"
    pem = serialization.Encoding.PEM
    private.write_bytes(key.private_bytes(pem, serialization.PrivateFormat.PKCS8,
                                          serialization.NoEncryption()))
    public.write_bytes(key.public_key().public_bytes(
        pem, serialization.PublicFormat.SubjectPublicKeyInfo))
    return private, public


# --------------------------------------------------------------------------------------
# compile


@pytest.mark.parametrize("mission", SHIPPED, ids=lambda p: p.stem)
def test_a_shipped_mission_compiles_to_an_image_image_check_accepts(
        tmp_path: Path, mission: Path) -> None:
    source = copy(mission, tmp_path)
    code, out, err = run("compile", source)
    assert code == 0, out + err
    path = source.with_suffix(".json")
    assert "PROVED" in out and f"{path}: image written" in out
    raw = path.read_bytes()
    data = json.loads(raw)
    assert raw == image.canonical_bytes(data) + b"\n"
    assert data["keel_image"] == 1 and data["verifier"] == __version__
    assert data["source"] == {"file": mission.name,
                              "sha256": hashlib.sha256(mission.read_bytes()).hexdigest()}
    assert data["proof"]["result"] == "proved" and data["proof"]["max_failures"] is None
    assert data["capacity"] == {"max_nodes": limits.MAX_NODES, "max_tasks": limits.MAX_TASKS}
    assert data["sha256"] == image.content_hash(data) and "signature" not in data
    content = data["content"]
    assert content["mission"] == data["mission"]
    assert [n["id"] for n in content["nodes"]] == list(range(len(content["nodes"])))
    assert [t["id"] for t in content["tasks"]] == list(range(len(content["tasks"])))
    assert all(t["component"] for t in content["tasks"])
    code, out, err = run("image-check", path)
    assert code == 0, err
    assert "valid image" in out and "unsigned" in out
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([source.name, path.name])


def test_the_image_holds_the_resolved_mission(tmp_path: Path) -> None:
    data = json.loads(compiled(tmp_path).read_bytes())
    content = data["content"]
    # prototype3 names no phase tasks, no startup grace, and no component for taskA's
    # consumer: every default is in the image.
    assert content["heartbeat"]["startup_grace_ms"] == 2000
    assert all(p["tasks"] == ["taskA", "taskB"] for p in content["phases"])
    tasks = {t["name"]: t for t in content["tasks"]}
    assert tasks["taskA"]["component"] == "producer"
    assert tasks["taskB"]["component"] == "consumer"
    assert tasks["taskA"]["essential"] is False and tasks["taskB"]["checkpoint"] is True
    assert [n["name"] for n in content["nodes"]] == ["PN1", "PN2", "PN3", "ST1"]
    assert content["nodes"][3]["role"] == "storage"


def with_tie_grace(directory: Path, value: int) -> Path:
    """prototype3 in ``directory`` with ``heartbeat.tie_grace: value`` (on its line 9)."""
    directory.mkdir(exist_ok=True)
    source = directory / SHIPPED[0].name
    text = SHIPPED[0].read_text()
    assert "heartbeat: {period_ms: 100, miss_limit: 3}\n" in text
    source.write_text(text.replace("miss_limit: 3}", f"miss_limit: 3, tie_grace: {value}}}", 1))
    return source


def test_tie_grace_is_in_the_image_only_when_the_mission_states_it(tmp_path: Path) -> None:
    # prototype3 states none: 0 (the ground is no voter), and its image holds no key, so the
    # image of a mission without it keeps the bytes and hash it had before the field.
    assert load_mission(SHIPPED[0]).heartbeat.tie_grace == 0
    raw = compiled(tmp_path).read_bytes()
    assert b"tie_grace" not in raw
    assert raw == (ROOT / "tests/missions/images/good/prototype3.json").read_bytes()
    source = with_tie_grace(tmp_path / "with", 3)
    assert load_mission(source).heartbeat.tie_grace == 3
    code, out, err = run("compile", source)
    assert code == 0, out + err
    path = source.with_suffix(".json")
    assert '"heartbeat":{"miss_limit":3,"period_ms":100,"startup_grace_ms":2000,"tie_grace":3}' \
        in path.read_text()
    assert json.loads(path.read_bytes())["content"]["heartbeat"]["tie_grace"] == 3
    assert run("image-check", path)[0] == 0


@pytest.mark.parametrize("value", [-1, 1001])
def test_a_tie_grace_out_of_range_is_refused_naming_it(tmp_path: Path, value: int) -> None:
    source = with_tie_grace(tmp_path / "mission", value)
    code, out, err = run("compile", source)
    assert code == 2, out + err
    assert f"{source}:9:" in err and "out-of-range: heartbeat.tie_grace: " in err, err
    assert not source.with_suffix(".json").exists()
    # An image that states it out of range (written by hand, sealed) is refused too.
    path = compiled(tmp_path)
    rewrite(path, lambda data: data["content"]["heartbeat"].update(tie_grace=value))
    assert "schema: content.heartbeat.tie_grace: " in refused(path)


def test_floats_stay_floats_and_integers_stay_integers(tmp_path: Path) -> None:
    text = SHIPPED[0].read_text().replace(
        "period_ms: 20}",
        "period_ms: 20,\n          health: {min: -1.5, max: 1e3}, params: {gain: 0.25, n: 3}}")
    source = tmp_path / "floats.yaml"
    source.write_text(text)
    code, out, err = run("compile", source)
    assert code == 0, out + err
    raw = source.with_suffix(".json").read_text()
    assert '"health":{"deadline_ms":null,"max":1000.0,"min":-1.5}' in raw
    assert '"params":{"gain":0.25,"n":3}' in raw and '"port":100,' in raw


def test_a_non_finite_number_is_refused(tmp_path: Path) -> None:
    text = SHIPPED[0].read_text().replace("period_ms: 20}", "period_ms: 20, health: {max: .inf}}")
    source = tmp_path / "inf.yaml"
    source.write_text(text)
    code, _, err = run("compile", source)
    assert code == 2
    assert "out-of-range: task taskA: health.max is inf" in err
    assert not source.with_suffix(".json").exists()


def test_compiling_twice_gives_the_same_bytes(tmp_path: Path) -> None:
    images = []
    for name in ("first", "second"):
        (tmp_path / name).mkdir()
        images.append(compiled(tmp_path / name).read_bytes())
    assert images[0] == images[1]


def test_a_mission_with_violations_writes_no_image(tmp_path: Path) -> None:
    source = copy(VIOLATED, tmp_path)
    code, out, err = run("compile", source)
    assert code == 1
    assert "violation" in out and "capacity:" in out
    assert "no image written" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == [source.name]


def test_an_undecided_mission_writes_no_image(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    def unknown(self: Prover) -> dict:
        raise Undecided("timeout")

    monkeypatch.setattr(Prover, "run", unknown)
    source = copy(SHIPPED[0], tmp_path)
    code, out, err = run("compile", source)
    assert code == 3 and "UNDECIDED" in out and "no image written" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == [source.name]


def test_a_failed_compile_leaves_an_earlier_image_as_it_was(tmp_path: Path) -> None:
    source = copy(VIOLATED, tmp_path)
    earlier = source.with_suffix(".json")
    earlier.write_bytes(b"earlier")
    code, _, err = run("compile", source)
    assert code == 1 and "left as it was" in err
    assert earlier.read_bytes() == b"earlier"
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([source.name, earlier.name])


def test_malformed_yaml_exits_2_and_writes_nothing(tmp_path: Path) -> None:
    source = tmp_path / "broken.yaml"
    source.write_text("mission: broken\nschema: 1\nnodes: [unclosed\n")
    code, out, err = run("compile", source)
    assert code == 2 and out == ""
    assert f"{source}:" in err and "yaml-syntax" in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken.yaml"]
    code, out, _ = run("compile", source, "--json")
    report = json.loads(out)
    assert code == 2 and report["result"] == "input-error" and report["image"] is None


def test_json_output_names_the_image(tmp_path: Path) -> None:
    source = copy(SHIPPED[1], tmp_path)
    target = tmp_path / "out" / "eo.json"
    target.parent.mkdir()
    code, out, _ = run("compile", source, "-o", target, "--json")
    report = json.loads(out)
    assert code == 0 and report["result"] == "proved" and report["valid"] is True
    assert report["image"] == str(target) and target.exists()
    assert not source.with_suffix(".json").exists()


def test_an_output_that_cannot_be_written_is_an_input_error(tmp_path: Path) -> None:
    source = copy(SHIPPED[0], tmp_path)
    code, _, err = run("compile", source, "-o", tmp_path / "missing" / "x.json")
    assert code == 2 and "cannot write" in err and "Traceback" not in err
    code, _, err = run("compile", source, "-o", source)
    assert code == 2 and "overwrite the mission file" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == [source.name]


def test_an_image_that_breaks_its_own_schema_is_not_written(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(limits, "capacity", lambda: {"max_nodes": 0, "max_tasks": 0})
    source = copy(SHIPPED[0], tmp_path)
    code, _, err = run("compile", source)
    assert code == 4 and "internal error" in err and "capacity.max_nodes" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == [source.name]


# --------------------------------------------------------------------------------------
# The runtime's capacity


def wide_mission(nodes: int, tasks: int) -> str:
    """One phase, one configuration: every task on the master, nothing tolerated."""
    lines = ["mission: wide", "schema: 1", "heartbeat: {period_ms: 100, miss_limit: 3}",
             "tolerance: {node_failures: 0, nodes: []}", "nodes:"]
    lines += [f"  N{i}: {{kind: processing}}" for i in range(nodes)]
    lines += ["tasks:"] + [f"  T{i}: {{port: {i + 1}}}" for i in range(tasks)]
    lines += ["phases:", "  main:", "    initial: C1", "    configurations:", "      C1:",
              "        master: N0", "        observers: [N1]", "        tasks:"]
    lines += [f"          T{i}: N0" for i in range(tasks)]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(("nodes", "tasks", "expected"), [
    (limits.MAX_NODES + 1, 1,
     f"{limits.MAX_NODES + 1} nodes: a mission holds at most {limits.MAX_NODES}"),
    (2, limits.MAX_TASKS + 1,
     f"{limits.MAX_TASKS + 1} tasks: a mission holds at most {limits.MAX_TASKS}"),
], ids=["nodes", "tasks"])
def test_a_mission_over_the_capacity_is_refused(tmp_path: Path, nodes: int, tasks: int,
                                                expected: str) -> None:
    source = tmp_path / "wide.yaml"
    source.write_text(wide_mission(nodes, tasks))
    code, out, err = run("compile", source)
    assert code == 2, out + err
    assert f"{source}:" in err and "out-of-range" in err and expected in err
    assert not source.with_suffix(".json").exists()


def test_a_mission_at_the_capacity_compiles(tmp_path: Path) -> None:
    source = tmp_path / "wide.yaml"
    source.write_text(wide_mission(limits.MAX_NODES, limits.MAX_TASKS))
    code, out, err = run("compile", source)
    assert code == 0, out + err
    assert run("image-check", source.with_suffix(".json"))[0] == 0


def test_the_verifiers_capacity_is_the_runtimes() -> None:
    # What the verifier proves, every node must boot: the capacity it checks is the one
    # the runtime is compiled with (core/fsm/types.hpp), stated there and mirrored here.
    types = (Path(__file__).resolve().parents[2] / "core" / "fsm" / "types.hpp").read_text()
    runtime = {name: int(value) for name, value in
               re.findall(r"inline constexpr int (kMaxNodes|kMaxTasks) = (\d+);", types)}
    assert runtime == {"kMaxNodes": limits.MAX_NODES, "kMaxTasks": limits.MAX_TASKS}


def test_an_image_over_the_loaders_capacity_is_refused(tmp_path: Path) -> None:
    path = compiled(tmp_path)

    def add_nodes(data: dict) -> None:
        nodes = data["content"]["nodes"]
        for i in range(len(nodes), limits.MAX_NODES + 1):
            nodes.append(dict(nodes[0], id=i, name=f"X{i}"))

    rewrite(path, add_nodes)
    err = refused(path)
    assert "over-limit" in err and f"{limits.MAX_NODES + 1} nodes" in err
    assert f"at most {limits.MAX_NODES}" in err


# --------------------------------------------------------------------------------------
# image-check: what a node refuses


def test_a_tampered_image_is_refused_naming_the_hash(tmp_path: Path) -> None:
    path = compiled(tmp_path)
    raw = path.read_bytes()
    assert raw.count(b'"port":100,') == 1
    path.write_bytes(raw.replace(b'"port":100,', b'"port":109,'))  # one byte of content
    err = refused(path)
    assert "tampered" in err and "sha256 mismatch" in err
    with pytest.raises(image.ImageError) as error:
        image.load_image(path)
    assert error.value.reason == "tampered"


def test_a_wrong_format_version_is_refused(tmp_path: Path) -> None:
    path = compiled(tmp_path)
    rewrite(path, lambda data: data.update(keel_image=2))
    err = refused(path)
    assert "format-version" in err and "image format 2" in err and "reads format 1" in err


def test_an_image_that_breaks_the_schema_is_refused(tmp_path: Path) -> None:
    path = compiled(tmp_path)
    rewrite(path, lambda data: data["content"]["tasks"][0].update(port=100.0))
    assert "schema: content.tasks.0.port" in refused(path)
    path = compiled(tmp_path)
    rewrite(path, lambda data: data["content"]["nodes"][0].pop("kind"))
    assert "schema: content.nodes.0" in refused(path)


def test_duplicate_keys_are_refused(tmp_path: Path) -> None:
    path = compiled(tmp_path)
    raw = path.read_bytes()
    path.write_bytes(raw.replace(b'{"capacity":', b'{"mission":"other","capacity":', 1))
    err = refused(path)
    assert "not-json" in err and "duplicate key 'mission'" in err


@pytest.mark.parametrize("value, why", [(b"1e400", "out of the range"),
                                        (b'"\\ud800"', "lone UTF-16 surrogate")])
def test_json_no_utf8_text_or_double_holds_is_refused(tmp_path: Path, value: bytes,
                                                      why: str) -> None:
    path = compiled(tmp_path)
    raw = path.read_bytes()
    path.write_bytes(raw.replace(b'{"capacity":', b'{"x":' + value + b',"capacity":', 1))
    err = refused(path)
    assert "not-json" in err and why in err


def test_a_signed_image_verifies_with_its_key_and_no_other(tmp_path: Path) -> None:
    private, public = write_key(tmp_path, "mission")
    _, other = write_key(tmp_path, "other")
    path = compiled(tmp_path, SHIPPED[0], "--sign-key", private)
    data = json.loads(path.read_bytes())
    signature = data["signature"]
    assert signature["alg"] == "ed25519" and len(base64.b64decode(signature["value"])) == 64
    key = serialization.load_pem_public_key(public.read_bytes())
    assert signature["key_id"] == image.key_id(key)
    code, out, err = run("image-check", path, "--public-key", public)
    assert code == 0, err
    assert f"signature verified (key id {signature['key_id']})" in out
    assert "wrong-key" in refused(path, "--public-key", other)
    # A forger who edits the content and recomputes the hash still lacks the key.
    rewrite(path, lambda d: d["content"]["tasks"][0].update(port=109))
    assert run("image-check", path)[0] == 0
    assert "bad-signature" in refused(path, "--public-key", public)


def test_the_signing_key_can_come_from_the_environment(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    private, public = write_key(tmp_path, "mission")
    monkeypatch.setenv("KEEL_SIGNING_KEY", str(private))
    path = compiled(tmp_path)
    assert "signature" in json.loads(path.read_bytes())
    assert run("image-check", path, "--public-key", public)[0] == 0


def test_an_unsigned_image_is_refused_when_a_key_is_expected(tmp_path: Path) -> None:
    _, public = write_key(tmp_path, "mission")
    path = compiled(tmp_path)
    assert "unsigned: the image is not signed" in refused(path, "--public-key", public)


def test_a_bad_signing_key_is_an_input_error(tmp_path: Path) -> None:
    _, public = write_key(tmp_path, "mission")
    source = copy(SHIPPED[0], tmp_path)
    code, _, err = run("compile", source, "--sign-key", public)
    assert code == 2 and "not a PEM private key" in err and "Traceback" not in err
    assert not source.with_suffix(".json").exists()


@pytest.mark.skipif(shutil.which("openssl") is None, reason="openssl is not installed")
def test_keys_made_as_the_readme_says_work(tmp_path: Path) -> None:
    private, public = tmp_path / "mission.key", tmp_path / "mission.pub"
    subprocess.run(["openssl", "genpkey", "-algorithm", "ed25519", "-out", private], check=True)
    subprocess.run(["openssl", "pkey", "-in", private, "-pubout", "-out", public], check=True)
    path = compiled(tmp_path, SHIPPED[0], "--sign-key", private)
    assert run("image-check", path, "--public-key", public)[0] == 0


def test_the_image_schema_names_things_as_the_mission_schema_does() -> None:
    schemas = ROOT / "config" / "schema"
    mission = json.loads((schemas / "mission.schema.json").read_text())
    image_schema = json.loads((schemas / "image.schema.json").read_text())
    assert image_schema["$schema"] == mission["$schema"]
    assert image_schema["$defs"]["name"]["pattern"] == mission["$defs"]["name"]["pattern"]
    assert image_schema["properties"]["keel_image"]["const"] == image.FORMAT_VERSION


# --------------------------------------------------------------------------------------
# Proved means it runs: the node binary's components (check/components.py).

def test_a_component_the_node_binary_lacks_is_a_violation_and_writes_no_image(
        tmp_path: Path) -> None:
    source = copy(SHIPPED[0], tmp_path)
    code, out, err = run("compile", source, "--components", "producer,passthrough",
                         "--format", "json")
    assert code == 1, out + err
    violations = json.loads(out)["violations"]
    assert [(v["kind"], v["task"]) for v in violations] == [("component-missing", "taskB")]
    assert violations[0]["line"] == 22  # taskB, whose component is `consumer`
    assert not source.with_suffix(".json").exists()
    # Every component there (a list file, as keel-node --list-components prints it): proved.
    names = tmp_path / "node.components"
    names.write_text("consumer\npassthrough\nproducer\n")
    code, out, err = run("check", source, "--components", f"@{names}")
    assert code == 0, out + err


def test_the_components_can_come_from_the_node_binary(tmp_path: Path) -> None:
    # A stand-in for keel-node: it prints what --list-components prints.
    binary = tmp_path / "node"
    binary.write_text("#!/bin/sh\n[ \"$1\" = --list-components ] && echo producer && exit 0\n"
                      "exit 2\n")
    binary.chmod(0o755)
    code, out, err = run("check", copy(SHIPPED[0], tmp_path), "--components", binary)
    assert code == 1 and "component-missing" in out, out + err


@pytest.mark.parametrize("spec", ["@/no/such/file", ",", "@"])
def test_an_unreadable_component_list_is_an_input_error(tmp_path: Path, spec: str) -> None:
    source = copy(SHIPPED[0], tmp_path)
    for command in ("check", "compile"):
        code, out, err = run(command, source, "--components", spec)
        assert code == 2, out + err
        assert "--components" in err
    assert not source.with_suffix(".json").exists()
