"""``keel-verify``: one command, several subcommands, each in its own module.

Every subcommand module exposes ``register(subparsers)``, which adds its parser and sets
``func`` to a callable taking the parsed arguments and returning the exit code. Exit codes
are the verifier's contract (docs/missions.md), the same for every subcommand:

* 0 proven / ok;
* 1 violations / failed (each with its counterexample);
* 2 input error (a file that does not parse or breaks its schema, a missing tool);
* 3 undecided (a solver answered unknown, TLC could not finish): never a pass;
* 4 internal error: keel-verify itself failed (an unexpected exception, an image that
  breaks its own schema, an incomplete installation). It prints one line,
  ``keel-verify: internal error: ...``; ``--debug`` (or ``KEEL_DEBUG=1``) adds the
  traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import sys
import traceback

from . import __version__

# Subcommand -> module. A module that is not part of this installation is left out of the
# help text rather than breaking the others.
SUBCOMMANDS: dict[str, str] = {
    "load": "keel_verify.load_cmd",
    "check": "keel_verify.check.cli",
    "compile": "keel_verify.compile",
    "image-check": "keel_verify.image",
    "synth": "keel_verify.synth.cli",
    "graph": "keel_verify.graph",
    "specs": "keel_verify.specs.cli",
    "trace": "keel_verify.trace.cli",
}

EXIT_OK = 0
EXIT_VIOLATIONS = 1
EXIT_INPUT_ERROR = 2
EXIT_UNDECIDED = 3
EXIT_INTERNAL_ERROR = 4

DEBUG_ENV = "KEEL_DEBUG"


def _add_debug(parser: argparse.ArgumentParser, default: object) -> None:
    parser.add_argument("--debug", action="store_true", default=default,
                        help=f"show the traceback of an internal error (also ${DEBUG_ENV}=1)")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="keel-verify",
        description="Verify Keel missions (Z3), protocols (TLC) and traces.",
        epilog="Exit codes: 0 proved/ok, 1 violations/failed, 2 input error, 3 undecided, "
               "4 internal error.",
    )
    parser.add_argument("--version", action="version", version=f"keel-verify {__version__}")
    _add_debug(parser, False)
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module_name in SUBCOMMANDS.values():
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as error:
            if error.name and module_name.startswith(error.name):
                continue
            raise
        module.register(subparsers)
    for subparser in subparsers.choices.values():
        # After the subcommand too; SUPPRESS keeps a --debug given before it.
        _add_debug(subparser, argparse.SUPPRESS)
    return parser


def _debug_wanted(argv: list[str] | None) -> bool:
    arguments = sys.argv[1:] if argv is None else argv
    return os.environ.get(DEBUG_ENV, "") not in ("", "0") or "--debug" in arguments


def internal_error(error: BaseException, debug: bool) -> int:
    """Report an unexpected exception as one line (and the traceback when debugging)."""
    if debug:
        traceback.print_exception(type(error), error, error.__traceback__, file=sys.stderr)
    text = " ".join(str(error).split()) or "no message"
    what = "" if type(error).__module__.startswith("keel_verify") else f"{type(error).__name__}: "
    hint = "" if debug else f" (--debug or {DEBUG_ENV}=1 shows the traceback)"
    print(f"keel-verify: internal error: {what}{text}{hint}", file=sys.stderr)
    return EXIT_INTERNAL_ERROR


def main(argv: list[str] | None = None) -> int:
    debug = _debug_wanted(argv)
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        debug = debug or bool(getattr(args, "debug", False))
        if not getattr(args, "func", None):
            parser.print_help(sys.stderr)
            return EXIT_INPUT_ERROR
        return int(args.func(args))
    except KeyboardInterrupt:
        print("keel-verify: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # The reader went away (``keel-verify ... | head``): nothing more to say to it.
        # Point stdout at /dev/null so that the flush at exit does not fail again.
        with contextlib.suppress(OSError, ValueError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    except Exception as error:  # the one place every unexpected error ends
        return internal_error(error, debug)


if __name__ == "__main__":
    sys.exit(main())
