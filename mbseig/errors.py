"""Exception hierarchy.

Every error that bad input can cause is a :class:`MbseigError`; the CLI turns each into one line
``FILE: ELEMENT: problem`` and exit code 2.  The classes also derive from Python's own exceptions so
that callers may catch ``ValueError`` or ``RuntimeError`` as usual.
"""

from __future__ import annotations


class MbseigError(Exception):
    """Base class: a problem with a case, a model or a requested computation."""

    def __init__(self, message: str, *, file: str | None = None, element: str | None = None):
        self.message = message
        self.file = file
        self.element = element
        super().__init__(self.one_line())

    def one_line(self) -> str:
        parts = [p for p in (self.file, self.element) if p]
        return ": ".join(parts + [self.message])

    def located(self, *, file: str | None = None, element: str | None = None) -> MbseigError:
        """Return a copy with the file and/or element filled in where still unknown."""
        return type(self)(self.message, file=self.file or file, element=self.element or element)


class CaseError(MbseigError, ValueError):
    """The case file is malformed or describes an inconsistent model."""


class ExpressionError(CaseError):
    """A numeric field holds an expression that is not allowed or cannot be evaluated."""


class EquilibriumError(MbseigError, RuntimeError):
    """No static equilibrium could be found (inconsistent constraints or unbalanced loads)."""


class SolverError(MbseigError, RuntimeError):
    """An eigensolver failed or its result did not pass its own checks."""


class SimulationError(MbseigError, RuntimeError):
    """The time-domain check cannot integrate the model (massless free motion, a failed step)."""


class ReportedWarning(UserWarning):
    """A warning whose text the command-line outputs carry (the beam-theory guidance, notes on
    the equilibrium): ``mbseig modes``, ``linearize`` and ``check`` print it with their results,
    so they do not repeat it on stderr (README, "Exit codes").  A library caller sees it as a
    Python warning as usual."""


class NumericalError(MbseigError, ArithmeticError):
    """A stage's arithmetic left the double-precision range: an overflow, a NaN, or a value
    that vanished below it.  The element is the stage (equilibrium, linearization, eigen,
    check) or the model element whose numbers overflowed; the message names the likely cause
    (README, "Input rules")."""
