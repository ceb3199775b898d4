"""`fgf ensemble`: ground truth for an fgf scene from explicit 3D realizations rendered classically.

    fgf ensemble scene.xml --realizations N -o mean.exr [--stderr se.exr]
                 [--resolution R] [--padding P] [--marginal auto|gamma|gaussian]
                 [--spp S] [--seed S] [--threads T]
                 [-D name=value]... [--png mean.png] [--quiet]

Each ``fgf`` medium is replaced by explicit grids ``sigma_t = rho * field``:
for pink noise (``--marginal gamma``, the default there) a Gaussian copula
with gamma marginals calibrated so that the grid's line-average variance
follows the model's; for k-fBm (``gaussian``) ``max(0, sigma_m + sigma_u)``
with ``sigma_u`` a fractional Gaussian field with the model's 1D ray
statistics. Fields are synthesised on a periodic domain ``--padding`` times
the grid (default 4). Each realization is rendered with delta/ratio
tracking, and the mean image and its per-pixel standard error are written.
The grid, the calibration, the fraction of clamped voxels and the grid's
exact line-average variance against the model's (worst ratio over the
rendered lengths) are printed. Ctrl-C writes the average of the
realizations finished so far (exit code 130).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from .._atomic import StagedOutputs

from ._cluster_args import add_cluster_options, check_cluster_options, client_for, summary_lost, wants_chunks
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
    p.add_argument(
        "--padding", type=float, default=None,
        help="periodic synthesis domain per axis, in grid sides, 1 to 16 (default 4)",
    )
    p.add_argument(
        "--marginal", choices=("auto", "gamma", "gaussian"), default="auto",
        help="one-point law of the extinction: calibrated gamma copula or clamped Gaussian (default: gamma for pink noise, gaussian for k-fBm)",
    )
    p.add_argument("--spp", type=int, default=None, help="samples per pixel per realization (default: the scene's)")
    p.add_argument("--seed", type=int, default=0, help="master seed (default 0)")
    add_scene_options(p)
    add_cluster_options(p, chunks=False)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from .. import ParameterError

    if args.realizations < 1:
        raise ParameterError(f"--realizations {args.realizations}: need at least 1 (2 for a standard error)")
    if args.resolution is not None and args.resolution < 2:
        raise ParameterError(f"--resolution {args.resolution}: need at least 2 voxels along the longest side")
    if args.padding is not None and not 1.0 <= args.padding <= 16.0:
        raise ParameterError(f"--padding {args.padding}: the periodic synthesis domain must be 1 to 16 grid sides per axis")
    out, png = check_scene_options(args, {"--stderr": args.stderr})
    check_cluster_options(args)
    with stage_outputs([("-o", out), ("--png", png), ("--stderr", args.stderr)]) as staged:
        return _ensemble(args, out, png, staged)


def _ensemble(args: argparse.Namespace, out: Path, png: Path, staged: StagedOutputs) -> int:
    from .. import _core
    from ..render import _defines_list

    t0 = time.perf_counter()
    lost = None
    if wants_chunks(args):
        from .. import cluster

        with client_for(args) as client:
            run_ = cluster.ensemble(
                args.scene,
                args.realizations,
                resolution=args.resolution,
                spp=args.spp,
                seed=args.seed,
                threads=args.threads,
                defines=_defines_list(args.defines),
                progress=False if args.quiet else "bar",
                client=client,
                checkpoint=args.checkpoint,
                padding=args.padding,
                marginal=args.marginal,
            )
        mean, se, info, interrupted, lost = run_.mean, run_.stderr, run_.info, run_.interrupted, run_.lost
    else:
        mean, se, info, interrupted = _core.ensemble_scene(
            args.scene,
            args.realizations,
            resolution=args.resolution,
            spp=args.spp,
            seed=args.seed,
            threads=args.threads,
            defines=_defines_list(args.defines),
            progress=None if args.quiet else "bar",
            padding=args.padding,
            marginal=args.marginal,
        )
    elapsed = time.perf_counter() - t0
    done = info["realizations_done"]
    if done == 0 and lost is not None:
        print(f"fgf ensemble: error: {lost}; no realization had finished, nothing written", file=sys.stderr)
        return 2
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
            exact = [g / t for g, t in zip(m["grid_variances"], m["model_variances"])]
            law = (
                f"gamma copula (H_field = {m['hurst_field']:.3f}, voxel alpha = {m['alpha_voxel']:.4g})"
                if m["marginal"] == "gamma"
                else f"gaussian, S_w3 = {m['sw_3d']:.4g}"
            )
            print(
                f"fgf ensemble: medium {m['medium']}: grid {nx}x{ny}x{nz} (synthesis domain "
                f"{'x'.join(str(v) for v in m['padded_shape'][::-1])}), voxel {m['spacing']:.4g}, {law}; "
                f"clamped voxels {100 * m['clamped_fraction']:.3f}%; mean sigma_t {m['mean_sigma_t']:.4g} "
                f"(model {m['model_mean_sigma_t']:.4g}); exact grid/model line-average variance "
                f"{min(exact):.3f} to {max(exact):.3f} over lengths {m['lengths'][0]:.3g} to {m['lengths'][-1]:.3g}; "
                f"over {m['variance_length']:.4g}: realised {m['realized_variance']:.4g} "
                f"vs continuum {m['continuum_variance']:.4g} ({100 * ratio:.1f}%)",
                file=sys.stderr,
            )
    code = summary_lost("ensemble", lost, written, f"the average of the {done} realizations", args.checkpoint)
    if code is not None:
        return int(code)
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
