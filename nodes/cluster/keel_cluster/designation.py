"""The ground's side of `designate NODE` (spec/Designate.tla, rule 3; docs/operations.md):
the WAIT and SPAN of each designation, and the designations the ground sent, which they
depend on.

The command every node is sent is `designate NODE WAIT SPAN ECHO`: the ground's vote for
NODE from WAIT heartbeat periods after NODE admits it until SPAN periods after NODE sent its
heartbeat number ECHO (the latest the ground read from NODE's status line). A designation of
node E with span S sent at ground time t0 is E's vote until t0 + (S + 1) periods at the
latest: E's heartbeat ECHO was sent before t0, and one period more covers the clocks'
drift. A designation of NODE waits the periods left, rounded up, of the latest such end the
ground gave another node (0 when none is left), so that NODE's vote never begins while
another node's may still hold; SPAN is WAIT + the vote span (VOTE_SPAN_PERIODS unless the
run says otherwise). Designating the node that holds the vote again renews it at once.

The designations are kept in memory and appended to the run directory's
DESIGNATIONS_FILE as they are sent, so that a launcher started again on the same run
directory still honours the spans given before it. Time is the ground's wall clock in
nanoseconds, passed in: nothing here reads a clock.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

VOTE_SPAN_PERIODS = 20  # the vote's span past its wait, in heartbeat periods (run --vote-span)
VOTE_SPAN_PERIODS_MAX = 100_000  # keel-node takes WAIT and SPAN up to 1 000 000 periods
DRIFT_PERIODS = 1  # a designation's end, as the ground bounds it, is this much later
DESIGNATIONS_FILE = "designations.jsonl"
# A line of DESIGNATIONS_FILE longer than this is not one the launcher wrote.
LINE_BYTES_MAX = 4096


@dataclass(frozen=True)
class Designation:
    """One `designate NODE WAIT SPAN ECHO` the ground sent at `sent_ns` (its wall clock),
    with the mission's heartbeat period then."""

    node: str
    wait_periods: int
    span_periods: int
    echo: int
    sent_ns: int
    period_ns: int

    @property
    def ends_ns(self) -> int:
        """The latest ground time at which this designation may still be the node's vote."""
        return self.sent_ns + (self.span_periods + DRIFT_PERIODS) * self.period_ns

    def arguments(self) -> list[str]:
        """The command's arguments, as keel-node takes them: NODE WAIT SPAN ECHO."""
        return [self.node, str(self.wait_periods), str(self.span_periods), str(self.echo)]

    def as_dict(self) -> dict[str, Any]:
        return {"t_ns": self.sent_ns, "node": self.node, "wait": self.wait_periods, "span": self.span_periods,
                "echo": self.echo, "period_ns": self.period_ns, "ends_t_ns": self.ends_ns}


class Designations:
    """The designations the ground sent in a run: for each node, the one that ends last
    (only that one bounds a later designation of another node)."""

    def __init__(self, path: Path | None = None):
        self.path = path
        self.latest: dict[str, Designation] = {}
        if path is not None:
            self._load(path)

    def terms(self, node: str, now_ns: int, period_ns: int,
              vote_span_periods: int = VOTE_SPAN_PERIODS) -> tuple[int, int]:
        """(WAIT, SPAN) of a designation of `node` sent at `now_ns`."""
        assert period_ns > 0, period_ns
        assert 1 <= vote_span_periods <= VOTE_SPAN_PERIODS_MAX, vote_span_periods
        left_ns = max([0, *(d.ends_ns - now_ns for name, d in self.latest.items() if name != node)])
        wait = -(-left_ns // period_ns)  # rounded up
        assert 0 <= wait * period_ns - left_ns < period_ns, (wait, left_ns)
        return wait, wait + vote_span_periods

    def designate(self, node: str, echo: int, now_ns: int, period_ns: int,
                  vote_span_periods: int = VOTE_SPAN_PERIODS) -> Designation:
        """The designation of `node` to send at `now_ns`, echoing its heartbeat `echo`."""
        assert echo >= 0, echo
        wait, span = self.terms(node, now_ns, period_ns, vote_span_periods)
        return Designation(node, wait, span, echo, now_ns, period_ns)

    def record(self, designation: Designation) -> str | None:
        """Remembers a designation about to be sent; None, or why the run directory's
        record could not be written (the designation is still remembered here)."""
        kept = self.latest.get(designation.node)
        if kept is None or designation.ends_ns >= kept.ends_ns:
            self.latest[designation.node] = designation
        if self.path is None:
            return None
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            with open(self.path, "a", encoding="utf-8") as stream:
                stream.write(json.dumps(designation.as_dict()) + "\n")
        except OSError as error:
            return f"{self.path}: cannot write: {error.strerror}"
        return None

    def _load(self, path: Path) -> None:
        """The designations an earlier launcher on the same run directory recorded; a line
        that does not read is skipped (a record cut short by a crash)."""
        try:
            text = path.read_text(encoding="utf-8")
        except OSError:
            return  # none yet
        for line in text.splitlines():
            if len(line) > LINE_BYTES_MAX:
                continue
            try:
                raw = json.loads(line)
                designation = Designation(str(raw["node"]), int(raw["wait"]), int(raw["span"]), int(raw["echo"]),
                                          int(raw["t_ns"]), int(raw["period_ns"]))
            except (ValueError, KeyError, TypeError, RecursionError):
                continue
            if designation.period_ns <= 0 or designation.span_periods < 0:
                continue
            kept = self.latest.get(designation.node)
            if kept is None or designation.ends_ns >= kept.ends_ns:
                self.latest[designation.node] = designation
