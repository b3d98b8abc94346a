"""Merging the nodes' traces: t_ns order, corrected for a sender stamped after its
receiver (verify/keel_verify/trace/load.py, causal_order). No TLC."""

from __future__ import annotations

from keel_verify.trace.load import Line, causal_order


def _line(t_us: int, node: str, action: str, **args: object) -> Line:
    return Line("t.ndjson", t_us, t_us * 1000, node, "switch", action, dict(args), {})


def _names(lines: list[Line]) -> list[str]:
    return [f"{line.node}.{line.action}" for line in lines]


def test_a_receipt_stamped_before_its_send_moves_after_it() -> None:
    # keel-node stamps a line after the step sent its messages: the Storage node may log
    # the write a few microseconds before the flush that sent it.
    lines = [_line(10, "ST1", "StoreCheckpoint", **{"from": "PN3"}, t="taskB", version=7),
             _line(12, "PN3", "FlushCheckpoint", n="PN3", t="taskB", version=7, final=False)]
    assert _names(causal_order(lines)) == ["PN3.FlushCheckpoint", "ST1.StoreCheckpoint"]


def test_a_receipt_whose_send_is_before_it_stays() -> None:
    # A periodic write of version 29 is stored; 2 ms later the task stops and its final
    # flush carries the same version 29. The store was caused by the periodic write: it
    # must not move after the final flush (and drag the Storage node's next lines, its
    # receipt of the Master's command, behind lines that needed them).
    lines = [_line(100, "PN3", "FlushCheckpoint", n="PN3", t="taskB", version=29, final=False),
             _line(101, "ST1", "StoreCheckpoint", **{"from": "PN3"}, t="taskB", version=29),
             _line(102, "ST1", "ReceiveCommand", n="ST1", c="S2", epoch=2, seq=2),
             _line(2100, "PN3", "FlushCheckpoint", n="PN3", t="taskB", version=29, final=True)]
    assert _names(causal_order(lines)) == _names(lines)


def test_an_effect_of_every_ack_waits_for_the_last() -> None:
    # CompleteSwitch waits for every node's ack: one ack before it is not its only cause.
    def ack(t_us: int, node: str) -> Line:
        line = _line(t_us, node, "Ack", n=node, kind="Activated")
        line.vars = {"epoch": 1, "seq": 1}
        return line
    complete = _line(20, "PN1", "CompleteSwitch", m="PN1", c="P1", seq=1)
    complete.vars = {"epoch": 1}
    lines = [ack(10, "PN2"), complete, ack(22, "PN3")]
    assert _names(causal_order(lines)) == ["PN2.Ack", "PN3.Ack", "PN1.CompleteSwitch"]


def test_an_exclude_on_the_grounds_hold_reads_ground_and_an_older_line_reads_false() -> None:
    # The Master's exclusion for the ground's hold logs `ground: true` (TraceConfigSwitch's
    # EvidenceSuffices takes the hold as its evidence); a line without it, of a build before
    # the Master's ground exclusion, reads `ground` false and still loads.
    from keel_verify.trace.switch import _record

    held = _line(10, "PN1", "Exclude", m="PN1", f="PN3", c="B", ground=True, mem=[], ev=[])
    older = _line(11, "PN1", "Exclude", m="PN1", f="PN3", c="B", own=True, mem=[], ev=[])
    assert "ground |-> TRUE" in _record(held, "Exclude", "PN1", set())
    assert "ground |-> FALSE" in _record(older, "Exclude", "PN1", set())
    assert "own |-> TRUE" in _record(older, "Exclude", "PN1", set())
