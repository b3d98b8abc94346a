"""One table of exit codes for every keel-verify subcommand (docs/missions.md, "Exit
codes"): on every bad mission fixture, `graph`, `synth`, `compile` and `load` exit as
`check` does, 1 for violations (a name or port that is wrong) and 2 for an input error (a
file that does not parse or breaks the schema); 3 when the solver cannot decide, for every
subcommand that proves; 4 for an internal error, for every subcommand. Once, `graph` and
`synth` exited 2 on missions `check` exits 1 on, and 1 on a mission it could not decide."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import pytest
from conftest import check_args
from keel_verify import mission as mission_module
from keel_verify.check.prover import Prover, Undecided
from keel_verify.cli import main

ROOT = Path(__file__).resolve().parents[2]
BAD = sorted((ROOT / "tests" / "missions" / "bad").glob("*.yaml"))


def exit_code(*argv: str) -> int:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        return main(list(argv))


@pytest.mark.parametrize("path", [p for p in BAD if not check_args(p)], ids=lambda p: p.stem)
def test_every_subcommand_exits_as_check_does(path: Path, tmp_path: Path) -> None:
    expected = exit_code("check", str(path))
    assert expected in (1, 2), expected
    codes = {
        "graph": exit_code("graph", str(path), "-o", str(tmp_path / "graph.dot")),
        "synth": exit_code("synth", str(path), "--no-check", "-o", str(tmp_path / "synth.yaml")),
        "compile": exit_code("compile", str(path), "-o", str(tmp_path / "image.json")),
        "load": exit_code("load", str(path)),
    }
    assert codes == dict.fromkeys(codes, expected), (expected, codes)


def test_both_exit_codes_are_among_the_fixtures() -> None:
    # The witness that the comparison is not vacuous: fixtures of both kinds exist.
    codes = {exit_code("check", str(p)) for p in BAD if not check_args(p)}
    assert codes == {1, 2}, codes


SHIPPED = ROOT / "config" / "prototype3.yaml"


def codes_of_every_subcommand(tmp_path: Path) -> dict[str, int]:
    """Each subcommand's exit code on a shipped mission, its outputs in tmp_path."""
    return {
        "check": exit_code("check", str(SHIPPED)),
        "graph": exit_code("graph", str(SHIPPED), "-o", str(tmp_path / "graph.dot")),
        "synth": exit_code("synth", str(SHIPPED), "-o", str(tmp_path / "synth.yaml")),
        "compile": exit_code("compile", str(SHIPPED), "-o", str(tmp_path / "image.json")),
        "load": exit_code("load", str(SHIPPED)),
    }


def test_every_subcommand_that_proves_exits_3_when_undecided(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def unknown(self: Prover) -> dict:
        raise Undecided("timeout")

    monkeypatch.setattr(Prover, "run", unknown)
    codes = codes_of_every_subcommand(tmp_path)
    del codes["load"]  # it proves nothing
    assert codes == dict.fromkeys(codes, 3), codes
    assert not (tmp_path / "image.json").exists()


def test_every_subcommand_exits_4_on_an_internal_error(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(*_args: object, **_kwargs: object) -> None:
        raise RuntimeError("planted")

    # Every subcommand reads its mission through the loader's rule checks.
    monkeypatch.setattr(mission_module, "_rule_errors", broken)
    codes = codes_of_every_subcommand(tmp_path)
    assert codes == dict.fromkeys(codes, 4), codes
