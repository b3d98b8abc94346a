"""What the console's tests and its benchmark share.

Run directories without a cluster: keel-sim traces split per node, as keel-node writes them
(`NAME.trace.ndjson`; the simulator's `env` lines, which keel-node never writes, in
`env.trace.ndjson`), beside the mission image `keel-verify compile` writes. `Writer`
appends their lines as a running cluster would.

The browser: headless Chromium (Debian's chromium and chromium-driver) driven by Selenium,
with nothing downloaded (`chromium()`), and `shows()`, which waits for the page to show
something and fails when it does not in time.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

ROOT = Path(os.environ.get("KEEL_ROOT", Path(__file__).resolve().parents[2]))
BUILD = Path(os.environ.get("KEEL_BUILD_DIR", ROOT / "build" / "default"))


def keel_sim() -> Path:
    path = BUILD / "nodes" / "sim" / "keel-sim"
    if not path.is_file():
        raise FileNotFoundError(f"keel-sim is not built in {BUILD} (./keel setup)")
    return path


def simulate(mission: str, seed: int, folder: Path) -> tuple[list[dict[str, Any]], str]:
    """keel-sim's trace of one seed (its lines in time order) and its `-v` report."""
    trace = folder / f"sim-{Path(mission).stem}-{seed}.ndjson"
    done = subprocess.run([str(keel_sim()), "run", str(ROOT / mission), "--seed", str(seed),
                           "--trace", str(trace), "-v"], capture_output=True, text=True, timeout=120,
                          check=False)
    if done.returncode != 0 or not trace.is_file():
        raise RuntimeError(f"keel-sim run {mission} --seed {seed} failed: {done.stderr[-2000:]}")
    lines = [json.loads(text) for text in trace.read_text().splitlines() if text.strip()]
    lines.sort(key=lambda line: line["t_ns"])
    return lines, done.stdout


def compile_image(mission: str, run_dir: Path) -> Path:
    run_dir.mkdir(parents=True, exist_ok=True)
    image = run_dir / f"{Path(mission).stem}.image.json"
    done = subprocess.run([sys.executable, "-m", "keel_verify.cli", "compile", str(ROOT / mission),
                           "-o", str(image)], capture_output=True, text=True, timeout=300, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"keel-verify compile {mission} failed: {done.stdout[-2000:]}{done.stderr[-2000:]}")
    return image


def file_of(line: dict[str, Any]) -> str:
    return f"{line['node'] or 'env'}.trace.ndjson"


def encode(line: dict[str, Any]) -> str:
    # keel-node's order of keys: t_ns and node first (the console reads them first).
    return json.dumps(line, separators=(",", ":")) + "\n"


class Writer:
    """Appends trace lines to a run directory's per-node files, flushed line by line, as
    keel-node does after each loop iteration."""

    def __init__(self, run_dir: Path):
        self.run_dir = run_dir
        run_dir.mkdir(parents=True, exist_ok=True)

    def write(self, lines: list[dict[str, Any]]) -> None:
        by_file: dict[str, list[str]] = {}
        for line in lines:
            by_file.setdefault(file_of(line), []).append(encode(line))
        for name, texts in by_file.items():
            with open(self.run_dir / name, "a", encoding="utf-8") as handle:
                handle.write("".join(texts))

    def write_raw(self, name: str, text: str) -> None:
        with open(self.run_dir / name, "a", encoding="utf-8") as handle:
            handle.write(text)


def run_dir_of(lines: list[dict[str, Any]], run_dir: Path) -> Path:
    """A finished run directory holding `lines`."""
    Writer(run_dir).write(lines)
    return run_dir


def first(lines: list[dict[str, Any]], fsm: str, action: str, after_ns: int = -1) -> dict[str, Any]:
    return next(x for x in lines if x["fsm"] == fsm and x["action"] == action and x["t_ns"] > after_ns)


# --- The browser ---------------------------------------------------------------------------

CHROMIUM = Path("/usr/bin/chromium")
CHROMEDRIVER = Path("/usr/bin/chromedriver")
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--window-size=1400,1300",
                  # No name resolves but 127.0.0.1: anything the page would load from the
                  # network fails, and page_problems() reports the failed load.
                  "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1"]
# Screenshots: the test's output folder in the build (KEEL_TEST_ARTIFACTS chooses another).
ARTIFACTS = Path(os.environ.get("KEEL_TEST_ARTIFACTS") or BUILD / "tests" / "cluster" / "console-browser")

# What the page shows, read in one round trip.
READ_PAGE = """
const text = (id) => document.getElementById(id).textContent;
return {config: text('current-config'), master: text('current-master'), clock: text('clock'),
        connection: text('connection'),
        notice: document.getElementById('notice').hidden ? '' : text('notice'),
        play: text('play'),
        events: [...document.querySelectorAll('#events li')].slice(0, 60).map((li) => li.textContent),
        measures: [...document.querySelectorAll('#measures tbody tr')].filter((tr) => tr.cells.length > 1)
          .map((tr) => [...tr.cells].map((td) => td.textContent)),
        nodes: Object.fromEntries([...document.querySelectorAll('#nodes tbody tr')].map((tr) =>
          [tr.id.slice(5), {role: tr.querySelector('.role').textContent,
                            epoch: tr.querySelector('.epoch').textContent,
                            config: tr.querySelector('.config').textContent,
                            tasks: tr.querySelector('.tasks').textContent,
                            state: tr.querySelector('.state').textContent}])),
        address: location.hash};
"""


class BrowserMissing(Exception):
    pass


@contextmanager
def chromium() -> Iterator[Any]:
    """A headless Chromium under Selenium; BrowserMissing says what to install."""
    missing = [str(p) for p in (CHROMIUM, CHROMEDRIVER) if not p.is_file()]
    if missing:
        raise BrowserMissing(f"{', '.join(missing)} missing: ./keel test installs Debian's chromium and "
                             "chromium-driver (setup_browser)")
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        raise BrowserMissing("selenium is not installed: ./keel setup installs nodes/cluster[dev]") from None
    os.environ["SE_OFFLINE"] = "true"  # Selenium Manager downloads nothing
    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for flag in CHROMIUM_FLAGS:
        options.add_argument(flag)
    profile = tempfile.mkdtemp(prefix="keel-console-chromium-")
    options.add_argument(f"--user-data-dir={profile}")
    driver = webdriver.Chrome(options=options, service=Service(str(CHROMEDRIVER)))
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def read_page(browser: Any) -> dict[str, Any]:
    return browser.execute_script(READ_PAGE)


def shows(browser: Any, what: str, check: Callable[[dict[str, Any]], bool], within_s: float) -> float:
    """Seconds until the page shows `what` (check holds); AssertionError after within_s."""
    start = time.monotonic()
    page: dict[str, Any] = {}
    while time.monotonic() - start <= within_s:
        page = read_page(browser)
        if check(page):
            return time.monotonic() - start
        time.sleep(0.02)
    raise AssertionError(f"the page did not show {what} within {within_s:g} s; it shows "
                         f"{json.dumps({k: page.get(k) for k in ('config', 'master', 'notice')})}, "
                         f"events {page.get('events', [])[:5]}")


def page_problems(browser: Any, closed: bool = False) -> list[str]:
    """What went wrong in the page since the last call: uncaught JavaScript errors, what its
    Content-Security-Policy refused, and loads that failed (`closed`: but for those from the
    console's own address the browser makes once the console has closed, its stream's
    reconnections and the icon)."""
    problems = []
    for entry in browser.get_log("browser"):
        message = entry["message"]
        if closed and message.startswith("http://127.0.0.1:") and "net::ERR_CONNECTION_REFUSED" in message:
            continue
        if ("Uncaught" in message or "Content Security Policy" in message or "Failed to load" in message
                or "net::ERR" in message or entry.get("source") in ("network", "security")):
            problems.append(message)
    return problems


def said(page: dict[str, Any], text: str) -> bool:
    return any(text in row for row in page["events"])


def screenshot(browser: Any, name: str) -> Path:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    browser.save_screenshot(str(path))
    return path
