"""Sweeps that survive faults: every task's result kept in a directory as it completes, so that
an interrupted study (Ctrl-C, a killed process, a full disk) rerun with the same directory
computes only the tasks it does not hold (``mbseig sweep ... --resume DIR``, docs/scaling.md).

The directory holds ``manifest.json`` (what the study is: the case's content, configuration,
grid, fixed parameters and options; a rerun with a different study refuses the directory) and
one file per completed task, ``{stage}-{index:06d}.npz``: the task's result as one JSON document
and the arrays it refers to (:func:`mbseig.records.encode`), written to a temporary file in the
same directory, flushed to disk and renamed over its final name, so that a file under its final
name is always complete (a rename within one directory is atomic on POSIX and Windows).  Read
back (:func:`mbseig.records.decode`, ``numpy.load`` with ``allow_pickle=False``), a result is
bit for bit what the task returned, so the outputs of a resumed study equal those of an
uninterrupted one byte for byte.  Nothing is pickled: reading builds numbers, containers,
arrays and mbseig's own data classes, and no file can name code to run, so a resume folder
from someone else is data and nothing more.  A folder of an earlier mbseig that pickled its
results (``*.pkl``) is refused in one line: its files are not opened.

A *deferred* checkpoint (``Checkpoint(directory, deferred=True)``) keeps the results in memory
and writes nothing until :meth:`Checkpoint.flush`: ``mbseig sweep`` without ``--resume`` holds
one, and when the sweep is interrupted (Ctrl-C) it writes the finished tasks to the directory
next to ``--out`` that its last line names.  Its tasks go to one file per stage,
``batch-{stage}-{n:03d}.npz`` (a dict index → result, written and renamed as above: one fsync,
not one per task, so that an interruption after thousands of points still ends at once); a
rerun with ``--resume`` reads them as it reads the single files.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import zipfile
from pathlib import Path

import numpy as np

from ..errors import CaseError, MbseigError
from ..records import RecordFormatError, decode, encode

__all__ = ["Checkpoint", "study_identity"]

MANIFEST = "manifest.json"
FORMAT = 2  # version of the directory's layout (1: pickled results, no longer read)
_RECORD = "__record__"  # the npz entry that holds the JSON document


def _dump(result) -> bytes:
    """One result as the bytes of an .npz file: the JSON document and its arrays."""
    data, arrays = encode(result)
    text = json.dumps(data, separators=(",", ":"))
    buf = io.BytesIO()
    np.savez(buf, **{_RECORD: np.frombuffer(text.encode(), dtype=np.uint8)}, **arrays)
    return buf.getvalue()


def _load(path):
    """A result file read back (module docstring); a file that names a class mbseig never writes
    is one line naming the file."""
    with np.load(path, allow_pickle=False) as npz:
        try:
            data = json.loads(bytes(npz[_RECORD]).decode())
            return decode(data, npz)
        except RecordFormatError as exc:
            raise CaseError(f"{path.name} {exc}: not read (a resume folder holds only what "
                            f"mbseig wrote)", file=str(path.parent), element="--resume") from None


#: what an unreadable result file raises (a truncated or foreign file): its task is computed again
_UNREADABLE = (OSError, EOFError, ValueError, KeyError, TypeError, IndexError,
               zipfile.BadZipFile, UnicodeDecodeError)


def _jsonable(x):
    """A JSON form of a study's inputs that is the same in every process (no hash order)."""
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in sorted(x.items(), key=lambda kv: str(kv[0]))}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (set, frozenset)):
        return sorted(_jsonable(v) for v in x)
    if isinstance(x, (np.ndarray, np.generic)):
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
        if any(self.dir.glob("*.pkl")):
            raise CaseError(f"{str(self.dir)!r} holds pickled results of an earlier mbseig "
                            f"(*.pkl): they are not opened (a pickle can run code); give an "
                            f"empty or new directory", element="--resume")
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
        return self.dir / f"{stage}-{int(i):06d}.npz"

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
        except _UNREADABLE:
            return False, None  # unreadable (a truncated file): computed again
        self.loaded.append((stage, int(i)))
        return True, result

    def _batch(self, stage) -> dict:
        """{index: result} of every batch file of ``stage`` (read once)."""
        if stage not in self._batches:
            held = {}
            for path in sorted(self.dir.glob(f"batch-{stage}-*.npz")):
                try:
                    part = _load(path)
                except CaseError:
                    raise
                except _UNREADABLE:
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
            self._atomic(self._path(stage, i), _dump(result))
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
            while (self.dir / f"batch-{stage}-{k:03d}.npz").exists():
                k += 1
            self._atomic(self.dir / f"batch-{stage}-{k:03d}.npz", _dump(part))
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
