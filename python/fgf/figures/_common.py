"""Shared plumbing of the figure groups: the run context, the result record of
a group, atomic PNG output and lookup of the fgf API a group depends on.

Nothing here knows about the physics; the group modules call the public fgf
API (``fgf.Fgf``, ``fgf.sample_optical_depth``, ``fgf.render``, ...) and only
arrange, average and plot what it returns.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np
import numpy.typing as npt

from .._atomic import write_atomic

if TYPE_CHECKING:
    from matplotlib.figure import Figure as MplFigure

__all__ = [
    "Unavailable",
    "need",
    "Figure",
    "GroupResult",
    "Context",
    "save_figure",
    "new_figure",
    "floats",
    "srgb_preview",
    "write_atomic",  # re-exported for the figure modules
]


class Unavailable(RuntimeError):
    """A figure group cannot run because part of the fgf API it needs is
    missing (not built, or not implemented yet). The message names it."""


def need(name: str) -> Any:
    """Return ``fgf.<name>`` or raise :class:`Unavailable` naming it.

    The figure groups look their dependencies up through this function so
    that a missing piece of the API marks the group unavailable in the
    gallery and in ``results.json`` instead of failing the whole run.
    """
    import fgf

    obj = getattr(fgf, name, None)
    if obj is None:
        raise Unavailable(f"fgf.{name} is not available in this build")
    return obj


@dataclasses.dataclass
class Figure:
    """One PNG of the gallery: file name (relative to the output directory),
    title and caption (with the parameters)."""

    file: str
    title: str
    caption: str


@dataclasses.dataclass
class GroupResult:
    """What a figure group produced: its figures and every plotted number."""

    figures: list[Figure] = dataclasses.field(default_factory=list)
    results: dict[str, Any] = dataclasses.field(default_factory=dict)


@dataclasses.dataclass
class Context:
    """Settings shared by the groups of one run.

    ``quick`` selects small resolutions and few realizations (the test-suite
    run); ``seed`` is the base seed, from which every group derives its own
    fixed seeds so that a run is reproducible; ``tick`` advances the group's
    progress bar by one step.
    """

    out: Path
    quick: bool
    seed: int
    tick: Callable[[], None]
    scene_dir: Path


def save_figure(fig: MplFigure, out: Path, name: str) -> str:
    """Save a matplotlib figure as ``out/name`` atomically (temporary file in
    the same directory, then ``os.replace``): an interrupted run never leaves
    a half-written PNG and never destroys a previous one."""
    return write_atomic(out / name, lambda fh: fig.savefig(fh, format="png", dpi=fig.dpi))


def new_figure(width: float, height: float) -> MplFigure:
    """A matplotlib figure drawn by the Agg canvas, without pyplot's global
    state (safe to use from a library and in tests)."""
    from matplotlib.figure import Figure as MplFigure

    return MplFigure(figsize=(width, height), dpi=100, layout="constrained")


def floats(a: npt.ArrayLike) -> Any:
    """A numpy array (any shape) as nested lists of Python floats for JSON
    (a float for a 0-d array)."""
    return np.asarray(a, dtype=float).tolist()


def srgb_preview(img: npt.ArrayLike, exposure: float = 0.0) -> npt.NDArray[np.float64]:
    """Display mapping of a linear RGB render: exposure (stops), clamp to
    [0, 1], then the sRGB transfer curve (the same order as fgf's PNG
    preview, formats.md "Output images")."""
    x = np.clip(np.asarray(img, dtype=np.float64) * 2.0**exposure, 0.0, 1.0)
    out: npt.NDArray[np.float64] = np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1.0 / 2.4) - 0.055)
    return out
