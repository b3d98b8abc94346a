"""``keel-verify compile MISSION.yaml [-o MISSION.json] [--sign-key KEY] [--format F]``.

Reads and proves the mission exactly as ``check`` does, and only when it is proved writes
the mission image a node flies (``config/schema/image.schema.json``): the fully resolved
mission, the proof's result, the verifier's version, the capacity, a SHA-256 of the
canonical content and, with a signing key, an Ed25519 signature. A mission the image
cannot hold is refused before it is proved: more nodes or tasks than the runtime's
capacity (``keel_verify/limits.py``), or a number JSON cannot write (``.inf``, ``.nan``).

The image is written to a temporary file beside the output and renamed into place, so
the output path holds either a complete image or what it held before. Compiling the same
file with the same verifier gives the same bytes: the image records no time.

Exit codes: 0 proved, image written; 1 violations; 2 input error (also a bad signing
key, a mission over the capacity, an output that cannot be written); 3 undecided;
4 internal error (the image built breaks its own schema). Only exit 0 writes an image.

Formats: as ``check``'s; ``json`` adds ``"image"`` (the path written, or null), and the CI
formats add a test case ``image`` (and a finding when a proved mission got no image).

Signing key: ``--sign-key KEY`` or the environment variable ``KEEL_SIGNING_KEY`` names an
Ed25519 private key in PEM (``openssl genpkey -algorithm ed25519 -out mission.key``); its
public key (``openssl pkey -in mission.key -pubout -out mission.pub``) goes to the nodes.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import math
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

from keel_verify import __version__, limits, report
from keel_verify.check.cli import (
    add_components_argument,
    build_report,
    components_of,
    input_error_json,
    print_human,
    progress_reporter,
    prove_online,
    to_json,
)
from keel_verify.check.components import ComponentsError
from keel_verify.check.core import InputError, check_file
from keel_verify.check.online import ProverFailed, ProverUnavailable, online_phases
from keel_verify.check.result import UNDECIDED, CheckResult
from keel_verify.image import (
    FORMAT_VERSION,
    MAX_IMAGE_BYTES,
    KeyFileError,
    encode_file,
    key_id,
    load_signing_key,
    schema_errors,
    seal,
)
from keel_verify.mission import MAX_FILE_BYTES, LoadError, Mission

EXIT_PROVED = 0
EXIT_VIOLATIONS = 1
EXIT_INPUT_ERROR = 2
EXIT_UNDECIDED = 3
EXIT_INTERNAL_ERROR = 4

SIGNING_KEY_ENV = "KEEL_SIGNING_KEY"

# The check's statistics an image records: what was proved, not how long it took or how
# the solver got there (those vary from run to run and from one Z3 to another).
PROOF_STATS = (
    "depth",
    "node_failures",
    "tolerance_nodes",
    "phases",
    "configurations",
    "levels",
    "states_bound",
)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "compile",
        help="prove a mission and write the image a node flies",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("mission", help="mission file (YAML, schema 1)")
    parser.add_argument("-o", "--output", metavar="IMAGE",
                        help="where to write the image (default: MISSION with .json suffix)")
    parser.add_argument("--sign-key", metavar="KEY",
                        help=f"Ed25519 private key (PEM) to sign the image with "
                             f"(default: ${SIGNING_KEY_ENV}, if set)")
    report.add_format_arguments(parser)
    parser.add_argument("--max-failures", type=int, metavar="K", default=None,
                        help="explore failure sequences of at most K failures "
                             "(default: every tolerated node); recorded in the image")
    parser.add_argument("--timeout", type=float, metavar="S", default=None,
                        help="give up after S seconds per solver query (undecided, exit 3)")
    parser.add_argument("--progress", action="store_true",
                        help="report every level of the search on stderr")
    add_components_argument(parser)
    parser.set_defaults(func=run)


# --------------------------------------------------------------------------------------
# What an image cannot hold


def _column(lines: list[str], line: int, name: str) -> int:
    """The 1-based column of ``name`` on a 1-based line (1 when it is not found)."""
    if 1 <= line <= len(lines):
        index = lines[line - 1].find(name)
        if index >= 0:
            return index + 1
    return 1


def _non_finite(where: str, value: Any) -> str | None:
    if isinstance(value, float) and not math.isfinite(value):
        return (f"{where} is {value}: a mission image holds only finite numbers "
                "(JSON has no infinity or NaN)")
    return None


def image_errors(mission: Mission, text: str) -> list[LoadError]:
    """What keeps a loaded mission out of an image, as errors at their lines."""
    lines = text.splitlines()
    file = mission.path
    errors: list[LoadError] = []

    def error(line: int, name: str, message: str) -> None:
        errors.append(LoadError(line, _column(lines, line, name), "out-of-range", message, file))

    for what, items, limit in (
        ("nodes", list(mission.nodes.values()), limits.MAX_NODES),
        ("tasks", list(mission.tasks.values()), limits.MAX_TASKS),
    ):
        if len(items) > limit:
            first_over = items[limit]
            error(
                first_over.line,
                first_over.name,
                f"{len(items)} {what}: a mission holds at most {limit} (the runtime's "
                f"capacity); {what[:-1]} {first_over.name} is the {limit + 1}th",
            )
    for task in mission.tasks.values():
        found = []
        if task.health is not None:
            found += [_non_finite(f"task {task.name}: health.min", task.health.min),
                      _non_finite(f"task {task.name}: health.max", task.health.max)]
        found += [_non_finite(f"task {task.name}: params.{k}", v) for k, v in task.params.items()]
        for message in filter(None, found):
            error(task.line, task.name, message)
    for phase in mission.phases.values():
        for task_name, params in phase.params.items():
            for key, value in params.items():
                message = _non_finite(f"phase {phase.name}: params.{task_name}.{key}", value)
                if message:
                    error(phase.line, phase.name, message)
    return sorted(errors)


def _admit(text: str) -> Any:
    def admit(mission: Mission) -> None:
        errors = image_errors(mission, text)
        if errors:
            raise InputError(errors)

    return admit


# --------------------------------------------------------------------------------------
# The image


def image_content(mission: Mission) -> dict[str, Any]:
    """The mission as ``keel-verify load --json`` prints it (every default applied), with
    an ``id`` on each node and task: its index in file order (a node's logical address)."""
    content = mission.to_json()
    for what in ("nodes", "tasks"):
        for index, item in enumerate(content[what]):
            item["id"] = index
    return content


def build_image(mission: Mission, result: CheckResult, source_name: str, source: bytes,
                max_failures: int | None) -> dict[str, Any]:
    """The image of a proved mission, without its hash and signature (see ``seal``)."""
    assert result.valid, "only a proved mission has an image"
    return {
        "keel_image": FORMAT_VERSION,
        "mission": mission.name,
        "verifier": __version__,
        "source": {"file": source_name, "sha256": hashlib.sha256(source).hexdigest()},
        "proof": {
            "result": result.status,
            "max_failures": max_failures,
            **{name: result.stats[name] for name in PROOF_STATS},
        },
        "capacity": limits.capacity(),
        "content": image_content(mission),
    }


def _read_source(path: Path) -> bytes | None:
    try:
        with open(path, "rb") as stream:
            return stream.read(MAX_FILE_BYTES + 1)
    except OSError:
        return None  # the loader reports why


def _write_atomically(path: Path, data: bytes) -> None:
    """Write to a temporary file in the same directory, then rename it over ``path``."""
    fd, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as stream:
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(temporary, 0o666 & ~umask)
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise


# --------------------------------------------------------------------------------------
# The command


def _say(message: str) -> None:
    print(f"keel-verify: compile: {message}", file=sys.stderr)


def _no_image(output: Path) -> None:
    kept = f" ({output} is left as it was)" if output.exists() else ""
    _say(f"no image written{kept}")


def _output_path(args: argparse.Namespace) -> Path:
    mission = Path(args.mission)
    return Path(args.output) if args.output else mission.with_suffix(".json")


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve() or (b.exists() and os.path.samefile(a, b))
    except OSError:
        return False


# Rules of the CI reports beyond check's violation kinds.
IMAGE_RULES = [
    report.Rule("image", "the mission was proved but its image could not be written"),
    report.Rule("input-error", "an argument or file compile needs cannot be used"),
]


def _ci_report(args: argparse.Namespace, code: int, result: CheckResult | None,
               errors: list[LoadError] | None, problem: str, written: str) -> report.Report:
    """check's report (when the mission was read) plus a test case for the image."""
    classname = f"keel-verify.compile.{args.mission}"
    if result is not None or errors is not None:
        outcome = build_report("compile", args.mission, result, errors)
        outcome.exit_code = code
    else:
        outcome = report.Report("compile", args.mission, f"{args.mission}: {problem}", code,
                                findings=[report.Finding("input-error", problem, args.mission)])
    outcome.rules = outcome.rules + IMAGE_RULES
    if written:
        outcome.cases.append(report.Case("image", classname, report.PASSED, details=written))
        outcome.summary += f"; {written}"
    elif problem:
        outcome.cases.append(report.Case("image", classname, report.FAILED, problem))
        if result is not None:  # proved, and yet no image: say why where it is read
            outcome.findings.append(report.Finding("image", problem, args.mission))
            outcome.summary += f"; {problem}"
    else:
        outcome.cases.append(report.Case("image", classname, report.SKIPPED,
                                          "not written: the mission is not proved"))
    return outcome


def _finish(args: argparse.Namespace, output: Path, code: int, *,
            result: CheckResult | None = None, errors: list[LoadError] | None = None,
            problem: str = "", written: str = "") -> int:
    """Say how compile ended, in the chosen format, and return its exit code.

    ``errors``: the input errors of a mission that could not be read; ``problem``: why no
    image was written although the mission was read (or before it was); ``written``: the
    line saying an image was written."""
    if problem:
        _say(problem)
    if args.format in report.CI_FORMATS:
        report.emit(_ci_report(args, code, result, errors, problem, written), args.format)
    elif errors is not None:
        if args.format == "json":
            json.dump(dict(input_error_json(args.mission, InputError(errors)), image=None),
                      sys.stdout, indent=2)
            print()
    elif result is not None and not problem:
        if args.format == "json":
            json.dump(dict(to_json(result), image=str(output) if written else None),
                      sys.stdout, indent=2)
            print()
        else:
            print_human(result, sys.stdout)
            if written:
                print(written)
    if errors is not None and args.format != "github":  # annotations already hold them
        for e in errors:
            print(e, file=sys.stderr)
    if code != EXIT_PROVED:
        _no_image(output)
    return code


def run(args: argparse.Namespace) -> int:
    mission_path = Path(args.mission)
    output = _output_path(args)
    if args.max_failures is not None and args.max_failures < 0:
        return _finish(args, output, EXIT_INPUT_ERROR,
                       problem="--max-failures must be 0 or more")
    if _same_file(mission_path, output):
        return _finish(args, output, EXIT_INPUT_ERROR,
                       problem=f"the image would overwrite the mission file {args.mission}; "
                               "name it with -o")
    key_path = args.sign_key or os.environ.get(SIGNING_KEY_ENV) or None
    signing_key = None
    if key_path:
        try:
            signing_key = load_signing_key(key_path)
        except KeyFileError as error:
            return _finish(args, output, EXIT_INPUT_ERROR, problem=f"signing key: {error}")

    try:
        components = components_of(args)
    except ComponentsError as error:
        return _finish(args, output, EXIT_INPUT_ERROR, problem=f"--components: {error}")

    source = _read_source(mission_path)
    text = (source or b"").decode("utf-8", "replace")
    try:
        result, mission = check_file(args.mission, args.max_failures, args.timeout,
                                     progress_reporter(args.progress, "compile"), _admit(text),
                                     components=components)
    except InputError as error:
        return _finish(args, output, EXIT_INPUT_ERROR, errors=error.errors)
    # A phase placed online flies what the placer answers: proved as check proves it
    # (keel-place --prove), or no image.
    if result.valid and mission is not None and online_phases(mission):
        try:
            prove_online(result, mission, args.max_failures)
        except ProverUnavailable as error:
            return _finish(args, output, EXIT_INPUT_ERROR, problem=str(error))
        except ProverFailed as error:
            return _finish(args, output, EXIT_INTERNAL_ERROR, problem=f"internal error: {error}")
    if not result.valid or mission is None:
        code = EXIT_UNDECIDED if result.status == UNDECIDED and not result.violations \
            else EXIT_VIOLATIONS
        return _finish(args, output, code, result=result)

    if source is None or _read_source(mission_path) != source:
        return _finish(args, output, EXIT_INPUT_ERROR, result=result,
                       problem=f"{args.mission} changed while it was being compiled")
    image = seal(build_image(mission, result, mission_path.name, source, args.max_failures),
                 signing_key)
    errors = schema_errors(image)
    if errors:
        return _finish(args, output, EXIT_INTERNAL_ERROR, result=result,
                       problem="internal error: the image breaks "
                               "config/schema/image.schema.json: " + "; ".join(errors[:5]))
    data = encode_file(image)
    if len(data) > MAX_IMAGE_BYTES:
        return _finish(args, output, EXIT_INPUT_ERROR, result=result,
                       problem=f"the image would be {len(data) / 2**20:.1f} MiB; a node reads "
                               f"at most {MAX_IMAGE_BYTES // 2**20} MiB")
    try:
        _write_atomically(output, data)
    except OSError as error:
        return _finish(args, output, EXIT_INPUT_ERROR, result=result,
                       problem=f"cannot write {output}: {error.strerror or error}")

    signed = ("unsigned" if signing_key is None
              else f"signed with key id {key_id(signing_key.public_key())}")
    return _finish(args, output, EXIT_PROVED, result=result,
                   written=f"{output}: image written ({len(data)} bytes, sha256 "
                           f"{image['sha256']}, {signed})")
