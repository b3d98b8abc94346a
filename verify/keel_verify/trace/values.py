"""A small reader for the TLA+ values TLC prints, to compare them with logged values."""

from __future__ import annotations

import re

_TOKEN = re.compile(
    r'\s*("(?:[^"\\]|\\.)*"|<<|>>|\|->|:>|@@|[{}\[\](),]|-?\d+|TRUE|FALSE|[A-Za-z_][\w]*)'
)


class _Reader:
    def __init__(self, text: str) -> None:
        self.tokens = _TOKEN.findall(text)
        self.i = 0

    def peek(self) -> str | None:
        return self.tokens[self.i] if self.i < len(self.tokens) else None

    def take(self) -> str:
        token = self.tokens[self.i]
        self.i += 1
        return token

    def items(self, close: str) -> list[object]:
        items: list[object] = []
        while self.peek() != close:
            items.append(self.value())
            if self.peek() == ",":
                self.take()
        self.take()
        return items

    def value(self) -> object:
        token = self.take()
        if token.startswith('"'):
            return token[1:-1].replace('\\"', '"').replace("\\\\", "\\")
        if token in ("TRUE", "FALSE"):
            return token == "TRUE"
        if re.fullmatch(r"-?\d+", token):
            return int(token)
        if token == "{":
            return frozenset(_hashable(item) for item in self.items("}"))
        if token == "<<":
            return tuple(self.items(">>"))
        if token == "[":
            fields: dict[object, object] = {}
            while self.peek() != "]":
                name = self.take()
                self.take()  # |->
                fields[name] = self.value()
                if self.peek() == ",":
                    self.take()
            self.take()
            return fields
        if token == "(":
            function: dict[object, object] = {}
            while True:
                key = self.value()
                self.take()  # :>
                function[_hashable(key)] = self.value()
                if self.peek() == "@@":
                    self.take()
                    continue
                self.take()  # )
                return function
        return token  # a model value


def _hashable(value: object) -> object:
    if isinstance(value, dict):
        return tuple(sorted((str(k), _hashable(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple)):
        return tuple(_hashable(v) for v in value)
    return value


def parse(text: str) -> object:
    """A TLC-printed value as Python: sets are frozensets, functions and records dicts."""
    return _Reader(text).value()


def from_json(value: object) -> object:
    """A logged JSON value in the same shape (lists are sets, objects functions)."""
    if isinstance(value, list):
        return frozenset(_hashable(from_json(v)) for v in value)
    if isinstance(value, dict):
        return {k: from_json(v) for k, v in value.items()}
    if value is None:
        return "none"
    return value


def normal(value: object) -> object:
    """Equal values compare equal: an empty function is an empty sequence."""
    if isinstance(value, tuple) and not value:
        return {}
    if isinstance(value, dict):
        return {str(k): normal(v) for k, v in value.items()}
    return value


def show(value: object) -> str:
    value = normal(value)
    if isinstance(value, frozenset):
        return "{" + ", ".join(sorted(show(v) for v in value)) + "}"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {show(v)}" for k, v in value.items()) + "}"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return value
    return str(value)
