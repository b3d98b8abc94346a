"""An explicit-state checker for spec/trace/TraceHeartbeat.tla, in Python.

It is a port of the trace spec (and of the Heartbeat.tla actions it calls) that reaches
what TLC's breadth-first search reaches: every state reachable from ``TraceInit`` by
``TraceNext``, each distinct state once, in layers of equal ``l`` (no step lowers it).
The trace is accepted when a state with ``l = Len(Log) + 1`` is reachable; otherwise
the first line no behaviour explains is the largest ``l`` reached. It counts the
distinct states as TLC does (``l`` and ``hidden`` are variables like the others), so the
two checkers can be compared state count for state count.
TLC stays the reference: engine.py asks it to diagnose a line the port gets stuck at,
and reports a disagreement between the two as undecided (never a pass).

The state is a tuple of integers, the sets of nodes as bitmasks (Order[i] is bit i, M
the bit after them) and ``missed[M]``, ``lossRun[M]`` as fixed-width fields of one
integer each:

    (free, sent, inFlight, lossRun[M], heard[M], missed[M], failed[M], heardOnce[M], env)

``inFlight`` holds the senders n of the messages <<n, M>> (M is the one monitor, and M's
own SendHeartbeat sends to Monitors \\ {M} = {}). ``env`` numbers the environment's
variables ``<<alive, unbooted, clock, downFor>>``, which only TickBy changes. ``l`` is
the index of the layer the search is in and ``hidden`` the level inside it: a line step
goes to the next layer at level 0, a hidden step to the next level, so each (layer,
level) is a set of its own and a state's successors are computed once per level.

What the port does not model (a record field of another type than the trace builder
writes, a ReceiveHeartbeat from a node not in Order, on which TLC stops with an error,
constants that break an ASSUME) gives the outcome "unsupported": TLC decides.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from itertools import combinations

ACCEPTED = "accepted"
STUCK = "stuck"
UNSUPPORTED = "unsupported"

# The arms of LineStep's CASE.
TICK, SUSPECT_TICK, SEND, RECEIVE, DECLARE, VIEW_CHANGE, RESTART, READMIT, REJOIN, WITHDRAW, \
    OTHER = range(11)
_KINDS = {"SendHeartbeat": SEND, "ReceiveHeartbeat": RECEIVE, "DeclareFailed": DECLARE,
          "ViewChange": VIEW_CHANGE, "Restart": RESTART, "Readmit": READMIT, "Rejoin": REJOIN,
          "Withdraw": WITHDRAW}
# NextStates: the lines that state the node's variables.
_STATES = {"Tick", "SendHeartbeat", "ReceiveHeartbeat", "DeclareFailed", "Readmit", "Rejoin",
           "Withdraw"}


@dataclass(frozen=True)
class Constants:
    """The constants of a TraceHeartbeat model, as heartbeat.jobs gives them to TLC."""

    nodes: tuple[str, ...]
    monitors: tuple[str, ...]
    m: str
    order: tuple[str, ...]  # Nodes \ {M} as a sequence
    miss_limit: int
    max_loss: int
    max_crashes: int
    startup_grace: int
    max_late_boots: int
    max_boot_delay: int
    max_hidden: int


@dataclass
class ExplicitRun:
    """The port's answer for one job."""

    outcome: str  # ACCEPTED, STUCK or UNSUPPORTED
    seconds: float
    distinct_states: int = 0
    max_l: int | None = None  # STUCK: the first line no behaviour of the spec explains
    message: str = ""


class Unsupported(Exception):
    """A model or a line the port does not cover: TLC must decide."""


# --------------------------------------------------------------------------------------
# The model's layout


class _Layout:
    """Bits and fields of the state, and the environment's values by number."""

    def __init__(self, c: Constants) -> None:
        _check_constants(c)
        self.c = c
        self.bit = {n: 1 << i for i, n in enumerate(c.order)}
        self.bit[c.m] = 1 << len(c.order)
        self.m_bit = self.bit[c.m]
        self.all = (1 << len(c.nodes)) - 1
        self.order_mask = self.all & ~self.m_bit
        self.watched = self.order_mask  # Watched(M) == Nodes \ {M}
        # missed[M][n] is at most StartupGrace (MissedAfterTick's Min; GraceAssumption);
        # lossRun[M][n] at most MaxLoss (LoseHeartbeat's guard).
        self.missed_width = max(1, c.startup_grace.bit_length())
        self.missed_max = (1 << self.missed_width) - 1
        self.loss_width = max(1, c.max_loss.bit_length())
        self.loss_max = (1 << self.loss_width) - 1
        index = {bit: i for i, bit in enumerate(sorted(self.bit.values()))}
        self.missed_shift = {bit: i * self.missed_width for bit, i in index.items()}
        self.loss_shift = {bit: i * self.loss_width for bit, i in index.items()}
        self.missed_clear = {bit: ~(self.missed_max << s) for bit, s in self.missed_shift.items()}
        self.loss_clear = {bit: ~(self.loss_max << s) for bit, s in self.loss_shift.items()}
        self.envs: list[tuple[int, int, int, tuple[int, ...]]] = []
        self.env_ids: dict[tuple[int, int, int, tuple[int, ...]], int] = {}

    def env(self, alive: int, unbooted: int, clock: int, down_for: tuple[int, ...]) -> int:
        key = (alive, unbooted, clock, down_for)
        found = self.env_ids.get(key)
        if found is None:
            found = self.env_ids[key] = len(self.envs)
            self.envs.append(key)
        return found

    def missed_of(self, packed: int, bit: int) -> int:
        return (packed >> self.missed_shift[bit]) & self.missed_max


def _check_constants(c: Constants) -> None:
    """Heartbeat.tla's ASSUMEs (TLC stops on a false one), and what the port covers."""
    naturals = (c.miss_limit, c.max_loss, c.max_crashes, c.startup_grace, c.max_late_boots,
                c.max_boot_delay, c.max_hidden)
    if any(isinstance(v, bool) or not isinstance(v, int) or v < 0 for v in naturals):
        raise Unsupported("a constant is not a natural number")
    if len(set(c.nodes)) != len(c.nodes) or c.m not in c.nodes:
        raise Unsupported("M is not one of the distinct Nodes")
    if tuple(c.monitors) != (c.m,):
        raise Unsupported("the port covers Monitors = {M} only")
    if sorted(c.order) != sorted(n for n in c.nodes if n != c.m):
        raise Unsupported("Order is not Nodes \\ {M} as a sequence")
    if c.miss_limit < 1 or c.startup_grace < c.miss_limit or c.max_crashes > len(c.nodes):
        raise Unsupported("an ASSUME of Heartbeat.tla does not hold")


# --------------------------------------------------------------------------------------
# Log: each record read once into what the steps compare


@dataclass(slots=True)
class _Line:
    kind: int
    n_bit: int  # e.n as a node's bit (0: not a node)
    missed_reason: bool  # e.reason = "missed"
    late: bool
    heard: int  # e.heard as a mask, -1 when it holds a name that is no node
    failed: int  # e.failed likewise
    failed_known: int  # the nodes in e.failed
    missed_domain: int  # the fields of DOMAIN e.missed
    missed: int  # e.missed packed, -1 when no state can have these values
    has_once: bool
    once: int  # e.heardOnce as a mask, -1 when it holds a name that is no node
    once_known: int  # the nodes in e.heardOnce (0 unless e.hasHeardOnce)
    next_states: bool  # NextStates at this line
    send: int  # the senders HiddenSend allows before this line
    lose: bool  # NextIs("Tick"): HiddenLose
    lossy: int  # e.lossy as a mask of nodes (a Tick's; 0 otherwise)
    uncounted: bool  # NextIs("SendHeartbeat"): UncountedTick (when free)
    relaxed: bool  # l = Relax: Matches holds whatever the variables


def _name(value: object, what: str) -> str:
    if type(value) is str:
        return value
    if value is None:
        return "none"  # tla.literal's None
    raise Unsupported(f"{what} is not a string")


def _names(value: object, bits: dict[str, int], what: str) -> tuple[int, int]:
    """A set of names as (the mask of its nodes, the mask or -1 when some is no node)."""
    if type(value) is not list:
        raise Unsupported(f"{what} is not a list")
    known, exact = 0, True
    for item in value:
        bit = bits.get(item if type(item) is str else _name(item, what))
        if bit is None:
            exact = False
        else:
            known |= bit
    return known, known if exact else -1


def _missed(value: object, layout: _Layout) -> tuple[int, int]:
    """DOMAIN e.missed as a mask of fields, and e.missed packed (-1: no state has it)."""
    if type(value) is not dict:
        raise Unsupported("missed is not an object")
    bits, shifts, width_max = layout.bit, layout.missed_shift, layout.missed_max
    domain, packed = 0, 0
    for key, count in value.items():
        if type(count) is not int:
            if not (type(count) is float and count.is_integer()):
                raise Unsupported("a missed count is not an integer")
            count = int(count)
        bit = bits.get(key)
        if bit is None:
            raise Unsupported("missed names a node the mission does not have")
        shift = shifts[bit]
        domain |= width_max << shift
        if packed >= 0 and 0 <= count <= width_max:
            packed |= count << shift
        else:
            packed = -1
    return domain, packed


def _compile(records: Iterable[dict[str, object]], layout: _Layout,
             relax: int) -> Iterator[_Line]:
    """The records one by one (a record read when the search needs it is not kept)."""
    bits = layout.bit
    before = {n: (1 << (i + 1)) - 1 for i, n in enumerate(layout.c.order)}  # n, Before(n)
    for index, e in enumerate(records, start=1):
        try:
            yield _read(e, index == relax, layout, bits, before)
        except (Unsupported, KeyError) as why:
            raise Unsupported(f"line {index}: {why}") from None


def _read(e: dict[str, object], relaxed: bool, layout: _Layout, bits: dict[str, int],
          before: dict[str, int]) -> _Line:
    action = e["action"]
    if type(action) is not str:
        raise Unsupported("the action is not a string")
    if action not in _STATES:  # a marker: the steps read only its action
        return _Line(_KINDS.get(action, OTHER), 0, False, False, 0, 0, 0, 0, 0, False, 0, 0,
                     False, 0, False, 0, False, relaxed)
    suspect, late, has_once = e["suspect"], e["late"], e["hasHeardOnce"]
    if type(suspect) is not bool or type(late) is not bool or type(has_once) is not bool:
        raise Unsupported("suspect, late or hasHeardOnce is not a boolean")
    kind = (SUSPECT_TICK if suspect else TICK) if action == "Tick" else _KINDS[action]
    n = _name(e["n"], "n")
    missed_reason = _name(e["reason"], "reason") == "missed"
    heard = _names(e["heard"], bits, "heard")[1]
    failed_known, failed = _names(e["failed"], bits, "failed")
    missed_domain, missed = _missed(e["missed"], layout)
    once_known, once = _names(e["heardOnce"], bits, "heardOnce")
    send = 0
    if kind == RECEIVE:
        # HiddenSend evaluates Before(Log[l].n): its CHOOSE fails (TLC stops) unless n is
        # in Order.
        if n not in before:
            raise Unsupported(f"a heartbeat from {n}, which is not in Order")
        send = before[n]
    elif action == "Tick":
        send = layout.order_mask
    lossy = _names(e["lossy"], bits, "lossy")[0] if action == "Tick" else 0
    return _Line(kind, bits.get(n, 0), missed_reason, late, heard, failed, failed_known,
                 missed_domain, missed, has_once, once, once_known if has_once else 0, True,
                 send, action == "Tick", lossy, action == "SendHeartbeat", relaxed)


# --------------------------------------------------------------------------------------
# The search


class _Search:
    def __init__(self, constants: Constants, records: Iterable[dict[str, object]],
                 relax: int) -> None:
        self.layout = _Layout(constants)
        self.lines = _compile(records, self.layout, relax)

    def init(self) -> set[tuple]:
        """TraceInit: Init (one state per choice of late nodes), l = 1, hidden = 0, free."""
        layout, c = self.layout, self.layout.c
        late_candidates = [layout.bit[n] for n in c.order]  # Nodes \ Monitors
        zeros = (0,) * len(c.nodes)
        states = set()
        for size in range(min(c.max_late_boots, len(late_candidates)) + 1):
            for chosen in combinations(late_candidates, size):
                unbooted = sum(chosen)
                env = layout.env(layout.all & ~unbooted, unbooted, 0, zeros)
                states.add((True, 0, 0, 0, 0, 0, 0, 0, env))
        return states

    def run(self) -> tuple[bool, int, int]:
        """(accepted, the largest l reached, distinct states). Every record is read, also
        after the search got stuck: one the port does not cover raises Unsupported."""
        max_hidden = self.layout.c.max_hidden
        layer = self.init()
        distinct = 0
        index = 0  # the line being explained: the trace spec's l
        for index, line in enumerate(self.lines, start=1):
            reached, count = self.hidden_closure(layer, line, max_hidden)
            distinct += count
            layer = self.line_step(reached, line)
            if not layer:
                for _ in self.lines:
                    pass
                return False, index, distinct
        return True, index + 1, distinct + len(layer)

    def hidden_closure(self, layer: set[tuple], line: _Line,
                       max_hidden: int) -> tuple[set[tuple], int]:
        """The states of layer l at every level (hidden = 0..MaxHidden), and how many
        distinct (state, hidden) pairs they are."""
        reached = set(layer)
        count = len(layer)
        current = layer
        for level in range(1, max_hidden + 1):
            following = self.hidden_steps(current, line)
            if not following:
                break
            count += len(following)
            if following == current:  # every further level is the same set
                count += len(current) * (max_hidden - level)
                break
            reached |= following
            current = following
        return reached, count

    # ---------------------------------------------------------------------------------
    # HiddenStep (its guards hidden < MaxHidden and l <= Len(Log) are the caller's)

    def hidden_steps(self, states: set[tuple], e: _Line) -> set[tuple]:
        layout = self.layout
        out: set[tuple] = set()
        add = out.add
        envs, m_bit, watched, order_mask = layout.envs, layout.m_bit, layout.watched, \
            layout.order_mask
        missed_clear, loss_shift, loss_max = layout.missed_clear, layout.loss_shift, \
            layout.loss_max
        max_loss = layout.c.max_loss
        send, lose, uncounted, next_states = e.send, e.lose, e.uncounted, e.next_states
        lossy = e.lossy
        failed_known, once_known = e.failed_known, e.once_known
        for s in states:
            free, sent, in_flight, loss, heard, missed, failed, once, env = s
            if send:
                # HiddenSend(n): n # M, Before(n) all sent, NextIs allows n, SendHeartbeat(n):
                # only the first node of Order that has not sent may.
                unsent = order_mask & ~sent
                n = unsent & -unsent
                if n & send and envs[env][0] & n:
                    add((free, sent | n, in_flight | n, loss, heard, missed, failed, once, env))
            if lose and in_flight:
                # HiddenLose(n): the first node of Order with a heartbeat in flight;
                # beyond the bound when n is in e.lossy or failed[M] (its run restarts),
                # else LoseHeartbeat(n, M) within the loss budget when M is alive.
                n = in_flight & -in_flight
                if n & (lossy | failed):
                    add((free, sent, in_flight ^ n, loss & layout.loss_clear[n], heard,
                         missed, failed, once, env))
                elif envs[env][0] & m_bit:
                    if (loss >> loss_shift[n]) & loss_max < max_loss:
                        add((free, sent, in_flight ^ n, loss + (1 << loss_shift[n]), heard,
                             missed, failed, once, env))
                else:
                    add((free, sent, in_flight ^ n, loss, heard, missed, failed, once, env))
            if free:
                if uncounted:  # UncountedTick
                    add((free, 0, 0, loss, 0, missed, failed, once | heard, env))
                if next_states:  # Adopt(n)
                    adopt = watched & ~failed & failed_known
                    while adopt:
                        n = adopt & -adopt
                        adopt ^= n
                        add((free, sent, in_flight, loss, heard, missed, failed | n, once, env))
                if missed:  # Rewatch: some missed[M][n] # 0
                    add((free, sent, in_flight, loss, 0, 0, failed, once, env))
            if next_states:
                forget = failed & ~failed_known  # Forget(n)
                while forget:
                    n = forget & -forget
                    forget ^= n
                    add((free, sent, in_flight, loss, heard | n, missed & missed_clear[n],
                         failed ^ n, once | n, env))
                hear = once_known & ~(once | heard)  # HearUnlogged(n), HearOther(n)
                while hear:
                    n = hear & -hear
                    hear ^= n
                    add((free, sent, in_flight, loss, heard, missed, failed, once | n, env))
                    if not failed & n:
                        add((free, sent, in_flight, loss, heard, missed & missed_clear[n],
                             failed, once | n, env))
        return out

    # ---------------------------------------------------------------------------------
    # LineStep: one arm of the CASE per kind of line; each is deterministic

    def line_step(self, states: set[tuple], e: _Line) -> set[tuple]:
        kind = e.kind
        if kind == RECEIVE:
            return self.receive(states, e)
        if kind in (TICK, SUSPECT_TICK):
            return self.tick(states, e)
        if kind == SEND:
            return self.send(states, e)
        if kind == DECLARE:
            return self.declare(states, e)
        if kind == VIEW_CHANGE:
            return {(True, *s[1:]) for s in states}
        if kind == RESTART:
            not_m = ~self.layout.m_bit
            return {(True, s[1] & not_m, s[2], s[3], 0, 0, 0, 0, s[8]) for s in states}
        if kind == READMIT:
            return self.readmit(states, e)
        if kind == REJOIN:
            return self.rejoin(states, e)
        if kind == WITHDRAW:
            return self.withdraw(states, e)
        return set()  # OTHER -> FALSE

    @staticmethod
    def _matches(e: _Line, heard: int, missed: int, failed: int, once: int) -> bool:
        """Matches(e) after a step other than a Tick (heard' is the state's heard)."""
        return e.relaxed or (
            (e.kind == DECLARE and e.missed_reason or heard == e.heard)
            and failed == e.failed
            and missed & e.missed_domain == e.missed
            and (not e.has_once or once | heard == e.once))

    def receive(self, states: set[tuple], e: _Line) -> set[tuple]:
        """ReceiveLine: a heartbeat of a node heard in the period changes nothing."""
        n = e.n_bit
        m_bit, envs = self.layout.m_bit, self.layout.envs
        loss_clear = self.layout.loss_clear[n]
        relaxed, want_heard, want_failed = e.relaxed, e.heard, e.failed
        domain, want_missed = e.missed_domain, e.missed
        want_once = e.once if e.has_once else None
        out = set()
        for s in states:
            free, sent, in_flight, loss, heard, missed, failed, once, env = s
            if heard & n:
                after = s
            elif in_flight & n and envs[env][0] & m_bit:  # ReceiveHeartbeat(M, n)
                heard |= n
                after = (free, sent, in_flight ^ n, loss & loss_clear, heard, missed, failed,
                         once, env)
            else:
                continue
            if relaxed or (heard == want_heard and failed == want_failed
                           and missed & domain == want_missed
                           and (want_once is None or once | heard == want_once)):
                out.add(after)
        return out

    def send(self, states: set[tuple], e: _Line) -> set[tuple]:
        """SendHeartbeat(M): M's messages go to Monitors \\ {M}, none."""
        m_bit, envs = self.layout.m_bit, self.layout.envs
        out = set()
        for s in states:
            free, sent, in_flight, loss, heard, missed, failed, once, env = s
            if sent & m_bit or not envs[env][0] & m_bit:
                continue
            if self._matches(e, heard, missed, failed, once):
                out.add((free, sent | m_bit, in_flight, loss, heard, missed, failed, once, env))
        return out

    def declare(self, states: set[tuple], e: _Line) -> set[tuple]:
        """DeclareLine: DeclareFailed(M, n) for a missed node, else n only joins failed (a
        node already declared that restarted or says it is excluded: failed stays)."""
        layout = self.layout
        n = e.n_bit & layout.watched  # n \in Watched(M)
        if not n:
            return set()
        c, m_bit, envs = layout.c, layout.m_bit, layout.envs
        out = set()
        for s in states:
            free, sent, in_flight, loss, heard, missed, failed, once, env = s
            if failed & n and e.missed_reason:
                continue
            if e.missed_reason:
                if not envs[env][0] & m_bit:
                    continue
                declare_at = c.miss_limit if once & n else c.startup_grace  # DeclareAt(M, n)
                if layout.missed_of(missed, n) < declare_at:
                    continue
            if self._matches(e, heard, missed, failed | n, once):
                out.add((free, sent, in_flight, loss, heard, missed, failed | n, once, env))
        return out

    def readmit(self, states: set[tuple], e: _Line) -> set[tuple]:
        """ReadmitLine: M forgets what it counted and declared of n."""
        return self._forget(states, e, withdrawn=False)

    def withdraw(self, states: set[tuple], e: _Line) -> set[tuple]:
        """WithdrawLine: Forget(n), logged: M withdraws its declaration of n, which proved
        alive (it counts as heard in the period under way)."""
        return self._forget(states, e, withdrawn=True)

    def _forget(self, states: set[tuple], e: _Line, withdrawn: bool) -> set[tuple]:
        """n leaves failed[M] and its count restarts. Readmitted (`withdrawn` False): n was
        declared or heard in the period, and a view change follows (free); withdrawn: n was
        declared, and counts as heard."""
        n = e.n_bit
        if not n:
            return set()
        clear = self.layout.missed_clear[n]
        out = set()
        for s in states:
            free, sent, in_flight, loss, heard, missed, failed, once, env = s
            if not (failed & n or (not withdrawn and heard & n)):
                continue
            failed &= ~n
            missed &= clear
            if withdrawn:
                heard |= n
                once |= n
            if self._matches(e, heard, missed, failed, once):
                out.add((free if withdrawn else True, sent, in_flight, loss, heard, missed, failed, once, env))
        return out

    def rejoin(self, states: set[tuple], e: _Line) -> set[tuple]:
        """RejoinLine, and the missed counts it logs (no Matches: heardOnce differs)."""
        kept = e.failed
        if kept < 0 or e.missed != 0:  # missed' is all 0: so must e.missed be
            return set()
        out = set()
        for s in states:
            _, sent, in_flight, loss, heard, missed, failed, once, env = s
            if kept & ~failed:  # e.failed \subseteq failed[M]
                continue
            out.add((True, sent, in_flight, loss, heard, 0, kept, 0, env))
        return out

    def tick(self, states: set[tuple], e: _Line) -> set[tuple]:
        """CountingTick(e) == ~e.late /\\ TickBy(Always), or
        SuspectTick(e) == (e.late \\/ heard[M] = {}) /\\ TickBy(Never); then Matches(e),
        which compares the heard of the period that ends."""
        layout = self.layout
        c, envs, m_bit, everyone = layout.c, layout.envs, layout.m_bit, layout.all
        miss_limit, grace = c.miss_limit, c.startup_grace
        watch = [(n, layout.missed_shift[n]) for n in sorted(layout.bit.values())
                 if n & layout.watched]
        missed_max = layout.missed_max
        counts = e.kind == TICK
        suspect_cause = e.late
        relaxed, want_heard, want_failed = e.relaxed, e.heard, e.failed
        domain, want_missed = e.missed_domain, e.missed
        want_once = e.once if e.has_once else None
        out = set()
        for s in states:
            _, sent, in_flight, loss, heard, missed, failed, once, env = s
            if not counts and not (suspect_cause or heard == 0):
                continue
            if counts and suspect_cause:  # rule 1: it logged a cause, it must suspect itself
                continue
            if not relaxed and (heard != want_heard or failed != want_failed):
                continue
            alive, unbooted, clock, down_for = envs[env]
            if alive & ~sent & everyone or in_flight:
                continue
            if unbooted and clock >= c.max_boot_delay:
                continue
            after = missed
            if alive & m_bit:
                pending = False
                for n, shift in watch:
                    if failed & n:
                        continue
                    count = (missed >> shift) & missed_max
                    if count >= (miss_limit if once & n else grace):  # Pending(M, n)
                        pending = True
                        break
                    if heard & n:
                        after -= count << shift
                    elif counts:
                        # MissedAfterTick: Min(count + 1, DeclareAt(M, n)), and not Pending
                        # means count < DeclareAt(M, n).
                        after += 1 << shift
                if pending:
                    continue
                once_after = once | heard
            else:
                once_after = once
            if not relaxed and (after & domain != want_missed
                                or want_once is not None and once_after != want_once):
                continue
            env_after = self._env_after_tick(env, heard | once)
            out.add((False, 0, 0, loss, 0, after, failed, once_after, env_after))
        return out

    def _env_after_tick(self, env: int, heard_once: int) -> int:
        """TickBy's downFor' and clock' (alive, unbooted unchanged)."""
        layout = self.layout
        alive, unbooted, clock, down_for = layout.envs[env]
        c = layout.c
        clock_after = min(clock + 1, c.max_boot_delay)
        if alive | unbooted == layout.all and not any(down_for):
            return env if clock_after == clock else layout.env(alive, unbooted, clock_after,
                                                               down_for)
        order = sorted(layout.bit.values())
        after = []
        for n, down in zip(order, down_for, strict=True):
            if alive & n or unbooted & n:
                after.append(0)
            else:  # DownForCap(n), with Monitors = {M}
                cap = (2 * c.miss_limit + 2 if heard_once & n else 2 * c.startup_grace + 2)
                after.append(min(down + 1, cap))
        return layout.env(alive, unbooted, clock_after, tuple(after))


def check(constants: Constants, records: Iterable[dict[str, object]],
          relax: int = 0) -> ExplicitRun:
    """Search TraceHeartbeat's states for the Log `records` (heartbeat._fields values)."""
    started = time.monotonic()
    try:
        accepted, reached, distinct = _Search(constants, records, relax).run()
    except Unsupported as why:
        return ExplicitRun(UNSUPPORTED, time.monotonic() - started, message=str(why))
    seconds = time.monotonic() - started
    if accepted:
        return ExplicitRun(ACCEPTED, seconds, distinct)
    return ExplicitRun(STUCK, seconds, distinct, max_l=reached)
