"""Why Mitsuba 3.9.1's ``volpath`` renders the corpus scene
``test_homo_emitter_inside_medium_volpath`` (lit by its area emitter only)
about 0.55 % darker than fgf: its light-sampling shadow rays lose light at
thin (``thindielectric``) sheets. See docs/compatibility.md, "The
emitter-in-medium bias".

Mitsuba's ``volpath`` traces a shadow ray through the surfaces it meets one
at a time: it starts with ``spawn_ray_to(target)`` (length
``(1 - ShadowEpsilon) · dist``), and after each crossing it adds the hit
distance ``t`` to the distance walked, re-spawns the ray off the crossed
surface (``spawn_ray``: the origin moves by ``(1 + max|p|) · RayEpsilon``
along the surface's normal) and gives it the length still left by that
count. The re-spawn offset is not counted, so the ray reaches beyond the
point where ``spawn_ray_to`` meant it to stop by up to the offset per
crossing, and it is displaced sideways from the line to the target by as
much. Both eat the shadow epsilon; where the light-sample point is seen at
a grazing angle, the displaced ray then meets the emitter's own surface
(a black ``diffuse``, null transmission 0) before its end, and the sample
counts as blocked although the segment is clear.

This module rebuilds that estimator in Python from the ``mitsuba``
package's own primitives (``sample_emitter_direction``, ``spawn_ray_to``,
``ray_intersect``, ``spawn_ray``, ``eval_null_transmission``,
``target_medium``, ``bsdf.sample``, ``pdf_emitter_direction``): a path
tracer with ``volpath``'s structure (depth counting, ``Null`` crossings,
power-heuristic MIS) on the scene, in RGB, where each light sample's shadow
ray is traced three ways on the same samples:

* ``mitsuba``: ``volpath``'s loop as it is;
* ``fixed_rem``: the same loop, the length left measured from the re-spawned
  origin to the intended end point (the sideways displacement kept);
* ``along_line``: each re-spawn moves along the ray, not along the normal,
  and the length left is measured to the intended end point (no
  displacement: the geometric test fgf's one-ray shadow query makes).

The medium's transmittance is applied in expectation (``exp(-σt·length)``
over the pieces of the segment inside it, the medium tracked with
``target_medium`` as ``volpath`` does), the same for the three loops. The
paired differences of the per-path estimates give the fraction of the image
the loop loses, with its standard error.

Run ``python tests/volpath_shadow_loop.py [paths] [--no-medium] [--shift S]``
(``--shift`` translates the whole scene, camera included, by ``(S, S, S)``:
the image must not change, but Mitsuba's offsets grow with ``max|p|``).
"""

from __future__ import annotations

import argparse
import math
import re
import shutil
from pathlib import Path
from typing import Any, Callable

import numpy as np

CORPUS_MD = Path(__file__).resolve().parent / "corpus" / "mitsuba-data"
PM = "tests/scenes/participating_media"
SCENE = "test_homo_emitter_inside_medium_volpath.xml"
ENVMAP = re.compile(r"<emitter\s+type=[\"']envmap[\"'][^>]*>.*?</emitter>", re.S)
SIGMA_T = 5.0  # the scene's medium: sigma_t 1, scale 5
ALBEDO = np.array([0.99, 0.99, 0.999])
MODES = ("mitsuba", "fixed_rem", "along_line")


def write_scene(root: Path, medium: bool = True, shift: float = 0.0, face_normals: bool = False, drop: tuple[str, ...] = (), grey_floor: float | None = None, copy: bool = True) -> Path:
    """The corpus scene lit by its area emitter only (the envmap removed),
    optionally without its medium, translated by ``(shift,)*3``, with face
    normals on its meshes and without the meshes named in ``drop`` (e.g.
    ``"sphere_base"``), the floor's checkerboard made uniform ``grey_floor``;
    written next to the original in a copy of the corpus under ``root``."""
    md = root / "mitsuba-data"
    if copy and not md.exists():
        shutil.copytree(CORPUS_MD, md)
    d = md / PM
    text, n = ENVMAP.subn("", (d / SCENE).read_text())
    assert n == 1 and '<emitter type="area">' in text
    if not medium:
        text = text.replace('<ref id="medium1" name="interior"/>', "")
    for name in drop:
        text, k = re.subn(rf'<shape type="obj">\s*<string name="filename" value="meshes/{name}.obj"/>.*?</shape>', "", text, flags=re.S)
        assert k == 1, name
    if face_normals:
        text = text.replace('<shape type="obj">', '<shape type="obj"><boolean name="face_normals" value="true"/>')
    tag = f"{'med' if medium else 'nomed'}_{shift:g}_{'f' if face_normals else 's'}_{'_'.join(drop)}_{grey_floor}"
    base = (d / "include" / "test-scene-base.xml").read_text()
    if grey_floor is not None:
        base, k = re.subn(r'(<rgb name="color[01]" value=")[^"]*', rf"\g<1>{grey_floor}", base)
        assert k == 2
    if shift:
        tr = f'<transform name="to_world"><translate value="{shift}, {shift}, {shift}"/></transform>'
        base = base.replace('<shape type="obj">', '<shape type="obj">' + tr)
        base, k = re.subn(r"(<lookat[^>]*/>)", rf'\1<translate value="{shift}, {shift}, {shift}"/>', base)
        assert k == 1
        text = text.replace('<shape type="obj">', '<shape type="obj">' + tr)
    if shift or grey_floor is not None:
        (d / "include" / f"base_{tag}.xml").write_text(base)
        text = text.replace("include/test-scene-base.xml", f"include/base_{tag}.xml")
    out = d / f"emitter_only_{tag}.xml"
    out.write_text(text)
    return out


class Tracer:
    """The Python volpath of the module docstring on one loaded scene."""

    def __init__(self, scene: Any, mi: Any):
        self.scene = scene
        self.mi = mi
        self.ctx = mi.BSDFContext()
        self.sensor = scene.sensors()[0]

    def shadow(self, it: Any, ds: Any, medium: Any, mode: str, on_surface: bool) -> float:
        """Transmittance (grey: the thin sheets' null transmission is grey)
        of the shadow ray from ``it`` to ``ds.p``, traced by ``mode``."""
        mi = self.mi
        ray = it.spawn_ray_to(ds.p)
        max_dist = ray.maxt
        end = ray.o + ray.d * max_dist
        if on_surface and it.is_medium_transition():
            medium = it.target_medium(ray.d)
        walked = 0.0
        tr = 1.0
        while True:
            if mode == "mitsuba":
                left = max_dist - walked
            else:
                left = float(np.dot(np.array(end - ray.o), np.array(ray.d)))
            if not left > 0:
                return tr
            ray.maxt = left
            si = self.scene.ray_intersect(ray)
            if medium is not None:
                tr *= math.exp(-SIGMA_T * (si.t if si.is_valid() else left))
            if not si.is_valid():
                return tr
            walked += si.t
            tr *= float(si.bsdf(ray).eval_null_transmission(si)[0])
            if tr == 0.0:
                return 0.0
            if mode == "along_line":
                mag = (1 + float(np.abs(np.array(si.p)).max())) * mi.math.RayEpsilon
                ray = mi.Ray3f(si.p + ray.d * mag, ray.d)
            else:
                ray = si.spawn_ray(ray.d)
            if si.is_medium_transition():
                medium = si.target_medium(ray.d)

    @staticmethod
    def mis(a: float, b: float) -> float:
        a, b = a * a, b * b
        w = a / (a + b) if a + b > 0 else 0.0
        return w if math.isfinite(w) else 0.0

    def nee(self, it: Any, medium: Any, rng: np.random.Generator, value_pdf: Callable[[Any], tuple[np.ndarray, float]], on_surface: bool) -> np.ndarray | None:
        """One light sample: its contribution (RGB) per shadow loop, rows in
        ``MODES`` order."""
        mi = self.mi
        ds, ev = self.scene.sample_emitter_direction(it, mi.Point2f(*rng.random(2)), False)
        if ds.pdf == 0:
            return None
        f, pdf = value_pdf(ds.d)
        if not f.any():
            return None
        c = f * np.array(ev) * self.mis(ds.pdf, 0.0 if ds.delta else pdf)
        return np.array([c * self.shadow(it, ds, medium, m, on_surface) for m in MODES])

    def path(self, rng: np.random.Generator, max_depth: int = 6) -> np.ndarray:
        """One camera path (uniform over the film); its radiance estimate
        per shadow loop, shape (len(MODES), 3)."""
        mi = self.mi
        ray, _ = self.sensor.sample_ray(0.0, 0.5, mi.Point2f(*rng.random(2)), mi.Point2f(0.5, 0.5))
        ray = mi.Ray3f(ray)
        thr = np.ones(3)
        depth = 0
        medium = None
        total = np.zeros((len(MODES), 3))
        specular = False
        last_it: Any = None
        last_pdf = 1.0
        si = self.scene.ray_intersect(ray)
        while depth < max_depth and thr.any():
            if medium is not None:
                tm = -math.log(1 - rng.random()) / SIGMA_T
                if tm < si.t:  # a real scattering event (no null collisions)
                    p = ray.o + ray.d * tm
                    thr = thr * ALBEDO
                    depth += 1
                    if depth >= max_depth:
                        break
                    it = mi.Interaction3f()
                    it.p, it.n, it.t, it.time = p, mi.Normal3f(0.0), 0.0, 0.0
                    iso = 1 / (4 * math.pi)
                    r = self.nee(it, medium, rng, lambda d: (np.full(3, iso), iso), False)
                    if r is not None:
                        total += thr * r
                    u = rng.random(2)
                    z = 1 - 2 * u[0]
                    s = math.sqrt(max(0.0, 1 - z * z))
                    ray = mi.Ray3f(p, mi.Vector3f(s * math.cos(2 * math.pi * u[1]), s * math.sin(2 * math.pi * u[1]), z))
                    si = self.scene.ray_intersect(ray)
                    specular, last_it, last_pdf = False, it, iso
                    continue
            if not si.is_valid():
                break
            em = si.emitter(self.scene)
            if em is not None:
                le = np.array(em.eval(si))
                if depth == 0 or specular:
                    total += thr * le
                else:
                    ds = mi.DirectionSample3f(self.scene, si, last_it)
                    total += thr * le * self.mis(last_pdf, self.scene.pdf_emitter_direction(last_it, ds))
            bsdf = si.bsdf(ray)
            if mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth) and depth + 1 < max_depth:

                def value_pdf(d: Any, si: Any = si, bsdf: Any = bsdf) -> tuple[np.ndarray, float]:
                    wo = si.to_local(d)
                    return np.array(bsdf.eval(self.ctx, si, wo)), bsdf.pdf(self.ctx, si, wo)

                r = self.nee(si, medium, rng, value_pdf, True)
                if r is not None:
                    total += thr * r
            bs, w = bsdf.sample(self.ctx, si, rng.random(), mi.Point2f(*rng.random(2)))
            thr = thr * np.array(w)
            ray = si.spawn_ray(si.to_world(bs.wo))
            if not mi.has_flag(bs.sampled_type, mi.BSDFFlags.Null):
                depth += 1
                last_it, last_pdf = mi.Interaction3f(si), bs.pdf
                specular = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
            if mi.has_flag(bs.sampled_type, mi.BSDFFlags.Smooth):
                specular = False
            if si.is_medium_transition():
                medium = si.target_medium(ray.d)
            si = self.scene.ray_intersect(ray)
        return total

    def run(self, n: int, seed: int, max_depth: int = 6) -> np.ndarray:
        """``n`` paths: shape (n, len(MODES), 3)."""
        rng = np.random.default_rng(seed)
        return np.array([self.path(rng, max_depth) for _ in range(n)])


def loss(est: np.ndarray, mode: str = "mitsuba", reference: str = "along_line") -> tuple[np.ndarray, np.ndarray]:
    """Relative difference ``mode/reference - 1`` of the image mean (RGB) and
    its standard error (delta method on the paired per-path estimates)."""
    a = est[:, MODES.index(mode)]
    b = est[:, MODES.index(reference)]
    mb = b.mean(0)
    r = a.mean(0) / mb
    resid = (a - r * b) / mb
    return r - 1, resid.std(0, ddof=1) / math.sqrt(len(est))


def main() -> None:
    import tempfile

    import mitsuba as mi

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", type=int, nargs="?", default=100_000)
    ap.add_argument("--no-medium", action="store_true")
    ap.add_argument("--shift", type=float, default=0.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--face-normals", action="store_true")
    ap.add_argument("--drop", action="append", default=[], help="a mesh to remove (sphere_base, sphere_tiny, torus2)")
    ap.add_argument("--max-depth", type=int, default=6)
    ap.add_argument("--grey-floor", type=float, default=None, help="the floor a uniform grey diffuse of this albedo")
    ap.add_argument("--render", type=int, default=0, metavar="K", help="also render Mitsuba volpath, K seeds x 64 spp")
    a = ap.parse_args()
    mi.set_variant("scalar_rgb")
    with tempfile.TemporaryDirectory() as tmp:
        path = write_scene(Path(tmp), medium=not a.no_medium, shift=a.shift, face_normals=a.face_normals, drop=tuple(a.drop), grey_floor=a.grey_floor)
        scene = mi.load_file(str(path))
        est = Tracer(scene, mi).run(a.paths, a.seed, a.max_depth)
        m = est.mean(0)
        print(f"{path.name}: {a.paths} paths; image mean per loop (RGB):")
        for k, mode in enumerate(MODES):
            print(f"  {mode:>10}: {m[k]}")
        for mode, ref in (("mitsuba", "along_line"), ("mitsuba", "fixed_rem"), ("fixed_rem", "along_line")):
            r, se = loss(est, mode, ref)
            print(f"  {mode} / {ref} - 1: {np.round(r * 100, 3)} % +- {np.round(se * 100, 3)}")
        if a.render:
            v = np.array([np.array(mi.render(scene, seed=s, spp=64))[..., :3].mean(axis=(0, 1), dtype=np.float64) for s in range(a.render)])
            print(f"  Mitsuba volpath {a.render} x 64 spp: {v.mean(0)} +- {v.std(0, ddof=1) / math.sqrt(a.render)}")


if __name__ == "__main__":
    main()
