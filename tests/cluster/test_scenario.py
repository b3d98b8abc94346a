"""Scenario files: every malformed input is refused with file:line and the reason."""

from __future__ import annotations

from pathlib import Path

import pytest

from keel_cluster.scenario import ScenarioError, load_scenario, parse_duration_s

NODES = {"PN1", "PN2", "PN3", "ST1"}
PROCESSING = ["PN1", "PN2", "PN3"]
PHASES = {"nominal", "science"}


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    return path


def test_durations() -> None:
    assert parse_duration_s("300ms", "x") == pytest.approx(0.3)
    assert parse_duration_s("5s", "x") == 5.0
    assert parse_duration_s("2m", "x") == 120.0
    assert parse_duration_s(1.5, "x") == 1.5
    with pytest.raises(ScenarioError, match="not a duration"):
        parse_duration_s("5 s", "x")


def test_events_are_parsed_and_sorted(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "duration: 12s\nevents:\n  - at 10s phase science\n  - at 5s kill PN2\n  - at 6s restart PN2\n"
        "  - at 8s partition PN3\n  - at 9s heal PN3\n",
    )
    scenario = load_scenario(path, NODES, PROCESSING, PHASES)
    assert scenario.duration_s == 12.0
    assert [str(e) for e in scenario.events] == [
        "at 5s kill PN2", "at 6s restart PN2", "at 8s partition PN3", "at 9s heal PN3",
        "at 10s phase science",
    ]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("events:\n  - at 5s explode PN2\n", ":2:5: unknown action 'explode'"),
        ("events:\n  - at 5s kill PN9\n", ":2:5: node 'PN9' is not in the mission"),
        ("events:\n  - at 5s phase downlink\n", "phase 'downlink' is not in the mission"),
        ("events:\n  - kill PN2 at 5s\n", "expected 'at TIME ACTION ARGUMENT'"),
        ("events:\n  - at soon kill PN2\n", "'soon' is not a duration"),
        ("duration: 4s\nevents:\n  - at 5s kill PN2\n", "after the end of the run"),
        ("events: at 5s kill PN2\n", "events must be a list"),
        ("evnts: []\n", ":1:1: unknown key 'evnts'"),
        ("events: [\n", "not valid YAML"),
        ("random: {seed: 1, kils: 2}\n", "unknown key(s) in random: kils"),
        ("- at 5s kill PN2\n", "a scenario is a mapping"),
    ],
)
def test_bad_scenarios(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(ScenarioError) as caught:
        load_scenario(write(tmp_path, text), NODES, PROCESSING, PHASES)
    assert message in str(caught.value)
    assert str(tmp_path / "s.yaml") in str(caught.value)


def test_random_campaign_is_reproducible(tmp_path: Path) -> None:
    text = "duration: 20s\nrandom: {seed: 7, kills: 3, restart_after: 2s, between: [2s, 12s]}\n"
    first = load_scenario(write(tmp_path, text), NODES, PROCESSING, PHASES).events
    again = load_scenario(write(tmp_path, text), NODES, PROCESSING, PHASES).events
    assert first == again
    kills = [e for e in first if e.action == "kill"]
    assert len(kills) == 3 and all(e.argument in PROCESSING for e in kills)
    assert len([e for e in first if e.action == "restart"]) == 3


def test_random_without_restart_never_kills_a_node_twice(tmp_path: Path) -> None:
    text = "duration: 20s\nrandom: {seed: 3, kills: 5}\n"
    events = load_scenario(write(tmp_path, text), NODES, PROCESSING, PHASES).events
    killed = [e.argument for e in events]
    assert len(killed) == len(set(killed)) == 3  # only three processing nodes exist


def test_a_ground_recovery_names_a_configuration_of_the_mission(tmp_path: Path) -> None:
    configs = {"P1", "P2", "P3", "P4", "S1"}
    scenario = load_scenario(write(tmp_path, "events:\n  - at 3s recover P1\n"), NODES, PROCESSING,
                             PHASES, configs)
    assert [str(e) for e in scenario.events] == ["at 3s recover P1"]
    with pytest.raises(ScenarioError, match=r"s.yaml:2:5: configuration 'P9' is not in the mission"):
        load_scenario(write(tmp_path, "events:\n  - at 3s recover P9\n"), NODES, PROCESSING, PHASES,
                      configs)


def test_a_pause_names_a_task_of_the_mission(tmp_path: Path) -> None:
    # The ground's pause-task and resume-task (docs/operations.md) name a task; one the
    # mission lacks is refused at its line.
    tasks = {"taskA", "taskB"}
    scenario = load_scenario(write(tmp_path, "events:\n  - at 3s pause-task taskA\n  - at 4s resume-task taskA\n"),
                             NODES, PROCESSING, PHASES, None, tasks)
    assert [str(e) for e in scenario.events] == ["at 3s pause-task taskA", "at 4s resume-task taskA"]
    with pytest.raises(ScenarioError, match=r"s.yaml:2:5: task 'taskZ' is not in the mission"):
        load_scenario(write(tmp_path, "events:\n  - at 3s pause-task taskZ\n"), NODES, PROCESSING, PHASES,
                      None, tasks)
