"""What runs on a worker: one chunk of samples, or one ensemble realization.

Tasks return fgf's errors as values (:class:`TaskError`) rather than raising
them: the exception classes of the native module do not pickle, and the
client re-raises them as the same class with the same one-line message.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, Optional, Union

import numpy as np
import numpy.typing as npt

from .. import _core
from ._film import FilmSums
from ._ship import ScenePayload, prepared


@dataclass(frozen=True)
class TaskError:
    """An fgf error raised on a worker: its class name and message."""

    kind: str
    message: str

    def raise_(self) -> None:
        cls = {"ParameterError": _core.ParameterError, "SceneError": _core.SceneError, "OSError": OSError}.get(
            self.kind, _core.FgfError
        )
        raise cls(self.message)


def _as_task_error(e: BaseException) -> TaskError:
    if isinstance(e, _core.ParameterError):
        return TaskError("ParameterError", str(e))
    if isinstance(e, _core.SceneError):
        return TaskError("SceneError", str(e))
    if isinstance(e, OSError):
        return TaskError("OSError", str(e))
    return TaskError("FgfError", str(e))


def worker_threads() -> Optional[int]:
    """The threads a Dask worker was given (``None`` outside a worker: all cores)."""
    try:
        from distributed import get_worker

        return int(get_worker().state.nthreads)
    except (ImportError, ValueError, AttributeError):
        return None


@dataclass
class Chunk:
    """A rendered chunk: its exact sums and the seconds its render took on
    the worker (what the client sizes later chunks by, ``_chunks.py``)."""

    sums: FilmSums
    seconds: float
    #: Ctrl-C stopped it before its last sample (a render on this machine).
    interrupted: bool = False


# One render at a time per worker process: a render uses all the worker's
# threads, and a second chunk sent ahead waits here, ready to start the
# moment the first ends (no scheduler round trip between them).
_render_lock = threading.Lock()


def render_task(payload: ScenePayload, s0: int, s1: int, seed: int, variance: bool) -> Union[Chunk, TaskError]:
    """The exact sums of samples ``[s0, s1)`` of the shipped scene."""
    try:
        scene = prepared(payload)
        with _render_lock:
            t0 = time.perf_counter()
            s, q, done, _ = _core.render_range(scene, s0, s1, seed=seed, variance=variance, threads=worker_threads())
            seconds = time.perf_counter() - t0
    except (_core.FgfError, OSError) as e:
        return _as_task_error(e)
    return Chunk(FilmSums(s, q, [(s0, s0 + done)]), seconds)


@contextlib.contextmanager
def materialized(payload: ScenePayload) -> Iterator[Path]:
    """The shipped scene written into a temporary folder (removed after)."""
    folder = Path(tempfile.mkdtemp(prefix="fgf-scene-"))
    try:
        for rel, data in payload.files:
            target = folder / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
        yield folder / payload.main
    finally:
        shutil.rmtree(folder, ignore_errors=True)


@dataclass
class Realization:
    """One ensemble realization: its image and its medium reports."""

    index: int
    image: npt.NDArray[np.float32]
    info: dict[str, Any]


def ensemble_task(
    payload: ScenePayload, index: int, options: dict[str, Any]
) -> Union[Realization, TaskError, None]:
    """Realization ``index`` of the ensemble of the shipped scene (``None`` if
    interrupted); ``options`` are ``ensemble_scene``'s keyword arguments."""
    try:
        with materialized(payload) as scene:
            mean, _, info, interrupted = _core.ensemble_scene(
                os.fspath(scene),
                1,
                threads=worker_threads(),
                defines=list(payload.defines),
                first=index,
                **options,
            )
    except (_core.FgfError, OSError) as e:
        return _as_task_error(e)
    if interrupted or info["realizations_done"] < 1:
        return None
    return Realization(index, mean, info)


@dataclass
class Node:
    """One truth node's classical render (unweighted) and its variance."""

    index: int
    image: npt.NDArray[np.float32]
    variance: Optional[npt.NDArray[np.float32]]


def truth_task(
    payload: ScenePayload, index: int, nodes: int, spp: Optional[int], seed: int, variance: bool
) -> Union[Node, TaskError, None]:
    """Node ``index`` of the truth of the shipped scene (``None`` if interrupted)."""
    try:
        with materialized(payload) as scene:
            img, var, interrupted = _core.render_truth_node(
                os.fspath(scene),
                index,
                nodes=nodes,
                spp=spp,
                seed=seed,
                threads=worker_threads(),
                defines=list(payload.defines),
                return_variance=variance,
            )
    except (_core.FgfError, OSError) as e:
        return _as_task_error(e)
    if interrupted or img is None:
        return None
    return Node(index, img, var)
