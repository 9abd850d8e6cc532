"""The fast paths of the reader and of the assembly build the same model as the general ones.

- repeated spatial bodies and bushings read at once (mbseig.casefile.batch.repeated_fields)
  against the member-by-member reader (the same case with ``enabled = 1`` on each repeated
  table, which the batch path declines and the member reader evaluates to "enabled"): the same
  coordinates, element names, mass matrix and gravity, exactly, and the same Φ, Φ_q, g, K, C
  and H(λ) at a configuration off the reference to 1e-12 relative (the reading is exact; the
  assembly of at least mbseig.model.batched.GROUP_MIN elements of one kind, lowered to 16
  here, is batched, whose sums run in another order: rounding);
- the batched kernels (QuadraticGroup) against each element's own methods, 1e-12 relative;
- bad input inside a repeated table: the batch declines and the member reader names the member
  with the same one-line message (texts written out here, the reader's rules);
- the kept values of repeated expressions: a result never stands for another value (0.0 and
  -0.0 told apart, as atan2 does).
"""

import math

import numpy as np
import pytest
from conftest import write_case

import mbseig
from mbseig.casefile.expr import evaluate
from mbseig.casefile.spatial import SpatialBuilder
from mbseig.casefile.spatial_readers import SpatialElementReaders
from mbseig.errors import CaseError
from mbseig.model import batched

CHAIN = """
schema_version = 1
dimension = 3
gravity = [0.0, 0.0, -9.81]
[parameters]
n = {n}
h = "2.0 / n"
m = "8.0 * h"
k = "2e8 / h"
kr = "2e4 / h"
[[bodies]]
repeat = {{ i = [1, "n"] }}
name = "b{{i}}"
mass = "m"
com = ["(i - 0.5) * h", "0.01 * sin(i)", 0.0]
inertia = ["m * 1e-3", "m * (5e-4 + h**2 / 12)", "m * (6e-4 + h**2 / 12)"]
{enabled}
[[forces]]
repeat = {{ i = [1, "n - 1"] }}
type = "bushing"
bodies = ["b{{i}}", "b{{i + 1}}"]
at = ["i * h", 0.0, 0.0]
stiffness = ["k", "k", "k", "kr", "kr", "1.5 * kr"]
damping = [1.0, 1.0, 1.0, 0.1, 0.1, 0.1]
{enabled}
[[forces]]
type = "bushing"
bodies = ["ground", "b1"]
at = [0.0, 0.0, 0.0]
stiffness = ["k", "k", "k", "kr", "kr", "1.5 * kr"]
[[joints]]
type = "spherical"
bodies = ["b{n}", "ground"]
at = [2.0, 0.0, 0.0]
"""

N = 80  # bodies; the assembly batches kinds of at least GROUP_MIN elements, set to 16 here


@pytest.fixture(autouse=True)
def _small_groups(monkeypatch):
    monkeypatch.setattr(batched, "GROUP_MIN", 16)


def _models(tmp_path):
    fast = mbseig.load_case(write_case(tmp_path, CHAIN.format(n=N, enabled=""), "fast.toml"))
    slow = mbseig.load_case(write_case(tmp_path, CHAIN.format(n=N, enabled="enabled = 1"),
                                       "slow.toml"))
    return fast, slow


def _close(a, b, what):
    a, b = (x.toarray() if hasattr(x, "toarray") else np.asarray(x) for x in (a, b))
    scale = max(np.abs(b).max(initial=0.0), 1e-300)
    assert a.shape == b.shape, what
    assert np.abs(a - b).max(initial=0.0) <= 1e-12 * scale, what


def test_batch_reader_builds_the_member_readers_model(tmp_path, monkeypatch):
    taken = []
    for cls, name in ((SpatialBuilder, "_bodies"), (SpatialElementReaders, "bushings")):
        original = getattr(cls, name)

        def spy(*args, _f=original, _name=name):
            out = _f(*args)
            taken.append((_name, out))
            return out
        monkeypatch.setattr(cls, name, spy)
    fast, slow = _models(tmp_path)
    # the fast case reads both tables at once; the slow one's bodies decline (enabled)
    assert taken == [("_bodies", True), ("bushings", True), ("_bodies", False)]
    assert fast.coordinate_names == slow.coordinate_names
    assert fast.coordinate_kinds == slow.coordinate_kinds
    assert np.array_equal(fast.q_init, slow.q_init)
    assert [f.name for f in fast.forces] == [f.name for f in slow.forces]
    assert [c.name for c in fast.constraints] == [c.name for c in slow.constraints]
    assert fast.element_ends == slow.element_ends
    assert sorted(fast.points) == sorted(slow.points)
    assert (fast.mass != slow.mass).nnz == 0 and fast.mass.nnz == slow.mass.nnz
    assert np.array_equal(fast.g_const, slow.g_const)
    rng = np.random.default_rng(1)
    q = fast.q_init + 1e-3 * rng.standard_normal(fast.n)
    qd = 1e-2 * rng.standard_normal(fast.n)
    lam = rng.standard_normal(fast.n_constraints)
    for what, f in (("phi", lambda m: m.phi(q)), ("phi_q", lambda m: m.phi_q(q)),
                    ("g", lambda m: m.generalized_force(q, qd)),
                    ("K", lambda m: m.force_jacobians(q, qd)[0]),
                    ("C", lambda m: m.force_jacobians(q, qd)[1]),
                    ("H", lambda m: m.constraint_hessian(q, lam)),
                    ("gamma", lambda m: m.gamma(q, qd))):
        _close(f(fast), f(slow), what)


def test_batched_kernels_equal_the_elements_own(tmp_path):
    model, _ = _models(tmp_path)
    rng = np.random.default_rng(2)
    q = model.q_init + 1e-3 * rng.standard_normal(model.n)
    qd = 1e-2 * rng.standard_normal(model.n)
    assert model._groups[0] and model._groups[2]  # both kinds are batched at this size
    _close(model.phi(q), np.concatenate([c.phi(q) for c in model.constraints]), "phi")
    _close(model.gamma(q, qd), np.concatenate([c.gamma(q, qd) for c in model.constraints]),
           "gamma")
    off = np.cumsum([0] + [c.n_eq for c in model.constraints])
    lam = rng.standard_normal(off[-1])
    H = model.constraint_hessian(q, lam).toarray()
    J = model.phi_q(q).toarray()
    H_ref, J_ref = np.zeros_like(H), np.zeros_like(J)
    for k, c in enumerate(model.constraints):
        H_ref[np.ix_(c.idx, c.idx)] += c.hess(q, lam[off[k]:off[k + 1]])
        J_ref[off[k]:off[k + 1], c.idx] += c.jac(q)
    _close(H, H_ref, "H")
    _close(J, J_ref, "phi_q")
    K, C = model.force_jacobians(q, qd)
    K_ref, C_ref = np.zeros((model.n, model.n)), np.zeros((model.n, model.n))
    g_ref = model.g_const.copy()
    for f in model.forces:
        Kf, Cf = f.jacobians(q, qd)
        K_ref[np.ix_(f.idx, f.idx)] += Kf
        C_ref[np.ix_(f.idx, f.idx)] += Cf
        g_ref[f.idx] += f.force(q, qd)
    _close(K, K_ref, "K")
    _close(C, C_ref, "C")
    _close(model.generalized_force(q, qd), g_ref, "g")


BAD_BODY = """
schema_version = 1
dimension = 3
[[bodies]]
repeat = { i = [1, 4] }
name = "b{i}"
mass = 1.0
com = ["i", 0.0, 0.0]
inertia = [1.0, "1.0 + 5 * max(0, 1 - abs(i - 3))", 1.0]
"""

BAD_BUSHING = """
schema_version = 1
dimension = 3
[[bodies]]
repeat = { i = [1, 4] }
name = "b{i}"
mass = 1.0
com = ["i", 0.0, 0.0]
inertia = [1.0, 1.0, 1.0]
[[forces]]
repeat = { i = [1, 4] }
type = "bushing"
bodies = ["b{i}", "b{i + 1}"]
at = ["i + 0.5", 0.0, 0.0]
stiffness = [1, 1, 1, 1, 1, 1]
"""


@pytest.mark.parametrize("text, message", [
    (BAD_BODY, "bodies[0] 'b{i}' (i=3): principal moments 1, 1, 6 violate the triangle "
               "inequality I3 <= I1 + I2 (no mass distribution has them)"),
    (BAD_BUSHING, "forces[0] (i=4): unknown body 'b5'"),
])
def test_bad_member_of_a_repeated_table_is_named(tmp_path, text, message):
    path = write_case(tmp_path, text)
    with pytest.raises(CaseError) as err:
        mbseig.load_case(path)
    assert str(err.value) == f"{path}: {message}"


def test_kept_expression_values_never_stand_for_another_value():
    for x in (1.0, -1.0, 0.0, -0.0, 1.0, 0.0, -0.0):  # repeated: kept values are used
        assert evaluate("atan2(0, x)", {"x": x}) == math.atan2(0.0, x)
        assert math.copysign(1.0, evaluate("x", {"x": x})) == math.copysign(1.0, x)
    assert evaluate("a * b", {"a": 2.0, "b": 3.0}) == 6.0
    assert evaluate("a * b", {"a": 2.0, "b": 4.0}) == 8.0  # another value of one name
    assert evaluate("pi", {}) == math.pi and evaluate("pi", {"pi": 3.0}) == 3.0


def test_small_spatial_mass_has_no_explicit_zeros(tmp_path):
    """Without point masses the bodies' blocks are the whole mass matrix, kept without explicit
    zeros as their former sum with an empty matrix kept it (the structure the solvers saw)."""
    model, _ = _models(tmp_path)
    assert model.mass.nnz == np.count_nonzero(model.mass.toarray())
