"""The console in a real browser: headless Chromium (Debian's chromium and chromium-driver,
installed by ./keel's setup_browser) driven by Selenium, on run directories written here
from keel-sim traces as a running cluster writes them. Screenshots are kept in the test's
output folder under the build directory (KEEL_TEST_ARTIFACTS chooses another).

Each check waits for the page to show something; `test_a_page_whose_feed_is_frozen_fails_
the_check` and `test_a_page_that_stops_applying_events_fails_the_check` show that the same
check fails when the page stops updating.
"""

from __future__ import annotations

import json
import shutil
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from keel_cluster import console

sys.path.insert(0, str(Path(__file__).resolve().parent))
import console_runs  # noqa: E402
from console_runs import Writer, read_page, said, screenshot, script_errors, shows  # noqa: E402

WITHIN_S = 1.0  # the page shows a new line within a second
MISSION = "config/prototype3.yaml"


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    try:
        with console_runs.chromium() as driver:
            yield driver
    except console_runs.BrowserMissing as missing:
        pytest.fail(str(missing))


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory) -> tuple[list[dict[str, Any]], Path]:
    """prototype3, seed 2 (PN3 crashes and restarts, then the Master PN1 crashes), and its image."""
    folder = tmp_path_factory.mktemp("sim")
    lines, _ = console_runs.simulate(MISSION, 2, folder)
    return lines, console_runs.compile_image(MISSION, folder / "image")


def fresh_run(simulated: tuple[list[dict[str, Any]], Path], folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(simulated[1], folder)
    return folder


def the_fault(lines: list[dict[str, Any]]) -> tuple[list[dict[str, Any]], list[dict[str, Any]], str, str]:
    """The lines before PN3's crash, those from it to the switch that follows, the sentence
    of the Master's exclusion and the configuration it leads to."""
    crash = console_runs.first(lines, "env", "Crash")
    exclude = console_runs.first(lines, "switch", "Exclude", crash["t_ns"])
    complete = console_runs.first(lines, "switch", "CompleteSwitch", exclude["t_ns"])
    before = [x for x in lines if x["t_ns"] < crash["t_ns"]]
    during = [x for x in lines if crash["t_ns"] <= x["t_ns"] <= complete["t_ns"]]
    sentence = f"{exclude['node']} excludes {exclude['args']['f']} -> {exclude['args']['c']}"
    return before, during, sentence, complete["args"]["c"]


class FrozenFeed(console.Feed):
    """A feed that stops reading the run directory when told: a console whose page stops
    updating."""

    frozen = False

    def poll_once(self) -> bool:
        if self.frozen:
            return False
        return super().poll_once()


def serve(feed: console.Feed, static_dir: Path = console.STATIC_DIR) -> console.ConsoleServer:
    server = console.ConsoleServer(feed, 0, static_dir)
    server.start()
    return server


def open_live(browser: Any, server: console.ConsoleServer, before: list[dict[str, Any]], run_dir: Path) -> None:
    Writer(run_dir).write(before)
    browser.get(server.url)
    initial = next(x for x in before if x["action"] == "CompleteSwitch")["args"]["c"]
    shows(browser, f"the initial configuration {initial}", lambda page: page["config"] == initial, 15)


def test_the_page_shows_an_exclusion_and_the_new_configuration_within_a_second(
        browser: Any, simulated: tuple[list[dict[str, Any]], Path], tmp_path: Path) -> None:
    lines, _ = simulated
    before, during, sentence, config = the_fault(lines)
    run_dir = fresh_run(simulated, tmp_path / "run")
    server = serve(console.Feed(run_dir))
    try:
        open_live(browser, server, before, run_dir)
        # Up to the Master's exclusion: the cluster's configuration is the one the Master
        # decided on, before the nodes have switched to it.
        decided = next(k for k, x in enumerate(during) if x["action"] == "Exclude") + 1
        Writer(run_dir).write(during[:decided])
        delay = shows(browser, f"'{sentence}' and configuration {config}",
                      lambda page: said(page, sentence) and page["config"] == config, WITHIN_S)
        print(f"the page showed the exclusion {delay * 1000:.0f} ms after it was written")
        master = during[decided - 1]["node"]
        assert read_page(browser)["nodes"][master]["config"] != config  # its own switch comes next
        Writer(run_dir).write(during[decided:])
        shows(browser, f"{master} in {config}", lambda page: page["nodes"][master]["config"] == config, WITHIN_S)
        page = read_page(browser)
        assert said(page, "Crash n=PN3"), page["events"]
        # What the page derives agrees with the server's state.
        state = json.loads(json.dumps(server.feed.fold.state))
        for name, node in page["nodes"].items():
            known = state["nodes"].get(name, {})
            assert node["role"] == known.get("role", "-") and node["config"] == known.get("config", "-"), name
        screenshot(browser, "live-exclusion")
        assert script_errors(browser) == []
    finally:
        server.close()


def test_a_page_whose_feed_is_frozen_fails_the_check(
        browser: Any, simulated: tuple[list[dict[str, Any]], Path], tmp_path: Path) -> None:
    lines, _ = simulated
    before, during, sentence, config = the_fault(lines)
    run_dir = fresh_run(simulated, tmp_path / "run")
    feed = FrozenFeed(run_dir)
    server = serve(feed)
    try:
        open_live(browser, server, before, run_dir)
        feed.frozen = True
        Writer(run_dir).write(during)
        with pytest.raises(AssertionError, match="did not show"):
            shows(browser, sentence, lambda page: said(page, sentence) and page["config"] == config, WITHIN_S)
        screenshot(browser, "frozen-feed")
        feed.frozen = False  # the same check passes once the feed reads again
        shows(browser, sentence, lambda page: said(page, sentence) and page["config"] == config, 5)
    finally:
        server.close()


def test_a_page_that_stops_applying_events_fails_the_check(
        browser: Any, simulated: tuple[list[dict[str, Any]], Path], tmp_path: Path) -> None:
    # A mutant of the page: once told, it drops what the feed sends.
    lines, _ = simulated
    before, during, sentence, config = the_fault(lines)
    mutant = tmp_path / "page"
    shutil.copytree(console.STATIC_DIR, mutant)
    script = (mutant / "console.js").read_text()
    original = "    receive(message.events || []);"
    assert original in script
    (mutant / "console.js").write_text(script.replace(original, "    if (!window.keelMutant) " + original.strip()))
    run_dir = fresh_run(simulated, tmp_path / "run")
    server = serve(console.Feed(run_dir), mutant)
    try:
        open_live(browser, server, before, run_dir)
        browser.execute_script("window.keelMutant = true;")
        Writer(run_dir).write(during)
        with pytest.raises(AssertionError, match="did not show"):
            shows(browser, sentence, lambda page: said(page, sentence) and page["config"] == config, WITHIN_S)
    finally:
        server.close()


def test_the_page_says_it_waits_for_traces_then_shows_them(
        browser: Any, simulated: tuple[list[dict[str, Any]], Path], tmp_path: Path) -> None:
    lines, _ = simulated
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    server = serve(console.Feed(run_dir))
    try:
        browser.get(server.url)
        shows(browser, "that it waits for traces", lambda page: "Waiting for traces" in page["notice"], 10)
        screenshot(browser, "waiting")
        shutil.copy(simulated[1], run_dir)
        Writer(run_dir).write(lines[:400])
        shows(browser, "the nodes", lambda page: "Waiting" not in page["notice"] and "PN1" in page["nodes"]
              and page["nodes"]["PN1"]["role"] != "-", 5)
    finally:
        server.close()


def test_a_finished_run_plays_back(browser: Any, simulated: tuple[list[dict[str, Any]], Path],
                                   tmp_path: Path) -> None:
    lines, _ = simulated
    run_dir = fresh_run(simulated, tmp_path / "run")
    Writer(run_dir).write(lines)
    (run_dir / "report.json").write_text(json.dumps({"events": []}))
    _, during, sentence, config = the_fault(lines)
    t0 = lines[0]["t_ns"]
    crash_s = (during[0]["t_ns"] - t0) / 1e9
    first_switch_s = (next(x for x in lines if x["action"] == "CompleteSwitch")["t_ns"] - t0) / 1e9
    final = [x for x in lines if x["action"] == "CompleteSwitch"][-1]["args"]["c"]
    server = serve(console.Feed(run_dir))
    try:
        # A link to a time in the run opens there, paused.
        middle = (first_switch_s + crash_s) / 2
        browser.get(f"{server.url}#t={middle:.3f}")
        shows(browser, "the run before the crash", lambda page: page["config"] == "P1"
              and not said(page, sentence) and page["clock"].startswith(f"t = +{middle:.3f}"), 10)
        screenshot(browser, "replay-before")
        # Play from there: the exclusion comes, at 1x, about its time after the crash.
        browser.find_element("id", "play").click()
        shows(browser, "the exclusion played back", lambda page: said(page, sentence) and page["config"] == config,
              5 + crash_s - middle)
        browser.find_element("id", "play").click()  # pause
        time.sleep(0.3)  # the render that shows where it paused
        paused = read_page(browser)["clock"]
        time.sleep(0.5)
        assert read_page(browser)["clock"] == paused
        assert read_page(browser)["address"].startswith("#t=")
        # Seek to the end: the run's last configuration.
        browser.execute_script("const s = document.getElementById('seek'); s.value = 1000;"
                               "s.dispatchEvent(new Event('input'));")
        shows(browser, f"the final configuration {final}", lambda page: page["config"] == final, 5)
        # And back to the start: the state is rebuilt, nothing of the end remains.
        browser.execute_script("const s = document.getElementById('seek'); s.value = 0;"
                               "s.dispatchEvent(new Event('input'));")
        shows(browser, "the start of the run", lambda page: not said(page, sentence)
              and page["config"] in ("-", "P1"), 5)
        browser.find_element("id", "live").click()
        shows(browser, "the end again", lambda page: page["config"] == final, 5)
        screenshot(browser, "replay-end")
        assert script_errors(browser) == []
    finally:
        server.close()
