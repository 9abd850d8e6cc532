"""The expression whitelist: values agree with direct computation; everything else is refused."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mbseig.casefile.expr import evaluate
from mbseig.errors import ExpressionError

numbers = st.floats(-1e3, 1e3, allow_nan=False).map(lambda x: round(x, 6))


@st.composite
def trees(draw, depth=0):
    """(text, value) pairs built together, so the value is an independent reference."""
    if depth > 3 or draw(st.booleans()):
        x = draw(numbers)
        return f"({x!r})", x
    op = draw(st.sampled_from(["+", "-", "*", "sqrt", "sin", "atan2", "neg"]))
    a_txt, a = draw(trees(depth + 1))
    if op == "sqrt":
        return f"sqrt(abs({a_txt}))", math.sqrt(abs(a))
    if op == "sin":
        return f"sin({a_txt})", math.sin(a)
    if op == "neg":
        return f"-{a_txt}", -a
    b_txt, b = draw(trees(depth + 1))
    if op == "atan2":
        return f"atan2({a_txt}, {b_txt})", math.atan2(a, b)
    return f"({a_txt} {op} {b_txt})", {"+": a + b, "-": a - b, "*": a * b}[op]


@settings(max_examples=200, deadline=None)
@given(trees())
def test_arithmetic_matches_direct_computation(tree):
    text, value = tree
    assert evaluate(text) == pytest.approx(value, rel=1e-12, abs=1e-12)


def test_parameters_constants_and_deg():
    assert evaluate("2*sqrt(k/m)", {"k": 1000.0, "m": 1.0}) == pytest.approx(2 * math.sqrt(1000))
    assert evaluate("deg(180)") == pytest.approx(math.pi)
    assert evaluate("x**2 % 5", {"x": 3.0}) == 4.0


@pytest.mark.parametrize("text", [
    "__import__('os')", "open('x')", "(1).__class__", "[1, 2]", "lambda: 1", "k if k else 1",
    "'a'", "sqrt(x=1)", "a.b", "1 < 2", "10**10**10", "exec('1')", "True", "",
])
def test_refused(text):
    with pytest.raises(ExpressionError):
        evaluate(text, {"k": 1.0, "a": 1.0})


def test_overflow_and_domain_errors_are_expression_errors():
    for text in ("exp(1000)", "sqrt(-1)", "1/0", "log(0)"):
        with pytest.raises(ExpressionError):
            evaluate(text)


def test_non_numbers_refused():
    for value in (True, None, [1.0], {"a": 1}):
        with pytest.raises(ExpressionError):
            evaluate(value)


@settings(max_examples=60, deadline=None)
@given(trees(), numbers, numbers)
def test_compiled_expressions_equal_the_tree_walk(pair, x, y):
    """An expression evaluated at a second set of values runs compiled (nested closures): the
    same float as walking its tree (the same operations in the same order), for every name."""
    from mbseig.casefile.expr import SCALAR, _compiled, parse, walk

    text, _ = pair
    text = f"{text} + p * q - q ** 2"
    for names in ({"p": x, "q": y}, {"p": y, "q": x}):
        want = float(walk(parse(text), names, text, SCALAR))
        assert float(_compiled(text)(names)) == want
        assert evaluate(text, names) == want


@pytest.mark.parametrize("text, names, message", [
    ("a + zz", {"a": 1.0}, "unknown name 'zz'"),
    ("a ** b", {"a": 1.0, "b": 2e4}, "exponent 20000 too large"),
])
def test_compiled_expressions_refuse_as_the_walk(text, names, message):
    """The errors found at evaluation are the walk's, compiled or not (second call)."""
    for _ in range(2):
        with pytest.raises(ExpressionError, match=message):
            evaluate(text, {**names, "a": names["a"] + _})
