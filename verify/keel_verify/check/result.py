"""What a check produces: violations with their counterexamples, and the verdict."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

PROVED = "proved"
VIOLATED = "violated"
UNDECIDED = "undecided"


@dataclass
class Step:
    """One move of a counterexample path: a detected failure or a planned phase change."""

    event: str  # "start" | "failure" | "phase" | "recovery"
    to: str  # configuration, "SAFE", or "?" for a missing edge
    node: str | None = None  # the failed node (event "failure"), the readmitted one ("recovery")
    phase: str | None = None  # the phase entered (events "start" and "phase")

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"event": self.event, "to": self.to}
        if self.node is not None:
            out["node"] = self.node
        if self.phase is not None:
            out["phase"] = self.phase
        return out


@dataclass
class Violation:
    kind: str
    phase: str
    config: str
    task: str | None
    node: str | None
    message: str
    failures: list[str] = field(default_factory=list)
    steps: list[Step] = field(default_factory=list)
    file: str = ""
    line: int = 0
    col: int = 0  # 0: not known (the reports then point at the line's first column)
    target: str = ""
    suggestion: str | None = None
    # The index (in the result's violations) of the violation this one follows from: an
    # on_phase move into a configuration that breaks a rule there, reported as that
    # configuration's own violation too. None: a root cause.
    cause: int | None = None

    @property
    def path(self) -> list[str]:
        return [s.to for s in self.steps]

    def sort_key(self) -> tuple[Any, ...]:
        return (self.line, self.kind, self.phase, self.config, self.task or "", self.node or "",
                self.target)

    def path_text(self) -> str:
        parts: list[str] = []
        for step in self.steps:
            if step.event == "start":
                parts.append(step.to)
            elif step.event == "failure":
                parts.append(f"--{step.node}--> {step.to}")
            elif step.event == "recovery":
                parts.append(f"++{step.node}++> {step.to}")
            else:
                parts.append(f"=={step.phase}==> {step.to}")
        return " ".join(parts)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "kind": self.kind,
            "phase": self.phase,
            "failures": list(self.failures),
            "path": self.path,
            "config": self.config,
            "task": self.task,
            "node": self.node,
            "message": self.message,
            "file": self.file,
            "line": self.line,
            "steps": [s.to_json() for s in self.steps],
        }
        if self.target:
            out["target"] = self.target  # the on_phase target phase
        if self.suggestion is not None:
            out["suggestion"] = self.suggestion
        if self.cause is not None:
            out["cause"] = self.cause
        return out


@dataclass
class Advisory:
    """Not a violation (the verdict and the exit code do not depend on it): a choice the
    mission leaves open that weakens what a running cluster can refuse."""

    rule: str
    task: str | None
    message: str
    file: str = ""
    line: int = 0

    def to_json(self) -> dict[str, Any]:
        return {"rule": self.rule, "task": self.task, "message": self.message,
                "file": self.file, "line": self.line}


@dataclass
class CheckResult:
    mission: str
    file: str
    status: str
    violations: list[Violation]
    stats: dict[str, Any]
    reason: str = ""  # why the result is undecided
    advisories: list[Advisory] = field(default_factory=list)

    @property
    def valid(self) -> bool:
        return self.status == PROVED

    def kinds(self) -> set[str]:
        return {v.kind for v in self.violations}

    def roots(self) -> list[Violation]:
        """The violations that follow from no other one (what the summary counts)."""
        return [v for v in self.violations if v.cause is None]

    def consequences(self, index: int) -> list[Violation]:
        return [v for v in self.violations if v.cause == index]
