"""Command line: ``mbseig SUBCOMMAND CASE [options]``.

Each subcommand lives in its own module with ``register(subparsers)`` adding its parser and a
``run(args) -> int`` handler.  :func:`main` turns every :class:`~mbseig.errors.MbseigError`, and
every command-line mistake argparse finds, into one line ``mbseig: FILE: ELEMENT: problem`` on
stderr and exit code 2 (README, "Exit codes").
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings

from ..errors import CaseError, MbseigError, ReportedWarning

__all__ = ["main", "SUBCOMMANDS"]

SUBCOMMANDS = ["linearize", "modes", "check", "sweep", "report", "bench"]
# commands whose output carries the text of every ReportedWarning (beam-theory guidance, notes on
# the equilibrium: mbseig.cli.common.output_notes), so the warning would only repeat it on stderr
REPORTING_COMMANDS = {"modes", "linearize", "check"}


class _Parser(argparse.ArgumentParser):
    """argparse with its errors as one line (exit 2) instead of a usage block."""

    def error(self, message):
        raise CaseError(f"{message} (see {self.prog} --help)", element="command line")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="mbseig", description="Modal and stability analysis of constrained multibody systems.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in SUBCOMMANDS:
        importlib.import_module(f".{name}", __name__).register(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        with warnings.catch_warnings():
            if args.command in REPORTING_COMMANDS:
                warnings.filterwarnings("ignore", category=ReportedWarning)
            return int(args.run(args) or 0)
    except MbseigError as exc:
        # one line whatever a message quotes (a name with a line break, a library's message)
        print("mbseig: " + " ".join(exc.one_line().splitlines()), file=sys.stderr)
        return 2
    except BrokenPipeError:
        return 1
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
