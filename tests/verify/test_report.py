"""The CI formats (--format sarif|junit|github) of check, compile, specs and trace: SARIF
2.1.0 results at file:line:col, JUnit test cases per violation kind, model or protocol,
GitHub annotations; TLC's progress while it runs; and the examples/ci/ hook and workflow
run against the sample missions repository."""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path
from xml.etree import ElementTree

import jsonschema
import pytest
import yaml
from conftest import check_args
from keel_verify import report
from keel_verify.check.model import KINDS
from keel_verify.cli import main
from keel_verify.specs import tlc

ROOT = Path(__file__).resolve().parents[2]
MISSIONS = Path("tests/verify/missions")
BAD = sorted(p.name for p in (ROOT / MISSIONS).glob("*.yaml")
             if not p.name.startswith(("valid", "schema")))
GOOD = MISSIONS / "valid-three-nodes.yaml"
CI = ROOT / "examples" / "ci"
SAMPLE = CI / "sample-missions"
JAR = tlc.find_jar()
needs_tlc = pytest.mark.skipif(JAR is None or shutil.which("java") is None,
                               reason="TLC jar or Java not installed (./keel setup)")
GITHUB_LINE = re.compile(
    r"^::(error|warning|notice) file=(?P<file>[^,]+),line=(?P<line>\d+),col=(?P<col>\d+),"
    r"title=(?P<title>[^:]+)::(?P<message>[^\n]+)$")

# The part of SARIF 2.1.0 (sarif-schema-2.1.0.json) these reports use, with its rules:
# what a consumer such as GitHub code scanning requires of a log.
SARIF_SUBSET = {
    "type": "object",
    "required": ["version", "$schema", "runs"],
    "properties": {
        "version": {"const": "2.1.0"},
        "$schema": {"type": "string", "pattern": "sarif-schema-2\\.1\\.0\\.json$"},
        "runs": {"type": "array", "minItems": 1, "items": {
            "type": "object",
            "required": ["tool", "results"],
            "properties": {
                "tool": {"type": "object", "required": ["driver"], "properties": {
                    "driver": {"type": "object", "required": ["name", "version", "rules"],
                               "properties": {
                                   "name": {"const": "keel-verify"},
                                   "version": {"type": "string"},
                                   "rules": {"type": "array", "items": {
                                       "type": "object", "required": ["id", "shortDescription"],
                                       "properties": {"id": {"type": "string"},
                                                      "shortDescription": {
                                                          "type": "object",
                                                          "required": ["text"]}}}}}}}},
                "results": {"type": "array", "items": {
                    "type": "object",
                    "required": ["ruleId", "level", "message", "locations"],
                    "properties": {
                        "ruleId": {"type": "string"},
                        "ruleIndex": {"type": "integer", "minimum": 0},
                        "level": {"enum": ["none", "note", "warning", "error"]},
                        "message": {"type": "object", "required": ["text"],
                                    "properties": {"text": {"type": "string", "minLength": 1}}},
                        "locations": {"type": "array", "minItems": 1, "items": {
                            "type": "object", "required": ["physicalLocation"],
                            "properties": {"physicalLocation": {
                                "type": "object", "required": ["artifactLocation", "region"],
                                "properties": {
                                    "artifactLocation": {
                                        "type": "object", "required": ["uri"],
                                        "properties": {"uri": {"type": "string",
                                                               "pattern": "^[^\\\\ ]+$"}}},
                                    "region": {
                                        "type": "object",
                                        "required": ["startLine", "startColumn"],
                                        "properties": {
                                            "startLine": {"type": "integer", "minimum": 1},
                                            "startColumn": {"type": "integer",
                                                            "minimum": 1}}}}}}}}}}},
            }}},
    },
}


def run(*argv: object) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def sarif_log(text: str) -> dict:
    log = json.loads(text)
    jsonschema.validate(log, SARIF_SUBSET)
    driver = log["runs"][0]["tool"]["driver"]
    rule_ids = [rule["id"] for rule in driver["rules"]]
    for result in log["runs"][0]["results"]:
        assert rule_ids[result["ruleIndex"]] == result["ruleId"]
    return log


def code_scanning_problems(logs: list[dict], category: str | None = None) -> list[str]:
    """What GitHub code scanning refuses in one upload of these SARIF logs (the rules of
    github/codeql-action/upload-sarif, which combines every file of a folder into one
    upload): two runs of one tool (tool.driver.name) under one category. A run's category
    is the action's `category` input when given (it overrides every run's), else what
    precedes the last '/' of its runAutomationDetails.id, else the workflow's and job's
    (one for every run of the job)."""
    seen: dict[tuple[str, str], int] = {}
    problems = []
    for log in logs:
        assert log["version"] == "2.1.0" and log["runs"], log
        for run in log["runs"]:
            run_id = run.get("automationDetails", {}).get("id")
            if category is not None:
                run_category = category
            elif run_id:
                run_category = run_id[: run_id.rfind("/")] if "/" in run_id else run_id
            else:
                run_category = "<workflow>/<job>"
            key = (run["tool"]["driver"]["name"], run_category)
            seen[key] = seen.get(key, 0) + 1
    for (tool, run_category), count in seen.items():
        if count > 1:
            problems.append(f"{count} runs of {tool} share the category {run_category!r}")
    return problems


def results_of(log: dict) -> list[tuple[str, str, int, int]]:
    """(ruleId, uri, line, column) of every result."""
    out = []
    for result in log["runs"][0]["results"]:
        location = result["locations"][0]["physicalLocation"]
        out.append((result["ruleId"], location["artifactLocation"]["uri"],
                    location["region"]["startLine"], location["region"]["startColumn"]))
    return out


def junit_cases(text: str) -> dict[str, str]:
    """Test case name -> passed | failure | error | skipped, from a well-formed document."""
    root = ElementTree.fromstring(text.encode())
    assert root.tag == "testsuites"
    (suite,) = root.findall("testsuite")
    cases = {}
    for case in suite.findall("testcase"):
        outcome = [child.tag for child in case if child.tag in ("failure", "error", "skipped")]
        cases[case.get("name")] = outcome[0] if outcome else "passed"
    counts = {tag: sum(1 for v in cases.values() if v == tag)
              for tag in ("failure", "error", "skipped")}
    assert int(suite.get("tests")) == len(cases)
    assert (int(suite.get("failures")), int(suite.get("errors")), int(suite.get("skipped"))) == (
        counts["failure"], counts["error"], counts["skipped"])
    return cases


@pytest.fixture(autouse=True)
def at_root(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)


# --------------------------------------------------------------------------------------
# check


@pytest.mark.parametrize("name", BAD)
def test_check_sarif_results_are_the_violations_at_their_lines(name: str) -> None:
    mission = MISSIONS / name
    extra = check_args(ROOT / mission)
    code, out, _ = run("check", mission, "--json", *extra)
    expected = sorted((v["kind"], v["line"]) for v in json.loads(out)["violations"])
    code_sarif, out, err = run("check", mission, "--format", "sarif", *extra)
    assert code_sarif == code == 1
    log = sarif_log(out)
    found = results_of(log)
    assert sorted((rule, line) for rule, _, line, _ in found) == expected
    assert {uri for _, uri, _, _ in found} == {mission.as_posix()}
    assert all(col >= 1 for *_, col in found)
    assert log["runs"][0]["invocations"][0]["exitCode"] == 1
    assert "violation" in err  # the summary, for the CI log


def test_check_sarif_points_at_the_key_on_its_line() -> None:
    code, out, _ = run("check", MISSIONS / "capability.yaml", "--format", "sarif")
    assert code == 1
    found = results_of(sarif_log(out))
    lines = (ROOT / MISSIONS / "capability.yaml").read_text().splitlines()
    for _, _, line, col in found:
        assert lines[line - 1][col - 1:].startswith(("P1:", "P2:", "P4:"))
    message = sarif_log(out)["runs"][0]["results"][1]["message"]["text"]
    assert "lacks fpga" in message and "failures: PN1" in message and "--PN1--> P2" in message


def test_check_sarif_of_a_proved_mission_has_no_results() -> None:
    code, out, _ = run("check", GOOD, "--format", "sarif")
    assert code == 0
    log = sarif_log(out)
    assert log["runs"][0]["results"] == []
    assert {rule["id"] for rule in log["runs"][0]["tool"]["driver"]["rules"]} >= set(KINDS)


def test_check_sarif_of_a_schema_error_is_at_its_line_and_column() -> None:
    code, out, _ = run("check", MISSIONS / "schema-wrong-type.yaml", "--format", "sarif")
    assert code == 2
    ((rule, uri, line, col),) = results_of(sarif_log(out))
    # The same position as the text output's file:line:col.
    _, _, text_err = run("check", MISSIONS / "schema-wrong-type.yaml")
    assert text_err.startswith(f"{uri}:{line}:{col}: wrong-type:") and rule == "schema"


def test_check_junit_has_a_case_per_kind() -> None:
    code, out, _ = run("check", MISSIONS / "capability.yaml", "--format", "junit")
    assert code == 1
    cases = junit_cases(out)
    assert list(cases) == list(KINDS)
    assert cases["capability"] == "failure"
    assert {v for k, v in cases.items() if k != "capability"} == {"passed"}
    code, out, _ = run("check", GOOD, "--format", "junit")
    assert code == 0 and set(junit_cases(out).values()) == {"passed"}
    code, out, _ = run("check", MISSIONS / "schema-wrong-type.yaml", "--format", "junit")
    cases = junit_cases(out)
    assert code == 2 and cases["schema"] == "failure"
    assert {v for k, v in cases.items() if k != "schema"} == {"skipped"}
    code, out, _ = run("check", MISSIONS / "port-conflict.yaml", "--format", "junit")
    cases = junit_cases(out)
    assert code == 1 and cases["port-conflict"] == "failure" and cases["capacity"] == "skipped"


def test_check_github_annotations() -> None:
    code, out, err = run("check", MISSIONS / "master-mismatch.yaml", "--format", "github")
    assert code == 1
    *annotations, summary = out.splitlines()
    assert annotations and all(GITHUB_LINE.match(line) for line in annotations)
    first = GITHUB_LINE.match(annotations[0])
    assert first["file"] == (MISSIONS / "master-mismatch.yaml").as_posix()
    assert first["title"] == "keel-verify check%3A master-mismatch"
    assert "master-mismatch 1" in summary and not summary.startswith("::")
    assert err == ""
    code, out, _ = run("check", GOOD, "--format", "github")
    assert code == 0 and out.count("\n") == 1 and "PROVED" in out


def test_a_checkpointed_task_without_a_state_bound_gets_an_advisory_and_nothing_else(
        tmp_path: Path) -> None:
    # GOOD states max_state_bytes for its checkpointed task: no advisory. Without it, every
    # format names the task at its line (an advisory, level note) and neither the verdict
    # nor the exit code changes.
    text = (ROOT / GOOD).read_text()
    assert ", max_state_bytes: 4096}" in text
    unbounded = tmp_path / "unbounded.yaml"
    unbounded.write_text(text.replace(", max_state_bytes: 4096}", "}"))
    line = next(i for i, row in enumerate(text.splitlines(), 1)
                if row.lstrip().startswith("consumer:"))
    advised = [("unbounded-state", "consumer", line)]
    for mission, expected in ((ROOT / GOOD, []), (unbounded, advised)):
        code, out, _ = run("check", mission, "--json")
        found = json.loads(out)
        assert code == 0 and found["valid"] is True
        assert [(a["rule"], a["task"], a["line"]) for a in found["advisories"]] == expected
        code, out, _ = run("check", mission)
        assert code == 0 and out.startswith(f"{mission}: mission") and "PROVED" in out
        advisories = [row for row in out.splitlines() if " advisory " in row]
        assert len(advisories) == len(expected)
        assert all(row.startswith(f"{mission}:{line}: advisory unbounded-state: task consumer "
                                  "is checkpointed and states no max_state_bytes")
                   for row in advisories)
        code, out, _ = run("check", mission, "--format", "sarif")
        results = sarif_log(out)["runs"][0]["results"]
        assert code == 0
        at_lines = [(r["ruleId"], r["level"], r["locations"][0]["physicalLocation"]["region"]
                     ["startLine"]) for r in results]
        assert at_lines == [(rule, "note", at) for rule, _, at in expected]
        code, out, _ = run("check", mission, "--format", "github")
        notices = [GITHUB_LINE.match(row) for row in out.splitlines() if row.startswith("::")]
        assert code == 0 and [(m[1], int(m["line"])) for m in notices] == [
            ("notice", at) for _, _, at in expected]


def test_json_is_an_alias_of_format_json() -> None:
    mission = MISSIONS / "capacity.yaml"
    code_a, a, _ = run("check", mission, "--json")
    code_b, b, _ = run("check", mission, "--format", "json")
    first, second = json.loads(a), json.loads(b)
    first["stats"] = second["stats"] = {}
    assert (code_a, first) == (code_b, second)
    err = io.StringIO()
    with contextlib.redirect_stderr(err), pytest.raises(SystemExit) as stopped:
        main(["check", str(mission), "--json", "--format", "sarif"])
    assert stopped.value.code == 2 and "not allowed with" in err.getvalue()


# --------------------------------------------------------------------------------------
# compile


def test_compile_sarif_and_junit(tmp_path: Path) -> None:
    image = tmp_path / "image.json"
    code, out, _ = run("compile", MISSIONS / "capability.yaml", "-o", image, "--format", "sarif")
    assert code == 1 and not image.exists()
    assert [rule for rule, *_ in results_of(sarif_log(out))] == ["capability"] * 3
    code, out, err = run("compile", GOOD, "-o", image, "--format", "junit")
    assert code == 0 and image.is_file()
    cases = junit_cases(out)
    assert cases["image"] == "passed" and set(cases.values()) == {"passed"}
    assert "image written" in err
    code, out, _ = run("compile", MISSIONS / "capability.yaml", "-o", image, "--format", "junit")
    assert code == 1 and junit_cases(out)["image"] == "skipped"


def test_compile_problem_before_proving_is_still_a_report(tmp_path: Path) -> None:
    code, out, _ = run("compile", GOOD, "-o", tmp_path / "x.json", "--sign-key",
                       tmp_path / "missing.key", "--format", "sarif")
    assert code == 2
    ((rule, uri, line, _),) = results_of(sarif_log(out))
    assert (rule, uri, line) == ("input-error", GOOD.as_posix(), 1)


def test_compile_github_annotation_for_an_unwritable_image(tmp_path: Path) -> None:
    code, out, _ = run("compile", GOOD, "-o", tmp_path / "no-such-dir" / "x.json",
                       "--format", "github")
    assert code == 2
    (annotation, summary) = out.splitlines()
    match = GITHUB_LINE.match(annotation)
    assert match and match["title"].endswith("%3A image") and "cannot write" in summary


# --------------------------------------------------------------------------------------
# The report module itself


def test_github_escapes_line_breaks_and_property_separators() -> None:
    outcome = report.Report("check", "m", "summary", 1, findings=[
        report.Finding("kind", "first line\nsecond, 100%", "dir/a,b:c.yaml", 3, 4)])
    (line, summary) = report.github(outcome)
    assert line == ("::error file=dir/a%2Cb%3Ac.yaml,line=3,col=4,title=keel-verify check%3A "
                    "kind::first line%0Asecond, 100%25")
    assert summary == "summary"


def test_junit_survives_control_characters_and_markup() -> None:
    outcome = report.Report("check", "<m>", "s", 1, cases=[
        report.Case("kind", "c", report.FAILED, "bad \x01 <x> & y", "details\x1b[0m")])
    root = ElementTree.fromstring(report.junit(outcome).encode())
    failure = root.find("testsuite/testcase/failure")
    assert failure is not None and "<x> & y" in failure.get("message")


def test_sarif_positions_are_one_based_and_uris_relative() -> None:
    outcome = report.Report("check", "m", "s", 1, findings=[
        report.Finding("kind", "message", str(ROOT / "dir with space" / "m.yaml"), 0, 0)])
    log = sarif_log(json.dumps(report.sarif(outcome)))
    assert results_of(log) == [("kind", "dir%20with%20space/m.yaml", 1, 1)]
    outside = report.Finding("kind", "message", "/elsewhere/m.yaml")
    assert report.artifact_uri(outside.file) == "file:///elsewhere/m.yaml"


# --------------------------------------------------------------------------------------
# specs and trace (TLC)

TOY = """---- MODULE Toy ----
EXTENDS Naturals
VARIABLE x
Init == x = 0
Step == x < 3 /\\ x' = x + 1
Spec == Init /\\ [][Step]_x
SmallInv == x <= 2
====
"""

TOY_MUTANT = """---- MODULE ToyHarmless ----
EXTENDS Toy
MutantSpec == Init /\\ [][x < 2 /\\ x' = x + 1]_x
====
"""


def _toy_spec_dir(tmp_path: Path) -> Path:
    """A model whose invariant fails at x = 3, and a mutant that does not break it."""
    spec_dir = tmp_path / "spec"
    (spec_dir / "mutants").mkdir(parents=True)
    (spec_dir / "Toy.tla").write_text(TOY)
    (spec_dir / "Toy.cfg").write_text("SPECIFICATION Spec\nINVARIANT SmallInv\n"
                                      "CHECK_DEADLOCK FALSE\n")
    (spec_dir / "mutants" / "ToyHarmless.tla").write_text(TOY_MUTANT)
    (spec_dir / "manifest.json").write_text(json.dumps({
        "models": [{"name": "Toy", "spec": "Toy", "module": "Toy", "config": "Toy.cfg",
                    "properties": ["SmallInv"], "distinct_states": 4}],
        "mutants": [{"name": "ToyHarmless", "base": "Toy", "module": "ToyHarmless",
                     "specification": "MutantSpec", "property": "SmallInv",
                     "exit_code": 12}],
    }, indent=2))
    return spec_dir


@needs_tlc
def test_specs_formats_on_a_failing_model_and_mutant(tmp_path: Path) -> None:
    spec_dir = _toy_spec_dir(tmp_path)
    common = ["specs", "--spec-dir", spec_dir, "--workers", "1", "--progress-interval", "0"]
    code, out, _ = run(*common, "--format", "sarif")
    assert code == 1
    found = {rule: (Path(uri).name, line) for rule, uri, line, _ in results_of(sarif_log(out))}
    # The violated invariant's definition, and the mutant's module.
    assert found == {"property-violated": ("Toy.tla", 7),
                     "mutant-not-rejected": ("ToyHarmless.tla", 1)}
    code, out, _ = run(*common, "--format", "junit")
    assert code == 1 and junit_cases(out) == {"Toy": "failure", "ToyHarmless": "failure"}
    code, out, _ = run(*common, "--format", "github")
    *annotations, summary = out.splitlines()
    assert code == 1 and len(annotations) == 2
    assert all(GITHUB_LINE.match(line) for line in annotations)
    assert "0/1 models passed, 0/1 mutants rejected" in summary


def test_specs_input_error_is_a_report(tmp_path: Path) -> None:
    code, out, err = run("specs", "--model", "NoSuchModel", "--format", "sarif")
    assert code == 2
    ((rule, uri, _, _),) = results_of(sarif_log(out))
    assert rule == "input-error" and uri.endswith("manifest.json")
    assert "unknown model" in err


def test_progress_lines_of_tlc_and_of_the_probe_are_read() -> None:
    line = ("Progress(17) at 2026-11-24 08:16:42: 8,337 states generated (8,337 s/min), "
            "3,584 distinct states found (3,584 ds/min), 559 states left on queue.")
    assert tlc.progress_of(line, 3.0) == tlc.Progress(3.0, 17, 8337, 3584, 559)
    assert tlc.progress_of("@keel-progress 19 12065 5115 756\n", 5.0) == tlc.Progress(
        5.0, 19, 12065, 5115, 756)
    assert tlc.progress_of("Starting... (2026-11-24 08:16:39)", 1.0) is None


@needs_tlc
def test_specs_reports_progress_while_tlc_runs() -> None:
    # A short interval, so that even a fast machine reports before the model is done.
    code, out, err = run("specs", "--model", "MCHeartbeatStartup", "--workers", "1",
                         "--progress-interval", "0.25")
    assert code == 0, out + err
    progress = re.findall(r"^keel-verify: specs: MCHeartbeatStartup: (\d+) s: depth \d+, "
                          r"([\d,]+) states generated, [\d,]+ distinct, [\d,]+ on the queue$",
                          err, re.MULTILINE)
    assert progress, err
    generated = [int(states.replace(",", "")) for _, states in progress]
    assert generated == sorted(generated) and generated[-1] > 0
    assert "@keel-progress" not in out + err
    code, out, err = run("specs", "--model", "MCHeartbeatStartup", "--workers", "1",
                         "--progress-interval", "0", "--json")
    assert code == 0 and "keel-verify: specs:" not in err
    assert json.loads(out)["results"][0]["distinct_states"] == 20492


FORGED = {"t_ns": 1000, "node": "PN3", "fsm": "election", "action": "BecomeMaster",
          "args": {"n": "PN3", "epoch": 2},
          "vars": {"role": "Master", "epoch": 2, "leader": "PN3", "suspects": [],
                   "lastCommand": 0}}


@needs_tlc
def test_trace_formats_point_at_the_unexplained_line(tmp_path: Path) -> None:
    trace = tmp_path / "forged.ndjson"
    trace.write_text(json.dumps(FORGED) + "\n")
    common = ["trace", trace, "--fsm", "election", "--jobs", "1"]
    code, out, _ = run(*common, "--format", "sarif")
    assert code == 1
    assert results_of(sarif_log(out)) == [("trace-mismatch", trace.as_uri(), 1, 1)]
    code, out, _ = run(*common, "--format", "junit")
    assert code == 1 and junit_cases(out) == {"election": "failure"}
    code, out, _ = run(*common, "--format", "github")
    (annotation, summary) = out.splitlines()
    assert GITHUB_LINE.match(annotation) and "BecomeMaster" in annotation
    assert "NOT a behaviour" in summary


@needs_tlc
def test_trace_input_error_is_at_its_line(tmp_path: Path) -> None:
    trace = tmp_path / "malformed.ndjson"
    trace.write_text(json.dumps(FORGED) + "\n" + '{"t_ns": 1, "node": "PN1"}\n')
    code, out, _ = run("trace", trace, "--format", "sarif")
    assert code == 2
    assert results_of(sarif_log(out)) == [("input-error", trace.as_uri(), 2, 1)]


# --------------------------------------------------------------------------------------
# examples/ci: the pre-commit hook and the workflow against the sample repository


def _environment() -> dict[str, str]:
    """keel-verify of this checkout first on the PATH, as an installed one would be."""
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    return env


def _hook_entry() -> list[str]:
    (hook,) = yaml.safe_load((CI / ".pre-commit-hooks.yaml").read_text())
    assert hook["id"] == "keel-verify-check" and hook["language"] == "system"
    return shlex.split(hook["entry"])


def test_the_missions_repository_config_declares_the_same_hook() -> None:
    config = yaml.safe_load((CI / "pre-commit-config.yaml").read_text())
    (hook,) = config["repos"][0]["hooks"]
    assert hook["id"] == "keel-verify-check"
    assert shlex.split(hook["entry"]) == _hook_entry()
    assert re.match(hook["files"], "missions/relay.yaml")
    assert not re.match(hook["files"], ".github/workflows/missions.yml")


@pytest.mark.skipif(shutil.which("keel-verify", path=str(Path(sys.executable).parent)) is None,
                    reason="keel-verify is not installed beside this Python")
@pytest.mark.parametrize(("files", "expected"), [
    (["missions/relay.yaml"], 0),
    (["missions/relay-fpga.yaml"], 1),
    (["missions/relay.yaml", "missions/relay-fpga.yaml"], 1),
])
def test_pre_commit_hook_on_the_sample_repository(files: list[str], expected: int) -> None:
    done = subprocess.run([*_hook_entry(), *files], cwd=SAMPLE, env=_environment(),
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == expected, done.stdout + done.stderr
    if expected:
        assert "missions/relay-fpga.yaml:24:7: capability:" in done.stdout
    assert "Traceback" not in done.stderr


@pytest.mark.skipif(shutil.which("bash") is None or shutil.which(
    "keel-verify", path=str(Path(sys.executable).parent)) is None,
                    reason="bash or keel-verify missing")
def test_workflow_script_on_the_sample_repository(tmp_path: Path) -> None:
    workflow = yaml.safe_load((CI / "github-workflow.yml").read_text())
    steps = {step.get("name"): step for step in workflow["jobs"]["prove"]["steps"]}
    upload = steps["Upload the SARIF results"]
    assert upload["uses"].startswith("github/codeql-action/upload-sarif@")
    assert upload["with"]["sarif_file"] == "sarif" and upload["if"] == "always()"
    repository = tmp_path / "missions-repo"
    shutil.copytree(SAMPLE, repository)
    done = subprocess.run(["bash", "-e", "-c", steps["Prove the missions"]["run"]],
                          cwd=repository, env=_environment(), capture_output=True, text=True,
                          timeout=300, check=False)
    assert done.returncode == 1, done.stdout + done.stderr  # relay-fpga is not proved
    annotations = [line for line in done.stdout.splitlines() if line.startswith("::error")]
    assert len(annotations) == 3
    logs = {path.name: sarif_log(path.read_text())
            for path in (repository / "sarif").glob("*.sarif")}
    assert set(logs) == {"missions_relay.yaml.sarif", "missions_relay-fpga.yaml.sarif"}
    # Code scanning takes both logs in one upload: each run its own category.
    assert code_scanning_problems(list(logs.values()), upload["with"].get("category")) == []
    assert {log["runs"][0]["automationDetails"]["id"] for log in logs.values()} == {
        "keel-verify/check/missions/relay.yaml/", "keel-verify/check/missions/relay-fpga.yaml/"}
    # The rule can fail: one category for the whole upload (as the action's `category`
    # input gives), or logs without automationDetails, is refused.
    assert code_scanning_problems(list(logs.values()), "keel-verify")
    bare = [{**log, "runs": [{k: v for k, v in run.items() if k != "automationDetails"}
                             for run in log["runs"]]} for log in logs.values()]
    assert code_scanning_problems(bare)
    assert results_of(logs["missions_relay.yaml.sarif"]) == []
    assert [(uri, line) for _, uri, line, _ in results_of(logs["missions_relay-fpga.yaml.sarif"])
            ] == [("missions/relay-fpga.yaml", 24), ("missions/relay-fpga.yaml", 25),
                  ("missions/relay-fpga.yaml", 27)]
