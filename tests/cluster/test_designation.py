"""`designate NODE` on the ground's side (keel_cluster/designation.py, Cluster.designate):
WAIT and SPAN by the ground's rule on a fake clock, the command keel-cluster signs and sends
(to stand-in nodes that print the status lines keel-node would), and every refusal before
anything is sent. No DDS, no keel-node: tests/node/test_cluster.py flies it on a real
cluster."""

from __future__ import annotations

import json
import stat
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from cryptography import x509
from cryptography.hazmat.primitives import hashes
from cryptography.hazmat.primitives.asymmetric import ec
from keel_cluster import launcher
from keel_cluster.designation import (
    DESIGNATIONS_FILE,
    VOTE_SPAN_PERIODS,
    Designation,
    Designations,
)
from keel_cluster.launcher import Cluster, LaunchError
from keel_cluster.scenario import ScenarioError, parse_event

ROOT = Path(__file__).resolve().parents[2]
TIE_GRACE = ROOT / "tests" / "sim" / "testdata" / "missions" / "prototype3_tie_grace.yaml"
PROTOTYPE3 = ROOT / "config" / "prototype3.yaml"
NODES = ["PN1", "PN2", "PN3", "ST1"]
PERIOD_NS = 100_000_000  # the mission's heartbeat.period_ms: 100
T0 = 1_000_000 * PERIOD_NS  # a ground time, on the fake clock

# A stand-in for keel-node: it keeps every control line it is sent in STANDIN_DIR/NAME.lines
# and answers `status` with a status line whose heartbeat_seq grows by 7 each time; a node
# named in STANDIN_SILENT answers nothing, one in STANDIN_OLD prints no heartbeat_seq.
STANDIN = """\
import json, os, sys
args = sys.argv[1:]
if "--list-components" in args:
    sys.exit(1)
name = args[args.index("--node") + 1]
silent = name in os.environ.get("STANDIN_SILENT", "").split(",")
old = name in os.environ.get("STANDIN_OLD", "").split(",")
seq = 40
with open(os.path.join(os.environ["STANDIN_DIR"], name + ".lines"), "a") as kept:
    for line in sys.stdin:
        kept.write(line)
        kept.flush()
        words = line.split()
        if words[:1] == ["quit"]:
            break
        if words[:1] == ["status"] and not silent:
            seq += 7
            status = {"node": name, "role": "Observer", "epoch": 1, "tasks": [], "stood_down": True,
                      "vote": False}
            if not old:
                status["heartbeat_seq"] = seq
            print(json.dumps(status), flush=True)
"""


class FakeClock:
    def __init__(self, now_ns: int = T0):
        self.now_ns = now_ns

    def __call__(self) -> int:
        return self.now_ns


# -- the ground's rule, on a fake clock ------------------------------------------------------


def test_the_first_designation_waits_for_nothing() -> None:
    designations = Designations()
    assert designations.terms("PN2", T0, PERIOD_NS) == (0, VOTE_SPAN_PERIODS)
    assert designations.terms("PN2", T0, PERIOD_NS, vote_span_periods=5) == (0, 5)
    designation = designations.designate("PN2", 57, T0, PERIOD_NS)
    assert designation.arguments() == ["PN2", "0", str(VOTE_SPAN_PERIODS), "57"]


def test_another_node_waits_out_the_span_plus_a_period_for_the_drift() -> None:
    designations = Designations()
    sent = designations.designate("PN1", 3, T0, PERIOD_NS)
    designations.record(sent)
    # PN1's vote ends by T0 + (20 + 1) periods at the latest.
    assert sent.ends_ns == T0 + 21 * PERIOD_NS
    assert designations.terms("PN2", T0, PERIOD_NS) == (21, 41)
    # The periods left, rounded up.
    assert designations.terms("PN2", T0 + 5 * PERIOD_NS + 1, PERIOD_NS) == (16, 36)
    assert designations.terms("PN2", T0 + 20 * PERIOD_NS, PERIOD_NS) == (1, 21)
    assert designations.terms("PN2", T0 + 21 * PERIOD_NS - 1, PERIOD_NS) == (1, 21)
    assert designations.terms("PN2", T0 + 21 * PERIOD_NS, PERIOD_NS) == (0, 20)
    # PN1 designated again renews its own vote at once.
    assert designations.terms("PN1", T0 + PERIOD_NS, PERIOD_NS) == (0, 20)


def test_the_wait_is_the_latest_span_given_any_other_node() -> None:
    designations = Designations()
    designations.record(designations.designate("PN1", 3, T0, PERIOD_NS))  # ends T0 + 21
    later = designations.designate("PN2", 9, T0 + 2 * PERIOD_NS, PERIOD_NS)
    assert (later.wait_periods, later.span_periods) == (19, 39)
    designations.record(later)  # ends T0 + 2 + 40 periods
    # PN3 waits out PN2's span, which ends last; PN1 waits out PN2's, not its own.
    assert designations.terms("PN3", T0 + 2 * PERIOD_NS, PERIOD_NS) == (40, 60)
    assert designations.terms("PN1", T0 + 2 * PERIOD_NS, PERIOD_NS) == (40, 60)
    assert designations.terms("PN2", T0 + 2 * PERIOD_NS, PERIOD_NS) == (19, 39)


def test_the_designations_are_kept_in_the_run_directory(tmp_path: Path) -> None:
    path = tmp_path / DESIGNATIONS_FILE
    first = Designations(path)
    assert first.record(first.designate("PN1", 3, T0, PERIOD_NS)) is None
    with open(path, "a", encoding="utf-8") as stream:
        stream.write('{"node": "PN3", "wait": "x"}\n{"t_ns": 1, "node": "PN3", "wai')  # cut short
    again = Designations(path)
    assert again.latest == {"PN1": Designation("PN1", 0, 20, 3, T0, PERIOD_NS)}
    assert again.terms("PN2", T0 + PERIOD_NS, PERIOD_NS) == (20, 40)
    assert json.loads(path.read_text().splitlines()[0]) == {
        "t_ns": T0, "node": "PN1", "wait": 0, "span": 20, "echo": 3, "period_ns": PERIOD_NS,
        "ends_t_ns": T0 + 21 * PERIOD_NS}


def test_designate_is_a_ground_command_of_the_scenarios_and_the_page() -> None:
    from keel_cluster.cli import PAGE_ACTIONS, designation_note
    from keel_cluster.security import GROUND_VERBS

    assert "designate" in GROUND_VERBS and "designate" in PAGE_ACTIONS
    event = parse_event("at 3s designate PN2", "s.yaml:4", set(NODES), {"nominal"})
    assert (event.action, event.argument) == ("designate", "PN2")
    with pytest.raises(ScenarioError, match="s.yaml:4: node 'PN9' is not in the mission"):
        parse_event("at 3s designate PN9", "s.yaml:4", set(NODES), {"nominal"})
    assert designation_note(Designation("PN2", 0, 20, 57, T0, PERIOD_NS)) == (
        "sent designate PN2 0 20 57: the ground's vote for PN2 from 0 periods after PN2 takes it until "
        "20 periods after its heartbeat 57")


# -- Cluster.designate, on stand-in nodes -------------------------------------------------------


@pytest.fixture(scope="module")
def security_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One credentials set for the module's clusters (openssl takes a while)."""
    from keel_cluster.security import ensure_credentials

    return ensure_credentials(TIE_GRACE, tmp_path_factory.mktemp("security")).directory


@pytest.fixture
def standin(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.delenv("KEEL_SIGNING_KEY", raising=False)
    monkeypatch.setattr(launcher, "_compiled", {})
    monkeypatch.setenv("STANDIN_DIR", str(tmp_path))
    path = tmp_path / "standin-node"
    path.write_text(f"#!{sys.executable}\n{STANDIN}")
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return path


def sent_lines(tmp_path: Path, node: str, count: int = 0) -> list[str]:
    """The lines but `status` and `quit` the stand-in `node` was sent, once it has read
    `count` of them (within 10 s)."""
    path = tmp_path / f"{node}.lines"
    deadline = time.monotonic() + 10
    while True:
        lines = [x for x in path.read_text().splitlines() if x not in ("status", "quit")] if path.is_file() else []
        if len(lines) >= count or time.monotonic() > deadline:
            return lines
        time.sleep(0.01)


def standin_cluster(tmp_path: Path, binary: Path, security_dir: Path | None, mission: Path = TIE_GRACE,
                    clock: FakeClock | None = None, **options: Any) -> Cluster:
    return Cluster(mission, NODES, tmp_path / "run", binary, echo=False, security_dir=security_dir,
                   insecure=security_dir is None, clock_ns=clock or FakeClock(), **options)


def test_designate_sends_every_node_the_signed_command_with_the_designees_heartbeat(
        tmp_path: Path, standin: Path, security_dir: Path) -> None:
    clock = FakeClock()
    with standin_cluster(tmp_path, standin, security_dir, clock=clock) as cluster:
        designation = cluster.designate("PN2")
        assert designation == Designation("PN2", 0, VOTE_SPAN_PERIODS, 47, T0, PERIOD_NS)
        assert cluster.image_path is not None
        image = json.loads(cluster.image_path.read_text())["sha256"][:16]
        for node in NODES:
            (line,) = sent_lines(tmp_path, node, 1)
            word, signature, text = line.split(" ", 2)
            assert word == "ground"
            assert text.startswith(f"keel-ground/1 image={image} seq=")
            assert text.endswith(f" designate PN2 0 {VOTE_SPAN_PERIODS} 47")
            operator = x509.load_pem_x509_certificate((security_dir / "operator" / "cert.pem").read_bytes())
            public = operator.public_key()
            assert isinstance(public, ec.EllipticCurvePublicKey)
            public.verify(bytes.fromhex(signature), text.encode(), ec.ECDSA(hashes.SHA256()))
        # Another node, five periods later, waits out PN2's span and a period more; its
        # ECHO is from the status line read now (the stand-in's second: 40 + 2 x 7).
        clock.now_ns += 5 * PERIOD_NS
        assert cluster.designate("PN3").arguments() == ["PN3", "16", str(16 + VOTE_SPAN_PERIODS), "54"]
        assert [e["argument"] for e in cluster.events if e["action"] == "designate"] == [
            "PN2 0 20 47", "PN3 16 36 54"]
    # Another launcher on the same run directory honours them.
    again = standin_cluster(tmp_path, standin, security_dir, clock=FakeClock(T0 + 6 * PERIOD_NS),
                            vote_span_periods=8)
    assert again.designations.terms("PN2", T0 + 6 * PERIOD_NS, PERIOD_NS, 8) == (36, 44)


def test_designate_refuses_what_no_node_could_take_and_sends_nothing(
        tmp_path: Path, standin: Path, security_dir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("STANDIN_SILENT", "PN3")
    monkeypatch.setenv("STANDIN_OLD", "PN2")
    monkeypatch.setattr(launcher, "STATUS_ANSWER_S", 0.3)
    with standin_cluster(tmp_path, standin, security_dir) as cluster:
        with pytest.raises(LaunchError, match=r"^no node PN9 in the mission \(its nodes: PN1, "):
            cluster.designate("PN9")
        with pytest.raises(LaunchError, match="^PN3 printed no status line within 0.3 s"):
            cluster.designate("PN3")
        with pytest.raises(LaunchError, match=r"^ST1 is no processing node \(interface\): only a monitor"):
            cluster.designate("ST1")
        with pytest.raises(LaunchError, match="^PN2's status line has no heartbeat_seq"):
            cluster.designate("PN2")
        cluster.kill("PN1")
        with pytest.raises(LaunchError, match="^PN1 is down"):
            cluster.designate("PN1")
        cluster.pause("PN2")
        with pytest.raises(LaunchError, match=r"^PN2 is stopped \(pause\)"):
            cluster.designate("PN2")
        cluster.resume("PN2")
        # A credentials set whose operator may not designate (keel-cluster credentials
        # --operator-verbs, or a set made before designate): every node would refuse it.
        cluster.credentials.tools["operator"]["verbs"] = ["phase", "exclude"]
        with pytest.raises(LaunchError, match=r"^the operator's grant in .* does not name designate \(phase, "):
            cluster.designate("PN2")
        assert cluster.designations.latest == {}
    # The stand-ins have exited: every line they were sent is in their files.
    assert all(sent_lines(tmp_path, node) == [] for node in NODES)
    assert not (tmp_path / "run" / DESIGNATIONS_FILE).exists()


def test_an_insecure_cluster_or_a_mission_without_tie_grace_cannot_designate(
        tmp_path: Path, standin: Path) -> None:
    with (standin_cluster(tmp_path / "insecure", standin, None) as cluster,
          pytest.raises(LaunchError, match="^an --insecure cluster cannot designate")):
        cluster.designate("PN2")
    security = tmp_path / "prototype3-security"
    with (standin_cluster(tmp_path / "no-grace", standin, security, mission=PROTOTYPE3) as cluster,
          pytest.raises(LaunchError, match="^the mission sets no heartbeat.tie_grace")):
        cluster.designate("PN2")
    assert all(sent_lines(tmp_path, node) == [] for node in NODES)
    assert not (tmp_path / "insecure" / "run" / DESIGNATIONS_FILE).exists()
