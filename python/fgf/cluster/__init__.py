"""Renders and ensembles split into chunks, on one machine or a Dask cluster.

A render is split into chunks of samples ``[s0, s1)``; each chunk returns
the exact fixed-point sums of its samples (:class:`FilmSums`,
``docs/theory.md`` §7.17), and the sums of all chunks merge by integer
addition, so the image is bit-identical to a single-process render with the
same seed and spp for any chunk size, any number of workers and any order in
which chunks finish. An ensemble maps over realization indices and merges
them in index order; a truth maps over its quadrature nodes, which
``fgf.truth`` sums in node order. ``docs/cluster.md`` is the user guide.

>>> from fgf import cluster                                          # doctest: +SKIP
>>> with cluster.open_client("local:2") as client:                   # doctest: +SKIP
...     run = cluster.render("scene.xml", spp=64, client=client, chunk_spp=8)
>>> run.image.shape                                                  # doctest: +SKIP

The sample-range API underneath: :func:`render_chunk` renders ``[s0, s1)``
and returns its :class:`FilmSums`; :meth:`FilmSums.merge` and
:meth:`FilmSums.finish` merge and finalize.

Dask is the optional extra ``fgf[cluster]``; without it, asking for a
cluster raises :class:`fgf.ParameterError` naming the extra (checkpoints on
one machine do not need it).
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Iterator, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from .. import _core
from .._progress import Progress
from . import _film
from ._chunks import CHUNK_SECONDS, Chunker
from ._film import FilmSums
from ._ship import ScenePayload, scene_files
from ._tasks import Chunk, Node, Realization, TaskError, ensemble_task, render_task, truth_task

if TYPE_CHECKING:
    from distributed import Client

__all__ = [
    "CHUNK_SECONDS",
    "ClusterError",
    "FilmSums",
    "ScenePayload",
    "open_client",
    "render",
    "render_chunk",
    "ensemble",
    "RenderRun",
    "EnsembleRun",
    "truth_nodes",
    "TruthRun",
    "scene_files",
]

F32 = npt.NDArray[np.float32]
#: Seconds to wait for a ``tcp://`` scheduler before giving up.
CONNECT_TIMEOUT = 10.0
#: Render chunks kept in flight per worker: the second one waits on the
#: worker, so the worker never idles for a scheduler round trip.
CHUNKS_AHEAD = 2
#: Dask settings of a ``local[:N]`` cluster: its periodic bookkeeping (the
#: statistical profiler every 10 ms, event-loop ticks every 20 ms, work
#: stealing, system and memory monitors) cost 8.2 % of a core with nothing
#: to do, 1.2 % with these (docs/cluster.md, "Cost model"). fgf's tasks
#: need none of it: chunks are sized and handed out by the client.
LOCAL_CLUSTER_CONFIG: dict[str, Any] = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "500ms",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.scheduler.work-stealing": False,
    "distributed.worker.memory.monitor-interval": "500ms",
}


class ClusterError(_core.FgfError):
    """The cluster is unreachable, or was lost during a job."""


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _distributed() -> Any:
    try:
        import distributed
    except ImportError:
        raise _core.ParameterError(
            "running on a cluster needs Dask, which is not installed: pip install 'fgf[cluster]' "
            "(the dask[distributed] package)"
        ) from None
    return distributed


def _stop_local(cluster: Any) -> None:
    """Close a ``LocalCluster`` of ours, its worker processes stopped at once.

    A graceful close asks each worker to finish and waits for it: about 1 s
    at the end of every ``local`` run (docs/cluster.md, "Cost model"), for
    nothing, since nothing in the workers is needed any more. So each nanny
    is told not to restart its worker, the worker process is killed, the
    cluster closed, and the lock file a killed worker leaves next to its
    scratch folder (which the nanny removes) is removed too.
    """
    folders = []
    # The scheduler logs the closed connections of the killed workers as
    # errors, with tracebacks: expected here, so not shown.
    log = logging.getLogger("distributed")
    level = log.level
    log.setLevel(logging.CRITICAL)
    try:
        for nanny in list(getattr(cluster, "workers", {}).values()):
            with contextlib.suppress(Exception):
                folders.append(nanny.worker_dir)
                nanny.close_gracefully()  # Dask's "do not restart it" signal
                pid = nanny.pid
                if pid:
                    os.kill(pid, signal.SIGKILL)
        cluster.close()
    finally:
        log.setLevel(level)
    for folder in folders:
        if folder:
            with contextlib.suppress(OSError):
                os.unlink(f"{folder}.dirlock")


@contextlib.contextmanager
def open_client(address: str, timeout: float = CONNECT_TIMEOUT) -> Iterator["Client"]:
    """A Dask client for ``address``, closed on exit.

    ``local`` or ``local:N`` starts a ``LocalCluster`` of ``N`` single-threaded
    worker processes (default: one per core); ``tcp://host:port`` (or
    ``tls://``) connects to a running scheduler, waiting at most ``timeout``
    seconds, else :class:`ClusterError`.
    """
    if address == "local" or address.startswith("local:"):
        n_text = address.partition(":")[2]
        if n_text:
            try:
                n = int(n_text)
            except ValueError:
                n = 0
            if n < 1:
                raise _core.ParameterError(f"--cluster {address}: N must be a positive integer (local:N workers)")
        else:
            n = os.cpu_count() or 1
        distributed = _distributed()
        import dask

        # The worker processes inherit an ignored SIGINT, so that Ctrl-C in a
        # terminal (sent to the whole process group) reaches only this
        # process, which cancels the futures and writes what finished.
        previous = signal.getsignal(signal.SIGINT) if _main_thread() else None
        if previous is not None:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            with dask.config.set(LOCAL_CLUSTER_CONFIG):
                cluster = distributed.LocalCluster(
                    n_workers=n,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                    # No dashboard, and the scheduler's small HTTP server (health
                    # checks) on a free port: two local runs at once would both
                    # want 8787, and the second would print a warning.
                    scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                    silence_logs=logging.ERROR,
                )
                client = distributed.Client(cluster)
        finally:
            if previous is not None:
                signal.signal(signal.SIGINT, previous)
        try:
            yield client
        finally:
            client.close()
            _stop_local(cluster)
        return
    if not (address.startswith("tcp://") or address.startswith("tls://")) or ":" not in address[6:]:
        raise _core.ParameterError(
            f"--cluster {address}: expected local, local:N or tcp://host:port (a running `dask scheduler`)"
        )
    distributed = _distributed()
    try:
        client = distributed.Client(address, timeout=timeout)
    except (OSError, TimeoutError) as e:
        reason = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise ClusterError(
            f"--cluster {address}: no Dask scheduler answered within {timeout:g} s ({reason}); "
            "start one with `dask scheduler` and workers with `dask worker ADDRESS`"
        ) from None
    try:
        yield client
    finally:
        with contextlib.suppress(Exception):
            client.close(timeout=2)


class _Bar:
    """Finished units across chunks: a tqdm bar (``True``/``"bar"``, on a
    terminal), a tqdm-like ``update(n)`` object, or ``callable(done, total)``."""

    def __init__(self, progress: Union[Progress, str], total: int, desc: str) -> None:
        self.total, self.done = total, 0
        self.bar: Any = None
        self.sink: Any = None
        if progress is True or progress == "bar":
            if sys.stderr.isatty():
                from tqdm import tqdm

                self.bar = tqdm(total=total, unit_scale=True, desc=desc, file=sys.stderr)
        elif progress is not False and progress is not None:
            self.sink = progress

    def add(self, n: int) -> None:
        self.done += n
        if self.bar is not None:
            self.bar.update(n)
        elif hasattr(self.sink, "update"):
            self.sink.update(n)
        elif callable(self.sink):
            self.sink(self.done, self.total)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


class _Saver:
    """Writes the checkpoint as results arrive, skipping a save while the
    time since the last one is under 10x what that save took (so saving
    costs at most ~10% of the run, and a small film is saved after every
    chunk)."""

    def __init__(self, path: Optional[str], make: Callable[[], tuple[dict[str, Any], dict[str, Any]]]) -> None:
        self.path, self.make = path, make
        self.last_end = 0.0
        self.last_cost = 0.0

    def maybe(self) -> None:
        if self.path is not None and time.perf_counter() - self.last_end >= 10 * self.last_cost:
            self.now()

    def now(self) -> None:
        if self.path is None:
            return
        t0 = time.perf_counter()
        meta, arrays = self.make()
        _film.save(self.path, meta, arrays)
        self.last_end = time.perf_counter()
        self.last_cost = self.last_end - t0


def _lost(address: str, e: BaseException) -> str:
    reason = str(e).splitlines()[0] if str(e) else type(e).__name__
    if "cancelled for reason:" in reason:
        reason = reason.split("cancelled for reason:", 1)[1].strip().rstrip(".")
    where = f" at {address}" if address else ""
    return f"lost the Dask scheduler{where} ({reason})"


class _Workers:
    """The number of workers of ``client``, asked of the scheduler at most
    every 2 s (each question is a round trip)."""

    def __init__(self, client: Any) -> None:
        self.client = client
        self.n = 1
        self.when = -math.inf

    def count(self) -> int:
        now = time.monotonic()
        if now - self.when >= 2.0:
            self.n = max(1, len(self.client.scheduler_info().get("workers", {})))
            self.when = now
        return self.n


def _listed(jobs: Sequence[tuple[Any, ...]]) -> Callable[[int], Optional[tuple[Any, ...]]]:
    """``jobs`` handed out in order, as :func:`_run` asks for them."""
    it = iter(jobs)
    return lambda _slots: next(it, None)


def _run(
    client: Any,
    next_job: Callable[[int], Optional[tuple[Any, ...]]],
    task: Callable[..., Any],
    shipped: Any,
    local: Callable[..., Any],
    on_result: Callable[[Any], bool],
    ahead: Optional[int] = None,
) -> tuple[bool, Optional[str]]:
    """Run the jobs (argument tuples) that ``next_job(slots)`` hands out
    (``None`` when there are no more; ``slots`` is the number of workers)
    locally in order, or as Dask tasks ``task(shipped, *job)``; pass each
    result to ``on_result`` (which returns ``False`` on an interrupted
    result). With ``ahead``, at most ``ahead`` tasks per worker are in flight
    and the next job is asked for as each result arrives (so that it can be
    sized by the results so far); without, all are submitted at once.
    Returns ``(interrupted, lost)``: Ctrl-C cancels what is left; a scheduler
    that disappears gives ``lost``, a message. Task errors are re-raised here."""
    if client is None:
        try:
            while (job := next_job(1)) is not None:
                if not on_result(local(*job)):
                    return True, None
        except KeyboardInterrupt:
            return True, None
        return False, None
    distributed = _distributed()
    pending: set[Any] = set()
    try:
        payload = client.scatter(shipped, broadcast=True, hash=False)
        workers = _Workers(client)
        arrived = distributed.as_completed()

        def fill() -> None:
            slots = workers.count() if ahead is not None else 1
            while ahead is None or len(pending) < ahead * slots:
                job = next_job(slots)
                if job is None:
                    return
                fut = client.submit(task, payload, *job, pure=False)
                pending.add(fut)
                arrived.add(fut)

        fill()
        for fut in arrived:
            pending.discard(fut)
            result = fut.result()
            fut.release()  # the worker may drop its copy of the result now
            if isinstance(result, TaskError):
                client.cancel(list(pending))
                result.raise_()
            if not on_result(result):
                client.cancel(list(pending))
                return True, None
            fill()
    except KeyboardInterrupt:
        with contextlib.suppress(Exception):
            client.cancel(list(pending))
        return True, None
    except (OSError, TimeoutError, distributed.client.FutureCancelledError, distributed.comm.CommClosedError) as e:
        return False, _lost(str(getattr(getattr(client, "scheduler", None), "address", "") or ""), e)
    return False, None


@dataclass
class RenderRun:
    """What :func:`render` returns."""

    image: F32
    variance: Optional[F32]
    #: Samples per pixel held (equal for all pixels).
    spp_done: int
    spp_requested: int
    interrupted: bool = False
    #: Set when the cluster was lost: the message; the finished chunks are
    #: in the image (and the checkpoint).
    lost: Optional[str] = None
    #: Samples per pixel taken from the checkpoint.
    resumed_spp: int = 0


def render_chunk(
    scene: Union[_core.PreparedScene, ScenePayload],
    s0: int,
    s1: int,
    seed: Optional[int] = None,
    variance: bool = False,
    threads: Optional[int] = None,
) -> FilmSums:
    """The exact sums of samples ``[s0, s1)`` of every pixel (fewer, from
    ``s0``, if interrupted by Ctrl-C)."""
    if isinstance(scene, ScenePayload):
        from ._ship import prepared

        scene = prepared(scene)
    s, q, done, _ = _core.render_range(scene, s0, s1, seed=seed, variance=variance, threads=threads)
    return FilmSums(s, q, [(s0, s0 + done)])


def _check_counts(spp: Optional[int], chunk_spp: Optional[int]) -> None:
    if spp is not None and spp < 1:
        raise _core.ParameterError(f"spp = {spp}; need at least 1 sample per pixel")
    if chunk_spp is not None and chunk_spp < 1:
        raise _core.ParameterError(f"--chunk-spp {chunk_spp}: need at least 1 sample per pixel per chunk")


def render(
    scene: Union[str, os.PathLike[str]],
    spp: Optional[int] = None,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    defines: Sequence[tuple[str, str]] = (),
    progress: Union[Progress, str] = True,
    return_variance: bool = False,
    client: Optional["Client"] = None,
    chunk_spp: Optional[int] = None,
    checkpoint: Optional[Union[str, os.PathLike[str]]] = None,
) -> RenderRun:
    """Render ``scene`` in chunks of samples, on the Dask ``client``'s
    workers or (``client=None``) here with ``threads``.

    A chunk has ``chunk_spp`` samples per pixel if given; by default each
    chunk is sized from the times of those finished to take about
    :data:`CHUNK_SECONDS` of rendering (``fgf.cluster._chunks``).

    With ``checkpoint``, the finished chunks are saved there atomically as
    they arrive, and a rerun with the same arguments resumes from it (``spp``
    may be raised); a checkpoint of another scene, seed or variance setting
    is refused with :class:`fgf.ParameterError`. The image has the bits of
    ``fgf.render`` with the same scene, spp and seed. Ctrl-C returns the
    chunks finished (``interrupted``); a lost cluster returns them with
    ``lost`` set.
    """
    _check_counts(spp, chunk_spp)
    defines = list(defines)
    path = os.fspath(scene)
    prep = _core.prepare_scene(path, defines)
    spp = prep.spp if spp is None else spp
    seed = prep.seed if seed is None else seed
    h, w = prep.height, prep.width
    payload = ScenePayload.from_file(path, defines) if (client is not None or checkpoint is not None) else None
    sums = FilmSums.empty(h, w, return_variance)
    meta = {
        "kind": "render",
        "scene_digest": payload.digest if payload else "",
        "seed": seed,
        "variance": return_variance,
        "width": w,
        "height": h,
    }
    ckpt = None if checkpoint is None else os.fspath(checkpoint)
    found = _film.resume(ckpt, meta)
    if found is not None:
        arrays = found[1]
        ranges = [(int(a), int(b)) for a, b in arrays["ranges"].reshape(-1, 2)]
        sums = FilmSums(arrays["sum"].astype(np.uint64), arrays.get("sum_sq"), ranges)
        top = max((b for _, b in ranges), default=0)
        if top > spp:
            raise _core.ParameterError(
                f"{ckpt}: the checkpoint holds samples up to {top} per pixel; --spp {spp} must be at least that"
            )
    resumed = sums.samples
    chunker = Chunker(sums.ranges, spp, w * h, chunk_spp)
    bar = _Bar(progress, w * h * chunker.remaining, "render")

    def make() -> tuple[dict[str, Any], dict[str, Any]]:
        arrays: dict[str, Any] = {"sum": sums.sum, "ranges": np.array(sums.ranges, dtype=np.int64).reshape(-1, 2)}
        if sums.sum_sq is not None:
            arrays["sum_sq"] = sums.sum_sq
        return meta, arrays

    saver = _Saver(ckpt, make)

    def next_job(slots: int) -> Optional[tuple[int, int, int, bool]]:
        r = chunker.take(slots)
        return None if r is None else (r[0], r[1], seed, return_variance)

    def local(s0: int, s1: int, *_: Any) -> Chunk:
        base = bar.done

        def forward(done: int, total: int) -> None:
            bar.add(base + done - bar.done)

        t0 = time.perf_counter()
        s, q, done, interrupted = _core.render_range(
            prep, s0, s1, seed=seed, variance=return_variance, threads=threads, progress=forward
        )
        return Chunk(FilmSums(s, q, [(s0, s0 + done)] if done else []), time.perf_counter() - t0, interrupted)

    def on_result(part: Chunk) -> bool:
        if part.sums.ranges:
            sums.merge(part.sums)
            chunker.observe(part.sums.samples, part.seconds)
            if client is not None:
                bar.add(w * h * part.sums.samples)
            saver.maybe()
        return not part.interrupted

    try:
        interrupted, lost = (
            _run(client, next_job, render_task, payload, local, on_result, ahead=CHUNKS_AHEAD)
            if chunker.remaining
            else (False, None)
        )
    finally:
        bar.close()
    if ckpt is not None and sums.samples > resumed:
        saver.now()
    image, var = sums.finish(spp)
    return RenderRun(image, var, sums.samples, spp, interrupted or sums.samples < spp, lost, resumed)


@dataclass
class EnsembleRun:
    """What :func:`ensemble` returns (``info`` as from ``fgf._core.ensemble_scene``)."""

    mean: F32
    stderr: F32
    info: dict[str, Any]
    interrupted: bool = False
    lost: Optional[str] = None
    resumed: int = 0
    done: list[int] = field(default_factory=list)


def merge_realizations(reals: Sequence[Realization], requested: int) -> tuple[F32, F32, dict[str, Any]]:
    """Mean and standard error of realizations, summed in index order in
    f64 exactly as the single-process ensemble sums them (so the bits
    match), with their medium reports combined."""
    reals = sorted(reals, key=lambda r: r.index)
    if not reals:
        raise _core.ParameterError("no realization finished")
    s = np.zeros(reals[0].image.shape, dtype=np.float64)
    s2 = np.zeros_like(s)
    for r in reals:
        v = r.image.astype(np.float64)
        s += v
        s2 += v * v
    n = len(reals)
    nf = float(n)
    m = s / nf
    mean = m.astype(np.float32)
    stderr: F32
    if n < 2:
        stderr = np.full(mean.shape, np.nan, dtype=np.float32)
    else:
        stderr = np.sqrt(np.maximum((s2 - nf * m * m) / (nf - 1.0), 0.0) / nf).astype(np.float32)
    media = []
    for k, first in enumerate(reals[0].info["media"]):
        # The plan's fields are the same in every realization; the measured
        # ones are means over realizations of equal grid size: the mean of the
        # per-realization values (the Rust merge divides sums instead, so the
        # last bits of these report numbers may differ; the images do not).
        item = dict(first)
        for name in ("realized_variance", "clamped_fraction", "mean_sigma_t"):
            if name in first:
                total = 0.0
                for r in reals:
                    total += r.info["media"][k][name]
                item[name] = total / nf
        media.append(item)
    info = {
        "realizations_done": n,
        "realizations_requested": requested,
        "spp": reals[0].info["spp"],
        "media": media,
    }
    return mean, stderr, info


def ensemble(
    scene: Union[str, os.PathLike[str]],
    realizations: int,
    resolution: Optional[int] = None,
    spp: Optional[int] = None,
    seed: int = 0,
    threads: Optional[int] = None,
    defines: Sequence[tuple[str, str]] = (),
    progress: Union[Progress, str] = True,
    client: Optional["Client"] = None,
    checkpoint: Optional[Union[str, os.PathLike[str]]] = None,
    padding: Optional[float] = None,
    marginal: Optional[str] = None,
    keep_realizations: bool = False,
) -> EnsembleRun:
    """The ensemble of ``fgf ensemble`` with one task per realization index,
    merged in index order: the same bits as the single-process ensemble.
    ``checkpoint`` saves the finished realizations as they arrive and resumes
    from them (``realizations`` may be raised)."""
    if realizations < 1:
        raise _core.ParameterError(f"realizations = {realizations}; need at least 1 (2 for a standard error)")
    _check_counts(spp, None)
    defines = list(defines)
    path = os.fspath(scene)
    payload = ScenePayload.from_file(path, defines)
    meta = {
        "kind": "ensemble",
        "scene_digest": payload.digest,
        "seed": seed,
        "resolution": resolution,
        "spp": spp,
        "padding": padding,
        "marginal": marginal,
    }
    ckpt = None if checkpoint is None else os.fspath(checkpoint)
    done = _film.resume_items(
        ckpt, meta, lambda i, found, arrays: Realization(i, arrays[f"r{i}"], found["infos"][str(i)])
    )
    resumed = len(done)
    options: dict[str, Any] = {"resolution": resolution, "spp": spp, "seed": seed, "padding": padding, "marginal": marginal}
    todo = [(r, options) for r in range(realizations) if r not in done]
    shape = None
    if todo:
        prep = _core.prepare_scene(path, defines)
        shape = (prep.width, prep.height, prep.spp if spp is None else spp)
    per = 0 if shape is None else shape[0] * shape[1] * shape[2]
    bar = _Bar(progress, per * len(todo), "ensemble")

    def make() -> tuple[dict[str, Any], dict[str, Any]]:
        m = dict(_film.items_meta(meta, done), infos={str(r): x.info for r, x in done.items()})
        return m, {f"r{r}": x.image for r, x in done.items()}

    saver = _Saver(ckpt, make)

    def local(index: int, *_: Any) -> Optional[Realization]:
        mean, _se, info, interrupted = _core.ensemble_scene(
            path, 1, threads=threads, defines=defines, first=index, **options
        )
        if interrupted or info["realizations_done"] < 1:
            return None
        return Realization(index, mean, info)

    def on_result(r: Optional[Realization]) -> bool:
        if r is None:
            return False
        done[r.index] = r
        bar.add(per)
        saver.maybe()
        return True

    try:
        interrupted, lost = (
            _run(client, _listed(todo), ensemble_task, payload, local, on_result) if todo else (False, None)
        )
    finally:
        bar.close()
    if ckpt is not None and len(done) > resumed:
        saver.now()
    kept = [x for r, x in done.items() if r < realizations]
    if not kept:
        nan = np.full((1, 1, 3), np.nan, dtype=np.float32)
        return EnsembleRun(nan, nan, {"realizations_done": 0, "media": []}, True, lost, resumed, [])
    mean, stderr, info = merge_realizations(kept, realizations)
    if keep_realizations:
        info["realizations"] = np.stack([x.image for x in sorted(kept, key=lambda x: x.index)])
    return EnsembleRun(
        mean, stderr, info, interrupted or len(kept) < realizations, lost, resumed, sorted(x.index for x in kept)
    )


@dataclass
class TruthRun:
    """What :func:`truth_nodes` returns: the node renders finished, by index."""

    nodes: dict[int, Node]
    interrupted: bool = False
    lost: Optional[str] = None
    resumed: int = 0


def truth_nodes(
    scene: Union[str, os.PathLike[str]],
    nodes: int,
    spp: Optional[int] = None,
    seed: int = 0,
    threads: Optional[int] = None,
    defines: Sequence[tuple[str, str]] = (),
    progress: Union[Progress, str] = True,
    return_variance: bool = False,
    client: Optional["Client"] = None,
    checkpoint: Optional[Union[str, os.PathLike[str]]] = None,
) -> TruthRun:
    """The classical renders of the ``nodes`` truth nodes of ``scene``, one
    Dask task per node (or here, with ``threads``); ``fgf.truth`` sums them
    in node order, so the truth has the same bits as without a client.
    ``checkpoint`` saves finished nodes as they arrive and resumes from them."""
    defines = list(defines)
    path = os.fspath(scene)
    payload = ScenePayload.from_file(path, defines)
    meta = {
        "kind": "truth",
        "scene_digest": payload.digest,
        "seed": seed,
        "spp": spp,
        "nodes": nodes,
        "variance": return_variance,
    }
    ckpt = None if checkpoint is None else os.fspath(checkpoint)
    done = _film.resume_items(ckpt, meta, lambda i, _found, arrays: Node(i, arrays[f"n{i}"], arrays.get(f"v{i}")))
    resumed = len(done)
    todo = [(i, nodes, spp, seed, return_variance) for i in range(nodes) if i not in done]
    prep = _core.prepare_scene(path, defines)
    per = prep.width * prep.height * (prep.spp if spp is None else spp)
    bar = _Bar(progress, per * len(todo), "truth")

    def make() -> tuple[dict[str, Any], dict[str, Any]]:
        arrays: dict[str, Any] = {f"n{i}": x.image for i, x in done.items()}
        arrays.update({f"v{i}": x.variance for i, x in done.items() if x.variance is not None})
        return _film.items_meta(meta, done), arrays

    saver = _Saver(ckpt, make)

    def local(index: int, *_: Any) -> Optional[Node]:
        img, var, interrupted = _core.render_truth_node(
            path, index, nodes=nodes, spp=spp, seed=seed, threads=threads, defines=defines,
            return_variance=return_variance,
        )
        if interrupted or img is None:
            return None
        return Node(index, img, var)

    def on_result(x: Optional[Node]) -> bool:
        if x is None:
            return False
        done[x.index] = x
        bar.add(per)
        saver.maybe()
        return True

    try:
        interrupted, lost = (
            _run(client, _listed(todo), truth_task, payload, local, on_result) if todo else (False, None)
        )
    finally:
        bar.close()
    if ckpt is not None and len(done) > resumed:
        saver.now()
    return TruthRun(done, interrupted or len(done) < nodes, lost, resumed)
