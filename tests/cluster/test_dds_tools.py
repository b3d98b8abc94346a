"""`./keel dds` (core/net/dds/tools/keel-dds-cli): the `cyclonedds` tool's samples of Keel's
topics read with the mission's names (keel-dds-names), here with a stand-in for the tool
that prints samples as `cyclonedds subscribe` does (the tool itself is optional:
`./keel setup --dds-tools`)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TOOLS = ROOT / "core" / "net" / "dds" / "tools"
IMAGE = ROOT / "tests" / "missions" / "images" / "good" / "prototype3.json"
sys.path.insert(0, str(ROOT / "tests"))
from docblocks import text_block  # noqa: E402

# As `cyclonedds subscribe KeelCommand` / KeelAck / KeelNodeState print them (0.10.2).
SAMPLES = """\
Command(
    source=1,
    destination=65535,
    port=0,
    epoch=2,
    sequence_number=40,
    kind=<CommandKind.COMMAND_SWITCH: 0>,
    sender=1,
    adopted=View(
        epoch=2,
        seq=1,
        configuration=1,
        base=1,
        master=1,
        failed=[0]
    ),
    joint=[
        View(
            epoch=1,
            seq=3,
            configuration=65535,
            base=3,
            master=0,
            failed=[
                1,
                2
            ]
        )
    ],
    handed_boot=0,
    activate_epoch=0,
    activate_seq=0,
    destinations=[2, 3]
)
Ack(
    source=3,
    destination=2,
    port=0,
    epoch=1,
    sequence_number=7,
    kind=<AckKind.ACK_CHECKPOINT: 2>,
    sender=3,
    ack_epoch=1,
    seq=0,
    view=0,
    prepared_reply=False,
    task=1,
    lineage=0,
    count=12,
    heartbeat_reply=[]
)
Ack(
    source=2,
    destination=0,
    port=0,
    epoch=1,
    sequence_number=8,
    kind=<AckKind.ACK_PREPARED: 0>,
    sender=2,
    ack_epoch=1,
    seq=1,
    view=1234,
    prepared_reply=False,
    task=0,
    lineage=0,
    count=0,
    heartbeat_reply=[]
)
NodeState(
    node=2,
    name='PN3',
    role=<Role.ROLE_OBSERVER: 2>,
    epoch=1,
    configuration_id=65534,
    configuration='',
    phase='nominal'
)
"""


def names(text: str, image: Path = IMAGE) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(TOOLS / "keel-dds-names"), str(image)], input=text,
                          capture_output=True, text=True, check=False)


def test_every_id_the_mission_names_reads_as_its_name() -> None:
    done = names(SAMPLES)
    assert done.returncode == 0, done.stderr
    lines = [line.strip() for line in done.stdout.splitlines()]
    for expected in ["source=1,  # PN2", "destination=65535,  # every node", "sender=1,  # PN2",
                     "configuration=1,  # P2", "master=1,  # PN2", "failed=[0]  # PN1",
                     "configuration=65535,  # SAFE", "base=3,  # P4", "master=0,  # PN1",
                     "1,  # PN2", "2  # PN3", "destination=2,  # PN3", "task=1,  # taskB",
                     "node=2,  # PN3", "configuration_id=65534,  # none (no view yet)",
                     "destinations=[2, 3]  # PN3, ST1"]:
        assert expected in lines, (expected, done.stdout)
    # Only a checkpoint acknowledgement's task is one; the rest passes unchanged.
    assert "task=0," in lines
    assert "epoch=2," in lines and "count=12," in lines and "seq=1," in lines
    assert len(lines) == len(SAMPLES.splitlines())


def test_an_unreadable_image_is_an_input_error(tmp_path: Path) -> None:
    bad = tmp_path / "not-an-image.json"
    bad.write_text("{}")
    done = names("x=1\n", bad)
    assert done.returncode == 2
    assert "not-an-image.json: not a mission image" in done.stderr
    done = names("x=1\n", tmp_path / "missing.json")
    assert done.returncode == 2 and "missing.json" in done.stderr


def fake_tool(tmp_path: Path) -> dict[str, str]:
    """A cache whose dds-tools venv holds a stand-in `cyclonedds` printing SAMPLES, and a
    run folder as keel-cluster leaves it (security/, the image)."""
    tool = tmp_path / "cache" / "dds-tools" / "bin" / "cyclonedds"
    tool.parent.mkdir(parents=True)
    (tmp_path / "samples.txt").write_text(SAMPLES)
    tool.write_text(f"#!/bin/sh\necho \"args: $*\"\ncat {tmp_path / 'samples.txt'}\n")
    tool.chmod(0o755)
    security = tmp_path / "run" / "security"
    security.mkdir(parents=True)
    (security / "dds-tool.xml").write_text("<CycloneDDS/>\n")
    (tmp_path / "run" / "prototype3.image.json").write_bytes(IMAGE.read_bytes())
    return {**os.environ, "KEEL_CACHE": str(tmp_path / "cache"), "KEEL_NET_BENCH": "/bin/true"}


def dds_cli(env: dict[str, str], *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(TOOLS / "keel-dds-cli"), *args], env=env, capture_output=True,
                          text=True, check=False)


def test_keel_dds_reads_the_run_folders_image(tmp_path: Path) -> None:
    env = fake_tool(tmp_path)
    security = str(tmp_path / "run" / "security")
    done = dds_cli(env, "--security", security, "--", "subscribe", "KeelCommand", "-i", "7")
    assert done.returncode == 0, done.stderr
    assert "args: subscribe KeelCommand -i 7" in done.stdout
    assert "master=1,  # PN2" in done.stdout
    # --raw: the tool's output as is; --mission: names from the image given.
    raw = dds_cli(env, "--security", security, "--raw", "--", "subscribe", "KeelCommand", "-i", "7")
    assert raw.returncode == 0 and "#" not in raw.stdout and "master=1," in raw.stdout
    given = dds_cli(env, "--mission", str(IMAGE), "--", "subscribe", "KeelCommand", "-i", "7")
    assert "master=1,  # PN2" in given.stdout
    # Only samples: the tool's other commands (ps --watch, performance) keep the terminal.
    listed = dds_cli(env, "--security", security, "--", "ps", "-i", "7")
    assert listed.returncode == 0 and "#" not in listed.stdout
    missing = dds_cli(env, "--mission", str(tmp_path / "none.json"), "--", "ps")
    assert missing.returncode == 2
    assert "none.json: no such file" in missing.stderr


def test_the_sample_docs_clusters_md_shows_is_what_it_prints() -> None:
    # The block, its names taken out, annotated again: the same lines.
    shown = text_block("docs/clusters.md", "Command(")
    raw = "\n".join(re.sub(r"  # .*$", "", line) for line in shown) + "\n"
    done = names(raw)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == shown
