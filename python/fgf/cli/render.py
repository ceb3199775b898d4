"""`fgf render`: render a Mitsuba 3 XML scene to a linear float32 EXR and an sRGB PNG preview.

    fgf render scene.xml -o out.exr [--spp N] [--seed S] [--threads T]
               [-D name=value]... [--variance var.exr] [--png out.png] [--quiet]
               [--cluster local[:N]|tcp://host:port] [--chunk-spp K] [--checkpoint FILE]

Ctrl-C stops after the units of work in flight (a long pass cut short is
dropped; on a cluster: cancels the chunks not finished) and writes the image
of the passes finished so far (every pixel has the same count), saying how
many; the exit code is then
130. With ``--cluster`` the samples are split into chunks of ``--chunk-spp``
rendered by Dask workers; with ``--checkpoint`` finished chunks are saved as
they arrive and a rerun resumes. The image has the same bits either way
(docs/cluster.md).
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
        "render",
        help="render a Mitsuba 3 XML scene (volumetric path tracing)",
        description=__doc__.split("\n\n")[0],
    )
    p.add_argument("scene", help="Mitsuba 3 XML scene file")
    p.add_argument("-o", "--output", required=True, help="output EXR (linear float32 RGB)")
    p.add_argument("--spp", type=int, default=None, help="samples per pixel (default: the scene's sample_count)")
    p.add_argument("--seed", type=int, default=None, help="sampler seed (default: the scene's, else 0)")
    p.add_argument("--variance", default=None, metavar="VAR.EXR", help="also write the per-pixel variance of the mean")
    add_scene_options(p)
    add_cluster_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from .. import _core
    from ..render import _defines_list

    out, png = check_scene_options(args, {"--variance": args.variance})
    check_cluster_options(args)
    if args.variance is not None and args.spp is not None and args.spp < 2:
        from .. import ParameterError

        raise ParameterError(f"--spp {args.spp} with --variance: the per-pixel variance needs at least 2 samples per pixel")
    defines = _defines_list(args.defines)
    with stage_outputs([("-o", out), ("--png", png), ("--variance", args.variance)]) as staged:
        return _render(args, out, png, defines, staged)


def _render(args: argparse.Namespace, out: Path, png: Path, defines: list[tuple[str, str]], staged: StagedOutputs) -> int:
    from .. import _core

    t0 = time.perf_counter()
    lost = None
    resumed = 0
    if wants_chunks(args):
        from .. import cluster

        with client_for(args) as client:
            run_ = cluster.render(
                args.scene,
                spp=args.spp,
                seed=args.seed,
                threads=args.threads,
                defines=defines,
                progress=False if args.quiet else "bar",
                return_variance=args.variance is not None,
                client=client,
                chunk_spp=args.chunk_spp,
                checkpoint=args.checkpoint,
            )
        img, var, done, interrupted, lost = run_.image, run_.variance, run_.spp_done, run_.interrupted, run_.lost
        resumed = run_.resumed_spp
    else:
        img, var, done, interrupted = _core.render_scene(
            args.scene,
            spp=args.spp,
            seed=args.seed,
            threads=args.threads,
            defines=defines,
            progress=None if args.quiet else "bar",
            return_variance=args.variance is not None,
        )
    elapsed = time.perf_counter() - t0
    if done == 0 and lost is not None:
        print(f"fgf render: error: {lost}; no chunk had finished, nothing written", file=sys.stderr)
        return 2
    if var is not None and done < 2:
        # The variance of a 1-sample mean is undefined (NaN): write nothing.
        print(
            f"fgf render: error: --variance needs at least 2 samples per pixel; {done} "
            f"{'were done before the interrupt' if interrupted else 'were rendered'}; nothing written",
            file=sys.stderr,
        )
        return 130 if interrupted else 2
    if done == 0:
        print("fgf render: interrupted before the first pass finished; nothing written", file=sys.stderr)
        return 130
    _core.write_exr(staged["-o"], img)
    _core.write_png(staged["--png"], img, args.exposure)
    if var is not None:
        _core.write_exr(staged["--variance"], var)
    staged.commit()
    written = ", ".join(str(p) for p in [out, png] + ([args.variance] if var is not None else []))
    h, w = img.shape[:2]
    code = summary_lost("render", lost, written, f"the image of the {done} samples per pixel", args.checkpoint)
    if code is not None:
        return int(code)
    if interrupted:
        print(
            f"fgf render: interrupted; wrote the image of {done} samples per pixel to {written}",
            file=sys.stderr,
        )
        return 130
    if not args.quiet:
        rate = w * h * (done - resumed) / max(elapsed, 1e-9)
        print(
            f"fgf render: {w}x{h}, {done} spp in {elapsed:.1f} s ({rate / 1e6:.2f} M samples/s); wrote {written}",
            file=sys.stderr,
        )
    return 0
