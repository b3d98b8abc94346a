"""The run's environment as trace validation reads it (keel_verify/trace/environment.py):
where the heartbeat spec's loss bound holds and where a fault lifts it. Each rule has a
case where a Tick's `lossy` names the sender and one where it does not."""

from __future__ import annotations

from keel_verify.trace.environment import Environment
from keel_verify.trace.load import Line

MS = 1_000_000
P = 100 * MS  # the period
NODES = ["PN1", "PN2", "PN3"]


def hb(t_ms: float, node: str, action: str, **args: object) -> Line:
    return Line("t", 0, int(t_ms * MS), node, "heartbeat", action, dict(args), {})


def env(t_ms: float, action: str, **args: object) -> Line:
    return Line("t", 0, int(t_ms * MS), None, "env", action, dict(args), {})


def steady(until_ms: int, skip: set[tuple[str, int]] = frozenset(),
           unheard: set[tuple[str, str, int]] = frozenset()) -> list[Line]:
    """Every node sends at 10 ms into each period and every other node hears it at 20 ms,
    but the sends in `skip` (node, period) and the receipts in `unheard` (receiver, sender,
    period)."""
    lines = []
    for k in range(until_ms // 100):
        for n in NODES:
            if (n, k) not in skip:
                lines.append(hb(k * 100 + 10, n, "SendHeartbeat", n=n))
                for m in NODES:
                    if m != n and (m, n, k) not in unheard:
                        lines.append(hb(k * 100 + 20, m, "ReceiveHeartbeat", m=m, n=n))
    return lines


def lossy(lines: list[Line], monitor: str, tick_ms: int, suspect: bool = False) -> list[str]:
    lines = sorted(lines, key=lambda line: line.t_ns)
    environment = Environment(lines, NODES, P)
    return environment.lossy(monitor, (tick_ms - 100) * MS, tick_ms * MS, suspect)


def test_a_quiet_run_keeps_the_bound_everywhere_but_before_first_receipts():
    lines = steady(1000)
    assert lossy(lines, "PN1", 500) == []
    # Before PN1 first heard anyone (20 ms) every link to it is pending.
    assert lossy(lines, "PN1", 5) == ["PN2", "PN3"]


def test_a_sender_that_sent_nothing_in_the_period_is_exempt():
    lines = steady(1000, skip={("PN3", 4)})
    assert lossy(lines, "PN1", 500) == ["PN3"]
    # A send only in the period's last quarter may reach the monitor after its Tick.
    late = [ln for ln in steady(1000) if not (ln.node == "PN3" and 400 <= ln.t_ns / MS < 500)]
    late.append(hb(490, "PN3", "SendHeartbeat", n="PN3"))
    assert lossy(late, "PN1", 500) == ["PN3"]


def test_a_suspect_tick_exempts_every_sender():
    assert lossy(steady(1000), "PN1", 500, suspect=True) == ["PN2", "PN3"]


def test_a_block_lifts_the_bound_on_its_link_until_the_receiver_hears_again():
    unheard = {("PN1", "PN2", k) for k in range(3, 7)}
    lines = steady(1200, unheard=unheard) + [env(300, "Block", **{"from": "PN2", "to": "PN1"}),
                                             env(650, "Heal")]
    assert lossy(lines, "PN1", 500) == ["PN2"]
    assert lossy(lines, "PN2", 500) == []  # the other direction is not cut
    assert lossy(lines, "PN1", 700) == ["PN2"]  # healed at 650, heard again at 720
    # A period later still (a receipt near a Tick may fall on either side of it), then no
    # more.
    assert lossy(lines, "PN1", 900) == ["PN2"]
    assert lossy(lines, "PN1", 1000) == []
    # Without its env lines the same silence is no fault the trace names.
    assert lossy(steady(1000, unheard=unheard), "PN1", 500) == []


def test_a_sim_partition_cuts_both_ways_between_its_sides():
    lines = steady(1000) + [env(300, "Partition", a=["PN1"], b=["PN2", "PN3"])]
    assert lossy(lines, "PN1", 500) == ["PN2", "PN3"]
    assert lossy(lines, "PN2", 500) == ["PN1"]


def test_a_cluster_partition_cuts_its_node_from_every_other_until_its_heal():
    unheard = {(m, n, k) for k in range(3, 6) for m in NODES for n in NODES
               if "PN3" in (m, n) and m != n}
    lines = steady(1000, unheard=unheard) + [env(300, "Partition", n="PN3"),
                                             env(550, "Heal", n="PN3")]
    assert lossy(lines, "PN1", 500) == ["PN3"]
    assert lossy(lines, "PN3", 500) == ["PN1", "PN2"]
    assert lossy(lines, "PN1", 900) == []


def test_deafness_cuts_every_link_to_its_node():
    lines = steady(1000) + [env(300, "Deaf", n="PN2")]
    assert lossy(lines, "PN2", 500) == ["PN1", "PN3"]
    assert lossy(lines, "PN1", 500) == []


def test_a_crash_lifts_the_bound_until_the_restarted_node_is_heard():
    skip = {("PN2", k) for k in range(3, 8)}
    lines = steady(1200, skip=skip) + [env(250, "Crash", n="PN2"), env(750, "Restart", n="PN2")]
    assert lossy(lines, "PN1", 500) == ["PN2"]
    assert lossy(lines, "PN1", 1100) == []
    # The restarted node hears every other afresh: pending until its first receipt (820).
    assert lossy(lines, "PN2", 800) == ["PN1", "PN3"]
    assert lossy(lines, "PN2", 1100) == []


def test_a_sim_pause_lasts_its_ms_and_a_cluster_pause_until_its_resume():
    sim = steady(1200) + [env(300, "Pause", n="PN3", ms=200)]
    assert lossy(sim, "PN1", 500) == ["PN3"]
    assert lossy(sim, "PN1", 800) == []
    cluster = steady(1200) + [env(300, "Pause", n="PN3"), env(700, "Resume", n="PN3")]
    assert lossy(cluster, "PN1", 700) == ["PN3"]
    assert lossy(cluster, "PN1", 1000) == []


def test_a_loss_burst_lifts_the_bound_from_its_start_until_the_next_receipt():
    unheard = {("PN1", "PN3", k) for k in (3, 4, 5)}
    lines = steady(1000, unheard=unheard) + [env(520, "LossBurst", n="PN3", m="PN1",
                                                 since_ns=310 * MS)]
    assert lossy(lines, "PN1", 400) == ["PN3"]
    assert lossy(lines, "PN1", 600) == ["PN3"]
    assert lossy(lines, "PN2", 400) == []
    assert lossy(lines, "PN1", 900) == []
