"""The pieces of the cluster path's overhead, measured one by one (the
numbers of docs/cluster.md, "Cost model"; the whole-run comparison is
``bench_cluster.py``).

On a ``local:1`` cluster and ``scenes/fgf-cube-pink.xml -D res=128``:

* idle: CPU used by a LocalCluster doing nothing (client, scheduler and
  worker processes), with Dask's default settings and with fgf's
  ``fgf.cluster.LOCAL_CLUSTER_CONFIG``;
* open/close: wall time of ``fgf.cluster.open_client("local:N")`` and of
  leaving it;
* shipping the scene and the first chunk on a fresh worker (which imports
  fgf and compiles the scene, kept for the later chunks);
* per chunk: ``--chunks`` chunks of ``--chunk-spp`` samples per pixel; the
  worker process's CPU beyond the same chunks rendered in this process
  (task handling, result serialization, Dask's bookkeeping), and the wall
  time the worker spends not rendering (the serial gap between chunks);
* pieces: one ``render_range`` call's fixed cost, serializing a chunk's sums
  (72 bytes per pixel) and merging them on the client.

CPU seconds are steadier than wall time on a shared machine; wall times
need a quiet one. Run::

    python benchmarks/cluster_overheads.py
    python benchmarks/cluster_overheads.py --chunk-spp 64 --chunks 10
"""

from __future__ import annotations

import argparse
import logging
import os
import pickle
import statistics
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def _tree_cpu() -> float:
    import psutil

    me = psutil.Process()
    total = 0.0
    for p in [me, *me.children(recursive=True)]:
        try:
            t = p.cpu_times()
        except psutil.Error:
            continue
        total += t.user + t.system
    return total


def idle_cpu(config: dict[str, Any], seconds: float) -> float:
    """Fraction of one core a LocalCluster(1) uses doing nothing."""
    import dask
    import distributed

    with dask.config.set(config):
        cluster = distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=logging.ERROR
        )
        client = distributed.Client(cluster)
    try:
        time.sleep(1.0)
        a = _tree_cpu()
        time.sleep(seconds)
        return (_tree_cpu() - a) / seconds
    finally:
        client.close()
        cluster.close()


def _process_cpu() -> float:
    return time.process_time()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default=str(ROOT / "scenes" / "fgf-cube-pink.xml"))
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--chunk-spp", type=int, default=16)
    ap.add_argument("--chunks", type=int, default=20)
    ap.add_argument("--idle-seconds", type=float, default=6.0)
    args = ap.parse_args()
    import distributed

    from fgf import _core, cluster
    from fgf.cluster import _film, _ship, _tasks

    defines = [("res", str(args.res))]
    k, n = args.chunk_spp, args.chunks

    print("idle LocalCluster(1), % of one core:")
    for name, cfg in (("Dask defaults", {}), ("LOCAL_CLUSTER_CONFIG", cluster.LOCAL_CLUSTER_CONFIG)):
        print(f"  {name:22s} {100 * idle_cpu(cfg, args.idle_seconds):5.1f} %", flush=True)

    for workers in (1, 2):
        t0 = time.perf_counter()
        with cluster.open_client(f"local:{workers}") as client:
            t1 = time.perf_counter()
            client.submit(int, 1).result()
            t2 = time.perf_counter()
        print(f"open_client('local:{workers}'): open {t1 - t0:.2f} s, close {time.perf_counter() - t2:.2f} s", flush=True)

    prep = _core.prepare_scene(args.scene, defines)
    pixels = prep.width * prep.height
    with cluster.open_client("local:1") as client:
        t0 = time.perf_counter()
        shipped = _ship.ScenePayload.from_file(args.scene, defines)
        payload = client.scatter(shipped, broadcast=True, hash=False)
        t1 = time.perf_counter()
        client.submit(_tasks.render_task, payload, 0, 1, 1, False, pure=False).result()  # compiled once
        t2 = time.perf_counter()
        client.submit(_tasks.render_task, payload, 1, 2, 1, False, pure=False).result()
        t3 = time.perf_counter()
        print(f"shipping the scene ({shipped.nbytes} bytes): {(t1 - t0) * 1e3:.0f} ms; first 1-spp chunk on a new "
              f"worker (imports fgf, compiles the scene) {(t2 - t1) * 1e3:.0f} ms, the next {(t3 - t2) * 1e3:.0f} ms",
              flush=True)
        before = client.run(_process_cpu)
        t0 = time.perf_counter()
        futures = [client.submit(_tasks.render_task, payload, 1 + i * k, 1 + (i + 1) * k, 1, False, pure=False)
                   for i in range(n)]
        rendering = 0.0
        for fut in distributed.as_completed(futures):
            rendering += fut.result().seconds
            fut.release()
        wall = time.perf_counter() - t0
        after = client.run(_process_cpu)
    worker_cpu = sum(after[w] - before[w] for w in before)
    c0 = time.process_time()
    for i in range(n):
        _core.render_range(prep, 1 + i * k, 1 + (i + 1) * k, seed=1, threads=1)
    here = time.process_time() - c0
    print(f"{n} chunks of {k} spp, {prep.width}x{prep.height}: {here / n * 1e3:.1f} ms of render CPU each;")
    print(f"  worker process CPU beyond it: {(worker_cpu - here) / n * 1e3:.1f} ms per chunk "
          f"({100 * (worker_cpu / here - 1):.1f} %)")
    print(f"  worker not rendering (serial gap): {(wall - rendering) / n * 1e3:.1f} ms per chunk "
          f"({100 * (wall / rendering - 1):.1f} %)", flush=True)

    fixed = []
    for kk in (1, 8):
        times = []
        for i in range(5):
            c0 = time.process_time()
            _core.render_range(prep, 100 + i * kk, 100 + (i + 1) * kk, seed=1, threads=1)
            times.append(time.process_time() - c0)
        fixed.append(statistics.median(times))
    per_spp = (fixed[1] - fixed[0]) / 7
    print(f"render_range: {per_spp * 1e3:.2f} ms CPU per spp, fixed cost per call {(fixed[0] - per_spp) * 1e3:.2f} ms")
    s, q, _, _ = _core.render_range(prep, 0, 1, seed=1, threads=1)
    sums = _film.FilmSums(s, q, [(0, 1)])
    reps = 20
    t0 = time.perf_counter()
    for _ in range(reps):
        blob = pickle.dumps(sums, protocol=5)
    t_pickle = (time.perf_counter() - t0) / reps
    acc = _film.FilmSums.empty(prep.height, prep.width, False)
    t0 = time.perf_counter()
    for i in range(reps):
        acc.merge(_film.FilmSums(s, None, [(i, i + 1)]))
    t_merge = (time.perf_counter() - t0) / reps
    print(f"a chunk's sums: {len(blob) / 1e6:.2f} MB ({len(blob) / pixels:.0f} bytes per pixel), "
          f"pickled in {t_pickle * 1e3:.2f} ms, merged in {t_merge * 1e3:.2f} ms")
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    return 0


if __name__ == "__main__":
    sys.exit(main())
