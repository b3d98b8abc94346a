"""Tests of ``keel-verify specs``: TLC output parsing, exit-code mapping, counterexample
rendering, .cfg retargeting, the manifest, --mission instantiation, and end-to-end runs
on a real mutant and on a toy spec whose checks must fail."""

from __future__ import annotations

import json
import os
import re
import shutil
from pathlib import Path

import pytest
from keel_verify.cli import main
from keel_verify.specs import counterexample, models, tlc
from keel_verify.specs.mission_models import (
    MissionModelError,
    _check_names,
    mission_models,
)

ROOT = Path(__file__).resolve().parents[2]
SPEC = ROOT / "spec"
JAR = tlc.find_jar()
needs_tlc = pytest.mark.skipif(JAR is None, reason="TLC jar not installed (./keel setup)")

SUCCESS_OUTPUT = """\
TLC2 Version 2.18 of 20 March 2023
Model checking completed. No error has been found.
  Estimates of the probability that TLC did not check all reachable states
3,517 states generated, 1,337 distinct states found, 0 states left on queue.
The depth of the complete state graph search is 16.
Finished in 06s at (2026-11-21 17:23:28)
"""

INVARIANT_OUTPUT = """\
Error: Invariant AccuracyInv is violated.
Error: The behavior up to this point is:
State 1: <Initial predicate>
/\\ alive = (PN1 :> TRUE @@ PN2 :> TRUE)
/\\ missed = (PN1 :> (PN1 :> 0 @@ PN2 :> 0) @@ PN2 :> (PN1 :> 0 @@ PN2 :> 0))
/\\ failed = (PN1 :> {} @@ PN2 :> {})

State 2: <Tick line 104, col 5 to line 118, col 50 of module Heartbeat>
/\\ alive = (PN1 :> TRUE @@ PN2 :> TRUE)
/\\ missed = (PN1 :> (PN1 :> 0 @@ PN2 :> 1) @@ PN2 :> (PN1 :> 0 @@ PN2 :> 0))
/\\ failed = (PN1 :> {} @@ PN2 :> {})

State 3: <EagerDeclareFailed line 11, col 5 to line 16, col 70 of module HeartbeatEagerDeclare>
/\\ alive = (PN1 :> TRUE @@ PN2 :> TRUE)
/\\ missed = (PN1 :> (PN1 :> 0 @@ PN2 :> 1) @@ PN2 :> (PN1 :> 0 @@ PN2 :> 0))
/\\ failed = (PN1 :> {PN2} @@ PN2 :> {})

2,006 states generated, 1,001 distinct states found, 12 states left on queue.
The depth of the complete state graph search is 3.
"""

LIVENESS_OUTPUT = """\
Error: Temporal properties were violated.
Error: The following behavior constitutes a counter-example:
State 1: <Initial predicate>
/\\ x = 0

State 2: <ProtocolNext line 3, col 8 to line 3, col 50 of module Toy>
/\\ x = 1

Back to state 1: <Step line 2, col 1 to line 2, col 10 of module Toy>

10 states generated, 5 distinct states found, 0 states left on queue.
"""


@pytest.mark.parametrize("code", [0, 10, 11, 12, 13, 14, 75, 76, 77, 150, 151, 152, 153])
def test_every_documented_exit_code_has_a_meaning(code: int) -> None:
    verdict, text = tlc.meaning(code)
    assert verdict in {tlc.PASS, tlc.VIOLATION, tlc.INPUT_ERROR, tlc.UNDECIDED}
    assert text
    if code == 0:
        assert verdict == tlc.PASS
    elif 10 <= code <= 14:
        assert verdict == tlc.VIOLATION
    elif code in (150, 151):
        assert verdict == tlc.INPUT_ERROR
    else:
        assert verdict == tlc.UNDECIDED


def test_no_exit_code_and_unknown_codes_are_undecided() -> None:
    assert tlc.meaning(None)[0] == tlc.UNDECIDED
    assert tlc.meaning(42)[0] == tlc.UNDECIDED


def test_success_needs_both_exit_code_and_final_line() -> None:
    result = tlc.parse_output(SUCCESS_OUTPUT, 0)
    assert result.verdict == tlc.PASS
    assert (result.distinct_states, result.states_generated, result.depth) == (1337, 3517, 16)
    truncated = SUCCESS_OUTPUT.replace("Model checking completed. No error has been found.", "")
    assert tlc.parse_output(truncated, 0).verdict == tlc.UNDECIDED
    # A violation exit code without TLC saying what was violated is not trusted either.
    assert tlc.parse_output(SUCCESS_OUTPUT, 12).verdict == tlc.UNDECIDED


def test_invariant_violation_names_the_property_and_keeps_the_trace() -> None:
    result = tlc.parse_output(INVARIANT_OUTPUT, 12)
    assert result.verdict == tlc.VIOLATION
    assert result.property == "AccuracyInv"
    assert [s.action for s in result.trace] == ["Init", "Tick", "EagerDeclareFailed"]
    assert result.trace[2].variables["failed"] == "(PN1 :> {PN2} @@ PN2 :> {})"


def test_temporal_violation_is_named_when_the_model_checks_one_property() -> None:
    cfg = "SPECIFICATION Spec\nPROPERTY MasterLiveness\n"
    result = tlc.parse_output(LIVENESS_OUTPUT, 13, cfg)
    assert result.property == "MasterLiveness"
    assert result.trace[-1].back_to == 1
    two = "PROPERTIES\n    A\n    B\n"
    assert tlc.parse_output(LIVENESS_OUTPUT, 13, two).property == "temporal property"


def test_step_labelled_with_next_is_named_after_the_called_action() -> None:
    disjunct = "    \\/ \\E n \\in S, m \\in msgs : Receive(n, m)"
    source = f"---- MODULE Toy ----\nProtocolNext ==\n{disjunct}\n"
    label = f"<ProtocolNext line 3, col 8 to line 3, col {len(disjunct)} of module Toy>"
    output = LIVENESS_OUTPUT.replace(
        "<ProtocolNext line 3, col 8 to line 3, col 50 of module Toy>", label
    )
    trace = counterexample.parse_trace(output, {"Toy": source})
    assert trace[1].action == "Receive"
    # Without the source, the label is kept as TLC printed it.
    assert counterexample.parse_trace(output)[1].action == "ProtocolNext"


def test_changes_follow_nested_functions_and_records() -> None:
    before = "(PN1 :> (PN1 :> 0 @@ PN2 :> 1) @@ PN2 :> (PN1 :> 0 @@ PN2 :> 0))"
    after = "(PN1 :> (PN1 :> 0 @@ PN2 :> 2) @@ PN2 :> (PN1 :> 0 @@ PN2 :> 0))"
    assert counterexample.changes(before, after) == [("[PN1][PN2]", "1", "2")]
    record_before = '[phase |-> "P1", failed |-> {}]'
    record_after = '[phase |-> "P2", failed |-> {}]'
    assert counterexample.changes(record_before, record_after) == [("[phase]", '"P1"', '"P2"')]
    assert counterexample.changes("{1}", "{1, 2}") == [("", "{1}", "{1, 2}")]
    assert counterexample.changes("<<1, 2>>", "<<1, 2>>") == []


def test_rendered_table_shows_only_what_changed() -> None:
    trace = tlc.parse_output(INVARIANT_OUTPUT, 12).trace
    table = counterexample.render(trace)
    rows = table.splitlines()
    tick = next(row for row in rows if " Tick " in row)
    assert "missed[PN1][PN2]: 0 -> 1" in tick
    declare = next(row for row in rows if "EagerDeclareFailed" in row)
    assert "failed[PN1]: {} -> {PN2}" in declare
    # alive never changes after Init, so it appears once, in the Init row.
    assert sum("alive" in row for row in rows) == 1


def test_retarget_cfg_keeps_the_constants_and_checks_one_property() -> None:
    base = (SPEC / "MCHeartbeat.cfg").read_text()
    cfg = models.retarget_cfg(base, "MutantSpec", "AccuracyInv")
    assert "SPECIFICATION MutantSpec" in cfg
    assert "INVARIANT AccuracyInv" in cfg
    assert "CompletenessInv" not in cfg and "SPECIFICATION Spec\n" not in cfg
    assert "MissLimit = 2" in cfg and "SYMMETRY MCSymmetry" in cfg
    election = (SPEC / "MCMasterElection.cfg").read_text()
    assert "PROPERTY MasterLiveness" in models.retarget_cfg(election, "M", "MasterLiveness")


def test_mutant_constants_override_the_base_model() -> None:
    base = (SPEC / "MCHeartbeat.cfg").read_text()
    cfg = models.retarget_cfg(base, "Spec", "AccuracyInv", {"MaxLoss": "2"})
    assert "    MaxLoss = 2\n" in cfg and "MaxLoss = 1" not in cfg
    with pytest.raises(models.ManifestError):
        models.retarget_cfg(base, "Spec", "AccuracyInv", {"NoSuchConstant": "1"})


def test_manifest_lists_every_model_and_mutant_once_and_cmake_registers_them() -> None:
    manifest = models.load_manifest(SPEC)
    names = [m.name for m in manifest.models] + [m.name for m in manifest.mutants]
    assert len(names) == len(set(names))
    cmake = (SPEC / "CMakeLists.txt").read_text()

    def cmake_list(name: str) -> set[str]:
        found = re.search(rf"set\({name}\b(.*?)\)", cmake, re.DOTALL)
        assert found, name
        return set(found.group(1).split())

    # CTest runs every model, mutant and witness but the manifest's "bench" ones (./keel
    # bench specs runs those); each spec keeps a model in CI.
    ci_models = {m.name for m in manifest.models if not m.bench}
    assert cmake_list("KEEL_SPEC_MODELS") == ci_models
    by_kind = {kind: {m.name for m in manifest.mutants if m.kind == kind and not m.bench}
               for kind in ("mutant", "witness")}
    assert cmake_list("KEEL_SPEC_MUTANTS") == by_kind["mutant"]
    # A CI model's witnesses are looked for in its own run (its test); the others (of bench
    # models) run one by one.
    by_name = {m.name: m for m in manifest.models}
    probed = {w for w in by_kind["witness"]
              if any(m.name == w and not by_name[m.base].bench and models.can_probe(by_name[m.base], m, SPEC)
                     for m in manifest.mutants)}
    assert cmake_list("KEEL_SPEC_WITNESSES") == by_kind["witness"] - probed
    assert len(probed) >= 45, len(probed)
    assert {m.spec for m in manifest.models if not m.bench} == {m.spec for m in manifest.models}
    # What CI keeps of the bench tier's cuts: a mutant of every property (of every spec) a
    # mutant breaks, and a witness of every spec that has one; but the mutants of the
    # bigger models' faults, which no CI model has (loss in a streak, two faults, a heal).
    bigger_faults = {"QuorumLapsedQuits", "RejoinAfterWithdrawal", "HeartbeatLossTwoSilent",
                     "ExclusionLossTwoSilent", "LeaseLossLapse", "LeaseTwoFaultsLapse"}

    def spec_of(entry: models.Mutant) -> str:
        return by_name[entry.base].spec

    def broken(ci_only: bool) -> set[tuple[str, str]]:
        return {(spec_of(m), m.property) for m in manifest.mutants
                if m.kind == "mutant" and m.name not in bigger_faults
                and not (ci_only and m.bench)}

    assert broken(True) == broken(False), broken(False) - broken(True)
    witnessed = {kind: {spec_of(m) for m in manifest.mutants
                        if m.kind == "witness" and not (kind and m.bench)}
                 for kind in (True, False)}
    assert witnessed[True] == witnessed[False], witnessed[False] - witnessed[True]
    for model in manifest.models:
        # Distinct states, or the states a simulation checked (a "simulate" model).
        assert isinstance(model.recorded_count, int), f"{model.name}: no recorded count"
        # A simulation is no CI model: CI's models are exhaustive.
        assert model.simulate is None or model.bench, model.name
    specs = {m.spec for m in manifest.models}
    assert specs == {"Heartbeat", "MasterElection", "ConfigSwitch", "Exclusion", "Lease", "Rejoin",
                     "Handoff", "Quorum", "LeaseStepDown", "ValueFault", "Durable", "EpochBound",
                     "ElectionLiar", "TakeOverEpoch", "PassOver", "HandedView",
                     "DivergedView", "Designate", "Ground", "Resign", "AskExclusion",
                     "DurableBoot", "Pause", "Online"}
    # Every property of every spec has a mutant that must break it.
    broken = {m.property for m in manifest.mutants if m.kind == "mutant"}
    type_checks = {"TypeOK", "LTypeOK", "RTypeOK", "HTypeOK", "STypeOK", "PTypeOK", "DTypeOK",
                   "GTypeOK", "ATypeOK", "BTypeOK"}
    unbroken = {
        "MasterOwnsEpochInv", "EpochMonotoneProp",
        # Handoff: the Storage node's own rule (it keeps the newest version it is sent).
        "StoredMonotoneProp",
    }
    for model in manifest.models:
        for prop in model.properties:
            assert prop in type_checks or prop in broken or prop in unbroken, (
                f"{prop} has no mutant")


SIMULATION_OUTPUT = """\
TLC2 Version 2.18 of 20 March 2023
Running Random Simulation with seed 7 with 1 worker on 2 cores with 1820MB heap.
Starting... (2026-11-30 16:12:19)
Computed 5 initial states...
Progress: 44,978 states checked.
Finished in 04s at (2026-11-30 16:12:29)
"""


def test_a_simulation_passes_on_finished_with_its_states_checked() -> None:
    result = tlc.parse_output(SIMULATION_OUTPUT, 0, simulate=True)
    assert result.verdict == tlc.PASS
    assert result.states_checked == 44978 and result.distinct_states is None
    # Read as an exhaustive run it is not a pass: TLC did not say "No error has been found".
    assert tlc.parse_output(SIMULATION_OUTPUT, 0).verdict == tlc.UNDECIDED
    cut = SIMULATION_OUTPUT.replace("Finished in 04s at (2026-11-30 16:12:29)\n", "")
    assert tlc.parse_output(cut, 0, simulate=True).verdict == tlc.UNDECIDED
    # A violation found in simulation reads as in an exhaustive run.
    violated = tlc.parse_output(INVARIANT_OUTPUT, 12, simulate=True)
    assert (violated.verdict, violated.property) == (tlc.VIOLATION, "AccuracyInv")


def test_a_manifest_simulation_is_parsed_and_checked(tmp_path: Path) -> None:
    spec_dir = _toy_spec_dir(tmp_path, 4)
    raw = json.loads((spec_dir / "manifest.json").read_text())
    raw["models"][0]["simulate"] = {"depth": 5, "traces": 3}
    raw["models"][0]["states_checked"] = 12
    (spec_dir / "manifest.json").write_text(json.dumps(raw))
    (model,) = models.load_manifest(spec_dir).models
    assert model.simulate == models.Simulation(depth=5, traces=3, seed=models.DEFAULT_SEED)
    assert model.recorded_count == 12
    assert model.simulate.tlc_args() == ["-simulate", "num=3", "-depth", "5", "-seed", "1"]
    for bad in ({"depth": 5}, {"depth": 0, "traces": 3}, {"depth": 5, "traces": 3, "x": 1}):
        raw["models"][0]["simulate"] = bad
        (spec_dir / "manifest.json").write_text(json.dumps(raw))
        with pytest.raises(models.ManifestError):
            models.load_manifest(spec_dir)


@needs_tlc
def test_a_simulated_model_runs_in_simulation_mode(tmp_path: Path, capsys) -> None:
    spec_dir = _toy_spec_dir(tmp_path, 4)
    raw = json.loads((spec_dir / "manifest.json").read_text())
    raw["models"][0]["simulate"] = {"depth": 10, "traces": 5, "seed": 3}
    (spec_dir / "manifest.json").write_text(json.dumps(raw))
    # No count recorded yet: the run passes TLC but fails the count, and says so.
    assert main(["specs", "--spec-dir", str(spec_dir), "--model", "Toy", "--json"]) == 1
    (result,) = json.loads(capsys.readouterr().out)["results"]
    assert result["verdict"] == tlc.PASS and result["simulation"]["traces"] == 5
    checked = result["states_checked"]
    assert isinstance(checked, int) and checked > 0
    raw["models"][0]["states_checked"] = checked
    (spec_dir / "manifest.json").write_text(json.dumps(raw))
    # The same seed, the same states: a reproducible pass.
    assert main(["specs", "--spec-dir", str(spec_dir), "--model", "Toy", "--json"]) == 0
    capsys.readouterr()
    # A violation found in simulation fails the model.
    (spec_dir / "Toy.cfg").write_text("SPECIFICATION Spec\nINVARIANT Below3\n"
                                      "CHECK_DEADLOCK FALSE\n")
    (spec_dir / "Toy.tla").write_text(TOY.replace("====", "Below3 == x < 3\n===="))
    assert main(["specs", "--spec-dir", str(spec_dir), "--model", "Toy", "--json"]) == 1
    (result,) = json.loads(capsys.readouterr().out)["results"]
    assert (result["exit_code"], result["property"]) == (12, "Below3")


def test_bench_mutants_and_witnesses_are_left_to_all(tmp_path: Path, capsys) -> None:
    spec_dir = _toy_spec_dir(tmp_path, 4)
    raw = json.loads((spec_dir / "manifest.json").read_text())
    raw["mutants"][0]["bench"] = True
    (spec_dir / "manifest.json").write_text(json.dumps(raw))
    assert main(["specs", "--list", "--spec-dir", str(spec_dir)]) == 0
    assert "ToyHarmless" not in capsys.readouterr().out
    assert main(["specs", "--list", "--all", "--spec-dir", str(spec_dir)]) == 0
    assert "ToyHarmless" in capsys.readouterr().out
    assert main(["specs", "--list", "--mutant", "ToyHarmless", "--spec-dir", str(spec_dir)]) == 0
    assert "ToyHarmless" in capsys.readouterr().out


def test_witnesses_are_invariants_of_their_base_module() -> None:
    manifest = models.load_manifest(SPEC)
    witnesses = [m for m in manifest.mutants if m.kind == "witness"]
    assert witnesses
    for witness in witnesses:
        base = manifest.model(witness.base)
        assert witness.module == base.module
        text = (SPEC / f"{base.module}.tla").read_text()
        assert re.search(rf"^{witness.property} ==", text, re.MULTILINE), witness.name
        cfg = models.retarget_cfg(base.cfg_text, "Spec", witness.property, invariant=True)
        assert f"INVARIANT {witness.property}" in cfg


def test_mission_models_follow_the_mission() -> None:
    name, built, facts = mission_models(ROOT / "config" / "earth_observation.yaml")
    assert [m.name for m in built] == [
        "MissionHeartbeat", "MissionHeartbeatStartup", "MissionMasterElection",
        "MissionConfigSwitchPhase", "MissionConfigSwitch", "MissionConfigSwitchPhaseCrash",
        "MissionConfigSwitchFailover"]
    assert name
    assert facts["priority"] == ["PN1", "PN2", "PN3", "PN4"]
    assert facts["monitors"] == ["PN1", "PN2", "PN3"]
    by_name = {m.name: m for m in built}
    heartbeat = by_name["MissionHeartbeat"].cfg_text
    assert "Monitors = {PN1, PN2, PN3}" in heartbeat
    assert "MissLimit = 3" in heartbeat and "MaxLoss = 2" in heartbeat
    # No startup_grace_ms in the file: 2000 ms, 20 periods of 100 ms; the late node boots
    # at most 20 - 3 periods late (boot delay + a loss streak of 2 < 20).
    assert facts["startup_grace_periods"] == 20
    assert "StartupGrace = 20" in heartbeat and "MaxLateBoots = 0" in heartbeat
    startup = by_name["MissionHeartbeatStartup"].cfg_text
    assert "Monitors = {PN1}" in startup
    assert "MaxLateBoots = 1" in startup and "MaxBootDelay = 17" in startup
    for switch in ("MissionConfigSwitch", "MissionConfigSwitchFailover"):
        assert "MaxLateBoots = 1" in by_name[switch].cfg_text
        assert "VIEW MCView" in by_name[switch].cfg_text
    election = by_name["MissionMasterElection"].extra_files["MissionMasterElection.tla"]
    assert "MissionPriority == <<PN1, PN2, PN3, PN4>>" in election
    assert "NumObservers = 2" in by_name["MissionMasterElection"].cfg_text
    assert "Storage = ST1" in by_name["MissionConfigSwitch"].cfg_text


def test_mission_startup_grace_sets_the_heartbeat_models(tmp_path: Path) -> None:
    text = (ROOT / "config" / "earth_observation.yaml").read_text()
    assert "heartbeat: {period_ms: 100, miss_limit: 3}" in text
    # 450 ms is 5 periods (rounded up); below the miss limit the grace is the miss limit.
    for grace_ms, periods in ((450, 5), (100, 3)):
        mission = tmp_path / f"grace{grace_ms}.yaml"
        mission.write_text(text.replace(
            "heartbeat: {period_ms: 100, miss_limit: 3}",
            f"heartbeat: {{period_ms: 100, miss_limit: 3, startup_grace_ms: {grace_ms}}}"))
        _name, built, facts = mission_models(mission)
        assert facts["startup_grace_periods"] == periods
        startup = {m.name: m for m in built}["MissionHeartbeatStartup"].cfg_text
        assert f"StartupGrace = {periods}" in startup
        assert f"MaxBootDelay = {periods - 3}" in startup


def test_node_names_that_are_not_identifiers_are_refused() -> None:
    with pytest.raises(MissionModelError):
        _check_names(["PN-1"])
    with pytest.raises(MissionModelError):
        _check_names(["Tick"])


@needs_tlc
def test_real_mutant_is_rejected_with_a_readable_counterexample(capsys) -> None:
    code = main(["specs", "--mutant", "SwitchActivateEarly", "--json"])
    report = json.loads(capsys.readouterr().out)
    assert code == 0 and report["ok"]
    (result,) = report["results"]
    assert result["status"] == "ok"
    assert (result["exit_code"], result["property"]) == (12, "NoDoubleActivationInv")
    actions = [step["action"] for step in result["counterexample"]]
    assert actions[0] == "Init" and actions[-1] == "Activate"
    assert "EarlyBroadcastActivate" in actions
    last = result["counterexample"][-1]["changes"]
    assert any(change["var"].startswith("active[") for change in last)


TOY = """---- MODULE Toy ----
EXTENDS Naturals
VARIABLE x
Init == x = 0
Step == x < 3 /\\ x' = x + 1
Spec == Init /\\ [][Step]_x
SmallInv == x <= 3
====
"""

TOY_MUTANT = """---- MODULE ToyHarmless ----
EXTENDS Toy
\\* Not broken at all: the property must hold, so the check must fail.
MutantSpec == Spec
====
"""


def _toy_spec_dir(tmp_path: Path, count: int) -> Path:
    spec_dir = tmp_path / "spec"
    (spec_dir / "mutants").mkdir(parents=True)
    (spec_dir / "Toy.tla").write_text(TOY)
    (spec_dir / "Toy.cfg").write_text(
        "SPECIFICATION Spec\nINVARIANT SmallInv\nCHECK_DEADLOCK FALSE\n"
    )
    (spec_dir / "mutants" / "ToyHarmless.tla").write_text(TOY_MUTANT)
    (spec_dir / "manifest.json").write_text(json.dumps({
        "models": [{"name": "Toy", "spec": "Toy", "module": "Toy", "config": "Toy.cfg",
                    "properties": ["SmallInv"], "distinct_states": count}],
        "mutants": [{"name": "ToyHarmless", "base": "Toy", "module": "ToyHarmless",
                     "specification": "MutantSpec", "property": "SmallInv",
                     "exit_code": 12}],
    }))
    return spec_dir


@needs_tlc
def test_toy_model_passes_with_the_right_count(tmp_path: Path) -> None:
    spec_dir = _toy_spec_dir(tmp_path, 4)
    assert main(["specs", "--spec-dir", str(spec_dir), "--model", "Toy", "--json"]) == 0


@needs_tlc
def test_wrong_state_count_and_unrejected_mutant_fail(tmp_path: Path, capsys) -> None:
    spec_dir = _toy_spec_dir(tmp_path, 5)
    assert main(["specs", "--spec-dir", str(spec_dir), "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    statuses = {r["name"]: (r["status"], r["summary"]) for r in report["results"]}
    assert statuses["Toy"][0] == "failed" and "4 distinct states" in statuses["Toy"][1]
    assert statuses["ToyHarmless"][0] == "failed"
    assert "NOT rejected" in statuses["ToyHarmless"][1]


@needs_tlc
def test_deadlock_is_a_violation_when_the_model_checks_for_it(tmp_path: Path, capsys) -> None:
    spec_dir = _toy_spec_dir(tmp_path, 4)
    (spec_dir / "Toy.cfg").write_text("SPECIFICATION Spec\nINVARIANT SmallInv\n")
    assert main(["specs", "--spec-dir", str(spec_dir), "--model", "Toy", "--json"]) == 1
    (result,) = json.loads(capsys.readouterr().out)["results"]
    assert (result["exit_code"], result["property"]) == (11, "deadlock")


@needs_tlc
def test_spec_that_does_not_parse_is_an_input_error(tmp_path: Path) -> None:
    spec_dir = _toy_spec_dir(tmp_path, 4)
    (spec_dir / "Toy.tla").write_text(TOY.replace("Init == x = 0", "Init == x = = 0"))
    assert main(["specs", "--spec-dir", str(spec_dir), "--model", "Toy"]) == 2


def _toy_with_witnesses(tmp_path: Path) -> Path:
    """The toy with two witnesses: x reaches 2 (reachable), x reaches 5 (never)."""
    spec_dir = _toy_spec_dir(tmp_path, 4)
    (spec_dir / "Toy.tla").write_text(TOY.replace("====", "NotTwoInv == x # 2\nNotFiveInv == x # 5\n===="))
    raw = json.loads((spec_dir / "manifest.json").read_text())
    raw["witnesses"] = [{"name": "ToyReachesTwo", "base": "Toy", "property": "NotTwoInv"},
                        {"name": "ToyReachesFive", "base": "Toy", "property": "NotFiveInv"}]
    (spec_dir / "manifest.json").write_text(json.dumps(raw))
    return spec_dir


@needs_tlc
def test_witnesses_are_looked_for_in_their_models_run(tmp_path: Path, capsys) -> None:
    # One TLC run checks the model and looks for both witnesses: the reachable one is
    # reached, the unreachable one fails (the property it guards would be vacuous).
    spec_dir = _toy_with_witnesses(tmp_path)
    assert main(["specs", "--spec-dir", str(spec_dir), "--no-mutants", "--model", "Toy", "--json"]) == 0
    (only,) = json.loads(capsys.readouterr().out)["results"]  # --no-mutants: no witness either
    assert only["name"] == "Toy"
    assert main(["specs", "--spec-dir", str(spec_dir), "--model", "Toy", "--json"]) == 1
    results = {r["name"]: r for r in json.loads(capsys.readouterr().out)["results"]}
    assert set(results) == {"Toy", "ToyReachesTwo", "ToyReachesFive"}
    assert results["Toy"]["status"] == "ok"
    assert results["ToyReachesTwo"]["status"] == "ok" and "reached" in results["ToyReachesTwo"]["summary"]
    assert results["ToyReachesFive"]["status"] == "failed"
    assert "NOT reached: no state of Toy's run violates NotFiveInv" in results["ToyReachesFive"]["summary"]
    for name in ("ToyReachesTwo", "ToyReachesFive"):
        assert results[name]["meaning"] == "looked for in Toy's run", results[name]
    # The whole manifest likewise; each witness on its own (by name, or
    # --separate-witnesses) in a run of its own, with the same verdicts.
    assert main(["specs", "--spec-dir", str(spec_dir), "--json", "--separate-witnesses"]) == 1
    results = {r["name"]: r for r in json.loads(capsys.readouterr().out)["results"]}
    assert results["ToyReachesTwo"]["status"] == "ok" and results["ToyReachesTwo"]["exit_code"] == 12
    assert results["ToyReachesFive"]["status"] == "failed"
    assert main(["specs", "--spec-dir", str(spec_dir), "--witness", "ToyReachesTwo", "--json"]) == 0
    (alone,) = json.loads(capsys.readouterr().out)["results"]
    assert alone["exit_code"] == 12 and alone["counterexample"], alone


def test_a_witness_is_looked_for_only_in_a_run_of_the_same_states(tmp_path: Path) -> None:
    # FairSpec adds fairness to Spec: the same states, so a witness of Spec is looked for
    # in a FairSpec model's run; a specification defined otherwise, or a simulation of
    # another seed, is not the same run.
    spec_dir = tmp_path / "spec"
    spec_dir.mkdir()
    (spec_dir / "A.tla").write_text("---- MODULE A ----\nFairSpec == Spec /\\ WF_x(Next)\n"
                                    "OtherSpec == Init /\\ [][Next]_x\n====\n")
    (spec_dir / "B.tla").write_text("---- MODULE B ----\nOtherSpec == Spec /\\ Fair\n====\n")
    model = models.Model("M", "A", "A", "SPECIFICATION FairSpec\n", [], 4)
    witness = models.Mutant("W", "M", "A", "Spec", "WInv", 12, kind="witness")
    assert models.fair_version_of(spec_dir, "FairSpec") == "Spec"
    assert models.can_probe(model, witness, spec_dir)
    assert models.fair_version_of(spec_dir, "OtherSpec") is None  # two definitions, one not Spec /\ ...
    (spec_dir / "C.tla").write_text("---- MODULE C ----\nBoundSpec == Spec /\\ [](x < 3)\n"
                                    "FairBoundSpec == Spec /\\ WF_x(Next) /\\ [](x < 3)\n====\n")
    assert models.fair_version_of(spec_dir, "BoundSpec") is None  # not fairness: fewer states
    assert models.fair_version_of(spec_dir, "FairBoundSpec") is None
    assert not models.can_probe(models.Model("M", "A", "A", "SPECIFICATION OtherSpec\n", [], 4), witness, spec_dir)
    simulated = models.Mutant("W", "M", "A", "Spec", "WInv", 12, kind="witness",
                              simulate=models.Simulation(depth=10, traces=5))
    assert not models.can_probe(model, simulated, spec_dir)
    module, cfg, files = models.probe_model(model, [witness])
    assert cfg.endswith("INVARIANT KeelWitnessProbe\n") and "SPECIFICATION FairSpec" in cfg
    assert 'PrintT(<<"keel-witness-reached", "W">>)' in files[f"{module}.tla"]
    assert models.probe_results('<<"keel-witness-reached", "W">>\nother') == {"W"}


def test_unknown_model_is_an_input_error() -> None:
    assert main(["specs", "--model", "NoSuchModel"]) == 2


def test_scratch_runs_leave_no_files_in_spec() -> None:
    before = sorted(p.name for p in SPEC.rglob("*"))
    assert not [n for n in before if "TTrace" in n or n == "states"]
    assert shutil.which("java") or JAR is None


def test_the_bench_models_are_checked_only_with_all(capsys: pytest.CaptureFixture[str]) -> None:
    # `keel-verify specs` (CI) leaves the manifest's "bench" models out; --all and an explicit
    # --model check them.
    bench = [m.name for m in models.load_manifest(SPEC).models if m.bench]
    assert "MCLease" in bench
    assert main(["specs", "--list", "--spec-dir", str(SPEC)]) == 0
    listed = capsys.readouterr().out
    assert "MCLeaseCrashes" in listed and not any(f" {name} " in listed for name in bench)
    assert main(["specs", "--list", "--all", "--spec-dir", str(SPEC)]) == 0
    listed = capsys.readouterr().out
    assert all(f" {name} " in listed for name in bench)
    assert main(["specs", "--list", "--model", "MCLease", "--spec-dir", str(SPEC)]) == 0
    assert "MCLease " in capsys.readouterr().out


def test_runs_start_costliest_first_and_are_reported_in_their_order() -> None:
    from keel_verify.specs.cli import run_all

    started: list[str] = []

    def run(name: str):  # type: ignore[no-untyped-def]
        def go() -> str:
            started.append(name)
            return name
        return go

    shown: list[object] = []
    runs = [(1, run("small")), (30, run("large")), (5, run("medium"))]
    outcomes = run_all(runs, 1, shown.append)  # type: ignore[arg-type]
    assert started == ["large", "medium", "small"]
    assert outcomes == shown == ["small", "large", "medium"]


def test_a_failing_run_stops_the_others_and_is_raised() -> None:
    from keel_verify.specs.cli import run_all

    def broken() -> object:
        raise RuntimeError("the runner broke")

    with pytest.raises(RuntimeError, match="the runner broke"):
        run_all([(2, broken), (1, lambda: "never shown")], 2,  # type: ignore[list-item]
                lambda outcome: None)


@pytest.mark.parametrize("jobs", ["0", "-1", "many"])
def test_jobs_must_be_positive_or_auto(jobs: str, tmp_path: Path) -> None:
    spec_dir = _toy_spec_dir(tmp_path, 4)
    assert main(["specs", "--spec-dir", str(spec_dir), "--jobs", jobs]) == 2


def test_short_runs_use_the_quick_compiler_only() -> None:
    jar = Path("tla2tools.jar")
    assert "-XX:TieredStopAtLevel=1" in tlc.java_command(jar, "1", None, quick=True)
    assert "-XX:TieredStopAtLevel=1" not in tlc.java_command(jar, "1", None)


@needs_tlc
def test_tlc_loads_its_classes_from_an_archive_dumped_once(tmp_path: Path, capsys,
                                                          monkeypatch) -> None:
    import subprocess

    from keel_verify import resources

    monkeypatch.setenv("KEEL_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv("KEEL_TLC_CDS", raising=False)
    java = resources.java_command()
    jar = resources.find_tlc_jar()
    assert jar is not None
    options = resources.class_archive_options(java, str(jar))
    if not options:
        pytest.skip("this JVM dumps no class-data-sharing archive (JDK 13 or later does)")
    archive = Path(options[0].split("=", 1)[1])
    assert archive.is_file() and archive.parent == tmp_path / "cache" / "tlc"
    made = archive.stat().st_mtime_ns
    assert resources.class_archive_options(java, str(jar)) == options
    assert archive.stat().st_mtime_ns == made  # dumped once
    assert [p.name for p in archive.parent.iterdir()] == [archive.name]  # no scratch left
    command = tlc.java_command(jar, "1", None)
    assert options[0] in command
    # The JVM loads TLC's classes from it (were the archive refused, they would come from
    # the jar): -Xshare:on makes a JVM that cannot map it fail instead.
    shown = subprocess.run([java, "-Xshare:on", *options, "-Xlog:class+load=info", "-cp",
                            str(jar), "tlc2.TLC", "-help"],
                           capture_output=True, text=True, timeout=120, check=False)
    assert re.search(r"tlc2\.TLC source: shared objects file", shown.stdout), shown.stdout[-2000:]
    # The same verdicts and state counts with the archive and without it.
    spec_dir = _toy_spec_dir(tmp_path, 4)
    reports = []
    for cds in ("1", "0"):
        monkeypatch.setenv("KEEL_TLC_CDS", cds)
        assert main(["specs", "--spec-dir", str(spec_dir), "--json"]) == 1
        reports.append([(r["name"], r["status"], r.get("distinct_states"))
                        for r in json.loads(capsys.readouterr().out)["results"]])
    assert reports[0] == reports[1]
    assert not any("SharedArchiveFile" in x for x in tlc.java_command(jar, "1", None))
    # A jar that is not there: no archive, and no attempt to dump one.
    monkeypatch.setenv("KEEL_TLC_CDS", "1")
    assert resources.class_archive_options(java, str(tmp_path / "none.jar")) == []
    # Another jar at the same path (a new download): another archive.
    copy = tmp_path / "tlc.jar"
    shutil.copyfile(jar, copy)
    first = resources.class_archive_options(java, str(copy))
    copy.write_bytes(copy.read_bytes())  # the same bytes, a new time
    os.utime(copy, ns=(made, made + 1))
    assert resources.class_archive_options(java, str(copy)) != first


@needs_tlc
def test_runs_side_by_side_give_every_result(tmp_path: Path, capsys) -> None:
    spec_dir = _toy_spec_dir(tmp_path, 4)
    assert main(["specs", "--spec-dir", str(spec_dir), "--jobs", "2", "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in report["results"]] == ["Toy", "ToyHarmless"]
    assert report["results"][0]["status"] == "ok"
    assert "NOT rejected" in report["results"][1]["summary"]


ENDLESS = """---- MODULE Endless ----
EXTENDS Naturals
VARIABLE x
Init == x = 0
Spec == Init /\\ [][x' = x + 1]_x
====
"""


@needs_tlc
def test_a_run_past_its_time_limit_is_undecided_and_killed(tmp_path: Path) -> None:
    (tmp_path / "Endless.tla").write_text(ENDLESS)
    assert JAR is not None
    result = tlc.run_tlc(JAR, tmp_path, "Endless", "SPECIFICATION Spec\n", workers="1",
                         timeout_s=3, quick=True)
    assert result.exit_code is None and result.verdict == tlc.UNDECIDED
    assert 2.5 < result.seconds < 30
    assert not tlc._RUNNING  # noqa: SLF001 -- no model checker is left running


@needs_tlc
def test_a_runs_cpu_time_is_its_own_process(tmp_path: Path) -> None:
    spec_dir = _toy_spec_dir(tmp_path, 4)
    assert JAR is not None
    result = tlc.run_tlc(JAR, spec_dir, "Toy", (spec_dir / "Toy.cfg").read_text(), workers="1",
                         quick=True)
    assert result.verdict == tlc.PASS and result.exit_code == 0
    assert 0.1 < result.cpu_seconds < 60
