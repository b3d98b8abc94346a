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
from console_runs import Writer, page_problems, read_page, said, screenshot, shows  # noqa: E402

WITHIN_S = 1.0  # the page shows a new line within a second (the one check of speed)
WAIT_S = 60.0  # any other wait for the page: generous, it is not a measure
MISSION = "config/prototype3.yaml"
MS = 1_000_000


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
    shows(browser, f"the initial configuration {initial}", lambda page: page["config"] == initial, WAIT_S)


def line(t_ms: float, node: str, fsm: str, action: str, variables: dict[str, Any] | None = None,
         **args: object) -> dict[str, Any]:
    return {"t_ns": int(t_ms * MS), "node": node, "fsm": fsm, "action": action, "args": args,
            "vars": variables or {}}


def server_state(feed: console.Feed, lines_written: int) -> dict[str, Any]:
    """The server's state once its feed has folded every line written and a pass found
    nothing more (a copy, taken under its lock)."""
    with feed.lock:
        assert feed.lock.wait_for(lambda: feed.fold.lines >= lines_written and feed.quiet, WAIT_S), \
            f"the feed folded {feed.fold.lines} of {lines_written} lines in {WAIT_S:g} s"
        return json.loads(json.dumps(feed.fold.state))


def shows_state(browser: Any, state: dict[str, Any]) -> None:
    """Waits until every node's row shows the role, the configuration and the hold the
    server's state has."""
    def agrees(page: dict[str, Any]) -> bool:
        return set(page["nodes"]) >= set(state["nodes"]) and all(
            node["role"] == (state["nodes"].get(name, {}).get("role") or "-")
            and node["config"] == str(state["nodes"].get(name, {}).get("config", "-"))
            and ("held (no lease)" in node["state"]) == bool(state["nodes"].get(name, {}).get("held"))
            for name, node in page["nodes"].items())

    shows(browser, "the server's state", agrees, WAIT_S)


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
        # What the page derives agrees with the server's state, once both have everything.
        shows_state(browser, server_state(server.feed, len(before) + len(during)))
        screenshot(browser, "live-exclusion")
        assert page_problems(browser) == []
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
        shows(browser, sentence, lambda page: said(page, sentence) and page["config"] == config, WAIT_S)
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
        shows(browser, "that it waits for traces", lambda page: "Waiting for traces" in page["notice"], WAIT_S)
        screenshot(browser, "waiting")
        shutil.copy(simulated[1], run_dir)
        Writer(run_dir).write(lines[:400])
        shows(browser, "the nodes", lambda page: "Waiting" not in page["notice"] and "PN1" in page["nodes"]
              and page["nodes"]["PN1"]["role"] != "-", WAIT_S)
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
              and not said(page, sentence) and page["clock"].startswith(f"t = +{middle:.3f}"), WAIT_S)
        screenshot(browser, "replay-before")
        # A replay has no cluster to command: no command line on the page.
        assert not browser.find_element("id", "command").is_displayed()
        # Play from there: the exclusion comes.
        browser.find_element("id", "play").click()
        shows(browser, "the exclusion played back", lambda page: said(page, sentence) and page["config"] == config,
              WAIT_S)
        browser.find_element("id", "play").click()  # pause
        shows(browser, "the play button", lambda page: page["play"] == "Play", WAIT_S)
        paused = read_page(browser)["clock"]  # drawn by the render that showed the button
        time.sleep(0.5)
        assert read_page(browser)["clock"] == paused
        assert read_page(browser)["address"].startswith("#t=")
        # Seek to the end: the run's last configuration.
        browser.execute_script("const s = document.getElementById('seek'); s.value = 1000;"
                               "s.dispatchEvent(new Event('input'));")
        shows(browser, f"the final configuration {final}", lambda page: page["config"] == final, WAIT_S)
        # And back to the start: the state is rebuilt, nothing of the end remains.
        browser.execute_script("const s = document.getElementById('seek'); s.value = 0;"
                               "s.dispatchEvent(new Event('input'));")
        shows(browser, "the start of the run", lambda page: not said(page, sentence)
              and page["config"] in ("-", "P1"), WAIT_S)
        browser.find_element("id", "live").click()
        shows(browser, "the end again", lambda page: page["config"] == final, WAIT_S)
        screenshot(browser, "replay-end")
        assert page_problems(browser) == []
    finally:
        server.close()


def test_events_that_arrive_out_of_order_take_their_place(browser: Any, tmp_path: Path) -> None:
    # PN1's lines first; then PN2's and ST1's, older, as a node whose file is read later: a
    # few (put in place one by one) and many (sorted).
    run_dir = tmp_path / "run"
    server = serve(console.Feed(run_dir))
    written = 0
    try:
        batches = [[line(start + step * k, node, "switch", "Hold" if k % 2 else "Release", n=node)
                    for k in range(count)]
                   for node, start, step, count in (("PN1", 1000, 10, 60), ("PN2", 1005, 40, 10),
                                                    ("ST1", 1002, 4, 100))]
        browser.get(server.url)
        rows = ("return [...document.querySelectorAll('#events li')]"
                ".map((li) => [Number(li.dataset.t), Number(li.dataset.i)]);")
        for batch in batches:
            Writer(run_dir).write(batch)
            written += len(batch)
            state = server_state(server.feed, written)
            shows_state(browser, state)
            # Every line is a row (170 in all, fewer than the list's 200), newest first.
            listed: list[list[int]] = []
            deadline = time.monotonic() + WAIT_S
            while len(listed) < written and time.monotonic() < deadline:
                listed = browser.execute_script(rows)
            assert len(listed) == written and listed == sorted(listed, reverse=True), batch[0]["node"]
        # Rebuilt from the start, the page's state is the server's.
        browser.execute_script("const s = document.getElementById('seek'); s.value = 0;"
                               "s.dispatchEvent(new Event('input'));")
        browser.find_element("id", "live").click()
        shows_state(browser, state)
        assert page_problems(browser) == []
    finally:
        server.close()


def test_the_whole_run_timeline_draws_the_newest_markers(browser: Any, tmp_path: Path) -> None:
    run_dir = tmp_path / "run"
    lines = [line(10 * k, "PN1", "switch", "Hold" if k % 2 else "Release", n="PN1") for k in range(6000)]
    lines.append(line(60_000, "PN2", "heartbeat", "DeclareFailed", m="PN2", n="LAST"))
    Writer(run_dir).write(lines)
    server = serve(console.Feed(run_dir))
    try:
        browser.get(server.url)
        shows(browser, "the last line", lambda page: said(page, "PN2 declares LAST failed"), WAIT_S)
        browser.execute_script("const w = document.getElementById('window'); w.value = '0';"
                               "w.dispatchEvent(new Event('change'));")
        drawn = ("return [...document.querySelectorAll('#timeline title')]"
                 ".some((t) => t.textContent.includes(arguments[0]));")
        deadline = time.monotonic() + WAIT_S
        while not browser.execute_script(drawn, "PN2 declares LAST failed"):
            assert time.monotonic() < deadline, "the timeline of the whole run does not draw its newest marker"
            time.sleep(0.1)
        assert browser.execute_script(
            "return document.querySelectorAll('#timeline .m').length;") == 4000
        screenshot(browser, "whole-run-markers")
        assert page_problems(browser) == []
    finally:
        server.close()


HOSTILE = "<img src=x onerror=window.keelPwned=1>"


@pytest.mark.parametrize("checked", [True, False], ids=["the-server-drops-it", "the-page-escapes-it"])
def test_hostile_trace_values_are_text_and_the_page_keeps_updating(
        browser: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, checked: bool) -> None:
    if not checked:  # the server's checks of each field's type off: what the page does alone
        monkeypatch.setattr(console, "FIELD_TYPES", {})
    run_dir = tmp_path / "run"
    server = serve(console.Feed(run_dir))
    try:
        Writer(run_dir).write([line(100, "PN1", "heartbeat", "Tick", {"missed": {"PN2": HOSTILE}}, m="PN1",
                                    late=False, silent=False),
                               line(110, "PN2", "switch", "Activate", {"active": HOSTILE, "role": HOSTILE},
                                    n="PN2", t=HOSTILE),
                               line(120, HOSTILE, "switch", "Hold", n=HOSTILE)])
        browser.get(server.url)
        shows(browser, "the hostile node's hold", lambda page: said(page, f"{HOSTILE} holds its tasks"), WAIT_S)
        Writer(run_dir).write([line(200, "PN1", "switch", "Release", n="PN1")])
        shows(browser, "a line after them", lambda page: said(page, "PN1 releases its tasks"), WAIT_S)
        assert browser.execute_script("return document.querySelectorAll('img').length;") == 0
        assert browser.execute_script("return window.keelPwned === undefined;")
        cells = browser.execute_script("return [...document.querySelectorAll('#links td')]"
                                       ".map((td) => td.textContent);")
        assert (HOSTILE in cells) == (not checked)
        assert read_page(browser)["nodes"][HOSTILE]["state"].startswith("up")
        screenshot(browser, f"hostile-{'checked' if checked else 'escaped'}")
        assert page_problems(browser) == []
    finally:
        server.close()


class FailingFeed(console.Feed):
    """A feed whose pass fails once when told."""

    fail = False

    def poll_once(self) -> bool:
        if self.fail:
            self.fail = False
            raise RuntimeError("a pass that fails")
        return super().poll_once()


def test_the_page_says_when_the_feed_failed_and_goes_on(browser: Any, tmp_path: Path) -> None:
    run_dir = tmp_path / "run"
    feed = FailingFeed(run_dir)
    server = serve(feed)
    try:
        Writer(run_dir).write([line(100, "PN1", "switch", "Hold", n="PN1")])
        browser.get(server.url)
        shows(browser, "the first line", lambda page: said(page, "PN1 holds its tasks"), WAIT_S)
        feed.fail = True
        shows(browser, "the failure", lambda page: "RuntimeError: a pass that fails" in page["notice"], WAIT_S)
        Writer(run_dir).write([line(200, "PN1", "switch", "Release", n="PN1")])
        shows(browser, "the next line", lambda page: said(page, "PN1 releases its tasks"), WAIT_S)
        assert page_problems(browser) == []
    finally:
        server.close()
