"""The ```text blocks of README.md and docs/ that show a program's output, held to what the
program prints in the test that runs it (tests/verify/test_docs_console.py lists every
such block and its test). Numbers are matched as patterns (times, counts and sizes differ
from run to run), but for digits that end a name (PN4, C5); a line `...` trims lines the
doc leaves out; every word, name and punctuation mark exactly."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# A number that stands alone (a time, a count, a ratio as x1.00, a timestamp's T01): a
# digit right after another letter is part of a name (PN4, C5, acca1) and matched exactly.
NUMBER = re.compile(r"(?<![A-SU-Za-wyz_])\d+(?:[.,]\d+)*")


def text_block(doc: str, first: str) -> list[str]:
    """The lines of the ```text block of `doc` (relative to the root) whose first line starts
    with `first`."""
    lines = (ROOT / doc).read_text().splitlines()
    for start, line in enumerate(lines):
        opens = line.strip() == "```text" and start + 1 < len(lines)
        if opens and lines[start + 1].startswith(first):
            end = lines.index("```", start + 1)
            return lines[start + 1:end]
    raise AssertionError(f"{doc}: no ```text block starting with {first!r}")


def pattern(line: str) -> re.Pattern[str]:
    """A doc line as a pattern: each number stands for any number."""
    parts = NUMBER.split(line.rstrip())
    return re.compile(NUMBER.pattern.join(re.escape(part) for part in parts) + "$")


def matches(shown: list[str], printed: list[str]) -> bool:
    """`printed` is what `shown` shows, line for line; a shown line `...` stands for any
    lines (none or more) up to the next line it shows."""
    if not shown:
        return not printed
    if shown[0].strip() == "...":
        return any(matches(shown[1:], printed[i:]) for i in range(len(printed) + 1))
    return bool(printed) and bool(pattern(shown[0]).match(printed[0])) and \
        matches(shown[1:], printed[1:])


def differs(shown: list[str], printed: list[str]) -> str | None:
    """None when `printed` is what `shown` shows (blank lines aside; `...` trims, see
    matches); else what differs, for the assertion's message: the first shown line the
    program did not print where the doc has it, and all it printed."""
    want = [line for line in shown if line.strip()]
    got = [line.rstrip() for line in printed if line.strip()]
    if matches(want, got):
        return None
    first = next((index for index in range(len(want))
                  if want[index].strip() != "..."
                  and not any(matches(want[:index + 1] + ["..."], got[:n])
                              for n in range(len(got) + 1))), None)
    where = (f"the doc's line {first + 1} is not printed where it shows it:\n  {want[first]}\n"
             if first is not None else
             f"the doc shows {len(want)} lines, the program printed {len(got)}\n")
    return where + "all it printed:\n  " + "\n  ".join(got)
