"""The batched evaluation of 3-D beam elements (mbseig.model.beam3d_kernel, beam3d_batch)
against each element evaluated alone.

References and tolerances:
- the per-element reference path (``Beam3DElement.force_reference``, ``mass_reference``,
  ``velocity_terms_reference``, ``jacobians_reference``: the element's formulas, themselves
  checked by complex step in tests/test_beams3d_corotational.py and against central differences
  in tests/test_check_flexible.py): 1e-12 of the largest entry (the same sums in another order;
  the velocity terms, a difference of terms up to ~100× the result, 1e-11);
- central differences (step 1e-6 of coordinates of order 1, truncation ~1e-12, rounding ~1e-10)
  of the batched force (its tangent K = −∂g/∂q) and of the batched mass (the velocity terms
  h = Ṁq̇ − ½∂(q̇ᵀMq̇)/∂q): 1e-6 of the largest entry.
"""

import pickle

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mbseig.errors import EquilibriumError
from mbseig.model import beam3d
from mbseig.model.affine import Affine, combine
from mbseig.model.beam3d import (
    Beam3DElement,
    BeamProperties3D,
    section_frame,
    section_properties,
)

START, END = np.array([0.1, -0.2, 0.3]), np.array([1.1, 0.4, 0.9])


def _props(theory):
    sp = section_properties(shape="rectangle", dims={"b": 0.02, "h": 0.05}, nu=0.3)
    return BeamProperties3D(E=2.1e11, G=2.1e11 / 2.6, rho=7800.0, A=sp["A"], Iy=sp["Iy"],
                            Iz=sp["Iz"], J=sp["J"], kappa_y=sp["kappa"], kappa_z=sp["kappa"],
                            theory=theory)


def _beam(n_el=5, theory="timoshenko", spins=None):
    """n_el elements on an oblique line, node 0 clamped (a constant frame: its elements have 12
    coordinates, the others 24), unequal element lengths, one shared BeamProperties3D."""
    props = _props(theory)
    R0 = section_frame(START, END, [0.0, 0.0, 1.0])
    s = np.cumsum(np.r_[0.0, 1.0 + 0.3 * np.arange(n_el)])
    s /= s[-1]
    pts = START + s[:, None] * (END - START)
    frames = [Affine.constant(np.concatenate([pts[0], np.eye(3).ravel()]))]
    for k in range(1, n_el + 1):
        frames.append(Affine(np.arange(12 * (k - 1), 12 * k), np.eye(12), np.zeros(12)))
    q0 = np.concatenate([np.concatenate([pts[k], np.eye(3).ravel()]) for k in range(1, n_el + 1)])
    spins = spins or [0.0] * n_el
    els = [Beam3DElement(f"b element {k + 1}", combine([(1.0, frames[k]), (1.0, frames[k + 1])],
                                                       stack=True),
                         props, float(s[k + 1] - s[k]) * np.linalg.norm(END - START), R0, spins[k])
           for k in range(n_el)]
    return els, q0


def _state(q0, rng, scale=0.05):
    """A deformed state: nodes moved, triads rotated (on the triad manifold), plus rates."""
    q = q0.copy()
    for k in range(q0.size // 12):
        q[12 * k:12 * k + 3] += scale * 0.1 * rng.normal(size=3)
        R = Rotation.from_rotvec(rng.normal(size=3) * scale).as_matrix()
        q[12 * k + 3:12 * k + 12] = R.T.ravel()
    return q, rng.normal(size=q0.size)


def _rel(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


@pytest.mark.parametrize("theory", ["timoshenko", "euler-bernoulli"])
def test_batched_equals_each_element_alone(theory):
    """Force, mass, velocity terms and tangent of every element of a beam (clamped first node:
    members of two widths; mixed spins), served from the batch, against the element alone:
    1e-12 (1e-11 for the velocity terms) of the largest entry, at three deformed states."""
    els, q0 = _beam(5, theory, spins=[0.0, 300.0, 0.0, -50.0, 800.0])
    rng = np.random.default_rng(1)
    for _ in range(3):
        q, qd = _state(q0, rng)
        got = {k: [getattr(e, k)(q, qd) for e in els] for k in ("force", "velocity_terms",
                                                                 "jacobians")}
        got["mass"] = [e.mass(q) for e in els]
        for e, g, m, h, (K, C) in zip(els, got["force"], got["mass"], got["velocity_terms"],
                                      got["jacobians"], strict=True):
            assert _rel(g, e.force_reference(q, qd)) <= 1e-12
            assert _rel(m, e.mass_reference(q)) <= 1e-12
            assert _rel(h, e.velocity_terms_reference(q, qd)) <= 1e-11
            Kr, Cr = e.jacobians_reference(q, qd)
            assert _rel(K, Kr) <= 1e-12
            if e.spin:
                assert _rel(C, Cr) <= 1e-12
            else:
                assert not np.any(C) and not np.any(Cr)
    assert {e.idx.size for e in els} == {12, 24}


def test_batched_tangent_and_velocity_terms_against_central_differences():
    """K = −∂g/∂q of the batched force, and h = Ṁq̇ − ½∂(q̇ᵀMq̇)/∂q of the batched mass, by
    central differences (step 1e-6): 1e-6 of the largest entry."""
    els, q0 = _beam(3, "timoshenko", spins=[0.0, 200.0, 0.0])
    rng = np.random.default_rng(2)
    q, qd = _state(q0, rng)
    step = 1e-6
    for e in els:
        idx = e.idx
        K, _ = e.jacobians(q, qd)
        Kfd = np.empty_like(K)
        for c, j in enumerate(idx):
            dq = np.zeros_like(q)
            dq[j] = step
            Kfd[:, c] = -(e.force(q + dq, qd) - e.force(q - dq, qd)) / (2 * step)
        if e.spin:  # the gyroscopic force's ∂/∂q (∝ Ω q̇) is left out of K: at rest only
            Kfd = np.empty_like(K)
            zero = np.zeros_like(qd)
            for c, j in enumerate(idx):
                dq = np.zeros_like(q)
                dq[j] = step
                Kfd[:, c] = -(e.force(q + dq, zero) - e.force(q - dq, zero)) / (2 * step)
        assert _rel(K, Kfd) <= 1e-6
        v = qd[idx]
        dq = np.zeros_like(q)
        dq[idx] = v
        ref = (e.mass(q + step * dq) - e.mass(q - step * dq)) @ v / (2 * step)
        for c, j in enumerate(idx):
            dq = np.zeros_like(q)
            dq[j] = step
            ref[c] -= v @ (e.mass(q + dq) - e.mass(q - dq)) @ v / (4 * step)
        assert _rel(e.velocity_terms(q, qd), ref) <= 1e-6


def test_served_results_follow_the_state_and_are_copies():
    """A batch is served only while the asking element's own coordinates are unchanged: after
    an in-place change of q the results are those of the new state (equal to the element
    alone, 1e-12); a served array changed by the caller does not change the next one."""
    els, q0 = _beam(4)
    rng = np.random.default_rng(3)
    q, qd = _state(q0, rng)
    for e in els:  # each alone (the first request), then in one batch
        e.force(q0, qd)
    first = [e.force(q, qd) for e in els]
    first[0][:] = 0.0  # the caller's copy
    assert np.any(els[0].force(q, qd))
    q[5] += 1e-3  # in place: node 1's triad (elements 1 and 2)
    for e in els:
        assert _rel(e.force(q, qd), e.force_reference(q, qd)) <= 1e-12
        assert _rel(e.mass(q), e.mass_reference(q)) <= 1e-12
    assert _rel(els[1].force(q, qd), first[1]) > 1e-6  # it did change
    assert np.array_equal(els[3].force(q, qd), first[3])  # untouched coordinates: same (batch)


def test_collapsed_member_raises_alone():
    """An element of zero length raises EquilibriumError naming it (as alone); the other
    members of its batch are evaluated as usual (equal to alone, 1e-12)."""
    els, q0 = _beam(3)
    q, qd = _state(q0, np.random.default_rng(6))
    for e in els:  # a batch of all three
        e.force(q, qd)
    q[12:15] = q[0:3]  # nodes 1 and 2 coincide: element 2 collapses
    assert _rel(els[0].force(q, qd), els[0].force_reference(q, qd)) <= 1e-12
    with pytest.raises(EquilibriumError, match="collapsed"):
        els[1].force(q, qd)
    with pytest.raises(EquilibriumError, match="collapsed"):
        els[1].force_reference(q, qd)
    assert _rel(els[2].force(q, qd), els[2].force_reference(q, qd)) <= 1e-12


def test_pickled_element_evaluates_alike():
    """The group's cache is not pickled (the properties pickle their fields only); an element
    read back evaluates equal to the original (1e-12) and the properties compare equal."""
    els, q0 = _beam(2)
    rng = np.random.default_rng(4)
    q, qd = _state(q0, rng)
    g = els[1].force(q, qd)
    assert "_batch" in els[1].props.__dict__
    back = pickle.loads(pickle.dumps(els[1]))
    assert "_batch" not in back.props.__dict__ and back.props == els[1].props
    assert _rel(back.force(q, qd), g) <= 1e-12


def test_reference_switch_and_complex_states_take_the_element_path(monkeypatch):
    """BATCHED = False and complex states evaluate the element alone: the same numbers (the
    reference itself, exactly; the complex state's real part to 1e-12)."""
    els, q0 = _beam(2)
    rng = np.random.default_rng(5)
    q, qd = _state(q0, rng)
    monkeypatch.setattr(beam3d, "BATCHED", False)
    assert np.array_equal(els[0].force(q, qd), els[0].force_reference(q, qd))
    monkeypatch.setattr(beam3d, "BATCHED", True)
    gc = els[0].force(q.astype(complex), qd)
    assert np.iscomplexobj(gc) and _rel(gc.real, els[0].force(q, qd)) <= 1e-12


def test_an_element_alone_and_in_its_batch_agree_exactly():
    """A member's numbers do not depend on the batch it is evaluated in (one padded width,
    sums term by term): alone and among all members, bitwise equal, so that M(q₀) − M_ref of
    a model is exactly zero where M_ref was formed element by element."""

    els, q0 = _beam(5, spins=[0.0, 300.0, 0.0, 0.0, 10.0])
    q, qd = _state(q0, np.random.default_rng(7))
    _assert_alone_equals_together(els, q, qd)


def _assert_alone_equals_together(els, q, qd):
    """Every kind of every member, evaluated among all members and alone: bitwise equal."""
    from mbseig.model.beam3d_batch import BatchGroup

    for kind in ("force", "mass", "velocity_terms", "jacobians"):
        together = BatchGroup().evaluate_all(kind, els, q, qd)
        for e, t in zip(els, together, strict=True):
            alone = BatchGroup().evaluate_all(kind, [e], q, qd)[0]
            assert all(np.array_equal(a, b) for a, b in zip(np.atleast_1d(alone),
                                                            np.atleast_1d(t), strict=True))


def test_assembled_model_equals_element_by_element(monkeypatch):
    """cases/overhung_rotor_friswell.toml (spinning Timoshenko shaft, disks welded to
    stations): the assembled g(q, q̇), M(q), K and C with the beams batched against
    ``BATCHED = False`` (each element alone), at a state off the equilibrium: 1e-12 of the
    largest entry."""
    from pathlib import Path

    from mbseig.casefile import load_case

    path = Path(__file__).resolve().parents[1] / "cases" / "overhung_rotor_friswell.toml"
    model = load_case(path)
    rng = np.random.default_rng(8)
    q = model.q_init + 1e-3 * rng.standard_normal(model.n)
    qd = rng.standard_normal(model.n)
    out = {}
    for batched in (True, False):
        monkeypatch.setattr(beam3d, "BATCHED", batched)
        K, C = model.force_jacobians(q, qd, dense=False)
        out[batched] = (model.generalized_force(q, qd), model.mass_matrix(q).toarray(),
                        K.toarray(), C.toarray())
    for a, b in zip(out[True], out[False], strict=True):
        assert _rel(a, b) <= 1e-12


def test_shared_maps_and_chunks_agree_exactly_with_each_member_alone(monkeypatch):
    """A free beam (every element on its two nodes' own 24 coordinates): its members share one
    node map, which the kernel stack broadcasts instead of copying, and a batch larger than
    ``CHUNK`` is evaluated chunk by chunk through views of the one stack.  Each member's
    numbers, together (in chunks of 2 here) and alone, bitwise equal, as for the stacked maps
    above; and the map is shared (one array for all members).  Two reference lengths (every
    other element prestrained by 10 %): the stack keeps the two element mass matrices once
    each and gathers every member's own."""
    from mbseig.model import beam3d_batch
    from mbseig.model.beam3d_batch import BatchGroup
    from mbseig.model.beam3d_kernel import Stack

    props = _props("timoshenko")
    R0 = section_frame(START, END, [0.0, 0.0, 1.0])
    n_el = 5
    pts = START + np.linspace(0.0, 1.0, n_el + 1)[:, None] * (END - START)
    frames = [Affine(np.arange(12 * k, 12 * k + 12), np.eye(12), np.zeros(12))
              for k in range(n_el + 1)]
    q0 = np.concatenate([np.concatenate([p, np.eye(3).ravel()]) for p in pts])
    length = np.linalg.norm(END - START) / n_el
    els = [Beam3DElement(f"b element {k + 1}", combine([(1.0, frames[k]), (1.0, frames[k + 1])],
                                                       stack=True),
                         props, length * (1.0 + 0.1 * (k % 2)), R0, 100.0 * k)
           for k in range(n_el)]
    stack = Stack([e.kernel_record() for e in els])
    assert stack.C.strides[0] == 0  # one map, broadcast
    distinct = {e.kernel_record()["M"].tobytes() for e in els}
    assert len(distinct) == 2 and stack.__dict__["_M"][0].shape[0] <= len(els)
    assert all(np.array_equal(stack.M[k], e.kernel_record()["M"]) for k, e in enumerate(els))
    assert all(np.array_equal(stack.part(slice(1, 4)).M[k], els[1 + k].kernel_record()["M"])
               for k in range(3))
    monkeypatch.setattr(beam3d_batch, "CHUNK", 2)
    q, qd = _state(q0, np.random.default_rng(11))
    _assert_alone_equals_together(els, q, qd)
    # and against the element's own formulas (the reference path), as the tests above
    for e, g in zip(els, BatchGroup().evaluate_all("force", els, q, qd), strict=True):
        assert _rel(g, e.force_reference(q, qd)) <= 1e-12
