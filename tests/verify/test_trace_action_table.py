"""The table "Trace actions and where each is checked" in docs/verification.md names every
(fsm, action) pair a trace can hold: a trace action added to the C++ fails here until the
table says how trace validation treats it, and a row whose action nothing logs any more
fails too.

The pairs are read from the sources by pattern, not from a run: in core/fsm/*.cpp and
core/node/*.cpp (not their tests), `X.trace("fsm", "Action", ...)`, `write_trace({"fsm",
"Action", ...})` and `act::Trace{"fsm", "Action", ...}`, and in config_switch.cpp and
reconfiguration_manager.cpp the helpers `trace("Action", ...)`, which log fsm "switch". A
trace call whose fsm or action is not a literal is reported as unrecognised: its pair
cannot be read. The environment lines are keel-sim's `environment("Action", ...)`
(nodes/sim/src) and keel-cluster's `ENV_ACTIONS` (nodes/cluster/keel_cluster).
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "verification.md"
SECTION = "## Trace actions and where each is checked"

# The helpers that log fsm "switch" for the action their caller names.
SWITCH_HELPERS = ("core/fsm/config_switch.cpp", "core/fsm/reconfiguration_manager.cpp")

MEMBER_CALL = re.compile(r'(?:\.|->)\s*(trace)\s*\(\s*"(\w+)"\s*,\s*"(\w+)"')
BRACED = re.compile(r'(?:\bwrite_(trace)\s*\(\s*|\bact::(Trace)\s*)\{\s*"(\w+)"\s*,\s*"(\w+)"')
HELPER_CALL = re.compile(r'(?<![\w.>:])(trace)\s*\(\s*"(\w+)"')
# Every place a trace line may be made: each must be one of the above or allowed below.
ANY_CALL = re.compile(r'\b(trace)\s*\(|\bwrite_(trace)\s*\(\s*\{|\bact::(Trace)\s*\{')
# The helpers' definitions, and their forwarding of the caller's action.
DEFINITION = re.compile(r'::(trace)\s*\(\s*const\s+char\s*\*')
FORWARD = re.compile(r'(?:\.|->)\s*(trace)\s*\(\s*"switch"\s*,\s*action\b')

ENVIRONMENT_CALL = re.compile(r'\benvironment\s*\(\s*"(\w+)"')
ENV_ACTIONS = re.compile(r"^ENV_ACTIONS\s*=\s*\{([^}]*)\}", re.MULTILINE)

Pair = tuple[str, str]


def cpp_sources() -> dict[str, str]:
    """core/fsm/*.cpp and core/node/*.cpp (their tests are in subdirectories), by path
    relative to the root."""
    paths = [*sorted((ROOT / "core" / "fsm").glob("*.cpp")),
             *sorted((ROOT / "core" / "node").glob("*.cpp"))]
    return {str(p.relative_to(ROOT)): p.read_text(encoding="utf-8") for p in paths}


def collect(sources: dict[str, str]) -> tuple[dict[Pair, set[str]], list[str]]:
    """The (fsm, action) pairs the sources log, each with the files that log it, and the
    trace calls whose pair cannot be read (as `file:line: text`)."""
    pairs: dict[Pair, set[str]] = {}
    unrecognised: list[str] = []
    for name, text in sources.items():
        known: set[int] = set()  # where the `trace` of each call read or allowed starts
        found: list[tuple[str, str]] = []
        for match in MEMBER_CALL.finditer(text):
            known.add(match.start(1))
            found.append((match[2], match[3]))
        for match in BRACED.finditer(text):
            known.add(match.start(1) if match[1] else match.start(2))
            found.append((match[3], match[4]))
        if name in SWITCH_HELPERS:
            for match in HELPER_CALL.finditer(text):
                known.add(match.start(1))
                found.append(("switch", match[2]))
            for match in FORWARD.finditer(text):
                known.add(match.start(1))
        for match in DEFINITION.finditer(text):
            known.add(match.start(1))
        for fsm, action in found:
            pairs.setdefault((fsm, action), set()).add(name)
        for match in ANY_CALL.finditer(text):
            start = next(match.start(g) for g in (1, 2, 3) if match[g])
            if start not in known:
                line = text.count("\n", 0, start) + 1
                unrecognised.append(f"{name}:{line}: {text.splitlines()[line - 1].strip()}")
    return pairs, unrecognised


def env_actions() -> dict[str, set[str]]:
    """The environment lines' actions keel-sim and keel-cluster write, each with its files."""
    out: dict[str, set[str]] = {}
    for path in sorted((ROOT / "nodes" / "sim" / "src").rglob("*.cpp")):
        for action in ENVIRONMENT_CALL.findall(path.read_text(encoding="utf-8")):
            out.setdefault(action, set()).add(str(path.relative_to(ROOT)))
    for path in sorted((ROOT / "nodes" / "cluster" / "keel_cluster").glob("*.py")):
        for body in ENV_ACTIONS.findall(path.read_text(encoding="utf-8")):
            for action in re.findall(r':\s*"(\w+)"', body):
                out.setdefault(action, set()).add(str(path.relative_to(ROOT)))
    return out


def table(text: str) -> list[tuple[int, Pair, set[str]]]:
    """The section's table rows: (line number, (fsm, action), the files named as emitting
    it)."""
    lines = text.splitlines()
    assert SECTION in lines, f"docs/verification.md has no section {SECTION!r}"
    rows = []
    in_table = False
    for number, line in enumerate(lines[lines.index(SECTION) + 1:], lines.index(SECTION) + 2):
        if line.startswith("#"):
            break
        if not line.startswith("|"):
            if in_table:
                break
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if not in_table:  # the header, then the separator
            in_table = True
            assert cells[:3] == ["fsm", "action", "emitted by (file)"], cells
            continue
        if set(line) <= set("|-: "):
            continue
        assert len(cells) == 5, f"docs/verification.md:{number}: {len(cells)} cells, not 5"
        rows.append((number, (cells[0].strip("`"), cells[1].strip("`")),
                     set(re.findall(r"`([^`]+)`", cells[2]))))
    return rows


def missing(emitted: dict[Pair, set[str]], rows: list[tuple[int, Pair, set[str]]]
            ) -> list[Pair]:
    """The emitted pairs that have no row."""
    named = {pair for _, pair, _ in rows}
    return sorted(set(emitted) - named)


def describe(pairs: list[Pair], emitted: dict[Pair, set[str]]) -> str:
    return "\n".join(f"  {fsm} {action} ({', '.join(sorted(emitted.get((fsm, action), ())))})"
                     for fsm, action in pairs)


EMITTED, UNRECOGNISED = collect(cpp_sources())
ENV = env_actions()
ROWS = table(DOC.read_text(encoding="utf-8"))


def test_the_scan_reads_every_kind_of_trace_call() -> None:
    assert not UNRECOGNISED, ("trace calls whose (fsm, action) this test cannot read; "
                              "teach collect() their form:\n  " + "\n  ".join(UNRECOGNISED))
    for pair in [("switch", "Backed"), ("heartbeat", "Tick"), ("election", "WarmBoot"),
                 ("switch", "Activate"), ("switch", "Exclude"), ("switch", "Recovered"),
                 ("switch", "StoreCheckpoint"), ("health", "TaskUnhealthy")]:
        assert pair in EMITTED, pair
    for action in ("Crash", "Restart", "Partition"):
        assert len(ENV[action]) == 2, (action, ENV[action])


def test_every_emitted_action_has_a_row() -> None:
    absent = missing(EMITTED, ROWS)
    assert not absent, (f"the C++ logs trace actions that docs/verification.md ({SECTION!r}) "
                        "does not name; add a row for each, saying how keel-verify trace "
                        "treats it:\n" + describe(absent, EMITTED))


def test_every_row_names_a_logged_action() -> None:
    named = [pair for _, pair, _ in ROWS]
    twice = sorted({pair for pair in named if named.count(pair) > 1})
    assert not twice, f"rows named twice: {twice}"
    stale = [f"docs/verification.md:{number}: {fsm} {action}" for number, (fsm, action), _ in ROWS
             if ((fsm, action) not in EMITTED if fsm != "env" else action not in ENV)]
    assert not stale, "rows of actions nothing logs:\n  " + "\n  ".join(stale)
    absent = sorted(set(ENV) - {action for _, (fsm, action), _ in ROWS if fsm == "env"})
    assert not absent, f"env lines keel-sim or keel-cluster write without a row: {absent}"


def test_every_row_names_the_files_that_log_it() -> None:
    wrong = []
    for number, (fsm, action), files in ROWS:
        actual = ENV.get(action, set()) if fsm == "env" else EMITTED.get((fsm, action), set())
        if files != actual:
            wrong.append(f"docs/verification.md:{number}: {fsm} {action}: the row names "
                         f"{sorted(files)}, the sources {sorted(actual)}")
    assert not wrong, "\n".join(wrong)


def test_an_action_without_a_row_is_reported() -> None:
    snippet = """
        out.trace("switch", "NoSuchAction", JsonObject().str(), vars_json());
        out_.trace("heartbeat",
                   "Tick", args, vars);
        out.trace("election", kind, args, vars);
    """
    helper = 'trace("AlsoNoSuchAction", args, out);\n'
    emitted, unrecognised = collect({"core/fsm/synthetic.cpp": snippet,
                                     "core/fsm/config_switch.cpp": helper})
    assert emitted == {("switch", "NoSuchAction"): {"core/fsm/synthetic.cpp"},
                       ("heartbeat", "Tick"): {"core/fsm/synthetic.cpp"},
                       ("switch", "AlsoNoSuchAction"): {"core/fsm/config_switch.cpp"}}
    assert missing(emitted, ROWS) == [("switch", "AlsoNoSuchAction"), ("switch", "NoSuchAction")]
    assert unrecognised == ['core/fsm/synthetic.cpp:5: out.trace("election", kind, args, vars);']


def test_the_checkers_read_only_actions_of_the_table() -> None:
    # The validators name the actions they read; each must be a row of the table (a name
    # changed in the C++ and not in a checker, or the reverse, fails here), and an old
    # trace's name must map onto a row (spec/NAMES.md, "Renamed actions").
    from keel_verify.trace import election, heartbeat, load, switch

    named = {pair for _, pair, _ in ROWS}
    read = {("election", a) for a in election.ACTIONS}
    read |= {("heartbeat", a) for a in heartbeat.ACTIONS}
    read |= {("switch", a) for a in switch.MANAGER if a != "TakeOver"}  # TakeOver: a BecomeMaster
    read |= {("switch", a) for a in switch.LEASE}
    assert sorted(read - named) == []
    assert all((fsm, new) in named and (fsm, old) not in named
               for (fsm, old), new in load.LEGACY_ACTIONS.items())
    assert ("election", "Suspect") in read and ("switch", "Exclude") in read
