"""Sweeps that survive faults: every task's result kept in a directory as it completes, so that
an interrupted study (Ctrl-C, a killed process, a full disk) rerun with the same directory
computes only the tasks it does not hold (``mbseig sweep ... --resume DIR``, docs/scaling.md).

The directory holds ``manifest.json`` (what the study is: the case's content, configuration,
grid, fixed parameters and options; a rerun with a different study refuses the directory) and
one file per completed task, ``{stage}-{index:06d}.pkl``: the task's result, written to a
temporary file in the same directory, flushed to disk and renamed over its final name, so that a
file under its final name is always complete (a rename within one directory is atomic on POSIX
and Windows).  Results are pickled: loaded, they are bit for bit what the task returned, so the
outputs of a resumed study equal those of an uninterrupted one byte for byte.  A checkpoint
directory is trusted as the Python that wrote it (pickles can hold code): resume only from
directories mbseig wrote.
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
    (stage, index) pairs read and written in this run (a task is never written twice).
    """

    def __init__(self, directory, identity: dict):
        self.dir = Path(directory)
        self.loaded, self.written = [], []
        try:
            self.dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise MbseigError(f"cannot create the resume directory {str(self.dir)!r}: "
                              f"{exc.strerror or exc}", element="--resume") from None
        manifest = self.dir / MANIFEST
        text = json.dumps(identity, indent=1, sort_keys=True) + "\n"
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

    def get(self, stage, i):
        p = self._path(stage, i)
        try:
            with p.open("rb") as fh:
                result = pickle.load(fh)
        except FileNotFoundError:
            return False, None
        except (OSError, EOFError, pickle.UnpicklingError, AttributeError, ImportError,
                IndexError, TypeError, ValueError):
            return False, None  # unreadable (another mbseig's layout): computed again
        self.loaded.append((stage, int(i)))
        return True, result

    def put(self, stage, i, result):
        key = (stage, int(i))
        if key in self.written:
            raise MbseigError(f"task {stage} {i} completed twice", element="--resume")
        self._atomic(self._path(stage, i), pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL))
        self.written.append(key)

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
