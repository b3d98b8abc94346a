"""Reports for CI: SARIF 2.1.0, JUnit XML and GitHub Actions annotations.

``check``, ``compile``, ``specs`` and ``trace`` take ``--format text|json|sarif|junit|github``
(``--json`` is ``--format json``). ``text`` and ``json`` are each command's own (docs/missions.md
states check's JSON); for the three CI formats a command describes its outcome once, as a
:class:`Report`, and this module writes it:

* **findings** (:class:`Finding`): what is wrong, where: a rule id (a violation kind, a
  failed model...), a level (``error``, or ``warning`` for an undecided result, which is
  never a pass), a message and a position ``file:line:col``. A finding without a known
  position points at line 1 of the file it is about. They become SARIF results and
  GitHub ``::error`` / ``::warning`` lines.
* **cases** (:class:`Case`): what was checked, passed or not: one per violation kind for
  ``check``, one per model, mutant or witness for ``specs``, one per protocol for
  ``trace``. They become JUnit test cases (passed, ``failure``, ``error`` or ``skipped``).

The document goes to stdout; with ``sarif`` and ``junit`` the command's one-line summary
goes to stderr, so that a CI log still says what happened. Exit codes do not depend on
the format.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO
from urllib.parse import quote

from keel_verify import __version__

FORMATS = ("text", "json", "sarif", "junit", "github")
CI_FORMATS = ("sarif", "junit", "github")

SARIF_VERSION = "2.1.0"
SARIF_SCHEMA = ("https://docs.oasis-open.org/sarif/sarif/v2.1.0/errata01/os/schemas/"
                "sarif-schema-2.1.0.json")
TOOL_NAME = "keel-verify"

ERROR = "error"
WARNING = "warning"
NOTE = "note"
LEVELS = (ERROR, WARNING, NOTE)

# JUnit outcomes of a case.
PASSED = "passed"
FAILED = "failed"
ERRORED = "error"
SKIPPED = "skipped"
CASE_STATUSES = (PASSED, FAILED, ERRORED, SKIPPED)


def add_format_arguments(parser: argparse.ArgumentParser) -> None:
    """``--format`` and its alias ``--json``, both setting ``args.format``."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--format", choices=FORMATS, default="text",
                       help="output: text (default), json, sarif (SARIF 2.1.0), junit "
                            "(JUnit XML) or github (GitHub Actions annotations)")
    group.add_argument("--json", dest="format", action="store_const", const="json",
                       help="same as --format json")


@dataclass(frozen=True)
class Rule:
    """A kind of finding: a stable id and a sentence saying what it means."""

    id: str
    description: str


@dataclass
class Finding:
    rule: str
    message: str
    file: str
    line: int = 1
    col: int = 1
    level: str = ERROR
    properties: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        assert self.level in LEVELS, self.level
        # Positions are 1-based; an unknown one is the start of the file.
        self.line = max(1, int(self.line or 1))
        self.col = max(1, int(self.col or 1))


@dataclass
class Case:
    name: str
    classname: str
    status: str = PASSED
    message: str = ""
    details: str = ""
    seconds: float = 0.0

    def __post_init__(self) -> None:
        assert self.status in CASE_STATUSES, self.status


@dataclass
class Report:
    """What one run of a command found and checked."""

    command: str  # "check", "compile", "specs", "trace"
    title: str  # what was checked: the mission, "protocol specs", the trace files
    summary: str  # the command's one-line verdict
    exit_code: int
    rules: list[Rule] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)
    cases: list[Case] = field(default_factory=list)
    seconds: float = 0.0
    # The input it ran on (a mission file): what tells this run from another of the same
    # command in one CI upload (SARIF's automationDetails). Defaults to `title`.
    subject: str = ""


# --------------------------------------------------------------------------------------
# Paths


def display_path(file: str) -> str:
    """A path as CI tools want it: relative to the working directory when it is inside it
    (GitHub resolves annotations and SARIF locations against the checkout), with '/'."""
    path = Path(file)
    if path.is_absolute():
        try:
            path = path.relative_to(Path.cwd())
        except ValueError:
            return path.as_posix()
    return path.as_posix()


def artifact_uri(file: str) -> str:
    """A SARIF artifactLocation.uri: a relative reference, or a file:// URI."""
    shown = display_path(file)
    if Path(shown).is_absolute():
        return Path(shown).as_uri()
    return quote(shown, safe="/-._~")


def find_line(path: Path, pattern: str) -> tuple[int, int]:
    """(line, column) of the first match of the regular expression ``pattern`` in the
    file, or (1, 1): where a TLA+ definition (``Name ==``) starts, for instance."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return 1, 1
    match = re.search(pattern, text, re.MULTILINE)
    if match is None:
        return 1, 1
    before = text[: match.start()]
    line = before.count("\n") + 1
    return line, match.start() - (before.rfind("\n") + 1) + 1


# --------------------------------------------------------------------------------------
# SARIF


def automation_id(report: Report) -> str:
    """SARIF's runAutomationDetails.id: `keel-verify/COMMAND/INPUT/`. GitHub code
    scanning takes what precedes the last '/' as the run's category, and refuses an
    upload in which two runs of one tool share a category: one SARIF log per mission
    file, uploaded together, must each have its own."""
    return f"{TOOL_NAME}/{report.command}/{display_path(report.subject or report.title)}/"


def sarif(report: Report) -> dict[str, Any]:
    """A SARIF 2.1.0 log with one run."""
    rule_ids = [rule.id for rule in report.rules]
    rules = list(report.rules)
    for finding in report.findings:
        if finding.rule not in rule_ids:  # every result's rule is described
            rule_ids.append(finding.rule)
            rules.append(Rule(finding.rule, finding.rule))
    results = []
    for finding in report.findings:
        result: dict[str, Any] = {
            "ruleId": finding.rule,
            "ruleIndex": rule_ids.index(finding.rule),
            "level": finding.level,
            "message": {"text": finding.message},
            "locations": [{
                "physicalLocation": {
                    "artifactLocation": {"uri": artifact_uri(finding.file)},
                    "region": {"startLine": finding.line, "startColumn": finding.col},
                },
            }],
        }
        if finding.properties:
            result["properties"] = finding.properties
        results.append(result)
    return {
        "$schema": SARIF_SCHEMA,
        "version": SARIF_VERSION,
        "runs": [{
            "tool": {"driver": {
                "name": TOOL_NAME,
                "version": __version__,
                "semanticVersion": __version__,
                "rules": [{"id": rule.id, "name": rule.id,
                           "shortDescription": {"text": rule.description}}
                          for rule in rules],
            }},
            "automationDetails": {"id": automation_id(report)},
            "invocations": [{
                "exitCode": report.exit_code,
                # The tool ran to a verdict (proved or violations); 2-4 mean it did not.
                "executionSuccessful": report.exit_code in (0, 1),
            }],
            "results": results,
            "properties": {"command": report.command, "summary": report.summary},
        }],
    }


# --------------------------------------------------------------------------------------
# JUnit XML

# XML 1.0 cannot hold most control characters, even escaped.
_XML_INVALID = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")


def _xml_text(text: str) -> str:
    return _XML_INVALID.sub("\ufffd", text)


def junit(report: Report) -> str:
    """A JUnit XML document: one test suite, one test case per :class:`Case`."""
    counts = {status: sum(1 for c in report.cases if c.status == status)
              for status in CASE_STATUSES}
    attributes = {
        "name": _xml_text(f"{TOOL_NAME} {report.command}: {report.title}"),
        "tests": str(len(report.cases)),
        "failures": str(counts[FAILED]),
        "errors": str(counts[ERRORED]),
        "skipped": str(counts[SKIPPED]),
        "time": f"{report.seconds:.3f}",
    }
    suites = ElementTree.Element("testsuites", attributes)
    suite = ElementTree.SubElement(suites, "testsuite", attributes)
    properties = ElementTree.SubElement(suite, "properties")
    for name, value in (("tool", f"{TOOL_NAME} {__version__}"),
                        ("exit_code", str(report.exit_code)),
                        ("summary", _xml_text(report.summary))):
        ElementTree.SubElement(properties, "property", {"name": name, "value": value})
    for case in report.cases:
        element = ElementTree.SubElement(suite, "testcase", {
            "name": _xml_text(case.name),
            "classname": _xml_text(case.classname),
            "time": f"{case.seconds:.3f}",
        })
        if case.status != PASSED:
            tag = {FAILED: "failure", ERRORED: "error", SKIPPED: "skipped"}[case.status]
            outcome = ElementTree.SubElement(element, tag,
                                             {"message": _xml_text(case.message)})
            if case.status != SKIPPED:
                outcome.set("type", case.name)
            if case.details:
                outcome.text = _xml_text(case.details)
        elif case.details:
            ElementTree.SubElement(element, "system-out").text = _xml_text(case.details)
    ElementTree.indent(suites)
    body = ElementTree.tostring(suites, encoding="unicode")
    return f'<?xml version="1.0" encoding="UTF-8"?>\n{body}\n'


# --------------------------------------------------------------------------------------
# GitHub Actions workflow commands


def _escape_data(text: str) -> str:
    return text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def _escape_property(text: str) -> str:
    return _escape_data(text).replace(":", "%3A").replace(",", "%2C")


def github(report: Report) -> list[str]:
    """``::error file=F,line=L,col=C,title=T::message`` per finding, then the summary."""
    lines = []
    for finding in report.findings:
        command = {ERROR: "error", WARNING: "warning", NOTE: "notice"}[finding.level]
        properties = ",".join(f"{key}={_escape_property(str(value))}" for key, value in (
            ("file", display_path(finding.file)), ("line", finding.line),
            ("col", finding.col), ("title", f"{TOOL_NAME} {report.command}: {finding.rule}")))
        lines.append(f"::{command} {properties}::{_escape_data(finding.message)}")
    lines.append(report.summary)
    return lines


# --------------------------------------------------------------------------------------
# Writing


def emit(report: Report, format_name: str, out: TextIO | None = None,
         err: TextIO | None = None) -> None:
    """Write ``report`` in one of the CI formats (stdout by default)."""
    out = out or sys.stdout
    err = err or sys.stderr
    if format_name == "sarif":
        json.dump(sarif(report), out, indent=2)
        out.write("\n")
    elif format_name == "junit":
        out.write(junit(report))
    elif format_name == "github":
        out.write("\n".join(github(report)) + "\n")
        return
    else:
        raise ValueError(f"not a CI format: {format_name}")
    print(f"{TOOL_NAME}: {report.command}: {report.summary}", file=err)
