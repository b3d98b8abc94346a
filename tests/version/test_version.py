"""The version lives in VERSION; every tool prints it with --version, and the Python
packages' copies (which an installed package carries) agree with it."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
VERSION = (ROOT / "VERSION").read_text().strip()


def test_the_version_is_semantic() -> None:
    assert re.fullmatch(r"\d+\.\d+\.\d+", VERSION)


@pytest.mark.parametrize("module", ["verify/keel_verify/__init__.py",
                                    "nodes/cluster/keel_cluster/__init__.py"])
def test_the_python_packages_carry_the_same_version(module: str) -> None:
    text = (ROOT / module).read_text()
    assert f'__version__ = "{VERSION}"' in text


def test_the_changelog_names_the_version() -> None:
    assert f"## {VERSION}" in (ROOT / "CHANGELOG.md").read_text()


def _build_dir() -> Path:
    return Path(os.environ.get("KEEL_BUILD_DIR", ROOT / "build" / "default"))


@pytest.mark.parametrize("command", [
    ["./keel", "--version"],
    [sys.executable, "-m", "keel_verify.cli", "--version"],
    [sys.executable, "-m", "keel_cluster.cli", "--version"],
    ["nodes/keel-node/keel-node", "--version"],
    ["nodes/sim/keel-sim", "--version"],
])
def test_every_tool_prints_it(command: list[str]) -> None:
    if command[0].startswith("nodes/"):
        binary = _build_dir() / command[0]
        if not binary.is_file():
            pytest.skip(f"{binary} is not built")
        command = [str(binary), *command[1:]]
    env = dict(os.environ, PYTHONPATH=f"{ROOT / 'verify'}:{ROOT / 'nodes' / 'cluster'}")
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=60,
                          env=env, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().endswith(VERSION), done.stdout
