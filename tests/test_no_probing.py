"""Traits are declared, never probed (issue "One pipeline"): no ``hasattr`` on an element, a model
or a result, and no ``getattr(x, "name", default)`` on an element.

What an element is drawn as, whether it is a load the statics may scale, whether it gives its
velocity terms in closed form, its reaction's role and wrench, a rotor's station map: each is a
class attribute of :mod:`mbseig.model.base` or the element class, read directly.  The scan is
of the source (the abstract syntax tree of every module of mbseig), so it cannot pass by a
path the tests do not run.

Allowed, each for its reason:
- ``arguments.py``: the checks of the public functions' arguments recognise what a user passed
  (an iterable, a sparse matrix) by its interface; that is what they are for;
- ``eigen/slepc.py``, ``studies/workers.py``: operating-system features (``os.geteuid``,
  ``signal.pthread_sigmask``) that some platforms lack;
- ``bench/``: the benchmarks measure other codes' objects as they come.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent / "mbseig"
ALLOWED_HASATTR = {"arguments.py", "eigen/slepc.py", "studies/workers.py"}
#: names an element is bound to in mbseig's loops over model.forces / model.constraints
ELEMENT_NAMES = {"e", "el", "elem", "element", "c", "f", "con", "force", "constraint", "w",
                 "wheel", "r", "rotor", "j", "joint"}


def _modules():
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if not rel.startswith("bench/"):
            yield rel, ast.parse(path.read_text(encoding="utf-8"))


def _calls(tree, name):
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                and node.func.id == name):
            yield node


def test_no_hasattr_outside_the_reasoned_places():
    found = [f"{rel}:{node.lineno}" for rel, tree in _modules() if rel not in ALLOWED_HASATTR
             for node in _calls(tree, "hasattr")]
    assert found == []


def test_no_getattr_with_a_default_on_an_element():
    found = []
    for rel, tree in _modules():
        for node in _calls(tree, "getattr"):
            obj = node.args[0] if node.args else None
            if (len(node.args) == 3 and isinstance(obj, ast.Name) and obj.id in ELEMENT_NAMES
                    and isinstance(node.args[1], ast.Constant)):
                found.append(f"{rel}:{node.lineno} getattr({obj.id}, {node.args[1].value!r}, ...)")
    assert found == []


def test_the_scan_sees_a_probe():
    """The two scans find what they forbid (so an empty result means there is none)."""
    tree = ast.parse("hasattr(e, 'stiffness')\ngetattr(e, 'magnitude', None)\n")
    assert len(list(_calls(tree, "hasattr"))) == 1
    assert [n.args[0].id for n in _calls(tree, "getattr")] == ["e"]
