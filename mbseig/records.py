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

__all__ = ["Record", "optional", "internal", "encode", "decode", "RecordFormatError",
           "NOT_DATA_MODULES"]


def optional(default=None):
    """A field left out of :meth:`Record.to_json` (and of the mapping view) while it is None."""
    return field(default=default, metadata={"optional": True})


def internal(default=None):
    """A field kept for a later stage (vectors, shapes) and never written to JSON."""
    return field(default=default, metadata={"internal": True}, repr=False, compare=False)


_FIELDS: dict = {}  # record class → {field name: whether it is optional}, in declaration order


def _fields(cls) -> dict:
    """The field list of a record class, read once (a sweep reads its points and their static
    records by key many times per point)."""
    spec = _FIELDS.get(cls)
    if spec is None:
        spec = _FIELDS[cls] = {f.name: bool(f.metadata.get("optional"))
                               for f in dataclasses.fields(cls)}
    return spec


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
        return [k for k, opt in _fields(type(self)).items()
                if not (opt and getattr(self, k) is None)]

    def items(self):
        return [(k, getattr(self, k)) for k in self.keys()]

    def __contains__(self, key) -> bool:
        opt = _fields(type(self)).get(key)
        return opt is not None and not (opt and getattr(self, key) is None)

    def __getitem__(self, key):
        if key not in self:
            raise KeyError(key)
        return getattr(self, key)

    def get(self, key, default=None):
        return getattr(self, key) if key in self else default

    def to_json(self) -> dict:
        """The fields in declaration order, without the internal and the unset optional ones."""
        return {f.name: v for f, v in self._present() if not f.metadata.get("internal")}


# ---- records written and read back exactly: JSON and arrays, never pickle -----------------
#
# A study's results are kept between runs (mbseig.studies.resume) as one JSON document and the
# arrays it refers to, in one ``.npz`` file read with ``allow_pickle=False``: reading builds
# numbers, strings, containers, numpy arrays and scalars, scipy sparse matrices and mbseig's
# own data classes (dataclasses of mbseig's modules, :class:`mbseig.modal.result.Verdict`),
# each field set as written and no constructor or method of theirs run.  Nothing in a file can
# name a function to call.  Every value comes back bit for bit: floats are written by ``repr``
# (shortest exact form), arrays as arrays (dtype and bytes kept), a tuple as a tuple, a dict
# with its keys' types and order.

#: modules whose classes are never data (they start processes, write files, run commands)
NOT_DATA_MODULES = ("mbseig.studies.resume", "mbseig.studies.runners", "mbseig.studies.workers",
                    "mbseig.cli", "mbseig.report", "mbseig.bench", "mbseig.plots")


class RecordFormatError(ValueError):
    """A stored record names a class mbseig never writes, or is not a record mbseig wrote."""


def encode(obj):
    """``obj`` as (a JSON-able structure, {name: numpy array}) for :func:`decode` (module
    section above)."""
    arrays: dict = {}
    return _enc(obj, arrays), arrays


def _enc(x, arrays):
    import numpy as np
    import scipy.sparse as sp

    if x is None or type(x) in (bool, str):  # (a str subclass such as Verdict: below)
        return x
    if isinstance(x, (np.ndarray, np.generic)):
        a = np.asarray(x)
        if a.dtype == object:
            return {"oa": list(a.shape), "v": [_enc(v, arrays) for v in a.ravel().tolist()]}
        key = f"a{len(arrays)}"
        arrays[key] = a
        return {"a": key, "scalar": isinstance(x, np.generic)}
    if type(x) is int:
        return x
    if type(x) is float:
        return {"f": repr(x)}
    if type(x) is complex:
        return {"c": [repr(x.real), repr(x.imag)]}
    if type(x) is list:
        return [_enc(v, arrays) for v in x]
    if type(x) is tuple:
        return {"t": [_enc(v, arrays) for v in x]}
    if type(x) is dict:
        return {"d": [[_enc(k, arrays), _enc(v, arrays)] for k, v in x.items()]}
    if type(x) in (set, frozenset):
        return {type(x).__name__: [_enc(v, arrays) for v in x]}
    if type(x) is bytes:
        return {"b": x.hex()}
    if sp.issparse(x) and x.format in ("csr", "csc", "coo"):
        parts = ([x.data, x.row, x.col] if x.format == "coo" else [x.data, x.indices, x.indptr])
        return {"sp": x.format, "shape": list(x.shape), "v": [_enc(p, arrays) for p in parts]}
    cls = type(x)
    name = f"{cls.__module__}:{cls.__qualname__}"
    if isinstance(x, str) and _data_module(cls.__module__):  # a word with attributes (Verdict)
        return {"word": name, "v": str.__str__(x),
                "attrs": [[k, _enc(v, arrays)] for k, v in vars(x).items()]}
    if dataclasses.is_dataclass(x) and _data_module(cls.__module__):
        return {"r": name, "f": [[f.name, _enc(getattr(x, f.name), arrays)]
                                 for f in dataclasses.fields(x)]}
    raise TypeError(f"{name} is not a record mbseig writes")


def _data_module(module: str) -> bool:
    return module.split(".")[0] == "mbseig" and not module.startswith(NOT_DATA_MODULES)


def _data_class(name):
    """The class ``module:qualname`` of one of mbseig's data modules (imported), or a
    :class:`RecordFormatError`."""
    import importlib

    module, _, qualname = str(name).partition(":")
    if not _data_module(module) or "." in qualname:
        raise RecordFormatError(f"names {module}.{qualname}, which mbseig never writes")
    try:
        cls = getattr(importlib.import_module(module), qualname, None)
    except ImportError:
        cls = None
    if not isinstance(cls, type):
        raise RecordFormatError(f"names {module}.{qualname}, which is not a class of mbseig")
    return cls


def decode(data, arrays):
    """The object :func:`encode` wrote: ``data`` its JSON structure, ``arrays`` a mapping of its
    arrays (e.g. an ``np.load(..., allow_pickle=False)`` file).  A class outside mbseig's data
    modules, or anything :func:`encode` never writes, is a :class:`RecordFormatError`."""
    return _dec(data, arrays)


def _dec(x, arrays):
    import numpy as np
    import scipy.sparse as sp

    if x is None or isinstance(x, (bool, int, str)):
        return x
    if isinstance(x, list):
        return [_dec(v, arrays) for v in x]
    if not isinstance(x, dict) or len(x) == 0:
        raise RecordFormatError(f"not a record mbseig writes: {str(x)[:60]}")
    if "f" in x and len(x) == 1:
        return float(x["f"])
    if "t" in x:
        return tuple(_dec(v, arrays) for v in x["t"])
    if "d" in x:
        return {_dec(k, arrays): _dec(v, arrays) for k, v in x["d"]}
    if "a" in x:
        a = np.asarray(arrays[x["a"]])
        return a[()] if x.get("scalar") else a
    if "c" in x:
        return complex(float(x["c"][0]), float(x["c"][1]))
    if "oa" in x:
        out = np.empty(len(x["v"]), dtype=object)
        out[:] = [_dec(v, arrays) for v in x["v"]]
        return out.reshape(x["oa"])
    if "set" in x or "frozenset" in x:
        kind = set if "set" in x else frozenset
        return kind(_dec(v, arrays) for v in x[kind.__name__])
    if "b" in x:
        return bytes.fromhex(x["b"])
    if "sp" in x:
        parts = [_dec(v, arrays) for v in x["v"]]
        shape = tuple(x["shape"])
        if x["sp"] == "coo":
            return sp.coo_matrix((parts[0], (parts[1], parts[2])), shape=shape)
        make = sp.csr_matrix if x["sp"] == "csr" else sp.csc_matrix
        return make((parts[0], parts[1], parts[2]), shape=shape)
    if "word" in x:
        cls = _data_class(x["word"])
        if not issubclass(cls, str):
            raise RecordFormatError(f"names {x['word']}, which is not a word")
        obj = str.__new__(cls, str(x["v"]))
        for name, value in x["attrs"]:
            object.__setattr__(obj, str(name), _dec(value, arrays))
        return obj
    if "r" in x:
        cls = _data_class(x["r"])
        if not dataclasses.is_dataclass(cls):
            raise RecordFormatError(f"names {x['r']}, which is not a record")
        names = {f.name for f in dataclasses.fields(cls)}
        obj = object.__new__(cls)
        for name, value in x["f"]:
            if name not in names:
                raise RecordFormatError(f"{cls.__name__} has no field {name!r}")
            object.__setattr__(obj, name, _dec(value, arrays))
        return obj
    raise RecordFormatError(f"not a record mbseig writes: {str(x)[:60]}")
