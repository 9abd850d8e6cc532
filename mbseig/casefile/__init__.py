"""The reader: TOML case files → :class:`~mbseig.model.Model` or
:class:`~mbseig.model.LinearCase`.  Nothing is solved here.

A case file is read and parsed once into a :class:`CaseSpec`, a picklable model factory:
``spec.build(config=..., **params)`` evaluates the parameters and builds the model from the
parsed content without touching the file again (matrix files are read once and kept), so a
sweep of many points, a report of many configurations or a mesh refinement parses the case once
and sends the content, not a path, to worker processes.

Only the entry points (the CLI, :mod:`mbseig.studies`, the top-level API) import this package;
the stages receive models (docs/design.md, "Layers").

- :mod:`~mbseig.casefile.expr`: whitelisted arithmetic expressions (never ``eval``);
- :mod:`~mbseig.casefile.fields`: typed element tables, templates, ``repeat``, ``enabled``;
- :mod:`~mbseig.casefile.builder`: points, masses, bodies, joints and forces → Model;
- :mod:`~mbseig.casefile.batch`: vectorized expansion of repeated elements;
- :mod:`~mbseig.casefile.flexible`: ``[[beams]]``, ``[[fe_bodies]]``, ``[refinement]``;
- :mod:`~mbseig.casefile.matrices`: linear cases;
- :mod:`~mbseig.casefile.report_table`: the ``[report]`` table.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from ..arguments import check
from ..errors import CaseError, MbseigError
from ..numerics import DOUBLE_RANGE, watched
from .builder import Builder
from .expr import evaluate
from .matrices import linear_case, matrix_file

__all__ = ["CaseSpec", "read_case", "load_case", "parse_param_overrides", "SCHEMA_VERSION"]

SCHEMA_VERSION = 1
READ_CAUSE = f"values of the case too large or too small together (beyond {DOUBLE_RANGE})"
_TOP_KEYS = {
    "schema_version", "title", "description", "source", "kind", "dimension", "gravity",
    "parameters", "points", "masses", "bodies", "joints", "forces", "matrices", "expected",
    "configurations", "report", "beams", "fe_bodies", "refinement", "inputs", "outputs",
    "urdf", "motion", "frames",
}


def motion_kind(data) -> str | None:
    """What a case's ``[motion]`` table asks for (DESIGN §8): ``"periodic"`` (``period``),
    ``"steady"`` (``speed`` or ``yaw_rate``), or None without a ``[motion]`` table (a static
    equilibrium).  Commands hand a moving case to the analysis of its kind."""
    motion = data.get("motion")
    if motion is None:
        return None
    if not isinstance(motion, dict):
        raise CaseError("[motion] must be a table", element="motion")
    if "period" in motion:
        return "periodic"
    if "speed" in motion or "yaw_rate" in motion:
        return "steady"
    raise CaseError("[motion] needs period (a periodic motion) or speed (a steady motion)",
                    element="motion")


def parse_param_overrides(items) -> dict:
    """``["n=20", "k=1e3"]`` → ``{"n": "20", "k": "1e3"}`` (values are expressions)."""
    out = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise CaseError(f"--param expects NAME=VALUE, got {item!r}")
        out[name.strip()] = value.strip()
    return out


@dataclass(eq=False)
class CaseSpec:
    """A parsed case: its TOML content, name, source path and folder (for matrix files).

    Call :meth:`build` (or the spec itself) for a model at a parameter point.  Picklable: a
    process pool or a Dask cluster receives the content, never re-reads the file.
    """

    data: dict
    name: str
    source: str
    base_dir: Path = Path(".")
    _matrices: dict = field(default_factory=dict, repr=False)

    @property
    def parameters(self) -> dict:
        """The ``[parameters]`` table as written (values may be expressions)."""
        table = self.data.get("parameters", {})
        return dict(table) if isinstance(table, dict) else {}

    @property
    def configurations(self) -> dict:
        table = self.data.get("configurations", {})
        return dict(table) if isinstance(table, dict) else {}

    def build(self, config: str | None = None, *, mesh=None, **params):
        """The model at these parameters (numbers or expressions overriding ``[parameters]``)
        and named configuration; ``mesh`` maps a beam's name or index to its element count."""
        try:
            with watched("reading the case", READ_CAUSE):
                return _build(self, config, params, mesh)
        except MbseigError as exc:
            raise exc.located(file=self.source) from None

    __call__ = build

    def read_matrix(self, fname, key, label):
        """A matrix file next to the case, read once and kept."""
        if (fname, key) not in self._matrices:
            self._matrices[(fname, key)] = matrix_file(self.base_dir / fname, key, label)
        return self._matrices[(fname, key)]


def read_case(path) -> CaseSpec:
    """Read and parse a case file once; its models are built from the parsed content.

    Parameters
    ----------
    path : str, pathlib.Path or dict
        A case file (TOML), or a case given as a Python dict with the structure of the TOML
        (validated when built, with the same messages).

    Returns
    -------
    CaseSpec
        The parsed case: ``spec.build(config, **params)`` gives its model at a parameter point.

    Raises
    ------
    CaseError
        One line naming the file and the element on any problem.

    Examples
    --------
    >>> from mbseig.casefile.examples import pendulum
    >>> spec = read_case(pendulum().data)
    >>> spec.build().n   # the bob's two coordinates
    2
    """
    check("read_case", locals())
    if isinstance(path, dict):
        title = path.get("title")
        name = title if isinstance(title, str) and title else "case"
        return CaseSpec(_expanded(path, Path.cwd() / name), name, "<dict>", Path.cwd())
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as exc:
        raise CaseError(f"cannot read case file: {exc.strerror or exc}", file=str(path)) from None
    except UnicodeDecodeError:
        raise CaseError("case file is not UTF-8 text", file=str(path)) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        if text.lstrip().startswith("<"):  # XML: a URDF given where a case file is read
            raise CaseError("not a case file but XML (a URDF?): write its case with `mbseig "
                            "import-urdf FILE --out CASE.toml`, or name it in a case's [urdf] "
                            "table", file=str(path)) from None
        raise CaseError(f"malformed TOML: {exc}", file=str(path)) from None
    return CaseSpec(_expanded(data, path), path.stem, str(path), path.parent)


def _expanded(data, path):
    """The case with its ``[urdf]`` table read into bodies, joints and springs (DESIGN §8),
    once per read: the parsed case carries the plain tables (files relative to ``path``)."""
    if "urdf" not in data:
        return data
    from .urdf import expand_urdf

    return expand_urdf(data, path)


def load_case(path, config: str | None = None, **params):
    """Read a case file and build its model (``read_case(path).build(config, **params)``).

    Parameters
    ----------
    path : str, pathlib.Path or dict
        A case file, or a case as a dict (:func:`read_case`).
    config : str, optional
        A named entry of the case's ``[configurations]`` table (a set of parameter values).
    **params
        Overrides of entries of the case's ``[parameters]`` table (numbers or expressions).

    Returns
    -------
    Model or LinearCase
        The built model (a ``kind = "linear"`` case gives its matrices).

    Raises
    ------
    CaseError
        One line naming the file and the element on any problem.

    Examples
    --------
    >>> from mbseig.casefile.examples import pendulum
    >>> model = load_case(pendulum().data, l=2.0)
    >>> model.parameters["l"]
    2.0
    """
    check("load_case", locals())
    return read_case(path).build(config, **params)


def _build(spec, config, overrides, mesh):
    data = spec.data
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise CaseError(f"unknown top-level field {unknown[0]!r}", element="case")
    version = data.get("schema_version", None)
    if version != SCHEMA_VERSION or isinstance(version, bool):
        raise CaseError(f"schema_version must be {SCHEMA_VERSION}, got {version!r}", element="case")
    params = _parameters(data.get("parameters", {}), data.get("configurations", {}), config,
                         dict(overrides or {}))
    kind = data.get("kind", "multibody")
    if "frames" in data and (kind != "multibody" or data.get("dimension") != 3):
        raise CaseError("[[frames]] names frames of 3-D bodies: it needs dimension = 3",
                        element="frames")
    description = str(data.get("description", data.get("title", "")))
    expected = data.get("expected", {})
    if not isinstance(expected, dict):
        raise CaseError("[expected] must be a table", element="expected")
    if kind == "linear":
        return linear_case(data, spec.name, spec.source, spec.read_matrix, params, description,
                           expected)
    if kind != "multibody":
        raise CaseError(f"kind must be 'multibody' or 'linear', got {kind!r}", element="case")
    if data.get("dimension") == 3:  # the 3-D reader and elements only where a case needs them
        from .spatial import SpatialBuilder as builder
    else:
        builder = Builder
    return builder(data, spec.name, spec.source, params, description, expected,
                   files=spec.read_matrix, mesh=mesh).build()


def _parameters(table, configurations, config, overrides):
    if not isinstance(table, dict):
        raise CaseError("[parameters] must be a table", element="parameters")
    raw = dict(table)
    if config is not None:
        if not isinstance(configurations, dict) or config not in configurations:
            known = ", ".join(sorted(configurations)) if isinstance(configurations, dict) else ""
            raise CaseError(f"unknown configuration {config!r} (known: {known or 'none'})",
                            element="configurations")
        chosen = configurations[config]
        if not isinstance(chosen, dict):
            raise CaseError("a configuration must be a table of parameter values",
                            element=f"configurations.{config}")
        for key, value in chosen.items():
            if key == "description":
                continue
            if key not in raw:
                raise CaseError(f"sets unknown parameter {key!r}",
                                element=f"configurations.{config}")
            raw[key] = value
    for key, value in overrides.items():
        if key not in raw:
            known = ", ".join(raw) or "none"
            raise CaseError(f"unknown parameter {key!r} (known: {known})", element="--param")
        raw[key] = value
    values: dict[str, float] = {}
    for key, value in raw.items():
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", key):
            raise CaseError(f"invalid parameter name {key!r}", element="parameters")
        try:
            values[key] = evaluate(value, values)
        except MbseigError as exc:
            raise exc.located(element=f"parameters.{key}") from None
    return values
