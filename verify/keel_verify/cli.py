"""``keel-verify``: one command, several subcommands, each in its own module.

Every subcommand module exposes ``register(subparsers)``, which adds its parser and sets
``func`` to a callable taking the parsed arguments and returning the exit code. Exit codes
are the verifier's contract (DESIGN.md): 0 proven/ok, 1 violations/failed, 2 input error,
3 undecided; ``compile`` adds 4, an internal error (the image it built breaks its schema).
"""

from __future__ import annotations

import argparse
import importlib
import sys

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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="keel-verify",
        description="Verify Keel missions (Z3), protocols (TLC) and traces.",
    )
    parser.add_argument("--version", action="version", version=f"keel-verify {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, module_name in SUBCOMMANDS.items():
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as error:
            if error.name and module_name.startswith(error.name):
                continue
            raise
        module.register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return EXIT_INPUT_ERROR
    try:
        return int(args.func(args))
    except KeyboardInterrupt:
        print("keel-verify: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
