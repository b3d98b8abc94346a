"""``keel-verify synth MISSION.yaml -o OUT.yaml``: synthesise a complete decision graph.

Keeps the mission's nodes, tasks, tolerance, phases (their tasks, initial configuration
names, planned phase changes and params) and replaces every phase's configurations and
edges by a synthesised graph (see ``keel_verify.synth.core``). The output is then
checked like any mission; exit 0 when it is proved, 1 when no valid graph exists (or,
which would be a bug, the output does not pass check), 2 for an input error.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

from keel_verify.check.core import check_mission
from keel_verify.check.result import PROVED
from keel_verify.generate import to_yaml
from keel_verify.mission import MissionError, load_mission, loads_mission
from keel_verify.synth.core import SynthError, synthesize


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "synth",
        help="synthesise a valid decision graph for a mission (Z3)",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("mission", help="mission file (YAML, schema 1)")
    parser.add_argument("-o", "--output", required=True, help="where to write the mission")
    parser.add_argument("--no-check", action="store_true",
                        help="do not prove the output (it is proved by default)")
    parser.set_defaults(func=run)


KEY = re.compile(r"^(?P<indent> *)(?P<key>[^\s#:'\"{\[][^:#]*?)\s*:(\s|$)")
TRAILING = re.compile(r"\s+#.*$")


def key_paths(lines: list[str]) -> list[tuple[str, ...] | None]:
    """Per line, the keys from the top of the YAML block down to the one it opens (None
    for a line that opens none: a comment, a blank line, a list item)."""
    stack: list[tuple[int, str]] = []
    paths: list[tuple[str, ...] | None] = []
    for line in lines:
        match = KEY.match(line)
        if not match:
            paths.append(None)
            continue
        indent = len(match["indent"])
        while stack and stack[-1][0] >= indent:
            stack.pop()
        stack.append((indent, match["key"]))
        paths.append(tuple(key for _, key in stack))
    return paths


def carry_comments(written: list[str], generated: list[str]) -> tuple[list[str], list[int]]:
    """The generated phases with the written ones' comments (and blank lines) kept before
    the key they stood above, and trailing comments kept on their key's line, wherever the
    generated phases have that key (a phase, a configuration, an edge list...). Returns
    those lines and the indices of the written comment lines no such key is left for."""
    before: dict[tuple[str, ...], list[int]] = {}
    trailing: dict[tuple[str, ...], str] = {}
    pending: list[int] = []
    unread: list[int] = []  # a trailing comment on a line with quotes: not parsed, dropped
    for index, (line, path) in enumerate(zip(written, key_paths(written), strict=True)):
        if path is None:
            if not line.strip() or line.lstrip().startswith("#"):
                pending.append(index)
            continue
        if pending:
            before[path] = pending
            pending = []
        if match := TRAILING.search(line):
            if '"' in line or "'" in line:
                unread.append(index)
            else:
                trailing[path] = match.group(0)
    out: list[str] = []
    for line, path in zip(generated, key_paths(generated), strict=True):
        if path is not None and path in before:
            out.extend(written[i] for i in before.pop(path))
        if path is not None and path in trailing and not TRAILING.search(line):
            line += trailing.pop(path)
        out.append(line)
    dropped = sorted(i for indices in before.values() for i in indices if written[i].strip())
    dropped += [i for i, (line, path) in enumerate(zip(written, key_paths(written), strict=True))
                if path is not None and path in trailing]
    # Comments after the block's last key, and trailing ones this reader does not parse.
    dropped += [i for i in pending if written[i].strip()] + unread
    return out, sorted(dropped)


def with_phases(source: str, data: dict, comment: str,
                dropped: list[int] | None = None) -> str:
    """The mission file as the user wrote it (comments, key order, flow or block style),
    with its `phases:` section replaced by the synthesised one, which `comment` heads; the
    comments written inside `phases:` stay above (or beside) the keys the synthesised
    phases keep, and the 1-based lines of those that found none are added to `dropped`.
    A file whose `phases:` is not one top-level block is written anew (to_yaml)."""
    lines = source.splitlines()
    starts = [i for i, line in enumerate(lines) if re.match(r"phases\s*:\s*(#.*)?$", line)]
    if len(starts) != 1:
        return to_yaml(data, comment)
    start = starts[0]
    # The block ends at the next top-level key; comments just above that key are its own.
    end = next((i for i in range(start + 1, len(lines))
                if lines[i] and not lines[i][0].isspace() and not lines[i].startswith("#")),
               len(lines))
    while end > start + 1 and lines[end - 1].startswith("#"):
        end -= 1
    generated = to_yaml({**data, "nodes": {}, "tasks": {}}, comment).splitlines()
    phases = generated[generated.index("phases:"):]
    phases, lost = carry_comments(lines[start:end], phases)
    if dropped is not None:
        dropped.extend(start + 1 + i for i in lost)
    heading = [f"# {line}" for line in comment.splitlines()]
    return "\n".join([*lines[:start], *heading, *phases, *lines[end:]]).rstrip("\n") + "\n"


def run(args: argparse.Namespace) -> int:
    try:
        mission = load_mission(args.mission)
    except MissionError as error:
        for e in error.errors:
            print(e, file=sys.stderr)
        # A file that does not parse or breaks the schema is an input error; a name or port
        # that is wrong is a violation, as `check` reports it (docs/missions.md, "Exit codes").
        return 2 if error.is_input_error else 1

    def progress(message: str) -> None:
        print(f"keel-verify: synth: {message}", file=sys.stderr, flush=True)

    try:
        result = synthesize(mission, progress)
    except SynthError as error:
        print(f"{args.mission}: synth: {error}", file=sys.stderr)
        return 1
    comment = (f"Decision graph synthesised by keel-verify synth from {args.mission}:\n"
               f"one configuration per phase and set of at most "
               f"{mission.tolerance.node_failures} failed tolerated nodes.")
    dropped: list[int] = []
    text = with_phases(Path(args.mission).read_text(encoding="utf-8-sig"), result.data, comment,
                       dropped)
    Path(args.output).write_text(text, encoding="utf-8")
    for line in dropped:
        print(f"{args.mission}:{line}: synth: this comment was about a part of the graph the "
              f"synthesised one does not have: not carried over", file=sys.stderr)
    moves = result.moves
    mean = sum(moves) / len(moves) if moves else 0.0
    print(f"{args.output}: {result.configurations} configurations in {len(mission.phases)} "
          f"phase(s); tasks moved per failure: mean {mean:.2f}, max {max(moves, default=0)}; "
          f"{result.seconds:.2f} s")
    if args.no_check:
        return 0
    start = time.perf_counter()
    try:
        written = loads_mission(text, args.output)
    except MissionError as error:  # pragma: no cover - the writer and loader disagree
        for e in error.errors:
            print(e, file=sys.stderr)
        return 1
    checked = check_mission(written)
    if checked.status != PROVED:
        print(f"{args.output}: check: {checked.status} ({len(checked.violations)} violations)",
              file=sys.stderr)
        # The exit code check gives (docs/missions.md, "Exit codes"): 3 when undecided.
        return 1 if checked.violations else 3
    print(f"{args.output}: check: PROVED ({time.perf_counter() - start:.2f} s)")
    return 0
