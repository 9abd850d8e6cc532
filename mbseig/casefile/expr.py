"""Safe arithmetic expressions for numeric case fields.

A case field may hold a number or a string such as ``"2*sqrt(k/m)*sin(pi/4)"``.  The string is
parsed with :mod:`ast` and walked node by node against a whitelist: numbers, names of parameters
and loop indices, ``+ - * / ** %``, unary minus, parentheses and the functions in
:data:`FUNCTIONS`.  Nothing is ever passed to Python's ``eval``; attribute access, subscripts,
comprehensions, lambdas, keywords and every other construct are rejected.
"""

from __future__ import annotations

import ast
import functools
import math
import operator
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import ExpressionError

__all__ = ["evaluate", "parse", "walk", "Dialect", "SCALAR", "FUNCTIONS", "CONSTANTS", "MAX_LENGTH"]

MAX_LENGTH = 500  # characters in one expression

FUNCTIONS = {
    "sqrt": math.sqrt,
    "sin": math.sin,
    "cos": math.cos,
    "tan": math.tan,
    "asin": math.asin,
    "acos": math.acos,
    "atan": math.atan,
    "atan2": math.atan2,
    "exp": math.exp,
    "log": math.log,
    "abs": abs,
    "min": min,
    "max": max,
    "deg": math.radians,  # deg(45) is 45 degrees expressed in radians
}
CONSTANTS = {"pi": math.pi, "e": math.e}

_BINARY = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
    ast.Mod: operator.mod,
}
_UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos}


def evaluate(value, names: Mapping[str, float] | None = None) -> float:
    """Return the float value of a number or of a whitelisted expression string.

    ``names`` maps parameter (and loop index) names to numbers.  Raises :class:`ExpressionError`
    with the offending text for anything that is not a finite number.
    """
    if isinstance(value, bool):
        raise ExpressionError(f"expected a number, got the boolean {value!r}")
    if isinstance(value, (int, float)):
        try:
            result = float(value)
        except OverflowError:  # a TOML integer beyond the double range
            raise ExpressionError(f"an integer of {len(str(abs(value)))} digits is beyond the "
                                  "double-precision range") from None
    elif isinstance(value, str):
        result = _evaluate_string(value, names or {})
    else:
        raise ExpressionError(f"expected a number or an expression string, got {value!r}")
    if not math.isfinite(result):
        raise ExpressionError(f"{value!r} is not finite ({result})")
    return result


@dataclass(frozen=True)
class Dialect:
    """What an expression may call and how it fails: scalar (math) or vectorized (numpy)."""

    functions: Mapping
    binary: Mapping
    fail: Callable[[str], Exception]


SCALAR = Dialect(FUNCTIONS, _BINARY, ExpressionError)


@functools.lru_cache(maxsize=4096)
def parse(text: str):
    """The syntax tree of an expression string (cached); ExpressionError if it cannot be parsed."""
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"expression longer than {MAX_LENGTH} characters")
    try:
        return ast.parse(text.strip(), mode="eval").body
    except SyntaxError:
        raise ExpressionError(f"cannot parse expression {text!r}") from None


@functools.lru_cache(maxsize=4096)
def _names_in(text: str) -> tuple:
    """The names an expression reads (after :func:`parse` accepted it)."""
    return tuple(sorted({n.id for n in ast.walk(parse(text)) if isinstance(n, ast.Name)}))


_VALUES: dict = {}  # (text, values of the names it reads) → its value: a repeated field's
_MAX_VALUES = 100_000  # members share it (an expression is a pure function of those names)
_MISSING = object()
_SEEN: set = set()  # expressions evaluated once: compiled when a second value is asked


def _evaluate_string(text: str, names: Mapping[str, float]) -> float:
    tree = parse(text)
    key = (text, *(names.get(n, _MISSING) for n in _names_in(text)))
    try:  # (a zero is not kept: -0.0 == 0.0 as keys, and atan2 tells them apart)
        if 0 in key:
            raise TypeError
        value = _VALUES.get(key)
    except (TypeError, ValueError):  # an array or a zero among the values: evaluated as it comes
        key, value = None, None
    if value is not None:
        return value
    try:
        run = _compiled(text) if text in _SEEN else None  # (compiled at its second value)
        value = float(run(names) if run is not None else walk(tree, names, text, SCALAR))
        if run is None and len(_SEEN) < _MAX_VALUES:
            _SEEN.add(text)
        if key is not None:
            if len(_VALUES) >= _MAX_VALUES:
                _VALUES.clear()
            _VALUES[key] = value
        return value
    except ExpressionError:
        raise
    except (ArithmeticError, ValueError, TypeError) as exc:
        raise ExpressionError(f"cannot evaluate {text!r}: {exc}") from None


@functools.lru_cache(maxsize=4096)
def _compiled(text: str):
    """The expression as nested closures, names → value: :func:`walk` with the SCALAR dialect
    without its dispatch per node (the same operations in the same order, the same errors at
    evaluation: an unknown name, a large exponent), or None where the tree holds a construct
    :func:`walk` refuses (it then raises its own error)."""
    try:
        return _closure(parse(text), text)
    except _Refused:
        return None


class _Refused(Exception):
    pass


def _closure(node, text):
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise _Refused
        value = float(node.value)
        return lambda names: value
    if isinstance(node, ast.Name):
        key = node.id
        const = CONSTANTS.get(key)

        def name(names):
            if key in names:
                value = names[key]
                return value if isinstance(value, np.ndarray) else float(value)
            if const is not None:
                return const
            raise ExpressionError(f"unknown name {key!r} in {text!r}")
        return name
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        left, right, op = _closure(node.left, text), _closure(node.right, text), \
            _BINARY[type(node.op)]
        if isinstance(node.op, ast.Pow):
            def power(names):
                a, b = left(names), right(names)
                if abs(b) > 1e4 if isinstance(b, float) else np.any(np.abs(b) > 1e4):
                    raise ExpressionError(f"exponent {np.max(np.abs(b)):g} too large in {text!r}")
                return op(a, b)
            return power
        return lambda names: op(left(names), right(names))
    if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
        operand, op = _closure(node.operand, text), _UNARY[type(node.op)]
        return lambda names: op(operand(names))
    if isinstance(node, ast.Call):
        if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS \
                or node.keywords:
            raise _Refused
        fn, args = FUNCTIONS[node.func.id], [_closure(a, text) for a in node.args]
        if len(args) == 1:
            (a0,) = args
            return lambda names: fn(a0(names))
        return lambda names: fn(*[a(names) for a in args])
    raise _Refused


def walk(node, names, text, dialect=SCALAR):
    """Value of a parsed expression against the whitelist (names may map to numpy arrays)."""
    fail = dialect.fail
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise fail(f"only numbers are allowed as constants in {text!r}")
        return float(node.value)
    if isinstance(node, ast.Name):
        if node.id in names:
            value = names[node.id]
            return value if isinstance(value, np.ndarray) else float(value)
        if node.id in CONSTANTS:
            return CONSTANTS[node.id]
        raise fail(f"unknown name {node.id!r} in {text!r}")
    if isinstance(node, ast.BinOp) and type(node.op) in dialect.binary:
        left = walk(node.left, names, text, dialect)
        right = walk(node.right, names, text, dialect)
        if isinstance(node.op, ast.Pow) and (abs(right) > 1e4 if isinstance(right, float)
                                             else np.any(np.abs(right) > 1e4)):
            raise fail(f"exponent {np.max(np.abs(right)):g} too large in {text!r}")
        return dialect.binary[type(node.op)](left, right)
    if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
        return _UNARY[type(node.op)](walk(node.operand, names, text, dialect))
    if isinstance(node, ast.Call):
        if not isinstance(node.func, ast.Name) or node.func.id not in dialect.functions:
            raise fail(f"function not allowed in {text!r}: {ast.unparse(node.func)}")
        if node.keywords:
            raise fail(f"keyword arguments are not allowed in {text!r}")
        args = [walk(a, names, text, dialect) for a in node.args]
        return dialect.functions[node.func.id](*args)
    raise fail(f"not allowed in an expression: {ast.unparse(node)!r} in {text!r}")
