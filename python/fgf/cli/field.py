"""``fgf field``: synthesize one fractional Gaussian field and write it.

The output format follows the extension of ``-o``: ``.npy`` (numpy, any
dims), ``.vol`` (Mitsuba 3 ``gridvolume``, float32), ``.vdb`` (OpenVDB
FloatGrid ``density``, for Houdini and Blender), ``.pbrt`` (pbrt-v4
``uniformgrid`` medium), ``.exr`` (2D, float32) or ``.png`` (2D greyscale;
the 0.5 and 99.5 percentiles map to black and white). Grids fill the box
``[0, n * spacing]`` on each axis in every 3D format (``docs/vdb.md``).
``--mean/--scale/--clamp-min`` map the zero-mean field ``f`` to a density
``max(clamp_min, mean + scale * f)`` before writing, e.g. for a renderer's
``sigma_t``.

Examples::

    fgf field --shape 512 512 --hurst 0.85 --seed 1 -o field.png
    fgf field --shape 128 128 128 --hurst -0.1 --spacing 0.0078125 \\
        --mean 4 --scale 1 --clamp-min 0 -o density.vol
    fgf field --shape 64 64 64 --hurst -0.2 --spacing 0.015625 \\
        --mean 4 --clamp-min 0 -o density.vdb
"""

from __future__ import annotations

from .._progress import check_int, check_seed
from ._args import echo

import argparse
import sys
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "field",
        help="synthesize a fractional Gaussian field (.npy/.vol/.vdb/.pbrt/.exr/.png)",
        description="Synthesize one fractional Gaussian field (docs/theory.md §1) and write it; see fgf.synthesize for the model.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="\n\n".join(__doc__.split("\n\n")[1:]),
    )
    p.add_argument("--shape", type=int, nargs="+", required=True, metavar="N", help="grid shape, C order: nx | ny nx | nz ny nx")
    p.add_argument("--hurst", type=float, required=True, help="Hurst parameter H: -d/2 white, (-d/2, 0) pink, (k-1, k) k-fBm, k <= 3")
    p.add_argument("--sw", type=float, default=None, help="white-noise strength S_w > 0 (default 1)")
    p.add_argument(
        "--sw-ray",
        type=float,
        default=None,
        metavar="SW_1D",
        help="3D only, instead of --sw: give the 1D ray model's S_w; uses S_w3 = S_w 2 pi (2H+1)",
    )
    p.add_argument("--spacing", type=float, default=1.0, help="grid spacing in scene units (default 1)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument(
        "--anchor",
        default="corner",
        help="k-fBm anchor: corner (default), center, none, or comma-separated sample indices (e.g. 0,10,10)",
    )
    p.add_argument("--padding", type=float, default=None, help="periodic domain size / grid size, >= 1 (default 1 pink, 2 k-fBm)")
    p.add_argument("--float64", action="store_true", help="synthesize in float64 (.npy keeps it; other formats store float32)")
    p.add_argument("--mean", type=float, default=0.0, help="density mapping: added mean (default 0)")
    p.add_argument("--scale", type=float, default=1.0, help="density mapping: factor on the field (default 1)")
    p.add_argument("--clamp-min", type=float, default=None, help="density mapping: lower clamp (default none)")
    p.add_argument("-o", "--output", required=True, help="output file: .npy, .vol, .vdb, .pbrt, .exr (2D) or .png (2D)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary")
    p.set_defaults(func=run)


def _anchor(text: str) -> str | list[int]:
    from .. import ParameterError

    t = text.strip().lower()
    if t in ("corner", "center", "centre", "none"):
        return t
    try:
        idx = [int(v) for v in t.split(",")]
        if any(not 0 <= v < 2**62 for v in idx):
            raise ValueError
        return idx
    except ValueError:
        raise ParameterError(
            f"invalid --anchor = {echo(text)}: not a keyword or a list of sample indices >= 0 (valid: corner, center, none, or e.g. 0,10,10)"
        ) from None


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from .. import FgfError, field

    from .._core import synthesize, write_field

    # Check the extension before spending time on the synthesis.
    out = args.output
    ext = out.rsplit(".", 1)[-1].lower() if "." in out else ""
    if ext not in ("npy", "vol", "vdb", "pbrt", "exr", "png"):
        raise FgfError(
            f"{out}: unknown output extension {'.' + ext if ext else '(none)'}; use .npy, .vol, .vdb, .pbrt, .exr or .png"
        )
    if ext in ("png", "exr") and len(args.shape) != 2:
        raise FgfError(f"{out}: {ext.upper()} output needs a 2D field, --shape has {len(args.shape)} axes; use .npy or .vol")
    sw = 1.0 if args.sw is None else args.sw
    if args.sw_ray is not None:
        if args.sw is not None:
            raise FgfError("--sw and --sw-ray are alternatives; give one of them")
        if len(args.shape) != 3:
            raise FgfError("--sw-ray applies to 3D fields only")
        sw = field.sw_3d_for_ray_statistics(args.hurst, args.sw_ray)
    shape = [check_int("--shape", n, 1, 2**62) for n in args.shape]
    f = synthesize(
        shape,
        args.hurst,
        sw,
        args.spacing,
        check_seed(args.seed),
        _anchor(args.anchor),
        args.padding,
        "float64" if args.float64 else "float32",
        None if args.quiet else "bar",
    )
    if ext in ("vdb", "pbrt"):
        s = _write_volume(out, ext, f, args)
    else:
        s = write_field(out, np.ascontiguousarray(f), args.spacing, args.mean, args.scale, args.clamp_min, (0.5, 99.5))
    if not args.quiet:
        print(
            f"wrote {out}: shape {tuple(f.shape)}, H = {args.hurst}, S_w = {sw:g}, values in [{s['min']:.4g}, {s['max']:.4g}]",
            file=sys.stderr,
        )
    if ext in ("vol", "vdb", "pbrt") and s["n_negative"] > 0:
        print(
            f"fgf field: warning: {s['n_negative']} voxels are negative; a density needs --mean/--scale/--clamp-min",
            file=sys.stderr,
        )
    return 0


def _write_volume(out: str, ext: str, f: npt.NDArray[np.floating[Any]], args: argparse.Namespace) -> dict[str, Any]:
    """Map the field to a density and write ``.vdb`` or ``.pbrt`` (float32)."""
    import numpy as np

    from .. import ParameterError, vdb

    for name, v in (("--mean", args.mean), ("--scale", args.scale), ("--clamp-min", args.clamp_min)):
        if v is not None and not np.isfinite(v):
            raise ParameterError(f"invalid {name} = {v}: must be finite")
    d = args.mean + args.scale * np.asarray(f, dtype=np.float64)
    if args.clamp_min is not None:
        d = np.maximum(d, args.clamp_min)
    d = d.astype(np.float32)
    if ext == "vdb":
        vdb.write_vdb(out, d, spacing=args.spacing)
    else:
        vdb.pbrt_uniformgrid(out, d, spacing=args.spacing)
    return {"min": float(d.min()), "max": float(d.max()), "n_negative": int((d < 0).sum())}
