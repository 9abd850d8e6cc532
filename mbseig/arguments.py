"""The public Python API checks its arguments here, in one place per function.

Each public function (``load_case``, ``read_case``, ``equilibrium``, ``linearize``, ``modes``,
``analyze``, ``run_sweep``, ``check_modes``, ``CaseBuilder``) begins with one call,
``check("name", locals())``, and :data:`RULES` holds what each argument must be.  A wrong
argument raises one :class:`ArgumentTypeError` (a ``TypeError``: the wrong kind of object) or
:class:`ArgumentValueError` (a ``ValueError``: the right kind, a value it cannot take) that
names the function and the argument, says what it expects and echoes the value given::

    run_sweep: axes must be a list of (name, values) pairs, e.g. [("f", numpy.linspace(0, 2.5,
    26))], got {'m1': array([1. , 1.5, 2. ])} (a dict)

Only the kind, the range and the agreement between arguments are checked here (a matrix P of
the size of M); what needs the computation (a finite linearization, a solvable equilibrium) is
checked by the stage that computes it.  The command line catches :class:`ArgumentError` as it
catches :class:`mbseig.errors.MbseigError`: one line, exit 2.

This module is the bottom layer of the package (it imports no other part of mbseig): the
classes of the results it accepts are recognised by name in their class hierarchy.
"""

from __future__ import annotations

import math
import numbers
import os

__all__ = ["check", "RULES", "ArgumentError", "ArgumentTypeError", "ArgumentValueError"]


class ArgumentError(Exception):
    """A public function was called with an argument it cannot take."""


class ArgumentTypeError(ArgumentError, TypeError):
    """An argument of the wrong kind (a string where a number goes, a dict for a list)."""


class ArgumentValueError(ArgumentError, ValueError):
    """An argument of the right kind with a value it cannot take (a negative tolerance)."""


def _echo(value) -> str:
    text = repr(value)
    text = " ".join(text.split())
    if len(text) > 80:
        text = text[:77] + "..."
    kind = type(value).__name__
    return f"{text} ({'an' if kind[0] in 'aeiou' else 'a'} {kind})"


def _real(x) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, bool) and type(x).__name__ != "bool_"


def _integer(x) -> bool:
    return isinstance(x, numbers.Integral) and not isinstance(x, bool)


def _flag(x) -> bool:
    return isinstance(x, bool) or type(x).__name__ == "bool_"


def _is_a(x, *names) -> bool:
    """Whether ``x`` is an instance of an mbseig class of one of these names (its MRO)."""
    return any(c.__name__ in names and c.__module__.startswith("mbseig.")
               for c in type(x).__mro__)


def _sparse(x) -> bool:
    return hasattr(x, "tocsr") and hasattr(x, "shape") and hasattr(x, "nnz")


class Rule:
    """What one argument must be: ``expects`` (the text of the message) and ``problem``,
    which returns None when the value is accepted, else the exception class."""

    def __init__(self, expects, problem):
        self.expects, self.problem = expects, problem


def _simple(expects, kind_ok, value_ok=lambda v: True):
    return Rule(expects, lambda v, a: (ArgumentTypeError if not kind_ok(v) else
                                       None if value_ok(v) else ArgumentValueError))


def optional(rule: Rule) -> Rule:
    out = Rule(f"None or {rule.expects}", lambda v, a: None if v is None else rule.problem(v, a))
    out.entry = getattr(rule, "entry", None)
    return out


TEXT = _simple("a string", lambda v: isinstance(v, str))
NAME = _simple("a non-empty string", lambda v: isinstance(v, str), lambda v: bool(v.strip()))
FLAG = _simple("True or False", _flag)
NUMBER = _simple("a finite number", _real, lambda v: math.isfinite(v))
POSITIVE = _simple("a positive finite number", _real, lambda v: math.isfinite(v) and v > 0)
NONNEGATIVE = _simple("a finite number >= 0", _real, lambda v: math.isfinite(v) and v >= 0)
CALLBACK = _simple("True, False, None or a callable",
                   lambda v: v is None or _flag(v) or callable(v))


def count(minimum: int) -> Rule:
    return _simple(f"an integer >= {minimum}", _integer, lambda v: v >= minimum)


def choice(*options) -> Rule:
    """One of ``options`` (all strings, or all integers: never a bool for 1)."""
    kind = _integer if _integer(options[0]) else (lambda v: isinstance(v, str))
    return _simple(f"one of {', '.join(repr(o) for o in options)}", kind,
                   lambda v: v in options)


def instance(what: str, *names) -> Rule:
    return _simple(what, lambda v: _is_a(v, *names))


PATH = _simple("a path (str or os.PathLike)", lambda v: isinstance(v, (str, os.PathLike)))
CASE_SOURCE = _simple("a path (str or os.PathLike) or a case dict",
                      lambda v: isinstance(v, (str, os.PathLike, dict)))
CASE = _simple("a path (str or os.PathLike), a case dict or a CaseSpec (mbseig.read_case)",
               lambda v: isinstance(v, (str, os.PathLike, dict)) or _is_a(v, "CaseSpec"))
PARAM = _simple("a finite number or an expression string",
                lambda v: isinstance(v, str) or _real(v),
                lambda v: isinstance(v, str) or math.isfinite(v))
MODEL = instance("a model built by mbseig.load_case (Model or LinearCase)", "Model", "LinearCase")
EQUILIBRIUM = instance("an Equilibrium (mbseig.equilibrium(model); a steady or periodic "
                       "reference from mbseig.find_reference)", "Equilibrium")
LINEAR = instance("a LinearModel (mbseig.linearize(model, eq))", "LinearModel")
MODES = instance("a Modes result (mbseig.modes(lin))", "Modes")


class Entries(Rule):
    """A dict whose keys are strings and whose every value follows ``entry`` (a wrong value
    is named by its key: ``params['m']``)."""

    def __init__(self, expects, entry: Rule):
        super().__init__(expects, lambda v, a: None if isinstance(v, dict) and all(
            isinstance(k, str) for k in v) else ArgumentTypeError)
        self.entry = entry


PARAMS = Entries("a dict {parameter name: number or expression string}", PARAM)


def _array(v, kinds, ndim):
    """``v`` as a numpy array of ``ndim`` dimensions and a dtype of ``kinds``, else None."""
    import numpy as np

    try:
        arr = np.asarray(v)
    except (TypeError, ValueError):
        return None
    return arr if arr.dtype.kind in kinds and arr.ndim == ndim else None


def _matrix_problem(v, a, like=None):
    import numpy as np

    if _sparse(v):
        shape = v.shape
    else:
        arr = _array(v, "biufc", 2)
        if arr is None:
            return ArgumentTypeError
        shape = arr.shape
    if shape[0] != shape[1]:
        return ArgumentValueError
    ref = a.get(like) if like else None
    if ref is not None and not _is_a(ref, "LinearModel") and _matrix_problem(ref, a) is None:
        if tuple(np.shape(ref) if not _sparse(ref) else ref.shape) != tuple(shape):
            return ArgumentValueError
    return None


def matrix(like=None) -> Rule:
    same = f" of the size of {like}" if like else ""
    return Rule(f"a square real or complex matrix{same} (numpy array, nested lists or "
                "scipy.sparse)", lambda v, a: _matrix_problem(v, a, like))


def _operator(v, a):  # modes(M, ...): a LinearModel or the matrix M
    return None if _is_a(v, "LinearModel") else _matrix_problem(v, a)


def _q_init(v, a):
    import numpy as np

    try:
        q = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        return ArgumentTypeError
    ref = getattr(a.get("model"), "q_init", None)
    n = None if ref is None else len(ref)
    if q.ndim != 1 or not np.all(np.isfinite(q)) or (n is not None and q.size != n):
        return ArgumentValueError
    return None


def _band(v, a):
    if not isinstance(v, (tuple, list)) or len(v) != 2 or not all(_real(x) for x in v):
        return ArgumentTypeError
    lo, hi = v
    return None if math.isfinite(lo) and math.isfinite(hi) and 0 <= lo < hi else ArgumentValueError


def _names(v, a):
    if isinstance(v, str) or not hasattr(v, "__iter__"):
        return ArgumentTypeError
    return None if all(isinstance(x, str) for x in v) else ArgumentTypeError


def _indices(v, a):
    if isinstance(v, str) or not hasattr(v, "__iter__"):
        return ArgumentTypeError
    v = list(v)
    if not all(_integer(i) for i in v):
        return ArgumentTypeError
    return None if all(i >= 1 for i in v) else ArgumentValueError


def _values(v, least=2):
    """None when ``v`` is a 1-D sequence of ``least`` or more finite numbers, else the error
    class."""
    import numpy as np

    if isinstance(v, (str, bytes, dict)) or not hasattr(v, "__len__"):
        return ArgumentTypeError
    arr = _array(v, "biuf", 1)
    if arr is None:
        return ArgumentTypeError
    return None if arr.size >= least and np.all(np.isfinite(arr)) else ArgumentValueError


def _axes(v, a):
    if isinstance(v, (str, bytes, dict)) or not isinstance(v, (list, tuple)) or not v:
        return ArgumentTypeError
    for k, pair in enumerate(v):
        if not isinstance(pair, (list, tuple)) or len(pair) != 2 or not isinstance(pair[0], str):
            return ArgumentTypeError
        bad = _values(pair[1], 2 if k == 0 else 1)
        if bad is not None:
            return bad
    return None


def _either_case_or_model(v, a):
    if v is None:
        return ArgumentTypeError if a.get("model") is None else None
    return CASE.problem(v, a)


def _resume(v, a):
    return (None if isinstance(v, (str, os.PathLike)) or _is_a(v, "Checkpoint")
            else ArgumentTypeError)


def _table(v, a):
    return None if isinstance(v, dict) else ArgumentTypeError


def _vector3(v, a):
    if isinstance(v, (str, bytes, dict)) or not hasattr(v, "__len__"):
        return ArgumentTypeError
    return None


TOLERANCE = POSITIVE
RULES: dict = {
    "read_case": {"path": CASE_SOURCE},
    "load_case": {"path": CASE_SOURCE, "config": optional(TEXT), "params": PARAMS},
    "equilibrium": {
        "model": MODEL, "tol": TOLERANCE, "max_iter": count(1), "rank_tol": TOLERANCE,
        "q_init": optional(Rule("a finite vector, one value per coordinate of the model", _q_init)),
        "xtol": optional(TOLERANCE), "floor_tol": TOLERANCE, "continuation": FLAG,
        "offer_stable": FLAG, "self_stress": choice("refuse", "report"),
        "compliance": optional(Rule("a dict {constraint name: compliance}", _table)),
        "blas": optional(count(1))},
    "linearize": {
        "model": MODEL, "eq": EQUILIBRIUM, "rank_tol": optional(TOLERANCE),
        "constraint_stiffness": FLAG, "sparse": optional(FLAG),
        "reference": optional(Rule("a list of coordinate names", _names)), "signals": FLAG},
    "modes": {
        "M": Rule("a LinearModel or a square real or complex matrix (numpy array, nested "
                  "lists or scipy.sparse)", _operator),
        "P": optional(matrix("M")), "Q": optional(matrix("M")), "solver": NAME,
        "N": optional(Rule("a matrix (numpy array or scipy.sparse)", lambda v, a: None
                           if _sparse(v) or hasattr(v, "shape") or isinstance(v, list)
                           else ArgumentTypeError)),
        "coordinate_names": optional(Rule("a list of coordinate names", _names)),
        "stability_rtol": NONNEGATIVE, "stability_atol": NONNEGATIVE, "safety": POSITIVE,
        "n_dominant": count(0), "rigid_rank_tol": TOLERANCE, "n_modes": optional(count(1)),
        "target": optional(NUMBER),
        "band": optional(Rule("a pair (lo, hi) of angular frequencies, 0 <= lo < hi", _band)),
        "eta_warn": TOLERANCE, "fused": FLAG},
    "analyze": {
        "case": Rule("a path (str or os.PathLike), a case dict or a CaseSpec, unless model= "
                     "is given", _either_case_or_model),
        "config": optional(TEXT), "params": optional(PARAMS), "solver": NAME,
        "constraint_stiffness": FLAG,
        "modes_options": optional(Rule("a dict of keyword options of mbseig.modes", _table)),
        "model": optional(MODEL),
        "refine": optional(Rule("a dict {modes, f_max, accuracy, max_elements}", _table))},
    "run_sweep": {
        "case": CASE,
        "axes": Rule('a list of (name, values) pairs, e.g. [("f", numpy.linspace(0, 2.5, 26))], '
                     "the first with at least 2 finite values, the others with at least 1",
                     _axes),
        "config": optional(TEXT), "fixed": optional(PARAMS), "jobs": optional(count(1)),
        "progress": CALLBACK, "xtol_rel": POSITIVE, "safety": POSITIVE,
        "stability_rtol": NONNEGATIVE, "continuation": FLAG, "curves": FLAG,
        "curve_values": optional(Rule("a list of at least 2 finite values",
                                               lambda v, a: _values(v))),
        "diagram": optional(TEXT),
        "resume": optional(Rule("a directory (str or os.PathLike) or a Checkpoint", _resume)),
        "lean": FLAG},
    "check_modes": {
        "model": MODEL, "eq": EQUILIBRIUM, "lin": LINEAR, "modes": MODES,
        "indices": optional(Rule("a list of mode numbers (integers >= 1)", _indices)),
        # (amplitude, periods, efolds, delta_rtol, omega_rtol, zero_delta_tol, rigid_tol,
        # ode_rtol, resolution_k and max_fast_periods: check_modes refuses a value that is not
        # a positive number itself, in a CaseError named by the option that mbseig check's
        # messages are, so they are not checked twice)
        "samples_per_period": count(1), "min_samples": count(1), "method": NAME,
        "mass_tol": POSITIVE, "recheck_amplification": POSITIVE,
        "defective_amplification": POSITIVE,
        "progress": optional(_simple("a callable (label, done, total)", callable))},
    "CaseBuilder": {
        "dimension": choice(1, 2, 3), "title": optional(TEXT),
        "gravity": optional(Rule("a vector (a list of numbers or expressions)", _vector3)),
        "description": optional(TEXT), "source": optional(TEXT), "schema_version": count(1),
        "kind": optional(TEXT)},
}


def check(function: str, arguments: dict) -> None:
    """Check ``arguments`` (the function's ``locals()`` at its first line) against
    ``RULES[function]``; raise the first problem found as one TypeError or ValueError that
    names the function and the argument, says what it expects and echoes the value."""
    for name, rule in RULES[function].items():
        if name not in arguments:
            continue
        value = arguments[name]
        error = rule.problem(value, arguments)
        if error is not None:
            raise error(f"{function}: {name} must be {rule.expects}, got {_echo(value)}")
        entry = getattr(rule, "entry", None)
        for key, item in (value.items() if entry is not None and value is not None else ()):
            error = entry.problem(item, arguments)
            if error is not None:
                raise error(f"{function}: {name}[{key!r}] must be {entry.expects}, "
                            f"got {_echo(item)}")
