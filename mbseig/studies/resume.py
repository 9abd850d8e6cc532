"""Sweeps that survive faults: every task's result kept in a directory as it completes, so that
an interrupted study (Ctrl-C, a killed process, a full disk) rerun with the same directory
computes only the tasks it does not hold (``mbseig sweep ... --resume DIR``, docs/scaling.md).

The directory holds ``manifest.json`` (what the study is: the case's content, configuration,
grid, fixed parameters and options; a rerun with a different study refuses the directory) and
one file per completed task, ``{stage}-{index:06d}.pkl``: the task's result, written to a
temporary file in the same directory, flushed to disk and renamed over its final name, so that a
file under its final name is always complete (a rename within one directory is atomic on POSIX
and Windows).  Results are pickled: loaded, they are bit for bit what the task returned, so the
outputs of a resumed study equal those of an uninterrupted one byte for byte.  A pickle can name
any Python callable to run while it is read, so results are read by a restricted unpickler
(:class:`_Loader`, the "restricting globals" pattern of the ``pickle`` documentation): it builds
only what mbseig writes, the classes of mbseig's own data (not those of the modules that write
files, start processes or run commands), numpy's arrays, scalars and dtypes, scipy's sparse
matrices and Python's plain containers.  A file that names anything else (``os.system``,
``builtins.eval``, a numpy function) is refused in one line naming it, before any of it runs: a
resume folder from someone else cannot run their code.

A *deferred* checkpoint (``Checkpoint(directory, deferred=True)``) keeps the results in memory
and writes nothing until :meth:`Checkpoint.flush`: ``mbseig sweep`` without ``--resume`` holds
one, and when the sweep is interrupted (Ctrl-C) it writes the finished tasks to the directory
next to ``--out`` that its last line names.  Its tasks go to one file per stage,
``batch-{stage}-{n:03d}.pkl`` (a dict index → result, written and renamed as above: one fsync,
not one per task, so that an interruption after thousands of points still ends at once); a
rerun with ``--resume`` reads them as it reads the single files.
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
from pathlib import Path

from ..errors import CaseError, MbseigError

__all__ = ["Checkpoint", "study_identity"]

MANIFEST = "manifest.json"
FORMAT = 1  # version of the directory's layout


#: mbseig modules whose classes a result never holds and whose constructors act on the world
_NOT_DATA = ("mbseig.studies.resume", "mbseig.studies.runners", "mbseig.studies.workers",
             "mbseig.cli", "mbseig.report", "mbseig.bench", "mbseig.plots")
#: numpy's functions that rebuild an array, a scalar or a dtype (nothing else of numpy's runs)
_NUMPY_REBUILD = {"_reconstruct", "scalar", "_frombuffer"}
_BUILTINS = {"complex", "set", "frozenset", "slice", "range", "bytearray", "bytes", "tuple",
             "list", "dict", "float", "int", "bool", "str"}


class _Refused(pickle.UnpicklingError):
    """A result file names a global mbseig never writes."""


class _Loader(pickle.Unpickler):
    """An unpickler that builds only what mbseig writes (module docstring); anything else is an
    :class:`pickle.UnpicklingError` naming it."""

    def find_class(self, module, name):
        root = module.split(".")[0]
        if module == "builtins" and name in _BUILTINS:
            return super().find_class(module, name)
        if root in ("numpy", "scipy", "mbseig") and "." not in name:
            obj = super().find_class(module, name)
            if root == "numpy" and (isinstance(obj, type) or name in _NUMPY_REBUILD):
                return obj
            if root == "scipy" and module.startswith("scipy.sparse") and isinstance(obj, type):
                return obj
            if (root == "mbseig" and isinstance(obj, type)
                    and not obj.__module__.startswith(_NOT_DATA)):
                return obj
        raise _Refused(f"refers to {module}.{name}, which mbseig never writes")


def _load(path):
    """A result file read by :class:`_Loader`: a refused global is one line naming the file."""
    with path.open("rb") as fh:
        try:
            return _Loader(fh).load()
        except _Refused as exc:
            raise CaseError(f"{path.name} {exc}: not read (a resume folder holds only what "
                            f"mbseig wrote)", file=str(path.parent), element="--resume") from None


def _jsonable(x):
    """A JSON form of a study's inputs that is the same in every process (no hash order)."""
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in sorted(x.items(), key=lambda kv: str(kv[0]))}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (set, frozenset)):
        return sorted(_jsonable(v) for v in x)
    if hasattr(x, "tolist"):
        return _jsonable(x.tolist())
    if isinstance(x, float):
        return repr(x)  # every bit: 0.1 and 0.1 + 1e-17 are different studies
    if x is None or isinstance(x, (bool, int, str)):
        return x
    return repr(x)


def study_identity(spec, **inputs) -> dict:
    """What a study is, for the manifest: a digest of the case's parsed content (so an edited
    case file is another study) and its inputs (grid, fixed parameters, options)."""
    content = json.dumps(_jsonable(getattr(spec, "data", None)), sort_keys=True)
    return {"format": FORMAT, "case": getattr(spec, "name", None),
            "case_digest": hashlib.sha256(content.encode()).hexdigest(), **_jsonable(inputs)}


class Checkpoint:
    """The completed tasks of one study in ``directory`` (module docstring).

    ``get(stage, i)`` returns (True, result) for a task held, (False, None) otherwise;
    ``put(stage, i, result)`` writes it atomically.  ``loaded`` and ``written`` list the
    (stage, index) pairs read and written in this run (a task is never written twice), and
    ``held(stage)`` counts the tasks of a stage held now (read or written).

    identity : what the study is (:func:`study_identity`); it may be given later by
        :meth:`bind` (the study that receives the checkpoint knows its inputs).
    deferred : hold the results in memory and write nothing before :meth:`flush`.
    """

    def __init__(self, directory, identity: dict | None = None, *, deferred: bool = False):
        self.dir = None if directory is None else Path(directory)
        self.deferred = bool(deferred)
        self.identity = None
        self.loaded, self.written = [], []
        self._memory: dict = {}  # (stage, index) -> result of a deferred checkpoint
        self._done: set = set()  # (stage, index) written in this run
        self._batches: dict = {}  # stage -> {index: result} read from the batch files
        self.flushed = False
        # grid points held (read or finished) and the study's total, kept up by the runner
        # (mbseig.studies.runners.Runner) for the line an interruption prints
        self.points = [0, 0]
        if identity is not None:
            self.bind(identity)

    def bind(self, identity: dict):
        """Set what the study is; a directory already written must hold the same study."""
        if self.identity is not None and self.identity != identity:
            raise MbseigError("one checkpoint given to two different studies", element="--resume")
        self.identity = identity
        if not self.deferred:
            self._open()
        return self

    def _open(self):
        """Create the directory and its manifest, or check the manifest it holds."""
        try:
            self.dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise MbseigError(f"cannot create the resume directory {str(self.dir)!r}: "
                              f"{exc.strerror or exc}", element="--resume") from None
        manifest = self.dir / MANIFEST
        text = json.dumps(self.identity, indent=1, sort_keys=True) + "\n"
        if manifest.exists():
            try:
                held = json.loads(manifest.read_text())
            except (OSError, ValueError):
                held = None
            if held != json.loads(text):
                what = ("not an mbseig resume directory" if held is None else
                        "the checkpoints of a different study (case, grid or options differ)")
                raise CaseError(f"{str(self.dir)!r} holds {what}: give an empty or new "
                                f"directory, or the one this study wrote", element="--resume")
        else:
            self._atomic(manifest, text.encode())

    def _path(self, stage, i):
        return self.dir / f"{stage}-{int(i):06d}.pkl"

    def held(self, stage) -> int:
        """The tasks of ``stage`` held now: read from the directory or completed in this run."""
        return len({i for s, i in self.loaded + self.written if s == stage})

    def get(self, stage, i):
        if self.deferred:
            return False, None  # (a deferred checkpoint reads nothing: a new study)
        try:
            result = _load(self._path(stage, i))
        except CaseError:
            raise  # a refused global: said, not recomputed around
        except FileNotFoundError:
            batch = self._batch(stage)
            if int(i) not in batch:
                return False, None
            result = batch[int(i)]
        except (OSError, EOFError, pickle.UnpicklingError, AttributeError, ImportError,
                IndexError, TypeError, ValueError):
            return False, None  # unreadable (another mbseig's layout): computed again
        self.loaded.append((stage, int(i)))
        return True, result

    def _batch(self, stage) -> dict:
        """{index: result} of every batch file of ``stage`` (read once)."""
        if stage not in self._batches:
            held = {}
            for path in sorted(self.dir.glob(f"batch-{stage}-*.pkl")):
                try:
                    part = _load(path)
                except CaseError:
                    raise
                except (OSError, EOFError, pickle.UnpicklingError, AttributeError,
                        ImportError, IndexError, TypeError, ValueError):
                    continue  # unreadable: its tasks are computed again
                if isinstance(part, dict):
                    held.update(part)
            self._batches[stage] = held
        return self._batches[stage]

    def put(self, stage, i, result):
        key = (stage, int(i))
        if key in self._done:
            raise MbseigError(f"task {stage} {i} completed twice", element="--resume")
        self._done.add(key)
        if self.deferred:
            self._memory[key] = result
        else:
            self._atomic(self._path(stage, i),
                         pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL))
        self.written.append(key)

    def flush(self) -> Path:
        """Write what a deferred checkpoint holds to its directory, one batch file per stage,
        and return the directory.  A directory that holds another study is left alone: the
        tasks go to the first free sibling ``DIR-2``, ``DIR-3``, ... (the caller names the
        one returned).  A checkpoint written as it went has nothing left to write."""
        if not self.deferred or self.flushed:
            return self.dir
        if self.identity is None:
            raise MbseigError("a checkpoint written before its study was named", element="--resume")
        base, n = self.dir, 1
        while True:
            try:
                self._open()
                break
            except CaseError:
                n += 1
                if n > 100:
                    raise
                self.dir = base.with_name(f"{base.name}-{n}")
        stages: dict = {}
        for (stage, i), result in self._memory.items():
            stages.setdefault(stage, {})[i] = result
        for stage, part in stages.items():
            k = 0
            while (self.dir / f"batch-{stage}-{k:03d}.pkl").exists():
                k += 1
            self._atomic(self.dir / f"batch-{stage}-{k:03d}.pkl",
                         pickle.dumps(part, protocol=pickle.HIGHEST_PROTOCOL))
        self.flushed = True
        return self.dir

    def _atomic(self, path, data: bytes):
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        try:
            with tmp.open("wb") as fh:
                fh.write(data)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, path)
        except OSError as exc:
            try:
                tmp.unlink()
            except OSError:
                pass
            raise MbseigError(f"cannot write {str(path)!r} ({exc.strerror or exc}); the tasks "
                              f"written before it are kept: rerun with --resume "
                              f"{str(self.dir)!r} once there is room", element="--resume") from None
