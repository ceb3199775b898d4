"""Renderer benchmark: fgf vs Mitsuba 3 on the two reference scenes.

    python benchmarks/bench_render.py [--res 256] [--spp 64] [--max-depth 64] [--threads N]

Renders ``../shared/scenes/cube-homogeneous.xml`` and
``cube-heterogeneous.xml`` (the folder beside the checkout) with fgf, with
Mitsuba ``scalar_rgb`` and, if Debian's ``libllvm19`` is installed, Mitsuba
``llvm_ad_rgb`` (``apt-get install -y libllvm19``; the script sets
``DRJIT_LIBLLVM_PATH`` itself). Each Mitsuba variant runs in its own
subprocess. For ``llvm_ad_rgb`` the kernel is compiled by a first render with
the same settings and the second, warm render is timed. Prints samples per
second (pixels × spp / wall time) and fgf's ratio to each.
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

SHARED = Path(__file__).resolve().parents[2] / "shared" / "scenes"
SCENES = ["cube-homogeneous.xml", "cube-heterogeneous.xml"]
LLVM19 = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"


def worker(variant: str, scene: str, res: int, spp: int, max_depth: int) -> None:
    """Run inside a subprocess: time one Mitsuba render, print JSON."""
    import mitsuba as mi

    mi.set_variant(variant)
    sc = mi.load_file(scene, res=str(res), spp=str(spp), max_depth=str(max_depth))
    if variant.startswith("llvm"):
        import drjit as dr

        dr.eval(mi.render(sc, spp=spp, seed=1))  # compile the kernel
        dr.sync_thread()
    c0 = cpu_seconds()
    t0 = time.perf_counter()
    img = mi.render(sc, spp=spp, seed=0)
    if variant.startswith("llvm"):
        import drjit as dr

        dr.eval(img)
        dr.sync_thread()
    print(json.dumps({"seconds": time.perf_counter() - t0, "cpu": cpu_seconds() - c0}))


def cpu_seconds() -> float:
    """CPU time of this process, all threads (user + system)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def run_mitsuba(variant: str, scene: Path, args) -> dict | None:
    env = dict(os.environ)
    if variant.startswith("llvm"):
        env["DRJIT_LIBLLVM_PATH"] = LLVM19
    cmd = [sys.executable, __file__, "--worker", variant, str(scene), str(args.res), str(args.spp), str(args.max_depth)]
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if r.returncode != 0:
        print(f"  mitsuba {variant} failed: {r.stderr.strip().splitlines()[-1:]}", file=sys.stderr)
        return None
    return json.loads(r.stdout.strip().splitlines()[-1])


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        worker(sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5]), int(sys.argv[6]))
        return 0
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--max-depth", type=int, default=64)
    ap.add_argument("--threads", type=int, default=None)
    args = ap.parse_args()

    import fgf

    variants = ["scalar_rgb"]
    if Path(LLVM19).exists():
        variants.append("llvm_ad_rgb")
    else:
        print(f"note: {LLVM19} is missing, skipping Mitsuba llvm_ad_rgb (apt-get install -y libllvm19)")
    load = os.getloadavg()
    print(f"# {args.res}x{args.res}, {args.spp} spp, max_depth {args.max_depth}; cores {os.cpu_count()}, "
          f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    samples = args.res * args.res * args.spp
    print("wall: samples / wall-clock second; cpu: samples / CPU-second (all threads), which is")
    print("robust to other jobs on the machine; ratios are fgf over the other renderer.")
    print(f"{'scene':<26} {'renderer':<22} {'seconds':>8} {'M/s wall':>9} {'ratio':>6} {'M/s cpu':>8} {'ratio':>6}")
    for name in SCENES:
        scene = SHARED / name
        defines = {"res": args.res, "spp": args.spp, "max_depth": args.max_depth}
        c0 = cpu_seconds()
        t0 = time.perf_counter()
        fgf.render(scene, seed=0, threads=args.threads, defines=defines, progress=False)
        t_fgf = time.perf_counter() - t0
        c_fgf = cpu_seconds() - c0
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
