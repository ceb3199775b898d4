"""Renderer benchmark: fgf vs Mitsuba 3 on the two reference scenes.

    python benchmarks/bench_render.py [--res 256] [--spp 64] [--max-depth 64] [--threads N] [--repeat 3]

Renders ``scenes/reference/cube-homogeneous.xml`` and
``cube-heterogeneous.xml`` with fgf, with Mitsuba ``scalar_rgb`` and, if
Debian's ``libllvm19`` is installed, Mitsuba ``llvm_ad_rgb``
(``apt-get install -y libllvm19``; the script sets ``DRJIT_LIBLLVM_PATH``
itself). Each Mitsuba variant runs in its own
subprocess. Every renderer is treated alike: one untimed warm-up render with
the same settings (for ``llvm_ad_rgb`` it compiles the kernel; for fgf it
starts the thread pool), then ``--repeat`` timed renders of which the fastest
counts, since other jobs on a shared machine only ever slow a render down.
The timed renders use different seeds. Prints samples per second
(pixels × spp / wall time, and per CPU-second) and fgf's ratio to each.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

# numpy's OpenBLAS threads spin on the same cores as the renderers; the
# benchmark does no linear algebra.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

REFERENCE = Path(__file__).resolve().parents[1] / "scenes" / "reference"
SCENES = ["cube-homogeneous.xml", "cube-heterogeneous.xml"]
LLVM19 = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"


def best_of(render, repeat: int) -> dict:
    """Warm up with one render, then time `repeat` renders (seeds 0, 1, ...);
    the fastest wall time and the least CPU time."""
    render(1000)
    runs = []
    for seed in range(repeat):
        c0 = cpu_seconds()
        t0 = time.perf_counter()
        render(seed)
        runs.append((time.perf_counter() - t0, cpu_seconds() - c0))
    return {"seconds": min(r[0] for r in runs), "cpu": min(r[1] for r in runs)}


def worker(variant: str, scene: str, res: int, spp: int, max_depth: int, repeat: int) -> None:
    """Run inside a subprocess: time Mitsuba renders, print JSON."""
    import mitsuba as mi

    mi.set_variant(variant)
    sc = mi.load_file(scene, res=str(res), spp=str(spp), max_depth=str(max_depth))

    def render(seed: int) -> None:
        img = mi.render(sc, spp=spp, seed=seed)
        if variant.startswith("llvm"):
            import drjit as dr

            dr.eval(img)
            dr.sync_thread()

    print(json.dumps(best_of(render, repeat)))


def cpu_seconds() -> float:
    """CPU time of this process, all threads (user + system)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def run_mitsuba(variant: str, scene: Path, args) -> dict | None:
    env = dict(os.environ)
    if variant.startswith("llvm"):
        env["DRJIT_LIBLLVM_PATH"] = LLVM19
    cmd = [sys.executable, __file__, "--worker", variant, str(scene), str(args.res), str(args.spp),
           str(args.max_depth), str(args.repeat)]
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if r.returncode != 0:
        print(f"  mitsuba {variant} failed: {r.stderr.strip().splitlines()[-1:]}", file=sys.stderr)
        return None
    return json.loads(r.stdout.strip().splitlines()[-1])


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        worker(sys.argv[2], sys.argv[3], *map(int, sys.argv[4:8]))
        return 0
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--max-depth", type=int, default=64)
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--repeat", type=int, default=3, help="timed renders per renderer (the fastest counts)")
    args = ap.parse_args()
    if min(args.res, args.spp, args.repeat) < 1 or args.max_depth < -1:
        ap.error("--res, --spp and --repeat must be >= 1, --max-depth >= -1")

    import fgf

    variants = ["scalar_rgb"]
    if Path(LLVM19).exists():
        variants.append("llvm_ad_rgb")
    else:
        print(f"note: {LLVM19} is missing, skipping Mitsuba llvm_ad_rgb (apt-get install -y libllvm19)")
    load = os.getloadavg()
    print(f"# {args.res}x{args.res}, {args.spp} spp, max_depth {args.max_depth}, best of {args.repeat} after a "
          f"warm-up; cores {os.cpu_count()}, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    samples = args.res * args.res * args.spp
    print("wall: samples / wall-clock second; cpu: samples / CPU-second (all threads), which is")
    print("robust to other jobs on the machine; ratios are fgf over the other renderer.")
    print(f"{'scene':<26} {'renderer':<22} {'seconds':>8} {'M/s wall':>9} {'ratio':>6} {'M/s cpu':>8} {'ratio':>6}")
    for name in SCENES:
        scene = REFERENCE / name
        defines = {"res": args.res, "spp": args.spp, "max_depth": args.max_depth}
        r = best_of(
            lambda seed: fgf.render(scene, seed=seed, threads=args.threads, defines=defines, progress=False),
            args.repeat,
        )
        t_fgf, c_fgf = r["seconds"], r["cpu"]
        w_fgf, u_fgf = samples / t_fgf, samples / c_fgf
        print(f"{name:<26} {'fgf':<22} {t_fgf:8.2f} {w_fgf / 1e6:9.3f} {'':>6} {u_fgf / 1e6:8.3f}")
        for v in variants:
            r = run_mitsuba(v, scene, args)
            if r is None:
                continue
            w, u = samples / r["seconds"], samples / r["cpu"]
            print(
                f"{name:<26} {'mitsuba ' + v:<22} {r['seconds']:8.2f} {w / 1e6:9.3f} {w_fgf / w:5.2f}x"
                f" {u / 1e6:8.3f} {u_fgf / u:5.2f}x"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
