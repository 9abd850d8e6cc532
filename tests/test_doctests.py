"""The examples in the public docstrings run, and print what they say (doctest), on the small
example cases of :mod:`mbseig.casefile.examples` (closed forms: ω_n = √(g/l), δ = c/(2m))."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = ["mbseig.casefile.examples", "mbseig.casefile", "mbseig.casefile.writer",
           "mbseig.statics", "mbseig.modal", "mbseig.modal.rules", "mbseig.eigen.dense",
           "mbseig.check.modes", "mbseig.studies.reference", "mbseig.studies.pipeline",
           "mbseig.studies.sweep", "mbseig.studies.report_data"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # an example that writes files writes them here
    module = importlib.import_module(name)
    res = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE,
                          verbose=False, report=True)
    assert res.attempted > 0, f"{name} has no examples"
    assert res.failed == 0
