"""Speed of ``fgf_volpath`` (fgf.mitsuba) against Mitsuba's own ``volpath``
in ``llvm_ad_rgb`` on an exponential scene.

The scene is the reference cube (a null-bounded homogeneous medium, sigma_t 4,
albedo 0.8, over a diffuse ground lit by a small area light; the same layout as
``scenes/fgf-cube-*.xml``). Each measurement is a whole process: Python start,
``import mitsuba`` (and ``fgf.mitsuba``), scene load, JIT compilation and the
render, timed from the parent. The two integrators alternate, ``--repeats``
times each (default 3), and the median of each is reported, with the
in-process render time (``mi.render`` plus the image read-back) alongside.

Usage::

    python benchmarks/bench_mitsuba_plugin.py [--res 256] [--spp 64] [--repeats 3] [--medium pink-reciprocal]

Needs LLVM 19 (Debian's ``libllvm19``, see ``scripts/setup.sh --test``).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

LIBLLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"

SCENE = """<scene version="3.0.0">
<integrator type="{integrator}"><integer name="max_depth" value="64"/></integrator>
<sensor type="perspective"><float name="fov" value="40"/><string name="fov_axis" value="x"/>
<transform name="to_world"><lookat origin="0,1.6,4" target="0,0.6,0" up="0,1,0"/></transform>
<sampler type="independent"/>
<film type="hdrfilm"><integer name="width" value="{res}"/><integer name="height" value="{res}"/>
<string name="pixel_format" value="rgb"/><rfilter type="box"/></film></sensor>
<shape type="cube"><transform name="to_world"><scale value="0.5"/><translate value="0,0.75,0"/></transform>
<bsdf type="null"/>{medium}</shape>
<shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/></transform>
<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
<shape type="rectangle"><transform name="to_world"><matrix value="-0.0490290338 0.107919143 0.880450906 -2.5
0 0.224471818 -0.440225453 2 -0.245145169 -0.0215838286 -0.176090181 0.5 0 0 0 1"/></transform>
<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
<emitter type="area"><rgb name="radiance" value="150"/></emitter></shape>
</scene>"""


MEDIA = {
    "homogeneous": '<medium type="homogeneous" name="interior"><float name="sigma_t" value="4"/>'
    '<float name="albedo" value="0.8"/></medium>',
    # Under volpath an fgf medium is its exponential counterpart (same mean
    # sigma_t and albedo): the same scene, the exponential flights' cost.
    "pink-reciprocal": '<medium type="fgf" name="interior"><float name="sigma_t" value="4"/>'
    '<float name="albedo" value="0.8"/><float name="hurst" value="-0.1"/><float name="sw" value="4"/>'
    '<string name="kernel" value="reciprocal"/></medium>',
}


def worker(integrator: str, res: int, spp: int, medium: str) -> None:
    """One measured process: render once, print JSON with the render time."""
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", LIBLLVM)
    import mitsuba as mi
    import numpy as np

    mi.set_variant("llvm_ad_rgb")
    if integrator == "fgf_volpath" or medium != "homogeneous":
        import fgf.mitsuba  # noqa: F401

    scene = mi.load_string(SCENE.format(integrator=integrator, res=res, medium=MEDIA[medium]))
    t0 = time.perf_counter()
    # (Mitsuba's stub types the seed as its UInt32; it takes an int.)
    img = np.array(mi.render(scene, spp=spp, seed=0))  # type: ignore[arg-type]
    dt = time.perf_counter() - t0
    print(json.dumps({"render_s": dt, "mean": float(img[..., :3].mean())}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument(
        "--medium",
        choices=list(MEDIA),
        default="homogeneous",
        help="homogeneous (default), or pink-reciprocal: fgf_volpath on pink noise against volpath on its exponential counterpart",
    )
    ap.add_argument("--worker", choices=["volpath", "fgf_volpath"], help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.worker:
        worker(a.worker, a.res, a.spp, a.medium)
        return
    times: dict[str, list[float]] = {"volpath": [], "fgf_volpath": []}
    render: dict[str, list[float]] = {"volpath": [], "fgf_volpath": []}
    means: dict[str, list[float]] = {"volpath": [], "fgf_volpath": []}
    for _ in range(a.repeats):
        for integ in ("volpath", "fgf_volpath"):
            cmd = [sys.executable, __file__, "--worker", integ, "--res", str(a.res), "--spp", str(a.spp), "--medium", a.medium]
            t0 = time.perf_counter()
            out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
            times[integ].append(time.perf_counter() - t0)
            r = json.loads(out.strip().splitlines()[-1])
            render[integ].append(r["render_s"])
            means[integ].append(r["mean"])
    print(f"{a.medium}, llvm_ad_rgb, {a.res}x{a.res}, {a.spp} spp, max_depth 64, median of {a.repeats} (alternated):")
    for integ in ("volpath", "fgf_volpath"):
        print(
            f"  {integ:12s} process {statistics.median(times[integ]):6.2f} s"
            f"   render {statistics.median(render[integ]):6.2f} s   image mean {statistics.median(means[integ]):.5f}"
        )
    ratio = statistics.median(times["fgf_volpath"]) / statistics.median(times["volpath"])
    ratio_r = statistics.median(render["fgf_volpath"]) / statistics.median(render["volpath"])
    print(f"  fgf_volpath / volpath: {ratio:.2f}x (whole process), {ratio_r:.2f}x (render only)")


if __name__ == "__main__":
    main()
