"""The one cache of model evaluations: the last few values of a quantity by the bytes of their
arguments (q, and λ where it enters).

A solve asks for Φ, Φ_q, g, K and H at one q several times (the Newton corrector, the force
scale, the static stability, the linearization), and assembling them is what costs; the model
keeps its last dense evaluations of a small model here (read-only, so that no caller changes a
kept one) and the statics keeps the quantities of one solve here
(:class:`mbseig.statics.cache.Memo`).
"""

from __future__ import annotations

__all__ = ["KeptValues"]


class KeptValues:
    """The last ``size`` values by key, oldest dropped first; ``readonly`` marks kept arrays
    (and the arrays of kept tuples) read-only."""

    def __init__(self, size, *, readonly=False):
        self.size, self.readonly = size, readonly
        self._values: dict = {}

    def get(self, key, compute):
        """The kept value of ``key``, or ``compute()`` kept under it."""
        hit = self._values.get(key)
        if hit is None:
            hit = compute()
            if self.readonly:
                for a in (hit if isinstance(hit, tuple) else (hit,)):
                    a.setflags(write=False)
            if len(self._values) >= self.size:
                self._values.pop(next(iter(self._values)))
            self._values[key] = hit
        return hit

    def peek(self, key):
        """The kept value of ``key``, or None (nothing computed)."""
        return self._values.get(key)

    def __len__(self):
        return len(self._values)
