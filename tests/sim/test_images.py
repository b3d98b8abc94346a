"""keel-sim flies what a node flies (nodes/sim/src/mission_image.hpp): a mission YAML is
compiled to a proven image first (cached by content), an unproved one is refused, and an
image runs exactly as the YAML it was compiled from."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("KEEL_BUILD_DIR", ROOT / "build" / "default"))
SIM = BUILD / "nodes" / "sim" / "keel-sim"
PROTOTYPE3 = ROOT / "config" / "prototype3.yaml"
PROTOTYPE3_IMAGE = ROOT / "tests" / "missions" / "images" / "good" / "prototype3.json"
UNPROVED = ROOT / "tests" / "missions" / "good" / "everything.yaml"


def sim(tmp: Path, mission: Path, **env: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(SIM), "run", str(mission), "--seed", "3", "--duration", "2s"],
                          capture_output=True, text=True, timeout=120, check=False,
                          env={**os.environ, "TMPDIR": str(tmp), **env})


def test_a_yaml_is_compiled_once_and_runs_as_its_image(tmp_path: Path) -> None:
    first = sim(tmp_path, PROTOTYPE3)
    assert first.returncode == 0, first.stderr
    assert "PROVED" in first.stderr  # compile's report, on stderr
    (cached,) = (tmp_path / "keel-sim-images").glob("*.json")
    os.utime(cached, (1_000_000, 1_000_000))
    again = sim(tmp_path, PROTOTYPE3)
    assert again.returncode == 0 and "PROVED" not in again.stderr  # the cached image
    assert cached.stat().st_mtime > 1_000_000  # used now: the cache keeps it longest
    image = sim(tmp_path, PROTOTYPE3_IMAGE)
    assert image.returncode == 0, image.stderr
    assert first.stdout == again.stdout == image.stdout


def test_the_cache_keeps_the_256_most_recently_used_images(tmp_path: Path) -> None:
    # 300 images compiled before, the oldest first; one of the oldest used since. Adding
    # prototype3's removes the 45 least recently used: the one used since stays.
    cache = tmp_path / "keel-sim-images"
    cache.mkdir()
    old = [cache / f"{i:064x}.json" for i in range(300)]
    for age, image in enumerate(reversed(old), start=1):
        image.write_text("{}")
        os.utime(image, (1_000_000 - age, 1_000_000 - age))
    os.utime(old[0], None)  # used now
    done = sim(tmp_path, PROTOTYPE3)
    assert done.returncode == 0, done.stderr
    kept = set(cache.glob("*.json"))
    assert len(kept) == 256
    assert old[0] in kept and set(old[1:46]).isdisjoint(kept) and set(old[46:]) <= kept
    assert len(kept - set(old)) == 1  # prototype3's


def test_an_unproved_mission_does_not_fly(tmp_path: Path) -> None:
    done = sim(tmp_path, UNPROVED)
    assert done.returncode == 2 and done.stdout == ""
    assert "keel-sim flies only a proven mission" in done.stderr
    assert not list((tmp_path / "keel-sim-images").glob("*.json"))


def test_without_the_verifier_a_yaml_is_refused_saying_how_to_compile(tmp_path: Path) -> None:
    done = sim(tmp_path, PROTOTYPE3, KEEL_PYTHON=str(tmp_path / "no-python"))
    assert done.returncode == 2 and done.stdout == ""
    assert "keel-verify compile" in done.stderr and "KEEL_PYTHON" in done.stderr


def test_a_bad_disk_fault_class_or_expected_rate_is_refused_with_exit_2(tmp_path: Path) -> None:
    cases = ((["--disk-faults", "storage-melts"], "unknown --disk-faults 'storage-melts'"),
             (["--expect-rate", "0.9"], "--expect-rate needs --expect"),
             (["--expect", "DurableStateInv", "--expect-rate", "1.5"], "a rate in (0, 1]"))
    for args, says in cases:
        done = subprocess.run([str(SIM), "campaign", str(PROTOTYPE3_IMAGE), "--seeds", "2",
                               *args],
                              capture_output=True, text=True, timeout=120, check=False,
                              env={**os.environ, "TMPDIR": str(tmp_path)})
        assert done.returncode == 2 and done.stdout == "", (args, done.stdout, done.stderr)
        assert says in done.stderr, (args, done.stderr)
