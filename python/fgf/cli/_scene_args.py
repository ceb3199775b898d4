"""Options and checks shared by the scene commands (`fgf render`, `fgf ensemble`).

Everything a run will write is checked before any work starts: each output
has the right extension and an existing directory, so a bad option never
costs a render and never replaces one of the user's files with a partial set
of outputs.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from .._atomic import StagedOutputs

SEED_MAX = 2**64 - 1


def add_scene_options(p: argparse.ArgumentParser) -> None:
    """``--threads``, ``-D``, ``--png``, ``--exposure``, ``--quiet``."""
    p.add_argument("--threads", type=int, default=None, help="worker threads (default: all cores)")
    p.add_argument(
        "-D",
        dest="defines",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override a <default> of the scene (repeatable)",
    )
    p.add_argument("--png", default=None, help="PNG preview path (default: the EXR path with .png)")
    p.add_argument("--exposure", type=float, default=0.0, help="PNG preview exposure in stops (default 0)")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")


def _check_output(option: str, path: Path, suffix: str) -> None:
    from .. import ParameterError

    if path.suffix.lower() != suffix:
        raise ParameterError(f"{option} {path}: the file name must end in {suffix}")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise ParameterError(f"{option} {path}: the directory {parent} does not exist")


def check_scene_options(args: argparse.Namespace, extra_exr: dict[str, str | None]) -> tuple[Path, Path]:
    """Validate the shared options and every output path; return ``(exr, png)``.

    ``extra_exr`` maps an option name (``--variance``, ``--stderr``) to its
    value (None when not given).
    """
    from .. import ParameterError

    if getattr(args, "spp", None) is not None and args.spp < 1:
        raise ParameterError(f"--spp {args.spp}: need at least 1 sample per pixel")
    if args.threads is not None and args.threads < 1:
        raise ParameterError(f"--threads {args.threads}: need at least 1 thread")
    if args.seed is not None and not 0 <= args.seed <= SEED_MAX:
        raise ParameterError(f"--seed {args.seed}: must be in [0, 2^64 - 1]")
    if not math.isfinite(args.exposure):
        raise ParameterError(f"--exposure {args.exposure}: must be a finite number of stops")
    out = Path(args.output)
    png = Path(args.png) if args.png else out.with_suffix(".png")
    _check_output("-o", out, ".exr")
    _check_output("--png", png, ".png")
    for option, value in extra_exr.items():
        if value is not None:
            _check_output(option, Path(value), ".exr")
    return out, png


def stage_outputs(outputs: list[tuple[str, str | Path | None]]) -> StagedOutputs:
    """Check every output of a run before it starts (``(option, path)``
    pairs, ``None`` for an output not asked for) and reserve each one's
    temporary file; the run writes those, then commits them together.
    Two options naming the same file are refused."""
    staged = StagedOutputs()
    try:
        for option, value in outputs:
            if value is not None:
                staged.add(option, value)
    except BaseException:
        staged.discard()
        raise
    return staged
