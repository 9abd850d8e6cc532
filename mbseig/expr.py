"""Safe arithmetic expressions for numeric case fields.

A case field may hold a number or a string such as ``"2*sqrt(k/m)*sin(pi/4)"``.  The string is
parsed with :mod:`ast` and walked node by node against a whitelist: numbers, names of parameters
and loop indices, ``+ - * / ** %``, unary minus, parentheses and the functions in
:data:`FUNCTIONS`.  Nothing is ever passed to Python's ``eval``; attribute access, subscripts,
comprehensions, lambdas, keywords and every other construct are rejected.
"""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Mapping

from .errors import ExpressionError

__all__ = ["evaluate", "FUNCTIONS", "CONSTANTS", "MAX_LENGTH"]

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
        result = float(value)
    elif isinstance(value, str):
        result = _evaluate_string(value, names or {})
    else:
        raise ExpressionError(f"expected a number or an expression string, got {value!r}")
    if not math.isfinite(result):
        raise ExpressionError(f"{value!r} is not finite ({result})")
    return result


def _evaluate_string(text: str, names: Mapping[str, float]) -> float:
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"expression longer than {MAX_LENGTH} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError:
        raise ExpressionError(f"cannot parse expression {text!r}") from None
    try:
        return float(_walk(tree.body, names, text))
    except ExpressionError:
        raise
    except (ArithmeticError, ValueError, TypeError) as exc:
        raise ExpressionError(f"cannot evaluate {text!r}: {exc}") from None


def _walk(node, names, text):
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise ExpressionError(f"only numbers are allowed as constants in {text!r}")
        return float(node.value)
    if isinstance(node, ast.Name):
        if node.id in names:
            return float(names[node.id])
        if node.id in CONSTANTS:
            return CONSTANTS[node.id]
        raise ExpressionError(f"unknown name {node.id!r} in {text!r}")
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        left = _walk(node.left, names, text)
        right = _walk(node.right, names, text)
        if isinstance(node.op, ast.Pow) and abs(right) > 1e4:
            raise ExpressionError(f"exponent {right:g} too large in {text!r}")
        return _BINARY[type(node.op)](left, right)
    if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
        return _UNARY[type(node.op)](_walk(node.operand, names, text))
    if isinstance(node, ast.Call):
        if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS:
            raise ExpressionError(f"function not allowed in {text!r}: {ast.unparse(node.func)}")
        if node.keywords:
            raise ExpressionError(f"keyword arguments are not allowed in {text!r}")
        args = [_walk(a, names, text) for a in node.args]
        return FUNCTIONS[node.func.id](*args)
    raise ExpressionError(f"not allowed in an expression: {ast.unparse(node)!r} in {text!r}")
