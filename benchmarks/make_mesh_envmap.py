"""Assets of ``scenes/reference/mesh-envmap.xml``, generated instead of committed.

    python benchmarks/make_mesh_envmap.py [--out scenes/reference/generated] [--force]
                                          [--quads N_U N_V] [--obj]

Writes into ``--out`` (default ``scenes/reference/generated/``, ignored by git):

* ``torus.ply``: a bumpy torus, binary little-endian PLY with positions,
  unit normals and texture coordinates per vertex: ``N_U × N_V`` quads
  (``2 · 400 · 150 = 120,000`` triangles by default; ``--quads 40 15`` makes
  the same shape of 1,200, whose data fit in the caches, for telling memory
  stalls from computation), radii 1 and 0.35, the tube radius
  modulated by ``0.04 sin(12·2πu) sin(6·2πv)``. The normals are those of the
  parametric surface (cross product of its two partial derivatives, computed
  analytically), so neither renderer's normal smoothing is involved. The seam
  vertices are duplicated so that ``(u, v)`` runs over ``[0, 1]`` without a
  wrap.
* ``torus.obj`` (with ``--obj``): the same mesh as an OBJ file, ``v``, ``vt``
  and ``vn`` lines (nine significant digits, which give the float32 values back) and ``f a/a/a b/b/b c/c/c``
  faces, for timing the OBJ reader (``docs/benchmarks.md``, "Our own OBJ
  reader"); the scene reads it with ``type="obj"`` and ``generated/torus.obj``.
* ``sky.exr``: a 256 × 128 latitude–longitude environment (linear RGB): a
  blue-to-white sky gradient above the horizon, a dim ground below, and a
  small bright sun, so that the luminance-sampled envmap matters.

Both are deterministic (no random numbers), so every run writes the same
bytes. ``bench_render.py`` and the tests call :func:`ensure` before using
the scene; it writes the files only when they are missing (or ``force``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "scenes" / "reference" / "generated"
N_U, N_V = 400, 150  # quads around the ring and around the tube
R_RING, R_TUBE, BUMP = 1.0, 0.35, 0.04
ENV_W, ENV_H = 256, 128


def torus(n_u: int = N_U, n_v: int = N_V) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Positions, unit normals, uvs (float32) and triangles (int32) of the bumpy torus
    of ``n_u × n_v`` quads."""
    u = np.linspace(0.0, 1.0, n_u + 1)
    v = np.linspace(0.0, 1.0, n_v + 1)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    a, b = 2 * np.pi * uu, 2 * np.pi * vv
    r = R_TUBE + BUMP * np.sin(12 * a) * np.sin(6 * b)
    dr_da = BUMP * 12 * np.cos(12 * a) * np.sin(6 * b)
    dr_db = BUMP * 6 * np.sin(12 * a) * np.cos(6 * b)
    ring = R_RING + r * np.cos(b)
    # The torus lies in the xz plane (y up): p = (ring cos a, r sin b, ring sin a).
    p = np.stack([ring * np.cos(a), r * np.sin(b), ring * np.sin(a)], axis=-1)
    dring_da = dr_da * np.cos(b)
    dring_db = dr_db * np.cos(b) - r * np.sin(b)
    dp_da = np.stack([dring_da * np.cos(a) - ring * np.sin(a), dr_da * np.sin(b),
                      dring_da * np.sin(a) + ring * np.cos(a)], axis=-1)
    dp_db = np.stack([dring_db * np.cos(a), dr_db * np.sin(b) + r * np.cos(b),
                      dring_db * np.sin(a)], axis=-1)
    n = np.cross(dp_db, dp_da)  # outward
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    uv = np.stack([uu, vv], axis=-1)
    idx = np.arange((n_u + 1) * (n_v + 1)).reshape(n_u + 1, n_v + 1)
    q00, q10 = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    q01, q11 = idx[:-1, 1:].ravel(), idx[1:, 1:].ravel()
    # Counter-clockwise seen from outside (so the geometric normal agrees with n).
    tris = np.concatenate([np.stack([q00, q01, q11], -1), np.stack([q00, q11, q10], -1)])
    def flat(x: np.ndarray) -> np.ndarray:
        return np.asarray(x.reshape(-1, x.shape[-1]), dtype=np.float32)

    return flat(p), flat(n), flat(uv), np.asarray(tris, dtype=np.int32)


def write_ply(path: Path, p: np.ndarray, n: np.ndarray, uv: np.ndarray, tris: np.ndarray) -> None:
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(p)}\n"
        + "".join(f"property float {c}\n" for c in ("x", "y", "z", "nx", "ny", "nz", "u", "v"))
        + f"element face {len(tris)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    verts = np.concatenate([p, n, uv], axis=1).astype("<f4")
    faces = np.zeros(len(tris), dtype=[("k", "u1"), ("i", "<i4", (3,))])
    faces["k"] = 3
    faces["i"] = tris
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(verts.tobytes())
        f.write(faces.tobytes())


def write_obj(path: Path, p: np.ndarray, n: np.ndarray, uv: np.ndarray, tris: np.ndarray) -> None:
    with open(path, "w") as f:
        for key, rows in (("v", p), ("vt", uv), ("vn", n)):
            f.writelines(f"{key} {' '.join(f'{x:.9g}' for x in row)}\n" for row in rows.tolist())
        f.writelines(f"f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}\n" for a, b, c in (tris + 1).tolist())


SUN_THETA, SUN_PHI = np.radians(50.0), np.radians(120.0)  # from +y; azimuth from +x toward +z


def sun_direction() -> np.ndarray:
    """Unit direction toward the centre of the sky's sun (40° above the horizon)."""
    return np.array([np.sin(SUN_THETA) * np.cos(SUN_PHI), np.cos(SUN_THETA),
                     np.sin(SUN_THETA) * np.sin(SUN_PHI)])


def sky() -> np.ndarray:
    """The environment image, (ENV_H, ENV_W, 3) float32; row 0 is straight up."""
    theta = (np.arange(ENV_H) + 0.5) / ENV_H * np.pi  # from +y
    phi = (np.arange(ENV_W) + 0.5) / ENV_W * 2 * np.pi
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    up = np.cos(th)
    t = np.clip(up, 0.0, 1.0)[..., None]
    zenith, horizon = np.array([0.25, 0.45, 1.0]), np.array([1.0, 1.0, 1.0])
    img = np.where(up[..., None] > 0, (1 - t) * horizon + t * zenith, np.array([0.3, 0.25, 0.2]))
    # Sun: a Gaussian spot of ~3° radius.
    d = np.stack([np.sin(th) * np.cos(ph), np.cos(th), np.sin(th) * np.sin(ph)], -1)
    ang = np.arccos(np.clip(d @ sun_direction(), -1.0, 1.0))
    img = img + (200.0 * np.exp(-((ang / np.radians(3.0)) ** 2)))[..., None] * np.array([1.0, 0.9, 0.7])
    return np.asarray(img, dtype=np.float32)


def ensure(out: Path = OUT, force: bool = False, quads: tuple[int, int] = (N_U, N_V),
           obj: bool = False) -> Path:
    """Write the assets into `out` if missing (or `force`); returns `out`."""
    out.mkdir(parents=True, exist_ok=True)
    ply, exr = out / "torus.ply", out / "sky.exr"
    if force or not ply.exists():
        write_ply(ply, *torus(*quads))
    if obj and (force or not (out / "torus.obj").exists()):
        write_obj(out / "torus.obj", *torus(*quads))
    if force or not exr.exists():
        import fgf

        fgf.write_exr(exr, sky())
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--force", action="store_true", help="rewrite existing files")
    ap.add_argument("--quads", type=int, nargs=2, default=(N_U, N_V), metavar=("N_U", "N_V"),
                    help="quads around the ring and the tube (a smaller mesh for the "
                    "experiment in docs/benchmarks.md; default %(default)s)")
    ap.add_argument("--obj", action="store_true", help="also write torus.obj")
    args = ap.parse_args()
    if min(args.quads) < 3 or args.quads[0] * args.quads[1] > 10_000_000:
        ap.error("--quads: each at least 3, at most 10,000,000 quads in all")
    out = ensure(args.out, args.force, tuple(args.quads), args.obj)
    n_u, n_v = args.quads
    print(f"wrote {out}/torus.ply ({2 * n_u * n_v} triangles) and {out}/sky.exr ({ENV_W}x{ENV_H})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
