"""Bad fixtures, one (or more) per violation kind, against golden outputs; the valid
missions of config/ are proved; malformed input gives exit 2 and file:line:col, never a
traceback. Regenerate the golden files with ``--update-golden`` or KEEL_UPDATE_GOLDEN=1."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import pytest
from conftest import check_args
from keel_verify.check.model import KINDS
from keel_verify.cli import main

ROOT = Path(__file__).resolve().parents[2]
MISSIONS = ROOT / "tests" / "verify" / "missions"
GOLDEN = ROOT / "tests" / "verify" / "golden"
BAD = sorted(p for p in MISSIONS.glob("*.yaml") if not p.name.startswith("valid"))


def run(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(argv))
    return code, out.getvalue(), err.getvalue()


def _kind_of(path: Path) -> str:
    return next(k for k in sorted(KINDS, key=len, reverse=True) if path.stem.startswith(k))


def _compare(name: str, text: str, update: bool) -> None:
    golden = GOLDEN / name
    if update:
        GOLDEN.mkdir(exist_ok=True)
        golden.write_text(text, encoding="utf-8")
    assert golden.exists(), f"no golden output {golden}; run with --update-golden"
    assert text == golden.read_text(encoding="utf-8")


def test_every_kind_has_a_bad_fixture() -> None:
    assert {_kind_of(p) for p in BAD} == set(KINDS)


@pytest.mark.parametrize("path", BAD, ids=lambda p: p.stem)
def test_bad_fixture_matches_golden(path: Path, update_golden: bool,
                                    monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    rel = str(path.relative_to(ROOT))
    kind = _kind_of(path)
    extra = check_args(path)
    code, out, err = run("check", rel, *extra)
    assert code == (2 if kind == "schema" else 1)
    _compare(f"{path.stem}.txt", f"exit {code}\n{out}{err}", update_golden)
    code, out, _ = run("check", rel, "--json", *extra)
    report = json.loads(out)
    assert kind in {v["kind"] for v in report["violations"]}
    assert report["valid"] is False
    report["stats"] = {}
    _compare(f"{path.stem}.json", json.dumps(report, indent=2) + "\n", update_golden)
    if kind != "schema":
        assert all(v["line"] > 0 and v["file"] == rel for v in report["violations"])


@pytest.mark.parametrize("mission", ["config/earth_observation.yaml", "config/prototype3.yaml",
                                     "tests/verify/missions/valid-three-nodes.yaml",
                                     "tests/verify/missions/valid-recovery-edges.yaml"])
def test_valid_missions_are_proved(mission: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    code, out, _ = run("check", mission)
    assert code == 0, out
    assert ": PROVED valid under every sequence" in out
    code, out, _ = run("check", mission, "--json")
    report = json.loads(out)
    assert report["valid"] is True and report["violations"] == [] and report["result"] == "proved"


def test_max_failures_bounds_the_depth(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    # The missing edge is after one failure: a bound of zero failures does not reach it.
    code, out, _ = run("check", "tests/verify/missions/missing-transition.yaml", "--max-failures", "0")
    assert code == 0, out
    code, _, _ = run("check", "tests/verify/missions/missing-transition.yaml", "--max-failures", "1")
    assert code == 1


LOADER_BAD = sorted((ROOT / "tests" / "missions" / "bad").glob("*.yaml"))


@pytest.mark.parametrize("path", LOADER_BAD, ids=lambda p: p.stem)
def test_malformed_input_is_reported_never_a_traceback(path: Path) -> None:
    code, out, err = run("check", str(path))
    assert "Traceback" not in out + err
    if path.stem.startswith(("unknown-reference", "port-conflict")):
        assert code == 1
        assert f"{path}:" in out
    else:
        assert code == 2
        first = err.splitlines()[0]
        file, line, col, _ = first.split(":", 3)
        assert file == str(path) and int(line) >= 1 and int(col) >= 1


def test_missing_file_is_an_input_error(tmp_path: Path) -> None:
    code, _, err = run("check", str(tmp_path / "absent.yaml"))
    assert code == 2 and "absent.yaml:1:1:" in err


def test_unknown_is_undecided_never_a_pass(monkeypatch: pytest.MonkeyPatch) -> None:
    import z3

    monkeypatch.setattr(z3.Solver, "check", lambda self, *assumptions: z3.unknown)
    monkeypatch.setattr(z3.Solver, "reason_unknown", lambda self: "timeout")
    code, out, _ = run("check", str(ROOT / "config" / "prototype3.yaml"))
    assert code == 3
    assert "UNDECIDED: the solver answered unknown (timeout); not proved" in out
    code, out, _ = run("check", str(ROOT / "config" / "prototype3.yaml"), "--json")
    report = json.loads(out)
    assert code == 3 and report["valid"] is False and report["result"] == "undecided"


def test_negative_bound_is_an_input_error() -> None:
    code, _, err = run("check", str(ROOT / "config" / "prototype3.yaml"), "--max-failures", "-1")
    assert code == 2 and "--max-failures" in err


def test_a_file_that_does_not_load_is_summarised_by_its_missions_name(tmp_path: Path) -> None:
    # A wrong name (a violation, exit 1) stops the load; the summary still names the
    # mission the file declares, not the file's stem, and says which node was meant.
    text = (ROOT / "tests" / "missions" / "good" / "minimal.yaml").read_text()
    assert "mission: minimal" in text and "t1: PN2" in text
    path = tmp_path / "pm.yaml"
    path.write_text(text.replace("t1: PN2", "t1: PM2"))
    code, out, _ = run("check", str(path))
    assert code == 1
    assert out.splitlines()[0].startswith(f"{path}: mission minimal: ")
    assert "node 'PM2' is not defined (did you mean 'PN2'?)" in out
