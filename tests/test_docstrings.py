"""Every public function documents every argument (python-control's ``docstrings_test.py``):
each function of ``mbseig.__all__`` has numpydoc ``Parameters`` (every argument of its
signature listed, ``*args``/``**kwargs`` by their starred names), ``Returns`` and ``Examples``
sections, and no ``Parameters`` entry names an argument the function does not take.  The
examples themselves run in tests/test_doctests.py."""

from __future__ import annotations

import inspect
import re

import pytest

import mbseig

SECTION = re.compile(r"^(\s*)([A-Z][A-Za-z ]+)\n\1(-{3,})\s*$", re.M)


def _public_functions():
    return sorted(name for name in mbseig.__all__
                  if inspect.isfunction(getattr(mbseig, name)))


def sections(doc: str) -> dict:
    """{section title: its text} of a numpydoc docstring."""
    doc = inspect.cleandoc(doc)
    found = list(SECTION.finditer(doc))
    return {m.group(2).strip(): doc[m.end():found[k + 1].start() if k + 1 < len(found) else None]
            for k, m in enumerate(found)}


def documented(text: str) -> set:
    """The argument names a Parameters section lists (``a, b : type`` lists two)."""
    names = set()
    for line in text.splitlines():
        if not line.strip() or line.startswith((" ", "\t")):
            continue  # a description line (indented under its entry)
        head = line.split(" : ")[0].rstrip(":").strip()
        names |= {n.strip() for n in head.split(",") if n.strip()}
    return names


def expected(fn) -> set:
    out = set()
    for p in inspect.signature(fn).parameters.values():
        prefix = {p.VAR_POSITIONAL: "*", p.VAR_KEYWORD: "**"}.get(p.kind, "")
        out.add(prefix + p.name)
    return out


@pytest.mark.parametrize("name", _public_functions())
def test_every_argument_is_documented(name):
    fn = getattr(mbseig, name)
    assert fn.__doc__, f"{name} has no docstring"
    sec = sections(fn.__doc__)
    for title in ("Returns", "Examples"):
        assert title in sec, f"{name}: no {title} section"
    want = expected(fn)
    if want:
        assert "Parameters" in sec, f"{name}: no Parameters section"
        got = documented(sec["Parameters"])
        assert want - got == set(), f"{name}: not documented: {sorted(want - got)}"
        assert got - want == set(), f"{name}: documents arguments it does not take: " \
                                    f"{sorted(got - want)}"


def test_the_check_sees_an_undocumented_argument():
    """The parser finds what it checks (so a passing test means what it says)."""
    def f(a, b, *rest, c=1, **more):
        """Do.

        Parameters
        ----------
        a, b : int
            Two.
        *rest
            More.
        c : int

        Returns
        -------
        None

        Examples
        --------
        >>> f(1, 2)
        """
    sec = sections(f.__doc__)
    assert documented(sec["Parameters"]) == {"a", "b", "*rest", "c"}
    assert expected(f) - documented(sec["Parameters"]) == {"**more"}
    assert {"Returns", "Examples"} <= set(sec)


def test_there_are_public_functions():
    assert {"analyze", "modes", "equilibrium", "linearize", "run_sweep"} <= set(
        _public_functions())
