"""The SDK as a team uses it (docs/components.md): `cmake --install` of this build into a
temporary prefix, then, outside Keel's tree and against that prefix only,

- examples/custom-component configured with find_package(Keel), built (its component, its
  node binary made by keel_add_node, its unit tests), its tests run, its mission proved and
  compiled by keel-verify, and the binary flown on a small insecure keel-cluster run whose
  logs must show the component checking, alarming, taking its phase's limits and resuming
  from its checkpoint on another node;
- what `./keel new component NAME` writes, built and tested the same way, and the names and
  folders it refuses.

Only the two small projects are compiled; Keel itself is not built again.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(os.environ.get("KEEL_ROOT", Path(__file__).resolve().parents[2]))
BUILD = Path(os.environ.get("KEEL_BUILD_DIR", ROOT / "build" / "default"))
EXAMPLE = ROOT / "examples" / "custom-component"
VERSION = (ROOT / "VERSION").read_text().strip()
sys.path.insert(0, str(ROOT / "tests"))
from docblocks import differs, text_block  # noqa: E402


def run(command: list[str], *, timeout: float = 600, cwd: Path | None = None,
        expect: int | None = 0) -> subprocess.CompletedProcess[str]:
    done = subprocess.run(command, capture_output=True, text=True, timeout=timeout, cwd=cwd, check=False)
    if expect is not None:
        assert done.returncode == expect, (
            f"{' '.join(command)}: exit {done.returncode}, expected {expect}\n"
            f"--- stdout\n{done.stdout[-6000:]}\n--- stderr\n{done.stderr[-6000:]}")
    return done


@pytest.fixture(scope="module")
def prefix(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """This build of Keel, installed as a team would install it."""
    if not (BUILD / "CMakeCache.txt").is_file():
        pytest.fail(f"{BUILD} is not a configured Keel build (KEEL_BUILD_DIR)")
    out = tmp_path_factory.mktemp("keel-prefix")
    run(["cmake", "--install", str(BUILD), "--prefix", str(out)])
    return out


def build(source: Path, build_dir: Path, prefix: Path) -> None:
    """Configures and builds a project against the installed Keel only (Debug: the quickest
    to compile; what is tested does not depend on optimisation)."""
    generator = ["-G", "Ninja"] if shutil.which("ninja") else []
    # keel_compile_mission() proves the project's mission with the verifier of the Python
    # that runs the tests (the project's venv, wherever KEEL_CACHE put it).
    verifier = Path(sys.executable).parent / "keel-verify"
    run(["cmake", "-S", str(source), "-B", str(build_dir), *generator, "-DCMAKE_BUILD_TYPE=Debug",
         f"-DCMAKE_PREFIX_PATH={prefix}", f"-DKEEL_VERIFY_EXECUTABLE={verifier}"])
    run(["cmake", "--build", str(build_dir), "--parallel", "2"])


def keel_verify(*args: str) -> subprocess.CompletedProcess[str]:
    # The verifier of the Python that runs the tests (the project's venv, wherever
    # KEEL_CACHE put it).
    return run([sys.executable, "-m", "keel_verify.cli", *args], timeout=120)


def test_the_installed_package_has_headers_libraries_and_config(prefix: Path) -> None:
    for path in ["include/keel/core/tasking/component.hpp", "include/keel/core/node/runtime.hpp",
                 "include/keel/node/main.hpp", "include/keel/node/components.hpp",
                 "bin/keel-node", "bin/keel-place"]:
        assert (prefix / path).is_file(), path
    config = next(prefix.glob("lib*/cmake/Keel"))
    for name in ["KeelConfig.cmake", "KeelConfigVersion.cmake", "KeelTargets.cmake", "KeelNode.cmake",
                 "keel_node_main.cpp.in"]:
        assert (config / name).is_file(), name
    assert not list(prefix.rglob("tests")), "no test folder is installed"
    assert list((config.parent.parent).glob("libkeel_node_main.a"))
    assert run([str(prefix / "bin" / "keel-node"), "--version"]).stdout == f"keel-node {VERSION}\n"


def test_the_example_builds_against_the_installed_keel_and_flies(prefix: Path, tmp_path: Path) -> None:
    build_dir = tmp_path / "build"
    build(EXAMPLE, build_dir, prefix)
    tests = run(["ctest", "--test-dir", str(build_dir), "--output-on-failure"], timeout=120)
    assert re.search(r"100% tests passed, 0 tests failed out of [1-9]", tests.stdout), tests.stdout

    node = build_dir / "limit_checker-node"
    components = run([str(node), "--list-components"]).stdout.split()
    assert "limit_checker" in components and "producer" in components, components
    assert run([str(node), "--version"]).stdout == f"limit_checker-node 0.1.0 (Keel {VERSION})\n"
    # docs/components.md shows both outputs as comments of its commands.
    guide = (ROOT / "docs" / "components.md").read_text()
    shown = re.search(r"^build/limit_checker-node --list-components +# (.*)$", guide, re.M)
    assert shown and shown[1].split() == components, (shown and shown[1], components)
    assert f"build/limit_checker-node --version             # limit_checker-node 0.1.0 (Keel {VERSION})" \
        in guide
    # keel-node's command line, under the binary's own name.
    usage = run([str(node), "--mission"], expect=2).stderr
    assert usage.startswith("limit_checker-node: --mission: unknown flag or missing value"), usage

    mission = EXAMPLE / "mission.yaml"
    checked = keel_verify("check", str(mission))
    assert "PROVED valid" in checked.stdout, checked.stdout
    # The guide's console block: what check and compile print, run as it shows them (from
    # the project's folder), numbers as patterns, the image's hash exactly.
    block = re.search(r"```console\n(\$ keel-verify check mission\.yaml\n.*?)```", guide, re.S)
    assert block, "docs/components.md: no console block of keel-verify check mission.yaml"
    shown = [line for line in block[1].splitlines() if not line.startswith("$ ")]
    printed = []
    for command in (["check", "mission.yaml"], ["compile", "mission.yaml", "-o", str(tmp_path / "mission.json")]):
        done = subprocess.run([sys.executable, "-m", "keel_verify.cli", *command], cwd=EXAMPLE, capture_output=True,
                              text=True, timeout=120, check=True)
        printed += done.stdout.replace(str(tmp_path / "mission.json"), "mission.json").splitlines()
    problem = differs(shown, printed)
    assert problem is None, problem
    # The build compiled the mission into its image (keel_compile_mission), checked against
    # the node binary's components.
    image = build_dir / "mission.json"
    assert json.loads(image.read_text())["proof"]["result"] == "proved"

    run_dir = tmp_path / "run"
    flown = run([sys.executable, "-m", "keel_cluster.cli", "run", str(image),
                 "--scenario", str(EXAMPLE / "scenario.yaml"), "--node-binary", str(node),
                 "--insecure", "--run-dir", str(run_dir), "--json", "--quiet"], timeout=120, expect=None)
    logs = {path.stem: path.read_text(errors="replace") for path in run_dir.glob("*.log")}
    assert flown.returncode == 0, f"keel-cluster run: exit {flown.returncode}\n{flown.stderr[-4000:]}\n" + \
        "\n".join(f"--- {name}.log\n{text[-3000:]}" for name, text in logs.items())
    report = json.loads(flown.stdout)
    where = json.dumps(report["final_status"], indent=1)

    # Cruise: PN3 runs the checker with the phase's limit, and the ramp passes it.
    assert "limits: started in phase cruise: telemetry within [0, 5], persistence 3" in logs["PN3"], \
        logs["PN3"]
    assert re.search(r"limits: telemetry \d+ above 5 for 3 samples: alarm 1 raised", logs["PN3"]), logs["PN3"]
    # Science moves it to PN2, configured with the phase's parameters and resumed from its
    # checkpoint; PN2 killed, the Master moves it to PN1 (S3), which resumes it from ST1.
    resumed = r"limits: resumed from checkpoint: (\d+) samples checked, (\d+) alarms raised; " \
              r"phase science: telemetry within \[0, 1000\], persistence 3"
    on_pn2 = re.search(resumed, logs["PN2"])
    assert on_pn2 and int(on_pn2.group(2)) >= 1, logs["PN2"]
    on_pn1 = re.search(resumed, logs["PN1"])
    assert on_pn1 and int(on_pn1.group(1)) > int(on_pn2.group(1)) and int(on_pn1.group(2)) >= 1, \
        logs["PN1"]
    assert "limits" in report["final_status"]["PN1"]["tasks"], where
    assert report["crashed_nodes"] == [], where
    # docs/components.md shows `grep limits: run/PN*.log | sort -t: -k2` of this run.
    grepped = sorted((f"run/{path.name}:{line}" for path in sorted(run_dir.glob("PN*.log"))
                      for line in path.read_text(errors="replace").splitlines()
                      if "limits:" in line), key=lambda line: line.split(":", 1)[1])
    problem = differs(text_block("docs/components.md", "run/PN"), grepped)
    assert problem is None, "docs/components.md's limits log: " + problem

    # A phase change that keeps the checker on its node reconfigures it there: the same
    # mission with S1 placing it on PN3 too, and only the phase change.
    text = mission.read_text()
    moved = "S1: {master: PN1, observers: [PN2, PN3], tasks: {telemetry: PN3, limits: PN2}}"
    assert moved in text
    staying = tmp_path / "staying.yaml"
    staying.write_text(text.replace(moved, moved.replace("limits: PN2", "limits: PN3")))
    (tmp_path / "staying-scenario.yaml").write_text("duration: 7s\nevents:\n  - at 4s phase science\n")
    image = tmp_path / "staying.json"
    keel_verify("compile", str(staying), "-o", str(image))
    run_dir = tmp_path / "staying-run"
    domain = 150 + os.getpid() % 50  # chosen (--domain) and printed
    flown = run([sys.executable, "-m", "keel_cluster.cli", "run", str(image),
                 "--scenario", str(tmp_path / "staying-scenario.yaml"), "--node-binary", str(node),
                 "--insecure", "--run-dir", str(run_dir), "--json", "--quiet",
                 "--domain", str(domain)], timeout=120, expect=None)
    pn3 = (run_dir / "PN3.log").read_text(errors="replace")
    assert flown.returncode == 0, flown.stderr[-4000:] + pn3[-3000:]
    announced = f"keel-cluster: DDS domain {domain} (samples: {(domain + 116) % 231}), insecure"
    assert announced in flown.stderr, flown.stderr
    # A hint that runs as printed, from the checkout (docs/clusters.md, "Watching").
    assert f"keel-cluster: watch it: ./keel dds -- ps -i {domain}" in flown.stderr, flown.stderr
    assert "limits stays here in phase science: reconfigured" in pn3, pn3
    stayed = re.search(resumed, pn3)
    assert stayed and int(stayed.group(2)) >= 1, pn3


def test_a_new_component_configures_and_builds(prefix: Path, tmp_path: Path) -> None:
    project = tmp_path / "projects" / "thermal_guard"
    made = run([str(ROOT / "keel"), "new", "component", "thermal_guard", "--dir", str(project)])
    assert "wrote component 'thermal_guard'" in made.stderr
    # The next steps name where keel-verify and keel-cluster come from, and the console
    # script pip installs runs (docs/components.md).
    assert f"pip install {ROOT}/verify {ROOT}/nodes/cluster" in made.stderr, made.stderr
    assert f"{ROOT}/keel cluster" in made.stderr, made.stderr
    script = Path(sys.executable).parent / "keel-cluster"
    assert "usage: keel-cluster" in run([str(script), "--help"]).stdout
    names = sorted(str(path.relative_to(project)) for path in project.rglob("*") if path.is_file())
    assert names == sorted(["CMakeLists.txt", "README.md", "mission.yaml", "scenario.yaml",
                            "thermal_guard.hpp", "thermal_guard.cpp", "tests/thermal_guard_test.cpp"]), names
    text = "\n".join((project / name).read_text() for name in names)
    assert "limit_checker" not in text and "LimitChecker" not in text and "limit-checker" not in text
    assert "class ThermalGuard final" in text and "mission: thermal-guard-example" in text

    build_dir = tmp_path / "build"
    build(project, build_dir, prefix)
    run(["ctest", "--test-dir", str(build_dir), "--output-on-failure"], timeout=120)
    node = build_dir / "thermal_guard-node"
    assert "thermal_guard" in run([str(node), "--list-components"]).stdout.split()
    assert "PROVED valid" in keel_verify("check", str(project / "mission.yaml")).stdout
    assert (build_dir / "mission.json").is_file()
    # A mission naming a component the node binary lacks fails the build, named.
    text = (project / "mission.yaml").read_text()
    assert "component: thermal_guard" in text
    (project / "mission.yaml").write_text(text.replace("component: thermal_guard",
                                                       "component: thermal_gaurd"))
    broken = run(["cmake", "--build", str(build_dir)], expect=None)
    assert broken.returncode != 0 and "component-missing" in broken.stdout + broken.stderr, \
        broken.stdout[-3000:] + broken.stderr[-3000:]
    assert "thermal_gaurd" in broken.stdout + broken.stderr

    # Refusals: an existing folder, a name that is not one, a built-in component's name.
    again = run([str(ROOT / "keel"), "new", "component", "thermal_guard", "--dir", str(project)], expect=2)
    assert "already exists" in again.stderr
    bad = run([str(ROOT / "keel"), "new", "component", "Thermal-Guard", "--dir", str(tmp_path / "x")], expect=2)
    assert "is not a component name" in bad.stderr and not (tmp_path / "x").exists()
    taken = run([str(ROOT / "keel"), "new", "component", "producer", "--dir", str(tmp_path / "y")], expect=2)
    assert "is taken" in taken.stderr and not (tmp_path / "y").exists()
