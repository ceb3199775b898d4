"""`fgf truth`: the exact ground truth of a scene with constant-α media (k-fBm, Davis), by quadrature over homogeneous realizations.

    fgf truth scene.xml -o truth.exr [--stderr se.exr] [--nodes N] [--spp S]
              [--seed S] [--threads T] [-D name=value]... [--png truth.png] [--quiet]
              [--cluster local[:N]|tcp://host:port] [--checkpoint FILE]

Each realization of a k-fBm ``fgf`` or ``davis`` medium is homogeneous
along rays, ``sigma = X sigma_m rho`` with ``X ~ Gamma(alpha, mean 1)``
(docs/theory.md §6). The truth is the average of classical renders over
``X`` by generalised Gauss–Laguerre quadrature: ``--spp`` samples per pixel
for each of the nodes (default count: the smallest that reproduces
``(1 + tau/alpha)^-alpha`` to 1e-4 at the scene's largest optical depth).
The scene's ``kernel`` is ignored. Ctrl-C stops and writes nothing (a
partial quadrature sum is no truth); the exit code is then 130. With
``--cluster`` each node is one Dask task (the nodes are summed here in node
order: the same bits); with ``--checkpoint`` finished nodes are saved as
they arrive, so an interrupted truth resumes (docs/cluster.md).
"""

from __future__ import annotations

import argparse
import sys
import time

from ._cluster_args import add_cluster_options, check_cluster_options, client_for
from ._scene_args import add_scene_options, check_scene_options, stage_outputs


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "truth",
        help="exact ground truth for constant-alpha media (k-fBm, Davis): quadrature over homogeneous realizations",
        description=__doc__.split("\n\n")[0],
    )
    p.add_argument("scene", help="Mitsuba 3 XML scene file with k-fBm fgf or davis media")
    p.add_argument("-o", "--output", required=True, help="output EXR (linear float32 RGB)")
    p.add_argument("--stderr", default=None, metavar="SE.EXR", help="also write the per-pixel standard error")
    p.add_argument("--nodes", type=int, default=None, help="quadrature nodes (default: adaptive, see docs/theory.md §6.3)")
    p.add_argument("--spp", type=int, default=None, help="samples per pixel of each node's render (default: the scene's)")
    p.add_argument("--seed", type=int, default=0, help="master seed (default 0)")
    add_scene_options(p)
    add_cluster_options(p, chunks=False)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from .. import ParameterError, _core
    from ..truth import truth, truth_plan

    if args.nodes is not None and not 1 <= args.nodes <= 4096:
        raise ParameterError(f"--nodes {args.nodes}: need 1 <= nodes <= 4096")
    out, png = check_scene_options(args, {"--stderr": args.stderr})
    check_cluster_options(args)
    plan = truth_plan(args.scene, nodes=args.nodes, defines=args.defines)
    spp = plan.spp if args.spp is None else args.spp
    if not args.quiet:
        how = "adaptive rule" if plan.auto_nodes else "--nodes"
        print(
            f"fgf truth: alpha = {plan.alpha:.4g}, {plan.nodes} nodes ({how}; closed form at tau_max = "
            f"{plan.tau_max:.3g} reproduced to {plan.closed_form_error:.1e}), {spp} spp per node",
            file=sys.stderr,
        )
    with stage_outputs([("-o", out), ("--png", png), ("--stderr", args.stderr)]) as staged:
        bar = None if args.quiet else _core.TruthBar(plan.nodes * plan.width * plan.height * spp, "truth")
        t0 = time.perf_counter()
        try:
            with client_for(args) as client:
                img, se = truth(
                    args.scene,
                    spp=args.spp,
                    nodes=plan.nodes,
                    seed=args.seed,
                    defines=args.defines,
                    progress=bar,
                    threads=args.threads,
                    return_stderr=True,
                    client=client,
                    checkpoint=args.checkpoint,
                )
        except KeyboardInterrupt:
            kept = f"; the finished nodes are in {args.checkpoint}" if args.checkpoint else ""
            print(f"fgf truth: interrupted; nothing written (a partial quadrature sum is no truth){kept}", file=sys.stderr)
            return 130
        finally:
            if bar is not None:
                bar.close()
        elapsed = time.perf_counter() - t0
        _core.write_exr(staged["-o"], img)
        _core.write_png(staged["--png"], img, args.exposure)
        if args.stderr is not None:
            _core.write_exr(staged["--stderr"], se)
        staged.commit()
    if not args.quiet:
        written = ", ".join(str(p) for p in [out, png] + ([args.stderr] if args.stderr is not None else []))
        h, w = img.shape[:2]
        print(f"fgf truth: {w}x{h}, {plan.nodes} nodes x {spp} spp in {elapsed:.1f} s; wrote {written}", file=sys.stderr)
    return 0
