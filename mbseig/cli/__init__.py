"""Command line: ``mbseig SUBCOMMAND CASE [options]``.

Each subcommand lives in its own module with ``register(subparsers)`` adding its parser and a
``run(args) -> int`` handler.  :func:`main` turns every :class:`~mbseig.errors.MbseigError`, and
every command-line mistake argparse finds, into one line ``mbseig: FILE: ELEMENT: problem`` on
stderr and exit code 2 (README, "Exit codes").

Ctrl-C (SIGINT) in the executable (:func:`console`): the first raises KeyboardInterrupt, which
the command turns into exit code 130 (a sweep after keeping its finished points and saying so
in one line, :func:`mbseig.cli.common.interrupt_line`); a second one ends the process at once:
the callbacks of ``ON_SECOND_INTERRUPT`` run (a sweep's line, if not said yet), the worker
processes are killed and the process exits with 130, without waiting for anything.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import signal
import sys
import threading
import warnings

from ..arguments import ArgumentError
from ..errors import CaseError, MbseigError, ReportedWarning

__all__ = ["main", "console", "SUBCOMMANDS"]

SUBCOMMANDS = ["linearize", "modes", "frf", "check", "sweep", "report", "bench", "import-urdf",
               "animate", "unbalance", "uncertainty"]
# one line each for ``mbseig --help`` without importing every command's module
SUBCOMMAND_HELP = {
    "linearize": "equilibrium and reduced linear model M, P, Q (and B, C, D of named signals)",
    "modes": "solve the modes and classify their stability",
    "frf": "frequency response, poles, zeros and DC gain of one input to one output",
    "check": "cross-check predicted modes against a nonlinear simulation",
    "sweep": "sweep parameters and track modes and stability boundaries",
    "report": "write a stability report (Markdown and self-contained HTML)",
    "bench": "measure speed against accuracy; write reports/benchmarks.md",
    "import-urdf": "write the plain 3-D case of a URDF robot",
    "animate": "write one period of a mode shape as a looping GIF",
    "unbalance": "synchronous response of a spinning rotor to an unbalance m·e",
    "uncertainty": "probability of instability under random parameters, with its interval",
}
# commands whose output carries the text of every ReportedWarning (beam-theory guidance, notes on
# the equilibrium: mbseig.cli.common.output_notes), so the warning would only repeat it on stderr
REPORTING_COMMANDS = {"modes", "linearize", "check"}
# commands that leave nothing open when they return (their output is on stdout and stderr, and
# any file they write is written and closed by then): the executable ends them without Python's
# interpreter teardown (:func:`console`)
PROMPT_EXIT = {"modes", "linearize"}


class _Parser(argparse.ArgumentParser):
    """argparse with its errors as one line (exit 2) instead of a usage block."""

    def error(self, message):
        raise CaseError(f"{message} (see {self.prog} --help)", element="command line")


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The parser; with ``only`` (a subcommand), only that command's module is imported and
    the others are listed by name and help line (startup time: each module pulls its stages)."""
    parser = _Parser(
        prog="mbseig", description="Modal and stability analysis of constrained multibody systems.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in SUBCOMMANDS:
        if only is None or name == only:
            importlib.import_module(f".{name.replace('-', '_')}", __name__).register(sub)
        else:
            sub.add_parser(name, help=SUBCOMMAND_HELP[name])
    return parser


def _chosen(argv):
    """The subcommand named by the command line (its first non-option word), or None."""
    for word in sys.argv[1:] if argv is None else argv:
        if not str(word).startswith("-"):
            return word if word in SUBCOMMANDS else None
    return None


def main(argv=None) -> int:
    parser = build_parser(_chosen(argv))
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
    except ArgumentError as exc:  # (a value the command line let through to the Python API)
        print("mbseig: " + " ".join(str(exc).splitlines()), file=sys.stderr)
        return 2
    except BrokenPipeError:
        return 1
    except KeyboardInterrupt:
        return 130


#: callables a second SIGINT runs before the process ends (mbseig.cli.common.KeptStudy)
ON_SECOND_INTERRUPT: list = []
_HELD = {"depth": 0, "pending": False}


@contextlib.contextmanager
def held():
    """A section a second SIGINT does not cut (the interrupted study keeping its points and
    saying so): the signal's handler runs in the main thread whichever thread receives it, so
    a mask cannot hold it off; it is noted, and the process ends as the section ends."""
    _HELD["depth"] += 1
    try:
        yield
    finally:
        _HELD["depth"] -= 1
        if not _HELD["depth"] and _HELD["pending"]:
            _end(130)


def _first_interrupt(signum, frame):
    signal.signal(signal.SIGINT, _second_interrupt)
    raise KeyboardInterrupt


def _second_interrupt(signum, frame):
    if _HELD["depth"]:
        _HELD["pending"] = True  # (the held section ends the process)
        return
    for say in list(ON_SECOND_INTERRUPT):
        try:
            say()
        except BaseException:  # (ending now: nothing may stop it)
            pass
    _end(130)


def _end(code):
    """End the process now with ``code``: worker processes killed, output flushed, no
    interpreter teardown (no wait on a pool's threads)."""
    mp = sys.modules.get("multiprocessing")
    if mp is not None:
        for child in mp.active_children():
            try:
                child.kill()
            except (OSError, ValueError, AttributeError):
                pass
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except (BrokenPipeError, OSError, ValueError):
        code = code or 1  # the output could not be delivered
    os._exit(code)


def console() -> None:
    """The ``mbseig`` executable (and ``python -m mbseig``): :func:`main`, then, for a command of
    ``PROMPT_EXIT``, the process ends as soon as its output streams are flushed, without the
    interpreter's teardown — freeing the numpy, scipy and mbseig modules object by object, which
    measured ≈ 35 ms on a 0.4 s ``mbseig modes`` of a small case and does nothing for a command
    that has written its output.  Other commands (worker pools, plots, reports, temporary
    files) exit normally, unless interrupted (exit 130: ended as a command of ``PROMPT_EXIT``,
    the worker processes killed first).  SIGINT is handled as the module docstring says.
    ``main`` itself always returns (tests and embedding call it)."""
    argv = sys.argv[1:]
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, _first_interrupt)
    code = main(argv)
    if _chosen(argv) in PROMPT_EXIT or code == 130:
        _end(code)  # (130: interrupted; a pool's threads are not waited for)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    console()
