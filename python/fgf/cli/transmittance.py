"""``fgf transmittance``: tabulate and plot an FGF transmittance against the
exponential of the same mean extinction.

Usage::

    fgf transmittance --sigma-t 4 --hurst -0.1 --sw 4              # table on stdout
    fgf transmittance --sigma-t 4 --hurst -0.1 --sw 4 -o tr.png    # + plot (.png/.pdf/.svg)
    fgf transmittance --sigma-t 4 --hurst 1.2 --sw 34 --length 1 -o tr.csv   # full table

Parameters follow :class:`fgf.Fgf` (``hurst = -0.5`` white, ``(-0.5, 0)`` pink,
``(k-1, k)`` k-fBm with ``--length``). Invalid values exit with code 2 and a
one-line message naming the parameter and its valid range. Output files are
written atomically (a temporary file in the same folder, then renamed).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from typing import IO, TYPE_CHECKING

from .._atomic import write_atomic

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt

    from ..transmittance import Exponential, Fgf

PLOT_EXTS = (".png", ".pdf", ".svg")
TABLE_EXTS = (".csv",)


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "transmittance",
        help="tabulate/plot the FGF transmittance Tr(t) against the exponential",
        description=(
            "Tabulate the gamma-closure transmittance of a fractional Gaussian field "
            "medium and compare it with the exponential of the same mean extinction. "
            "Prints a table; with -o writes a plot (.png, .pdf, .svg) or a full table (.csv)."
        ),
    )
    p.add_argument("--sigma-t", type=float, required=True, metavar="S",
                   help="mean extinction sigma_t (1/length), > 0")
    p.add_argument("--hurst", type=float, required=True, metavar="H",
                   help="Hurst parameter: -0.5 white, (-0.5, 0) pink, (k-1, k) k-fBm; not 0 or an integer")
    p.add_argument("--sw", type=float, required=True, metavar="SW",
                   help="white-noise strength S_w, > 0")
    p.add_argument("--length", type=float, default=None, metavar="L",
                   help="k-fBm characteristic length L > 0 (required for hurst > 0, refused otherwise)")
    p.add_argument("--t-max", type=float, default=3.0, metavar="T",
                   help="largest distance (default: 3)")
    p.add_argument("--rows", type=int, default=11, metavar="N",
                   help="rows of the printed table (default: 11)")
    p.add_argument("--points", type=int, default=200, metavar="N",
                   help="samples of the plot / CSV table (default: 200)")
    p.add_argument("-o", "--output", default=None, metavar="FILE",
                   help="write a plot (.png, .pdf, .svg) or a table (.csv)")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    p.set_defaults(func=run)


def _check(args: argparse.Namespace) -> None:
    from .. import ParameterError

    if not (math.isfinite(args.t_max) and args.t_max > 0):
        raise ParameterError(f"invalid --t-max = {args.t_max}: must be finite and > 0 (valid: 0 < t_max < inf)")
    if args.rows < 2:
        raise ParameterError(f"invalid --rows = {args.rows}: need at least 2 (valid: rows >= 2)")
    if args.points < 2:
        raise ParameterError(f"invalid --points = {args.points}: need at least 2 (valid: points >= 2)")


def _describe(m: Fgf) -> str:
    p = m.params
    extra = f", length={p['length']:g}" if p["length"] is not None else ""
    name = {"white": "white noise", "pink": "pink noise", "k-fbm": f"{p['k']}-fBm"}[p["regime"]]
    return f"Fgf {name}: sigma_t={p['sigma_t']:g}, hurst={p['hurst']:g}, sw={p['sw']:g}{extra}"


def _columns(m: Fgf, e: Exponential, t: npt.NDArray[np.float64]) -> dict[str, npt.NDArray[np.float64]]:
    return {
        "t": t,
        "tr": m.tr(t),
        "tr_exponential": e.tr(t),
        "pdf": m.pdf(t),
        "medium_surface": m.medium_surface(t),
        "medium_medium": m.medium_medium(t),
        "alpha": m.alpha(t),
        "variance": m.variance(t),
    }


def _write_csv(path: str, cols: dict[str, npt.NDArray[np.float64]]) -> None:
    import numpy as np

    names = list(cols)
    data = np.column_stack([cols[n] for n in names])

    def write(fh: IO[bytes]) -> None:
        np.savetxt(fh, data, delimiter=",", header=",".join(names), comments="", fmt="%.17g")

    write_atomic(path, write)


def _write_plot(path: str, m: Fgf, e: Exponential, t: npt.NDArray[np.float64], title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    tr, tr_e = m.tr(t), e.tr(t)
    for ax, log in ((ax0, False), (ax1, True)):
        ax.plot(t, tr, label="FGF (gamma closure)", color="C0")
        ax.plot(t, tr_e, label="exponential, same mean", color="C1", linestyle="--")
        ax.set_xlabel("distance t")
        ax.set_ylabel("Tr(t)")
        if log:
            ax.set_yscale("log")
            ax.set_title("log scale")
        else:
            ax.set_ylim(0, 1.02)
            ax.set_title("linear scale")
        ax.grid(True, alpha=0.3)
        ax.legend()
    fig.suptitle(title)

    fmt = os.path.splitext(path)[1].lstrip(".").lower()

    def write(fh: IO[bytes]) -> None:
        fig.savefig(fh, format=fmt)

    try:
        write_atomic(path, write)
    finally:
        plt.close(fig)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from .. import Exponential, Fgf, FgfError

    _check(args)
    ext = os.path.splitext(args.output)[1].lower() if args.output else None
    if args.output is not None and ext not in PLOT_EXTS + TABLE_EXTS:
        raise FgfError(
            f"unsupported output extension {ext or '(none)'!r} for {args.output}: "
            f"use {', '.join(PLOT_EXTS + TABLE_EXTS)}"
        )
    if args.output is not None:
        folder = os.path.dirname(os.path.abspath(args.output))
        if not os.path.isdir(folder):
            raise FileNotFoundError(f"output folder does not exist: {folder}")
    m = Fgf(args.sigma_t, hurst=args.hurst, sw=args.sw, length=args.length)
    e = Exponential(args.sigma_t)
    title = _describe(m)

    if not args.quiet:
        t = np.linspace(0.0, args.t_max, args.rows)
        cols = _columns(m, e, t)
        print(f"# {title}; sigma_bar={m.sigma_bar:g}")
        header = ("t", "Tr", "Tr_exp", "pdf", "alpha")
        print("".join(f"{h:>14}" for h in header))
        for i in range(len(t)):
            row = (cols["t"][i], cols["tr"][i], cols["tr_exponential"][i], cols["pdf"][i], cols["alpha"][i])
            print("".join(f"{v:>14.6g}" for v in row))

    if args.output is not None:
        t = np.linspace(0.0, args.t_max, args.points)
        if ext in TABLE_EXTS:
            _write_csv(args.output, _columns(m, e, t))
        else:
            _write_plot(args.output, m, e, t, title)
        if not args.quiet:
            print(f"fgf transmittance: wrote {args.output}", file=sys.stderr)
    return 0
