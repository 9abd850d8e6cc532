"""Command line: ``mbseig SUBCOMMAND CASE [options]``.

Each subcommand lives in its own module with ``register(subparsers)`` adding its parser and a
``run(args) -> int`` handler.  :func:`main` turns every :class:`~mbseig.errors.MbseigError` into
one line ``mbseig: FILE: ELEMENT: problem`` on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from ..errors import MbseigError

__all__ = ["main", "SUBCOMMANDS"]

SUBCOMMANDS = ["linearize", "modes", "check", "sweep", "report", "bench"]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mbseig", description="Modal and stability analysis of constrained multibody systems.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in SUBCOMMANDS:
        importlib.import_module(f".{name}", __name__).register(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.run(args) or 0)
    except MbseigError as exc:
        print(f"mbseig: {exc.one_line()}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        return 1
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
