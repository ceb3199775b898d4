"""Renderer benchmark as users run it: ``fgf render`` against Mitsuba 3's ``mitsuba`` CLI.

    python benchmarks/bench_render.py [--spp 1024] [--repeats 3] [--res 256] [--max-depth 64]
                                      [--threads N] [--scene NAME]... [--no-warmup] [--no-inprocess]
    python benchmarks/bench_render.py --scaling [--res 128] [--spp 64] [--repeats 3]

Default mode: whole processes, the way a user renders a scene file:

    fgf render SCENE -D spp=1024 -D res=256 -D max_depth=64 -o fgf.exr --quiet
    mitsuba -m llvm_ad_rgb -D spp=1024 -D res=256 -D max_depth=64 -o mitsuba.exr SCENE

(Python start-up, imports, scene loading, Dr.Jit's kernel compilation or the
kernel cache, the render and writing the image are all in the time; fgf also
writes its PNG preview). The two alternate, the first of each round taking
turns, for ``--repeats`` rounds (3 or more for a figure you report); each is
preceded by one untimed run of each (it fills Dr.Jit's kernel cache and the
page cache, as for a user's second render). Reported: the median wall time,
the median CPU seconds of the process and its threads
(``getrusage(RUSAGE_CHILDREN)``, user + system) and the speed-up of fgf, i.e.
Mitsuba's time over fgf's. A second, separate column keeps the old in-process
figure: ``fgf.render`` and ``mi.render`` inside an already started Python,
64 spp, best of ``--repeats`` after a warm-up render, in M samples/s; it
leaves out start-up and compilation and is not what a user waits for.

``--scaling``: (1) thread scaling, ``fgf.render`` in-process with 1 and 2
threads (best of ``--repeats``, wall and CPU time), and (2) linearity of the
cost in resolution and spp, as instructions per sample of the render loop
counted by callgrind (``benchmarks/callgrind.sh``; deterministic, so it can be
measured on a loaded machine): it should not change with either.

The scenes are ``scenes/reference/cube-homogeneous.xml`` and
``cube-heterogeneous.xml`` (their ``res``, ``spp`` and ``max_depth``
defaults are overridden by ``-D``). Mitsuba's llvm variant needs Debian's
``libllvm19`` (``scripts/setup.sh --test`` installs it; this script sets
``DRJIT_LIBLLVM_PATH``). Results: docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# numpy's OpenBLAS threads spin on the same cores as the renderers; the
# benchmark does no linear algebra.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "scenes" / "reference"
SCENES = ["cube-homogeneous.xml", "cube-heterogeneous.xml"]
LLVM19 = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
INPROCESS_SPP = 64


def executable(name: str) -> str:
    """The console script `name` of this Python's environment, else from PATH."""
    here = Path(sys.executable).parent / name
    if here.exists():
        return str(here)
    found = shutil.which(name)
    if found is None:
        sys.exit(f"bench_render: error: no `{name}` command (install the package that provides it)")
    return found


def children_cpu() -> float:
    """User + system seconds of the finished, waited-for child processes."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(cmd: list[str], env: dict[str, str]) -> tuple[float, float]:
    """Run `cmd` to completion; (wall seconds, CPU seconds of the process)."""
    c0 = children_cpu()
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        tail = r.stderr.strip().splitlines()[-3:]
        sys.exit(f"bench_render: error: {' '.join(cmd)} exited with {r.returncode}: {tail}")
    return wall, children_cpu() - c0


def commands(scene: Path, out: Path, args: argparse.Namespace) -> dict[str, list[str]]:
    defines = [f"spp={args.spp}", f"res={args.res}", f"max_depth={args.max_depth}"]
    fgf = [executable("fgf"), "render", str(scene), "-o", str(out / "fgf.exr"), "--quiet"]
    mts = [executable("mitsuba"), "-m", "llvm_ad_rgb", "-o", str(out / "mitsuba.exr")]
    for d in defines:
        fgf += ["-D", d]
        mts += ["-D", d]
    if args.threads is not None:
        fgf += ["--threads", str(args.threads)]
        mts += ["-t", str(args.threads)]
    return {"fgf": fgf, "mitsuba": mts + [str(scene)]}


def processes(scene: Path, args: argparse.Namespace) -> dict[str, dict[str, float]]:
    """Alternated whole-process runs; medians of wall and CPU time per renderer."""
    env = dict(os.environ, DRJIT_LIBLLVM_PATH=os.environ.get("DRJIT_LIBLLVM_PATH", LLVM19))
    runs: dict[str, list[tuple[float, float]]] = {"fgf": [], "mitsuba": []}
    with tempfile.TemporaryDirectory(prefix="bench_render_") as tmp:
        cmds = commands(scene, Path(tmp), args)
        if args.warmup:
            for name in ("fgf", "mitsuba"):
                timed(cmds[name], env)
        for k in range(args.repeats):
            order = ("fgf", "mitsuba") if k % 2 == 0 else ("mitsuba", "fgf")
            for name in order:
                runs[name].append(timed(cmds[name], env))
    return {
        name: {"wall": statistics.median(r[0] for r in rs), "cpu": statistics.median(r[1] for r in rs)}
        for name, rs in runs.items()
    }


def self_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def best_of(render, repeat: int) -> dict[str, float]:
    """One warm-up render, then `repeat` timed ones (seeds 0, 1, ...): the
    fastest wall time and the least CPU time of this process."""
    render(1000)
    runs = []
    for seed in range(repeat):
        c0 = self_cpu()
        t0 = time.perf_counter()
        render(seed)
        runs.append((time.perf_counter() - t0, self_cpu() - c0))
    return {"seconds": min(r[0] for r in runs), "cpu": min(r[1] for r in runs)}


def mitsuba_worker(scene: str, res: int, spp: int, max_depth: int, repeat: int, threads: int) -> None:
    """Inside a subprocess: in-process Mitsuba llvm_ad_rgb renders; prints JSON."""
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LLVM19)
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    if threads > 0:
        dr.set_thread_count(threads)
    sc = mi.load_file(scene, res=str(res), spp=str(spp), max_depth=str(max_depth))

    def render(seed: int) -> None:
        img = mi.render(sc, spp=spp, seed=seed)
        dr.eval(img)
        dr.sync_thread()

    print(json.dumps(best_of(render, repeat)))


def inprocess(scene: Path, args: argparse.Namespace) -> dict[str, float]:
    """M samples/s of in-process renders at INPROCESS_SPP (see the module docs)."""
    import fgf

    samples = args.res * args.res * INPROCESS_SPP
    defines = {"res": args.res, "spp": INPROCESS_SPP, "max_depth": args.max_depth}
    r = best_of(
        lambda seed: fgf.render(scene, seed=seed, threads=args.threads, defines=defines, progress=False),
        args.repeats,
    )
    out = {"fgf": samples / r["seconds"] / 1e6}
    env = dict(os.environ, DRJIT_LIBLLVM_PATH=os.environ.get("DRJIT_LIBLLVM_PATH", LLVM19))
    cmd = [sys.executable, __file__, "--mitsuba-worker", str(scene), str(args.res), str(INPROCESS_SPP),
           str(args.max_depth), str(args.repeats), str(args.threads or 0)]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.exit(f"bench_render: error: in-process Mitsuba failed: {p.stderr.strip().splitlines()[-1:]}")
    out["mitsuba"] = samples / json.loads(p.stdout.strip().splitlines()[-1])["seconds"] / 1e6
    return out


def compare(args: argparse.Namespace) -> None:
    load = os.getloadavg()
    print(f"# {args.res}x{args.res}, {args.spp} spp, max_depth {args.max_depth}, threads "
          f"{args.threads or 'default'}; whole processes, alternated, median of {args.repeats}"
          f"{' after a warm-up run each' if args.warmup else ''}; cores {os.cpu_count()}, "
          f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    print("# speed-up = Mitsuba llvm_ad_rgb time / fgf time (> 1: fgf is faster)")
    cols = f"{'wall s':>8} {'CPU s':>8} {'speed-up wall':>13} {'speed-up CPU':>12}"
    side = f" | in-process {INPROCESS_SPP} spp, M samples/s" if args.inprocess else ""
    print(f"{'scene':<24} {'renderer':<20} {cols}{side}")
    for name in args.scene:
        scene = REFERENCE / name if not Path(name).exists() else Path(name)
        r = processes(scene, args)
        ip = inprocess(scene, args) if args.inprocess else {}
        f, m = r["fgf"], r["mitsuba"]
        for who, label in (("fgf", "fgf"), ("mitsuba", "mitsuba llvm_ad_rgb")):
            x = r[who]
            su = f"{m['wall'] / f['wall']:12.2f}x {m['cpu'] / f['cpu']:11.2f}x" if who == "fgf" else f"{'':>13} {'':>12}"
            extra = f" | {ip[who]:8.3f}" if ip else ""
            if ip and who == "fgf":
                extra += f" ({ip['fgf'] / ip['mitsuba']:.2f}x)"
            print(f"{scene.stem:<24} {label:<20} {x['wall']:8.2f} {x['cpu']:8.2f} {su}{extra}")


def callgrind(scene: Path, spp: int, threads: int, defines: list[str]) -> dict[str, str]:
    """`benchmarks/callgrind.sh`'s figures for one render."""
    cmd = ["bash", str(ROOT / "benchmarks" / "callgrind.sh"), str(scene), str(spp), str(threads), *defines]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"bench_render: error: {' '.join(cmd)}: {p.stderr.strip().splitlines()[-1:]}")
    words = p.stdout.split()
    return dict(zip(words[::2], words[1::2]))


def scaling(args: argparse.Namespace) -> None:
    import fgf

    scene = REFERENCE / args.scene[0] if not Path(args.scene[0]).exists() else Path(args.scene[0])
    load = os.getloadavg()
    print(f"# {scene.name}; cores {os.cpu_count()}, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    samples = args.res * args.res * args.spp
    defines = {"res": args.res, "spp": args.spp, "max_depth": args.max_depth}
    print(f"## threads: fgf.render in-process, {args.res}x{args.res}, {args.spp} spp, best of {args.repeats}")
    base = None
    for threads in (1, 2):
        r = best_of(
            lambda seed: fgf.render(scene, seed=seed, threads=threads, defines=defines, progress=False),
            args.repeats,
        )
        base = base or r
        print(f"threads {threads}: {r['seconds']:7.3f} s wall, {r['cpu']:7.3f} s CPU, "
              f"{samples / r['seconds'] / 1e6:7.3f} M samples/s; speed-up {base['seconds'] / r['seconds']:.2f}x, "
              f"CPU {r['cpu'] / base['cpu']:.2f}x of 1 thread")
    print("## instructions per sample of the render loop (callgrind, 1 thread unless said)")
    print(f"{'res':>5} {'spp':>5} {'threads':>7} {'instructions':>14} {'per sample':>11} {'hash':>17}")
    grid = [(32, 16, 1), (64, 16, 1), (128, 16, 1), (64, 4, 1), (64, 64, 1), (64, 16, 2)]
    totals: dict[tuple[int, int, int], int] = {}
    for res, spp, threads in grid:
        c = callgrind(scene, spp, threads, [f"res={res}", f"max_depth={args.max_depth}"])
        totals[(res, spp, threads)] = int(c["instructions"])
        # With more threads the workers' instructions are outside render_range's
        # inclusive count: compare the totals with the 1-thread run instead.
        per = c["per-sample"] if threads == 1 else f"{totals[(res, spp, threads)] / totals[(res, spp, 1)]:.4f}x 1t"
        print(f"{res:5d} {spp:5d} {threads:7d} {c['instructions']:>14} {per:>11} {c['hash']:>17}")


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "--mitsuba-worker":
        mitsuba_worker(sys.argv[2], *map(int, sys.argv[3:8]))
        return 0
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", action="append", help="scene file, or a name in scenes/reference (default: both)")
    ap.add_argument("--res", type=int, default=None, help="image side (default 256; 128 with --scaling)")
    ap.add_argument("--spp", type=int, default=None, help="samples per pixel (default 1024; 64 with --scaling)")
    ap.add_argument("--max-depth", type=int, default=64)
    ap.add_argument("--threads", type=int, default=None, help="threads of both renderers (default: theirs)")
    ap.add_argument("--repeats", type=int, default=3, help="rounds (median) or in-process renders (best)")
    ap.add_argument("--no-warmup", dest="warmup", action="store_false", help="no untimed first run")
    ap.add_argument("--no-inprocess", dest="inprocess", action="store_false",
                    help=f"leave out the in-process {INPROCESS_SPP}-spp column")
    ap.add_argument("--scaling", action="store_true", help="thread scaling and cost linearity instead")
    args = ap.parse_args()
    args.scene = args.scene or SCENES
    args.res = args.res or (128 if args.scaling else 256)
    args.spp = args.spp or (64 if args.scaling else 1024)
    if min(args.res, args.spp, args.repeats) < 1 or args.max_depth < -1 or (args.threads or 1) < 1:
        ap.error("--res, --spp, --repeats and --threads must be >= 1, --max-depth >= -1")
    if not args.scaling and not Path(LLVM19).exists() and "DRJIT_LIBLLVM_PATH" not in os.environ:
        ap.error(f"{LLVM19} is missing: Mitsuba's llvm_ad_rgb needs it (apt-get install -y libllvm19)")
    if args.scaling:
        scaling(args)
    else:
        compare(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
