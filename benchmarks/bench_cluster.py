"""Benchmark: a render of about 60 s on one machine, threads (the ordinary
path) against ``--cluster local:N`` (Dask worker processes), to measure the
cluster path's overhead and the throughput per worker.

Each configuration is a whole ``fgf render`` process (so the LocalCluster's
start-up, the scene shipping and the final merge are counted), timed from
outside; configurations are alternated within each round and the median of
``--rounds`` (>= 3) rounds is reported, so a load change on a shared machine
affects every configuration alike. Every cluster image is checked to be
byte-identical to the threaded one. Configurations:

* ``threads:N`` — ``fgf render --threads N``, today's single-process path;
* ``local:N`` — ``fgf render --cluster local:N``, N single-threaded Dask
  worker processes, chunks sized automatically (``--chunk-spp K`` to fix
  them instead), N = 1 and 2 by default.

Overhead = time(local:N) / time(threads:N) - 1 (target <= 5 %); throughput
per worker = samples / s / N. The CPU seconds of each whole process tree
(client, scheduler, workers) are reported too: on a loaded machine they are
a steadier measure of the work the cluster adds than wall time. Run when the
machine is quiet::

    python benchmarks/bench_cluster.py --calibrate           # the --spp of a ~60 s 2-thread render
    python benchmarks/bench_cluster.py --spp 16384 --rounds 3 --json bench_cluster.json
    python benchmarks/bench_cluster.py --spp 64 --rounds 3   # a quick end-to-end check

The scene defaults to ``scenes/fgf-cube-pink.xml`` at ``-D res=128``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_once(scene: str, defines: list[str], spp: int, out: Path, extra: list[str]) -> tuple[float, float]:
    """Wall and CPU seconds (all processes of the run) of one ``fgf render``."""
    cmd = [sys.executable, "-m", "fgf", "render", scene, "--spp", str(spp), "--seed", "1", "-o", str(out), "--quiet"]
    for d in defines:
        cmd += ["-D", d]
    c0 = _children_cpu()
    t0 = time.perf_counter()
    r = subprocess.run(cmd + extra, capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd + extra)} failed: {r.stderr.strip()}")
    return dt, _children_cpu() - c0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default=str(ROOT / "scenes" / "fgf-cube-pink.xml"))
    ap.add_argument("-D", dest="defines", action="append", default=None, help="scene define (default res=128)")
    ap.add_argument("--spp", type=int, default=16384, help="samples per pixel (default 16384: ~60 s with 2 threads)")
    ap.add_argument("--chunk-spp", type=int, default=None, help="fix the chunk size (default: automatic)")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--calibrate", action="store_true", help="print the spp of a ~60 s 2-thread render and exit")
    ap.add_argument("--json", default=None, help="also write the results here")
    args = ap.parse_args()
    if args.rounds < 3:
        ap.error("--rounds must be at least 3 (the median of 3 or more)")
    defines = args.defines or ["res=128"]
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        if args.calibrate:
            # Two renders, so that the process start-up (most of a short
            # render) is not extrapolated as if it were rendering time.
            t_lo = run_once(args.scene, defines, 16, t / "c.exr", ["--threads", "2"])[0]
            t_hi = run_once(args.scene, defines, 256, t / "c.exr", ["--threads", "2"])[0]
            per_spp = max(t_hi - t_lo, 1e-3) / 240
            spp = max(16, round((60 - t_lo) / per_spp + 16))
            print(f"16 spp in {t_lo:.1f} s, 256 spp in {t_hi:.1f} s with 2 threads: use --spp {spp} for ~60 s")
            return 0
        configs: list[tuple[str, list[str]]] = []
        for n in args.workers:
            configs.append((f"threads:{n}", ["--threads", str(n)]))
            chunks = [] if args.chunk_spp is None else ["--chunk-spp", str(args.chunk_spp)]
            configs.append((f"local:{n}", ["--cluster", f"local:{n}", *chunks]))
        times: dict[str, list[float]] = {name: [] for name, _ in configs}
        cpus: dict[str, list[float]] = {name: [] for name, _ in configs}
        reference = None
        for r in range(args.rounds):
            order = configs if r % 2 == 0 else configs[::-1]
            for name, extra in order:
                out = t / f"{name.replace(':', '_')}.exr"
                wall, cpu = run_once(args.scene, defines, args.spp, out, extra)
                times[name].append(wall)
                cpus[name].append(cpu)
                data = out.read_bytes()
                if reference is None:
                    reference = data
                elif data != reference:
                    raise SystemExit(f"{name}: the image differs from the first render (bit-identity broken)")
                print(f"round {r + 1}: {name:10s} {wall:7.1f} s wall {cpu:7.1f} s cpu", file=sys.stderr, flush=True)
    import fgf

    p = fgf._core.prepare_scene(args.scene, [tuple(d.split("=", 1)) for d in defines])
    samples = p.width * p.height * args.spp
    results = {"scene": args.scene, "defines": defines, "spp": args.spp, "chunk_spp": args.chunk_spp,
               "rounds": args.rounds, "cpu_count": os.cpu_count(), "load_avg": os.getloadavg(), "configs": {}}
    print(f"{'config':10s} {'median s':>9s} {'Msamples/s':>11s} {'per worker':>11s} {'overhead':>9s} "
          f"{'cpu s':>8s} {'cpu over':>9s}")
    for n in args.workers:
        base = statistics.median(times[f"threads:{n}"])
        base_cpu = statistics.median(cpus[f"threads:{n}"])
        for name in (f"threads:{n}", f"local:{n}"):
            med = statistics.median(times[name])
            cpu = statistics.median(cpus[name])
            rate = samples / med / 1e6
            over = med / base - 1.0
            results["configs"][name] = {"times": times[name], "median": med, "msamples_per_s": rate,
                                        "per_worker": rate / n, "overhead_vs_threads": over,
                                        "cpu_seconds": cpus[name], "cpu_median": cpu,
                                        "cpu_overhead_vs_threads": cpu / base_cpu - 1.0}
            print(f"{name:10s} {med:9.1f} {rate:11.3f} {rate / n:11.3f} {100 * over:8.1f}% "
                  f"{cpu:8.1f} {100 * (cpu / base_cpu - 1.0):8.1f}%")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
