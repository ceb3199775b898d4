"""Walk benchmark: fgf's BVH against Mitsuba 3's (Embree, called by Dr.Jit's
LLVM backend) on the same mesh and the same rays, one thread each.

    python benchmarks/bench_rays.py [--rays 1048576] [--passes 5] [--repeats 3] [--quads N_U N_V]
                                    [--fgf-bin PATH]

The mesh is the reference scene's bumpy torus (``benchmarks/make_mesh_envmap.py``,
120,000 triangles, in its own space). Two sets of rays are written once to a
temporary folder, and both tools read them:

* ``bounce``: from the centroids of random triangles, offset by 10⁻³ to a random
  side, into uniformly random directions on that side (the rays a rough BSDF
  sends off the mesh); the nearest hit of each.
* ``sun``: from the same points, offset outward, toward the sun of the scene's
  sky (50° from the zenith): shadow rays, which ask only whether anything is
  hit (fgf ``Geometry::occluded``, Mitsuba ``Scene.ray_test``).

Each (tool, set) runs in a fresh process: it loads the mesh and builds its
tree, reads the rays, traces all of them once untimed (Mitsuba compiles its
kernel then), then ``--passes`` timed passes, and reports the median pass.
The tools alternate, the first of each round taking turns, for ``--repeats``
rounds. Printed: the median over the rounds in million rays per second, fgf's
speed relative to Mitsuba's, and each tool's answers (rays hit, mean distance
of the nearest hits), which must agree.

fgf's side is the ``trace_rays`` example (``crates/fgf-render/examples``),
built here with the repository's native flags but without the profile-guided
optimisation of the Python module (``--fgf-bin``: a ``trace_rays`` built
elsewhere, e.g. from another commit, to compare two versions of the walk). This is a component measure inside warm
processes: it leaves out loading, tree building and start-up, and says how
fast each walks a tree, not what a user waits for (that is ``bench_render.py``).
Mitsuba's llvm variant needs Debian's ``libllvm19``. Results: docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
import make_mesh_envmap as mme  # noqa: E402
from bench_render import LLVM19, cpu_description  # noqa: E402

MITSUBA = r"""
import json, sys, time
import numpy as np
import drjit as dr
import mitsuba as mi
ply, rays, query, passes = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
mi.set_variant("llvm_ad_rgb")
dr.set_thread_count(1)
scene = mi.load_dict({"type": "scene", "mesh": {"type": "ply", "filename": ply}})
r = np.fromfile(rays, dtype="<f4").reshape(-1, 6)
ray = mi.Ray3f(mi.Point3f(*(mi.Float(r[:, k]) for k in range(3))),
               mi.Vector3f(*(mi.Float(r[:, k]) for k in range(3, 6))))
def trace():
    out = scene.ray_test(ray) if query == "any" else scene.ray_intersect_preliminary(ray).t
    dr.eval(out)
    dr.sync_thread()
    return out
trace()
seconds = []
for _ in range(passes):
    t0 = time.perf_counter()
    out = trace()
    seconds.append(time.perf_counter() - t0)
out = np.asarray(out)
hit = out if query == "any" else np.isfinite(out)
sum_t = 0.0 if query == "any" else float(out[hit].astype(np.float64).sum())
print(json.dumps({"seconds": seconds, "rays": len(r), "hits": int(hit.sum()), "sum_t": sum_t}))
"""


def make_rays(p: np.ndarray, tris: np.ndarray, n: int, seed: int = 5) -> dict[str, np.ndarray]:
    """The two ray sets (see the module docs), each (n, 6) float32."""
    rng = np.random.default_rng(seed)
    t = tris[rng.integers(0, len(tris), n)]
    a, b, c = (p[t[:, k]].astype(np.float64) for k in range(3))
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    centroid = (a + b + c) / 3
    side = np.where(rng.random((n, 1)) < 0.5, 1.0, -1.0)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d *= np.sign((d * normal).sum(1, keepdims=True)) * side
    sun = mme.sun_direction()
    outward = np.sign((normal * sun).sum(1, keepdims=True))
    outward[outward == 0] = 1.0
    return {
        "bounce": np.hstack([centroid + 1e-3 * side * normal, d]).astype("<f4"),
        "sun": np.hstack([centroid + 1e-3 * outward * normal,
                          np.broadcast_to(sun, (n, 3))]).astype("<f4"),
    }


def run(cmd: list[str], env: dict[str, str]) -> dict[str, Any]:
    out = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if out.returncode != 0:
        sys.exit(f"bench_rays: {' '.join(cmd[:3])} failed:\n{out.stderr.strip()}")
    result: dict[str, Any] = json.loads(out.stdout.strip().splitlines()[-1])
    return result


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rays", type=int, default=1 << 20, help="rays per set (default %(default)s)")
    ap.add_argument("--passes", type=int, default=5, help="timed passes per process (default 5)")
    ap.add_argument("--repeats", type=int, default=3, help="alternated rounds (default 3)")
    ap.add_argument("--quads", type=int, nargs=2, default=None, metavar=("N_U", "N_V"),
                    help="the torus's quads (default: the reference scene's 400 150)")
    ap.add_argument("--fgf-bin", type=Path, default=None,
                    help="a trace_rays executable to use instead of building this checkout's")
    args = ap.parse_args()
    if not 1 <= args.rays <= 1 << 26 or args.passes < 1 or args.repeats < 1:
        ap.error("--rays: 1 to 2^26; --passes, --repeats: at least 1")
    quads = tuple(args.quads) if args.quads else (mme.N_U, mme.N_V)
    if min(quads) < 3 or quads[0] * quads[1] > 10_000_000:
        ap.error("--quads: each at least 3, at most 10,000,000 quads in all")
    if args.fgf_bin is not None:
        if not args.fgf_bin.is_file():
            ap.error(f"--fgf-bin: no file {args.fgf_bin}")
        fgf_bin = str(args.fgf_bin)
    else:
        subprocess.run(["cargo", "build", "-q", "--release", "-p", "fgf-render", "--example",
                        "trace_rays", "--manifest-path", str(ROOT / "Cargo.toml")], check=True)
        target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
        fgf_bin = str(target / "release" / "examples" / "trace_rays")
    env = dict(os.environ, DRJIT_LIBLLVM_PATH=os.environ.get("DRJIT_LIBLLVM_PATH", LLVM19))
    with tempfile.TemporaryDirectory() as tmp:
        p, n, uv, tris = mme.torus(*quads)
        ply = Path(tmp) / "torus.ply"
        mme.write_ply(ply, p, n, uv, tris)
        sets = make_rays(p, tris, args.rays)
        print(f"# cpu: {cpu_description()}")
        print(f"mesh: {len(tris)} triangles; {args.rays} rays per set; one thread; "
              f"{args.passes} passes per process, median; {args.repeats} rounds")
        for name, rays in sets.items():
            path = Path(tmp) / f"{name}.f32"
            rays.tofile(path)
            query = "nearest" if name == "bounce" else "any"
            cmds = {
                "fgf": [fgf_bin, str(ply), str(path), query, str(args.passes)],
                "mitsuba": [sys.executable, "-c", MITSUBA, str(ply), str(path), query,
                            str(args.passes)],
            }
            speed: dict[str, list[float]] = {"fgf": [], "mitsuba": []}
            answers = {}
            for r in range(args.repeats):
                for tool in (["fgf", "mitsuba"] if r % 2 == 0 else ["mitsuba", "fgf"]):
                    res = run(cmds[tool], env)
                    speed[tool].append(res["rays"] / statistics.median(res["seconds"]) / 1e6)
                    answers[tool] = res
            f, m = statistics.median(speed["fgf"]), statistics.median(speed["mitsuba"])
            print(f"{name} ({query}): fgf {f:.2f} Mrays/s (rounds "
                  + " ".join(f"{x:.2f}" for x in speed["fgf"]) + f"), Mitsuba {m:.2f} (rounds "
                  + " ".join(f"{x:.2f}" for x in speed["mitsuba"]) + f"): fgf at {f / m:.2f}x")
            for tool, res in answers.items():
                line = f"    {tool}: {res['hits']} of {res['rays']} rays hit"
                if query == "nearest" and res["hits"]:
                    line += f", mean distance {res['sum_t'] / res['hits']:.6f}"
                print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
