"""Batched evaluation of the 3-D beam elements behind the one-element interface.

The model and the time-domain check ask every element in turn for its force, mass, velocity
terms or tangent at one state (``element.force(q, q̇)`` …).  The elements of a beam share one
:class:`BatchGroup` (kept on their :class:`~mbseig.model.beam3d_local.BeamProperties3D`, which
they share); when an element asks at a state its group has not evaluated, the group evaluates
at once, with :mod:`mbseig.model.beam3d_kernel`, every element that asked since its last batch
(the elements the caller evaluates together), and the others' requests at that state are then
served from the batch.

A result is served only when the asking element's own coordinates q[idx] (and q̇[idx] where the
quantity depends on them) equal, byte for byte, those of the batch: it depends on nothing else,
so a served result is the element's own at the state asked, whatever else changed.  An element
not in the batch is evaluated alone (a batch of one) and joins the next batch.  Each result is
served once (the caller owns the array, and the group keeps no batch alive after its members
were served); an element that asks again at the same state starts a new batch.  A member's
numbers do not depend
on the batch it is evaluated in (:class:`~mbseig.model.beam3d_kernel.Stack`), so that, e.g.,
M(q₀) − M_ref is exactly zero for a mass formed element by element when the model was built.
"""

from __future__ import annotations

import numpy as np

from ..errors import EquilibriumError
from . import beam3d_kernel as kern

__all__ = ["KINDS", "BatchGroup", "group_of"]

#: what a group evaluates, and whether it depends on q̇
KINDS = {"force": True, "jacobians": False, "mass": False, "velocity_terms": True}
#: stacks of member sets kept per group (a model's elements, and a few others)
STACKS_KEPT = 4
#: members evaluated together at most (their work arrays: about 20 kB a member each)
CHUNK = 1024


def group_of(props) -> BatchGroup:
    """The group of the elements that share ``props`` (made at the first request)."""
    group = props.__dict__.get("_batch")
    if group is None:
        group = BatchGroup()
        object.__setattr__(props, "_batch", group)
    return group


_SERVED = (b"", None)  # a member's entry once its result was served


class _Cache:
    """One kind's last batch: member → (key, result), and the members asked since."""

    def __init__(self):
        self.entries, self.asked = {}, {}


class BatchGroup:
    """The evaluation cache of the elements of one beam (module docstring)."""

    def __init__(self):
        self.caches = {kind: _Cache() for kind in KINDS}
        self.stacks = {}

    def evaluate(self, kind, element, q, qd):
        """The element's ``kind`` at (q, q̇), from the group's batch (module docstring)."""
        idx = element.idx
        key = q[idx].tobytes() + (qd[idx].tobytes() if KINDS[kind] else b"")
        cache = self.caches[kind]
        hit = cache.entries.get(element)
        if hit is None or hit[0] != key or hit[1] is None:
            if hit is None:  # not in the batch: alone, and in the next batch
                members = [element]
            else:
                members = [m for m in cache.asked if m is not element] + [element]
                cache.entries, cache.asked = {}, {}
            n = q.shape[0]
            members = [m for m in members if m is element or (m.idx.size and m.idx.max() < n)]
            results = self._run(kind, members, q, qd)
            for m, r in zip(members, results, strict=True):
                mi = m.idx
                cache.entries[m] = (q[mi].tobytes() + (qd[mi].tobytes() if KINDS[kind] else b""),
                                    r)
            hit = cache.entries[element]
        cache.asked[element] = None
        # served once: the caller owns it; a served entry is evaluated anew whatever its key,
        # so it keeps none (17,125 keys of 192 bytes a kind on a beam of 10⁵ DOF)
        cache.entries[element] = _SERVED
        result = hit[1]
        if isinstance(result, EquilibriumError):
            raise result
        return result

    def prime(self, kind, members, q, qd):
        """Evaluate ``kind`` of every member at (q, q̇) in one batch, each result then served
        once by :meth:`evaluate` (the caller is about to ask them all: the model's assembly)."""
        members = [m for m in members if m.idx.size and m.idx.max() < q.shape[0]]
        if not members:
            return
        cache = self.caches[kind]
        cache.entries, cache.asked = {}, {}
        dep = KINDS[kind]
        for m, r in zip(members, self._run(kind, members, q, qd), strict=True):
            mi = m.idx
            cache.entries[m] = (q[mi].tobytes() + (qd[mi].tobytes() if dep else b""), r)

    def evaluate_all(self, kind, members, q, qd):
        """``kind`` of every member at (q, q̇), evaluated together (no cache; the results of a
        collapsed member are its EquilibriumError)."""
        return self._run(kind, list(members), q, qd)

    # -- the batch ---------------------------------------------------------------------------
    def _stack(self, members):
        key = tuple(id(m) for m in members)
        hit = self.stacks.get(key)
        if hit is None or any(a is not b for a, b in zip(hit[0], members, strict=True)):
            if len(self.stacks) >= STACKS_KEPT:
                self.stacks.pop(next(iter(self.stacks)))
            hit = (tuple(members), kern.Stack([m.kernel_record() for m in members]))
            self.stacks[key] = hit
        return hit[1]

    def _run(self, kind, members, q, qd):
        """``kind`` of the members, CHUNK members at a time through the one stack (a member's
        numbers do not depend on its batch; the work arrays are a chunk's, not the beam's)."""
        st = self._stack(members)
        if len(members) <= CHUNK:
            return self._run_stack(kind, st, members, q, qd)
        out = []
        for a in range(0, len(members), CHUNK):
            part = slice(a, a + CHUNK)
            out += self._run_stack(kind, st.part(part), members[part], q, qd)
        return out

    def _run_stack(self, kind, st, members, q, qd):
        z = st.z(q)
        sizes = st.sizes
        if kind in ("mass", "velocity_terms"):  # (a collapsed member: not finite, as alone)
            TC = kern.velocity_map(z, kern.frame(z)) @ st.C
            if kind == "mass":
                Mq = kern.mass_q(TC, st.M)
                return [Mq[k, :s, :s] for k, s in enumerate(sizes)]
            h = st.to_q(kern.velocity_terms_z(z, st.z(qd, offset=False), st.M))
            return [h[k, :s] for k, s in enumerate(sizes)]
        d = z[:, 12:15] - z[:, 0:3]
        collapsed = np.einsum("ni,ni->n", d, d) == 0.0
        if np.any(collapsed):  # their own error; the other members are evaluated as usual
            z = np.where(collapsed[:, None], _UNIT, z)
        spin = bool(np.any(st.spin))
        if spin:
            TC = kern.velocity_map(z, kern.frame(z)) @ st.C
        p, length, e, X, ex = kern.measures(z, st.l0)
        Up, Upp = kern.energy_derivatives(st, p, hessian=kind == "jacobians")
        if kind == "force":
            g = -st.to_q(kern.force_z(z, Up, length, e, X, ex))
            if spin:  # − Ω Tᵀ G T q̇
                v = np.einsum("nij,nj->ni", st.G, np.einsum("nim,nm->ni", TC, qd[st.idx]))
                g = g - st.spin[:, None] * np.einsum("nim,ni->nm", TC, v)
            out = [g[k, :s] for k, s in enumerate(sizes)]
        else:
            K = st.Ct @ kern.stiffness_z(z, Up, Upp, length, e, X, ex) @ st.C
            if spin:
                C = st.spin[:, None, None] * (TC.transpose(0, 2, 1) @ st.G @ TC)
                out = [(K[k, :s, :s], C[k, :s, :s]) for k, s in enumerate(sizes)]
            else:  # no spin: every member's C is one read-only block of zeros
                Z = _zeros(K.shape[1])
                out = [(K[k, :s, :s], Z[:s, :s]) for k, s in enumerate(sizes)]
        for k in np.flatnonzero(collapsed):
            out[k] = EquilibriumError("beam element collapsed to zero length",
                                      element=members[k].name)
        return out


_ZEROS = {}


def _zeros(m):
    """One read-only m × m block of zeros (the damping of the members that do not spin)."""
    Z = _ZEROS.get(m)
    if Z is None:
        Z = np.zeros((m, m))
        Z.setflags(write=False)
        _ZEROS[m] = Z
    return Z


# a placeholder configuration for a collapsed member (its result is its error)
_UNIT = np.zeros(24)
_UNIT[12] = 1.0
_UNIT[6:9] = _UNIT[18:21] = [0.0, 1.0, 0.0]
_UNIT[9:12] = _UNIT[21:24] = [0.0, 0.0, 1.0]
