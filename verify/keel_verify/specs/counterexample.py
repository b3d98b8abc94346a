"""TLC's error trace, read and shown as a table of what changed.

TLC prints a counterexample as a list of full states::

    State 3: <DeclareFailed line 120, col 5 to line 126, col 60 of module Heartbeat>
    /\\ alive = (PN1 :> TRUE @@ PN2 :> FALSE)
    /\\ failed = ...

:func:`parse_trace` reads that into :class:`State` objects (action name, variables as
TLC printed them); :func:`render` prints one row per step with the action taken and only
the variables that changed, and for a function-valued variable only the entries that
changed (``missed[PN1][PN2]: 0 -> 1``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

_STATE = re.compile(r"^State (\d+): (.*)$")
_BACK_TO = re.compile(r"^Back to state (\d+)")
_ACTION = re.compile(
    r"^<(\w+)(?: line (\d+), col (\d+) to line (\d+), col (\d+) of module (\w+))?>$"
)
# A disjunct of a next-state relation that quantifies over a state variable, such as
# "\E n \in Nodes, msg \in msgs : ReceiveCommand(n, msg)": TLC cannot split it into
# one action per value, so it labels the step with the enclosing definition (Next).
_QUANTIFIED_CALL = re.compile(r"^\\E\s.*:\s*(\w+)\(.*\)\s*$")
_ASSIGNMENT = re.compile(r"^/\\ (\w+) = (.*)$")


@dataclass
class State:
    """One state of a counterexample and the step that led to it."""

    number: int
    action: str
    variables: dict[str, str] = field(default_factory=dict)
    stuttering: bool = False
    back_to: int | None = None

    def as_json(self) -> dict[str, object]:
        return {
            "state": self.number,
            "action": self.action,
            "vars": self.variables,
            "stuttering": self.stuttering,
            "back_to": self.back_to,
        }


def parse_trace(output: str, sources: dict[str, str] | None = None) -> list[State]:
    """The states of the (last) counterexample in TLC's output, in order.

    ``sources`` (module name -> text) lets a step that TLC labels with a whole
    next-state relation be named after the action the disjunct calls.
    """
    states: list[State] = []
    current: State | None = None
    name: str | None = None
    for raw in output.splitlines():
        line = raw.rstrip()
        if match := _STATE.match(line):
            number, label = int(match.group(1)), match.group(2).strip()
            if number == 1 and states:
                states = []  # a later trace replaces an earlier one
            current = State(number=number, action=_action_name(label, sources or {}))
            if label == "Stuttering":
                current.stuttering = True
            states.append(current)
            name = None
        elif match := _BACK_TO.match(line):
            number = int(match.group(1))
            states.append(State(number=len(states) + 1, action="(loop)", back_to=number))
            current, name = None, None
        elif current is not None and (match := _ASSIGNMENT.match(line)):
            name = match.group(1)
            current.variables[name] = match.group(2).strip()
        elif current is not None and name is not None and line.startswith(" "):
            current.variables[name] += " " + line.strip()
        elif not line.strip():
            name = None
    return states


def _action_name(label: str, sources: dict[str, str]) -> str:
    if label == "<Initial predicate>":
        return "Init"
    if label == "Stuttering":
        return "(stuttering)"
    match = _ACTION.match(label)
    if not match:
        return label
    name, line, col, end_line, end_col, module = match.groups()
    if module in sources and line == end_line:
        lines = sources[module].splitlines()
        row = int(line) - 1
        if 0 <= row < len(lines):
            span = lines[row][int(col) - 1 : int(end_col)].strip()
            if call := _QUANTIFIED_CALL.match(span):
                return call.group(1)
    return name


# --- Values ------------------------------------------------------------------------
# TLC prints functions over model values as ``(a :> 1 @@ b :> 2)`` and records as
# ``[f |-> 1, g |-> 2]``; both are split into entries so a change can be shown per entry.


def _split_top(text: str, separator: str) -> list[str]:
    """Split ``text`` at ``separator`` where it is not nested in brackets or quotes."""
    parts: list[str] = []
    depth = 0
    quoted = False
    start = 0
    i = 0
    while i < len(text):
        ch = text[i]
        if ch == '"':
            quoted = not quoted
        elif not quoted:
            if text.startswith("<<", i) or text.startswith(">>", i):
                depth += 1 if ch == "<" else -1
                i += 2
                continue
            if ch in "([{":
                depth += 1
            elif ch in ")]}":
                depth -= 1
            elif depth == 0 and text.startswith(separator, i):
                parts.append(text[start:i].strip())
                i += len(separator)
                start = i
                continue
        i += 1
    parts.append(text[start:].strip())
    return parts


def _entries(value: str) -> dict[str, str] | None:
    """The entries of a function or record value, or None for any other value."""
    value = value.strip()
    if value.startswith("(") and value.endswith(")") and ":>" in value:
        inner = value[1:-1]
        result: dict[str, str] = {}
        for part in _split_top(inner, "@@"):
            key, sep, item = part.partition(":>")
            if not sep:
                return None
            result[key.strip()] = item.strip()
        return result
    if value.startswith("[") and value.endswith("]") and "|->" in value:
        result = {}
        for part in _split_top(value[1:-1], ","):
            key, sep, item = part.partition("|->")
            if not sep:
                return None
            result[key.strip()] = item.strip()
        return result
    return None


def changes(before: str | None, after: str) -> list[tuple[str, str | None, str]]:
    """The changed entries between two values of a variable: (path, old, new) triples.

    Nested functions are followed, so ``missed`` changes as ``[PN1][PN2]: 0 -> 1``.
    """
    if before is None:
        return [("", None, after)]
    if before == after:
        return []
    old_entries, new_entries = _entries(before), _entries(after)
    if old_entries is None or new_entries is None or old_entries.keys() != new_entries.keys():
        return [("", before, after)]
    found: list[tuple[str, str | None, str]] = []
    for key, new_value in new_entries.items():
        for path, old, new in changes(old_entries[key], new_value):
            found.append((f"[{key}]{path}", old, new))
    return found


def step_changes(states: list[State]) -> list[tuple[State, list[tuple[str, str | None, str]]]]:
    """For every state, the (variable path, old, new) changes from the state before."""
    rows = []
    previous: dict[str, str] = {}
    for state in states:
        if state.back_to is not None or state.stuttering:
            rows.append((state, []))
            continue
        diff: list[tuple[str, str | None, str]] = []
        for name, value in state.variables.items():
            old = previous.get(name) if previous else None
            if not previous:
                diff.append((name, None, value))
            else:
                diff.extend((name + path, o, n) for path, o, n in changes(old, value))
        rows.append((state, diff))
        previous = state.variables
    return rows


def render(states: list[State], width: int = 100) -> str:
    """The counterexample as a table: step, action, changed variables."""
    if not states:
        return "  (TLC printed no trace)"
    lines = [f"  {'step':>4}  {'action':<24}  changes", f"  {'-' * 4}  {'-' * 24}  {'-' * 40}"]
    for state, diff in step_changes(states):
        if state.back_to is not None:
            lines.append(f"  {'':>4}  {'(loop)':<24}  back to step {state.back_to}: "
                         "the behaviour repeats from there forever")
            continue
        if state.stuttering:
            lines.append(f"  {state.number:>4}  {'(stuttering)':<24}  nothing changes "
                         "from here on")
            continue
        if state.action == "Init":
            text = [f"{name} = {new}" for name, _, new in diff]
        else:
            text = [f"{name}: {old} -> {new}" for name, old, new in diff] or ["(no change)"]
        first = True
        for item in text:
            for chunk in _wrap(item, width - 34):
                label = f"  {state.number:>4}  {state.action:<24}  " if first else " " * 34
                lines.append(label + chunk)
                first = False
    return "\n".join(lines)


def _wrap(text: str, width: int) -> list[str]:
    if len(text) <= width:
        return [text]
    chunks = []
    while len(text) > width:
        cut = text.rfind(" ", 0, width)
        cut = cut if cut > width // 2 else width
        chunks.append(text[:cut])
        text = "    " + text[cut:].lstrip()
    chunks.append(text)
    return chunks
