"""Shared test setup: the tests' own modules are importable, and ``--update-golden`` (or
KEEL_UPDATE_GOLDEN=1) rewrites the golden outputs instead of comparing with them."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parents[1] / "verify"))


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--update-golden", action="store_true",
                     help="rewrite tests/verify/golden/ from the current output")


@pytest.fixture
def update_golden(request: pytest.FixtureRequest) -> bool:
    return bool(request.config.getoption("--update-golden")) or os.environ.get(
        "KEEL_UPDATE_GOLDEN") == "1"


def check_args(path: Path) -> list[str]:
    """The arguments a bad fixture needs besides the file (a `# check-args: ...` line:
    component-missing is found only against a node binary's components)."""
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("# check-args:"):
            return line.split(":", 1)[1].split()
    return []
