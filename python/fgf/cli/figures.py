"""`fgf figures`: regenerate the paper's figures, a gallery and the numbers.

    fgf figures --out DIR [--quick] [--quiet] [--seed N] [--only GROUP ...] [--scene-dir DIR]

Writes DIR/*.png, DIR/index.html (open it in a browser) and DIR/results.json
(every number plotted). DIR is created if missing; unrelated files in it are
kept. ``--quick`` uses small resolutions and few realizations (a few minutes
on two cores). A progress bar per figure group is shown on stderr when it is
a terminal, unless ``--quiet``.

Exit status: 0 when every figure group was made; 1 when some group could not
run because this build lacks part of the fgf API it needs (each is named on
stderr and in the gallery); 2 on bad arguments or I/O errors.
"""

from __future__ import annotations

import argparse
import sys

SEED_MAX = 2**64 - 1
#: Larger than every offset a figure group adds to the base seed.
SEED_OFFSET_MAX = 1000


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from ..figures import GROUPS

    p = sub.add_parser(
        "figures",
        help="regenerate the paper's figures with a gallery and results.json",
        description="Regenerate the figures of Guo et al. 2019 (docs/theory.md §5): PNGs, an HTML gallery "
        "(DIR/index.html) and every plotted number (DIR/results.json).",
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output directory (created if missing)")
    p.add_argument("--quick", action="store_true", help="small resolutions, few realizations (minutes)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.add_argument("--seed", type=int, default=2019, help="base seed (default 2019)")
    p.add_argument(
        "--only",
        nargs="+",
        choices=list(GROUPS),
        metavar="GROUP",
        help=f"make only these figure groups ({', '.join(GROUPS)})",
    )
    p.add_argument(
        "--scene-dir",
        metavar="DIR",
        help="directory of the figure scenes (default: scenes/figures of the fgf source checkout)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import errno
    import os
    import time

    from .. import ParameterError
    from ..figures import make_figures

    # Every group derives its seeds as --seed + an offset below SEED_OFFSET_MAX;
    # checked here, before the output directory is created.
    if not 0 <= args.seed <= SEED_MAX - SEED_OFFSET_MAX:
        raise ParameterError(
            f"invalid --seed = {args.seed}: must be in [0, {SEED_MAX - SEED_OFFSET_MAX}] "
            f"(the figure groups derive seeds up to --seed + {SEED_OFFSET_MAX})"
        )

    if args.scene_dir is not None and not os.path.isdir(args.scene_dir):
        # Checked before any figure is made: a typo should not cost the
        # minutes of the other groups and then end as a "not made" line.
        absent = not os.path.exists(args.scene_dir)
        err = FileNotFoundError if absent else NotADirectoryError
        what = "no such directory" if absent else "not a directory"
        raise err(errno.ENOENT if absent else errno.ENOTDIR, f"--scene-dir: {what}", args.scene_dir)
    start = time.perf_counter()
    report = make_figures(
        args.out,
        quick=args.quick,
        seed=args.seed,
        groups=args.only,
        progress=not args.quiet,
        scene_dir=args.scene_dir,
    )
    missing = {n: g["reason"] for n, g in report["groups"].items() if g["status"] != "ok"}
    for name, reason in missing.items():
        print(f"fgf figures: group '{name}' not made: {reason}", file=sys.stderr)
    if not args.quiet:
        n_fig = sum(len(g["figures"]) for g in report["groups"].values())
        print(
            f"fgf figures: {n_fig} figures in {time.perf_counter() - start:.0f} s -> {args.out}/index.html",
            file=sys.stderr,
        )
    return 1 if missing else 0
