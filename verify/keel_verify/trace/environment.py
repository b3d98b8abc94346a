"""The environment of a run, read from its trace: where the heartbeat spec's loss bound
holds and where the run's faults lift it (spec/trace/TraceHeartbeat.tla, `lossy`).

Heartbeat.tla assumes a channel that loses at most MaxLoss heartbeats in a row on a link
(MaxLoss < MissLimit), between nodes that run and send every period; under that bound no
live node is ever declared. A run's faults break the assumption on purpose: a partition,
a deaf or paused node, a crash, a burst of losses the simulator drew, a node whose loop
stalled and sent nothing. The trace says where: keel-sim and keel-cluster write the faults
they inject as `env` lines, and every node logs its own sends. This module turns those
into, for each Tick line of a monitor M, the senders n whose missing heartbeat in the
period that ends may be a loss beyond the bound (the link n -> M was faulty, or n did not
send); everywhere else a streak of more than MaxLoss periods in which n sent and M heard
nothing is no behaviour of the spec, and the trace is rejected at that Tick.

A link is faulty (an interval of time, sender n to receiver m):

- from a fault that cuts it until it heals, then until m hears n again (a heal, a resume, a
  restart each need a heartbeat to get through, and a restarted process must first be
  discovered): `Partition` (keel-sim: sides `a` and `b`; keel-cluster: node `n` cut from
  every other), `Block` (`from` -> `to`), `Deaf` (every link to `n`), `DeafTo` (from the
  nodes `from` to `n`), until `Heal` (keel-cluster's names its node: that node's links); `Crash` or `PowerLoss` of either end until its
  `Restart` or `Boot`; `Pause` of either end for its `ms` (keel-sim) or until its `Resume`
  (keel-cluster); `Lie` of n for its `ms` (its heartbeats may be refused);
- `LossBurst` (keel-sim: heartbeats lost in a row on the link reached MissLimit, since
  `since_ns`): from `since_ns` until m hears n again;
- from the start of the run, and from m's own restart, until m first hears n (a node that
  boots later, or that DDS discovers late, is silent to m until then).

A Tick's `lossy` set also holds every node when M's own period ran late or M heard no one
(a suspect Tick: M's loop, not the channel, missed the period), and each node n that
logged no SendHeartbeat in the first three quarters of the period (its loop stalled or it
was down: a heartbeat sent in the last quarter may arrive after M's Tick, as a line's time
stamp may lag its send). Losses of a node M holds failed are exempt in the spec itself.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right
from collections.abc import Iterable

from .load import Line

# Env lines that stop a node, and those that start it again.
DOWN = ("Crash", "PowerLoss")
UP = ("Restart", "Boot")
FOREVER = 1 << 62


def _names(value: object) -> list[str]:
    if isinstance(value, str):
        return [value]
    if isinstance(value, list):
        return [v for v in value if isinstance(v, str)]
    return []


class Environment:
    """The faulty intervals of every link of a run, and each node's sends."""

    def __init__(self, lines: list[Line], nodes: Iterable[str], period_ns: int) -> None:
        self.nodes = list(nodes)
        self.period_ns = period_ns
        known = set(self.nodes)
        # Receipts: (receiver, sender) -> sorted times of the receiver's ReceiveHeartbeat.
        self._heard: dict[tuple[str, str], list[int]] = {}
        self._sends: dict[str, list[int]] = {n: [] for n in self.nodes}
        for line in lines:
            if line.fsm != "heartbeat" or line.node not in known:
                continue
            if line.action == "ReceiveHeartbeat":
                sender = line.args.get("n")
                if isinstance(sender, str):
                    self._heard.setdefault((line.node, sender), []).append(line.t_ns)
            elif line.action == "SendHeartbeat":
                self._sends[line.node].append(line.t_ns)
        # (sender, receiver) -> [start, end] intervals, each ending when the receiver
        # hears the sender again after the fault.
        self.faulty: dict[tuple[str, str], list[tuple[int, int]]] = {}
        links = [(a, b) for a in self.nodes for b in self.nodes if a != b]
        for link in links:  # the run's start: until the receiver first hears the sender
            self._until_heard(link, 0, 0)
        cut: set[tuple[str, str]] = set()  # links a partition, a block or deafness cuts
        stopped: set[str] = set()  # nodes down (crashed) or paused (until Resume)
        opened: dict[tuple[str, str], int] = {}

        def faulty_now(link: tuple[str, str]) -> bool:
            return link in cut or link[0] in stopped or link[1] in stopped

        for line in lines:
            if line.fsm != "env":
                continue
            a, t, action = line.args, line.t_ns, line.action
            before = {link for link in links if faulty_now(link)}
            if action == "Partition":
                if "a" in a or "b" in a:
                    side_a, side_b = set(_names(a.get("a"))), set(_names(a.get("b")))
                else:  # keel-cluster: node `n` cut from every other
                    side_a = set(_names(a.get("n")))
                    side_b = known - side_a
                for x in side_a & known:
                    cut |= {link for y in side_b & known if x != y for link in ((x, y), (y, x))}
            elif action == "Block":
                src, dst = a.get("from"), a.get("to")
                if src in known and dst in known and src != dst:
                    cut.add((src, dst))
            elif action == "Deaf":
                for n in _names(a.get("n")):
                    cut |= {(x, n) for x in known if x != n}
            elif action == "DeafTo":
                for n in _names(a.get("n")):
                    cut |= {(x, n) for x in _names(a.get("from")) if x in known and x != n}
            elif action == "Heal":
                healed = set(_names(a.get("n"))) & known  # keel-cluster: `n`'s links
                cut = {link for link in cut if healed and not healed & set(link)}
            elif action in DOWN:
                stopped |= set(_names(a.get("n"))) & known
            elif action in UP:
                for n in set(_names(a.get("n"))) & known:
                    stopped.discard(n)
                    for x in known - {n}:  # the restarted node hears every other afresh
                        self._until_heard((x, n), t, t)
            elif action == "Resume":
                stopped -= set(_names(a.get("n")))
            elif action in ("Pause", "Lie"):
                ms = a.get("ms")
                for n in set(_names(a.get("n"))) & known:
                    if isinstance(ms, int) and not isinstance(ms, bool):  # keel-sim
                        ends = t + ms * 1_000_000
                        for link in links:
                            if link[0] == n or (action == "Pause" and link[1] == n):
                                self._until_heard(link, t, ends)
                    elif action == "Pause":  # keel-cluster: until its Resume
                        stopped.add(n)
            elif action == "LossBurst":
                src, dst = a.get("n"), a.get("m")
                since = a.get("since_ns", t)
                if src in known and dst in known and isinstance(since, int):
                    self._until_heard((src, dst), min(since, t), t)
            for link in links:
                now = faulty_now(link)
                if now and link not in before:
                    opened[link] = t
                elif not now and link in before:
                    self._until_heard(link, opened.pop(link, t), t)
        for link, start in opened.items():
            self.faulty.setdefault(link, []).append((start, FOREVER))

    def _until_heard(self, link: tuple[str, str], start: int, ended: int) -> None:
        """Link (sender, receiver) faulty from `start` until the receiver's first receipt
        of the sender after `ended`."""
        sender, receiver = link
        heard = self._heard.get((receiver, sender), [])
        i = bisect_right(heard, ended)
        end = heard[i] if i < len(heard) else FOREVER
        self.faulty.setdefault(link, []).append((start, end))

    def lossy(self, monitor: str, previous_tick: int | None, tick: int,
              suspect: bool) -> list[str]:
        """The senders whose loss before the monitor's Tick at `tick` (the period from
        `previous_tick`) is beyond the bound's reach."""
        others = [n for n in self.nodes if n != monitor]
        if suspect:
            return others
        period = self.period_ns
        begin = previous_tick if previous_tick is not None else tick - period
        out = []
        for n in others:
            sends = self._sends.get(n, [])
            i = bisect_left(sends, begin)
            sent = i < len(sends) and sends[i] <= tick - period // 4
            if not sent or any(start <= tick and end >= begin - period
                               for start, end in self.faulty.get((n, monitor), ())):
                out.append(n)
        return out
