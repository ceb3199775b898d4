"""`fgf ensemble`: ground truth for an fgf scene from explicit 3D realizations rendered classically.

    fgf ensemble scene.xml --realizations N -o mean.exr [--stderr se.exr]
                 [--resolution R] [--spp S] [--seed S] [--threads T]
                 [-D name=value]... [--png mean.png] [--quiet]

Each ``fgf`` medium is replaced by explicit grids
``sigma_t = max(0, sigma_m rho + sigma_u)`` (``sigma_u`` a fractional Gaussian
field with the model's 1D ray statistics), each realization is rendered with
delta/ratio tracking, and the mean image and its per-pixel standard error
are written. The grid resolution, the fraction of clamped voxels and the
realised against continuum line-average variance are printed. Ctrl-C writes
the average of the realizations finished so far (exit code 130).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from .._atomic import StagedOutputs

from ._scene_args import add_scene_options, check_scene_options, stage_outputs


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "ensemble",
        help="ground truth: average classical renders of explicit realizations of the fgf media",
        description=__doc__.split("\n\n")[0],
    )
    p.add_argument("scene", help="Mitsuba 3 XML scene file with fgf media")
    p.add_argument("--realizations", "-n", type=int, required=True, help="number of realizations (>= 2 for a standard error)")
    p.add_argument("-o", "--output", required=True, help="output EXR of the mean (linear float32 RGB)")
    p.add_argument("--stderr", default=None, metavar="SE.EXR", help="also write the per-pixel standard error of the mean")
    p.add_argument(
        "--resolution", type=int, default=None, help="voxels along the longest side of each medium's box (default 64)"
    )
    p.add_argument("--spp", type=int, default=None, help="samples per pixel per realization (default: the scene's)")
    p.add_argument("--seed", type=int, default=0, help="master seed (default 0)")
    add_scene_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from .. import ParameterError, _core
    from ..render import _defines_list

    if args.realizations < 1:
        raise ParameterError(f"--realizations {args.realizations}: need at least 1 (2 for a standard error)")
    if args.resolution is not None and args.resolution < 2:
        raise ParameterError(f"--resolution {args.resolution}: need at least 2 voxels along the longest side")
    out, png = check_scene_options(args, {"--stderr": args.stderr})
    with stage_outputs([("-o", out), ("--png", png), ("--stderr", args.stderr)]) as staged:
        return _ensemble(args, out, png, staged)


def _ensemble(args: argparse.Namespace, out: Path, png: Path, staged: StagedOutputs) -> int:
    from .. import _core
    from ..render import _defines_list

    t0 = time.perf_counter()
    mean, se, info, interrupted = _core.ensemble_scene(
        args.scene,
        args.realizations,
        resolution=args.resolution,
        spp=args.spp,
        seed=args.seed,
        threads=args.threads,
        defines=_defines_list(args.defines),
        progress=None if args.quiet else "bar",
    )
    elapsed = time.perf_counter() - t0
    done = info["realizations_done"]
    if done == 0:
        print("fgf ensemble: interrupted before the first realization finished; nothing written", file=sys.stderr)
        return 130
    _core.write_exr(staged["-o"], mean)
    _core.write_png(staged["--png"], mean, args.exposure)
    if args.stderr is not None:
        _core.write_exr(staged["--stderr"], se)
    staged.commit()
    written = ", ".join(str(p) for p in [out, png] + ([args.stderr] if args.stderr is not None else []))
    if not args.quiet or interrupted:
        for m in info["media"]:
            nx, ny, nz = m["shape"]
            ratio = m["realized_variance"] / m["continuum_variance"]
            print(
                f"fgf ensemble: medium {m['medium']}: grid {nx}x{ny}x{nz}, voxel {m['spacing']:.4g}, "
                f"S_w3 = {m['sw_3d']:.4g}; clamped voxels {100 * m['clamped_fraction']:.3f}%; "
                f"line-average variance over {m['variance_length']:.4g}: realised {m['realized_variance']:.4g} "
                f"vs continuum {m['continuum_variance']:.4g} ({100 * ratio:.1f}%)",
                file=sys.stderr,
            )
    if interrupted:
        print(
            f"fgf ensemble: interrupted; wrote the average of {done} of {args.realizations} realizations to {written}",
            file=sys.stderr,
        )
        return 130
    if not args.quiet:
        h, w = mean.shape[:2]
        print(
            f"fgf ensemble: {done} realizations of {w}x{h} at {info['spp']} spp in {elapsed:.1f} s; wrote {written}",
            file=sys.stderr,
        )
    return 0
