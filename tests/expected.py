"""Evaluate the ``[expected]`` table of a case (closed forms stated in the case file)."""

import numpy as np

from mbseig.casefile.expr import evaluate


def _series(spec, params, keys):
    if isinstance(spec, list):
        return [tuple(evaluate(x, params) for x in (item if isinstance(item, list) else [item]))
                for item in spec]
    var = spec["index"]
    first, last = (int(evaluate(b, params)) for b in spec["range"])
    out = []
    for j in range(first, last + 1):
        names = {**params, var: float(j)}
        out.append(tuple(evaluate(spec[k], names) for k in keys))
    return out


def expected_omega_n(expected, params):
    if "omega_n" not in expected:
        return None
    return np.array([v[0] for v in _series(expected["omega_n"], params, ["formula"])])


def expected_eigenvalues(expected, params):
    if "eigenvalues" not in expected:
        return None
    return np.array([complex(re, im)
                     for re, im in _series(expected["eigenvalues"], params, ["re", "im"])])
