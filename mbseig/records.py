"""Typed records that cross stages: frozen dataclasses with read access by field name.

A result that one stage hands to another (a sweep point, a stability boundary, a fold, a
boundary curve, the static-stability record of an equilibrium) is a frozen dataclass built in
one place.  :class:`Record` gives it the read-only mapping view (``r["value"]``, ``r.get(...)``,
``"kind" in r``) that tables, plots and JSON writers use, and :meth:`Record.to_json`, which
writes its fields in declaration order, leaving out the fields marked ``internal`` (arrays kept
for a later stage, never written) and the optional ones that are unset (``None``).

    @dataclass(frozen=True)
    class Fold(Record):
        value: float
        branch: str | None = optional()

A record is never changed in place: :func:`dataclasses.replace` gives a new one.
"""

from __future__ import annotations

import dataclasses
from dataclasses import field

__all__ = ["Record", "optional", "internal"]


def optional(default=None):
    """A field left out of :meth:`Record.to_json` (and of the mapping view) while it is None."""
    return field(default=default, metadata={"optional": True})


def internal(default=None):
    """A field kept for a later stage (vectors, shapes) and never written to JSON."""
    return field(default=default, metadata={"internal": True}, repr=False, compare=False)


class Record:
    """Mixin of frozen dataclasses: read access by field name, ordered JSON (module docstring)."""

    __slots__ = ()

    def _present(self):
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.metadata.get("optional") and value is None:
                continue
            yield f, value

    def keys(self):
        return [f.name for f, _ in self._present()]

    def items(self):
        return [(f.name, v) for f, v in self._present()]

    def __contains__(self, key) -> bool:
        return key in self.keys()

    def __getitem__(self, key):
        if key not in self.keys():
            raise KeyError(key)
        return getattr(self, key)

    def get(self, key, default=None):
        return self[key] if key in self.keys() else default

    def to_json(self) -> dict:
        """The fields in declaration order, without the internal and the unset optional ones."""
        return {f.name: v for f, v in self._present() if not f.metadata.get("internal")}
