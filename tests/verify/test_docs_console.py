"""The console blocks of README.md and docs/ that show keel-verify's output are run, and
what they show must be what it prints: a change that alters an output fails here until the
doc follows. Times (`0.02 s`), and the states TLC searched before it found a mutant's
violation, are matched as a pattern; sizes, hashes, lines and columns exactly (the image
is canonical JSON, the same on every machine).

A block is a fenced ```console block; a line `$ COMMAND` is run, the lines up to the next
`$` are its expected output (stdout and stderr, in the order the terminal shows them), a
trailing `# exit N` is its expected exit code; a shown line starting with `...` stands for
lines the doc trims. `./keel verify` is keel-verify from the
project's venv; `cd DIR` changes the directory for the block's later lines. Every other
command is not run here: each such block is named in NOT_RUN_HERE with the test that
covers it, and a block that runs nothing else fails.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
KEEL_VERIFY = Path(sys.executable).parent / "keel-verify"

# Blocks whose commands need what this test does not build (file, first command): where
# their output is checked instead.
NOT_RUN_HERE = {
    ("docs/components.md", "keel-verify check mission.yaml"):
        "a project ./keel new writes: tests/sdk/test_sdk.py builds and checks it",
    ("docs/cross-build.md", "./keel cross aarch64"):
        "the cross toolchain and qemu: tests/cross (CTest label cross)",
}

# The ```text blocks: each shows a program's output, held to what it prints by the test
# named (tests/docblocks.py: numbers as patterns), or shows no output (None: why).
TEXT_BLOCKS = {
    ("docs/clusters.md", "Keel earth-observation demo"): "tests/demo/test_demo.py",
    ("docs/clusters.md", "Command("): "tests/cluster/test_dds_tools.py",
    ("docs/components.md", "run/PN"): "tests/sdk/test_sdk.py",
    ("docs/components.md", "created --configure"): None,  # the component's lifecycle
    ("docs/missions.md", "tests/verify/missions/online/earth-observation-online.yaml: phase"):
        "tests/verify/test_placement_modes.py",  # needs keel-place
}

TIME = re.compile(r"\b\d+\.\d+ s\b")


def blocks() -> list[tuple[str, int, list[str]]]:
    """(file relative to the root, line of the fence, the block's lines)."""
    found = []
    for path in DOCS:
        lines = path.read_text().splitlines()
        start = None
        for number, line in enumerate(lines, 1):
            if line.strip() == "```console" and start is None:
                start = number
            elif line.strip() == "```" and start is not None:
                found.append((str(path.relative_to(ROOT)), start, lines[start:number - 1]))
                start = None
    return found


def commands(block: list[str]) -> list[tuple[str, list[str]]]:
    """(command, the output lines shown after it) for each `$` line."""
    out: list[tuple[str, list[str]]] = []
    for line in block:
        if line.startswith("$ "):
            out.append((line[2:].strip(), []))
        elif out:
            out[-1][1].append(line)
    return out


# How far TLC got when it found a mutant's violation, and the counterexample it found
# first, depend on its workers' timing.
SEARCHED = re.compile(r"\[[\d,]+ states, ")
COUNTEREXAMPLE = re.compile(r"counterexample \(\d+ states")
# keel-verify specs' progress (stderr, every few seconds): no doc shows it.
PROGRESS = re.compile(r"^keel-verify: specs: \S+: \d+ s: depth ")


def masked(line: str) -> str:
    line = COUNTEREXAMPLE.sub("counterexample (<n> states", line.rstrip())
    return SEARCHED.sub("[<n> states, ", TIME.sub("<t> s", line))


def shows(got: list[str], want: list[str]) -> bool:
    """`got` is what `want` shows: line for line, but that a line of `want` starting with
    `...` (a trimmed part, e.g. a long counterexample) stands for any lines up to the
    next line it shows."""
    if not want:
        return not got
    if want[0].lstrip().startswith("..."):
        return any(shows(got[i:], want[1:]) for i in range(len(got) + 1))
    return bool(got) and got[0] == want[0] and shows(got[1:], want[1:])


BLOCKS = blocks()


def test_every_text_block_is_held_to_the_output_it_shows() -> None:
    found = set()
    for path in DOCS:
        lines = path.read_text().splitlines()
        for number, line in enumerate(lines[:-1]):
            if line.strip() != "```text":
                continue
            file = str(path.relative_to(ROOT))
            opening = lines[number + 1]
            key = next((k for k in TEXT_BLOCKS if k[0] == file and opening.startswith(k[1])), None)
            assert key is not None, (
                f"{file}:{number + 1}: a ```text block no test holds: if it shows a program's "
                "output, compare it in the test that runs the program (tests/docblocks.py) and "
                "name that test in TEXT_BLOCKS; if not, name it there with None")
            found.add(key)
    assert found == set(TEXT_BLOCKS), set(TEXT_BLOCKS) - found
    for (file, first), test in TEXT_BLOCKS.items():
        if test is not None:
            source = (ROOT / test).read_text()
            assert file in source and first in source, f"{test} does not compare {file}'s block"


def test_the_docs_have_console_blocks() -> None:
    names = {(file, commands(block)[0][0]) for file, _, block in BLOCKS if commands(block)}
    assert ("README.md", "./keel verify compile config/earth_observation.yaml -o eo.json") in names
    assert set(NOT_RUN_HERE) <= names, set(NOT_RUN_HERE) - names


@pytest.mark.skipif(not os.access(KEEL_VERIFY, os.X_OK),
                    reason="keel-verify is not beside this Python")
@pytest.mark.parametrize(("file", "line", "block"), BLOCKS,
                         ids=[f"{file}:{line}" for file, line, _ in BLOCKS])
def test_a_console_block_shows_what_keel_verify_prints(file: str, line: int, block: list[str],
                                                        tmp_path: Path) -> None:
    steps = commands(block)
    assert steps, f"{file}:{line}: a console block without a `$ ` command"
    if (file, steps[0][0]) in NOT_RUN_HERE:
        pytest.skip(NOT_RUN_HERE[(file, steps[0][0])])
    # The repository's files, seen from a scratch folder, so that outputs written by the
    # commands (eo.json) go there; examples/ is copied, since blocks cd into it and write.
    for name in ("config", "tests"):
        (tmp_path / name).symlink_to(ROOT / name)
    shutil.copytree(ROOT / "examples", tmp_path / "examples",
                    ignore=shutil.ignore_patterns("build*"))
    cwd = tmp_path
    ran = 0
    for command, shown in steps:
        text, _, comment = command.partition("#")
        words = shlex.split(text)
        expected_exit = int(m[1]) if (m := re.search(r"\bexit (\d+)", comment)) else None
        if words[:1] == ["cd"]:
            cwd = cwd / words[1]
            assert cwd.is_dir(), f"{file}:{line}: cd {words[1]}: no such folder"
            continue
        if words[:2] == ["./keel", "verify"]:
            words = [str(KEEL_VERIFY), *words[2:]]
        elif words[:1] == ["keel-verify"]:
            words = [str(KEEL_VERIFY), *words[1:]]
        else:
            pytest.fail(f"{file}:{line}: `{command}` is not keel-verify: run it here or name "
                        "its block in NOT_RUN_HERE")
        if "specs" in words[1:2] and not {"--mutant", "--model", "--witness"} & set(words):
            # The whole set of TLC models: spec.* in CTest runs them, one test each.
            continue
        target = None
        if ">" in words:
            at = words.index(">")
            words, target = words[:at], words[at + 1]
        # One pipe for both streams, unbuffered: the order a terminal shows (but for a
        # redirected stdout, which goes to its file).
        env = dict(os.environ, KEEL_ROOT=str(ROOT), PYTHONUNBUFFERED="1")
        done = subprocess.run(words, cwd=cwd, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE if target else subprocess.STDOUT,
                              text=True, timeout=300, check=False, env=env)
        ran += 1
        if expected_exit is not None:
            assert done.returncode == expected_exit, (command, done.stdout[-2000:])
        if target is not None:
            (cwd / target).write_text(done.stdout)
            printed = done.stderr.splitlines()
        else:
            printed = done.stdout.splitlines()
        want = [masked(x) for x in shown if x.strip()]
        got = [masked(x) for x in printed if x.strip() and not PROGRESS.match(x)]
        assert shows(got, want), (
            f"{file}:{line}: `{command}` prints\n  " + "\n  ".join(got)
            + "\nwhere the doc shows\n  " + "\n  ".join(want))
    assert ran, f"{file}:{line}: no command of the block ran"
