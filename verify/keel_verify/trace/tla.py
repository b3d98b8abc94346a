"""JSON values as TLA+ literals (TLC 2.18 has no Json module: the trace is TLA+ data)."""

from __future__ import annotations

import re

_FIELD = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


def string(value: str) -> str:
    return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'


def literal(value: object) -> str:
    """A JSON value as TLA+: strings, integers, booleans, sets (from lists), functions
    (``("a" :> 1 @@ "b" :> 2)``, from objects, so an empty object is an empty function)."""
    if value is None:
        return '"none"'
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if value.is_integer():
            return str(int(value))
        raise ValueError(f"a fraction ({value}) has no TLA+ literal here")
    if isinstance(value, str):
        return string(value)
    if isinstance(value, list):
        return "{" + ", ".join(sorted({literal(item) for item in value})) + "}"
    if isinstance(value, dict):
        if not value:
            return "<<>>"
        pairs = (f"{string(str(k))} :> {literal(v)}" for k, v in value.items())
        return "(" + " @@ ".join(pairs) + ")"
    raise ValueError(f"no TLA+ literal for {value!r}")


def record(fields: dict[str, object]) -> str:
    """A TLA+ record; the values are already TLA+ text."""
    for name in fields:
        if not _FIELD.match(name):
            raise ValueError(f"{name!r} is not a record field name")
    return "[" + ", ".join(f"{name} |-> {text}" for name, text in fields.items()) + "]"


def sequence(items: list[str], indent: str = "    ") -> str:
    if not items:
        return "<<>>"
    return "<<\n" + ",\n".join(indent + item for item in items) + "\n>>"
