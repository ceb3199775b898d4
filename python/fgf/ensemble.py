"""Ground truth from explicit realizations of ``fgf`` media.

Each ``fgf`` medium of the scene is replaced, realization by realization,
by an explicit 3D grid ``sigma_t(x) = max(0, sigma_m rho(x) + sigma_u(x))``
where ``sigma_u`` is a fractional Gaussian field synthesised with the 1D ray
statistics of the model (``S_w3 = S_w 2pi(2H+1)``, ``docs/theory.md`` §1); every
realization is rendered classically (delta/ratio tracking) and the images
are averaged. The per-pixel standard error of that average comes with it.
The full description (grid placement, clamping, the grid-variance caveat)
is in the Rust module ``fgf_render::ensemble``.

>>> import fgf                                                            # doctest: +SKIP
>>> mean, se = fgf.ensemble("scenes/fgf-cube-pink.xml", realizations=16,
...                         spp=16, defines={"res": 64})                  # doctest: +SKIP
>>> model = fgf.render("scenes/fgf-cube-pink.xml", spp=256, defines={"res": 64})  # doctest: +SKIP
>>> ((model - mean) / se).std()   # about 1 where the model is exact      # doctest: +SKIP
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any, Literal, Union, overload

import numpy as np
import numpy.typing as npt

from . import _core

#: Most voxels along a medium's longest side that :func:`ensemble` accepts
#: (a larger grid could not fit in memory; the bound keeps the voxel count's
#: arithmetic far from overflow).
MAX_RESOLUTION = 65536

if TYPE_CHECKING:
    from ._progress import Progress
    from .render import Defines

#: A mean or standard-error image: ``(H, W, 3)`` float32.
Image = npt.NDArray[np.float32]

__all__ = ["ensemble"]


@overload
def ensemble(
    scene: str | os.PathLike[str],
    realizations: int = 16,
    resolution: int | None = None,
    spp: int | None = None,
    seed: int = 0,
    threads: int | None = None,
    defines: Defines = None,
    progress: Progress = True,
    return_info: Literal[False] = False,
) -> tuple[Image, Image]: ...
@overload
def ensemble(
    scene: str | os.PathLike[str],
    realizations: int = 16,
    resolution: int | None = None,
    spp: int | None = None,
    seed: int = 0,
    threads: int | None = None,
    defines: Defines = None,
    progress: Progress = True,
    *,
    return_info: Literal[True],
) -> tuple[Image, Image, dict[str, Any]]: ...
@overload
def ensemble(
    scene: str | os.PathLike[str],
    realizations: int = 16,
    resolution: int | None = None,
    spp: int | None = None,
    seed: int = 0,
    threads: int | None = None,
    defines: Defines = None,
    progress: Progress = True,
    return_info: bool = False,
) -> Union[tuple[Image, Image], tuple[Image, Image, dict[str, Any]]]: ...
def ensemble(
    scene: str | os.PathLike[str],
    realizations: int = 16,
    resolution: int | None = None,
    spp: int | None = None,
    seed: int = 0,
    threads: int | None = None,
    defines: Defines = None,
    progress: Progress = True,
    return_info: bool = False,
) -> Union[tuple[Image, Image], tuple[Image, Image, dict[str, Any]]]:
    """Average classical renders of explicit realizations of the scene's ``fgf`` media.

    Parameters
    ----------
    scene : path
        A Mitsuba 3 XML scene with at least one ``fgf`` medium (each must be
        the ``interior`` of some shape; ``nonexponential`` media and white
        noise, ``hurst = -0.5``, have no 3D field and are refused).
    realizations : int
        Number ``N >= 1`` of independent realizations (``N >= 2`` for a
        standard error).
    resolution : int, optional
        Voxels along the longest side of each medium's bounding box
        (default 64); the other sides get the same voxel size.
    spp : int, optional
        Samples per pixel of each realization's render (default: the
        scene's ``sample_count``).
    seed : int
        Master seed; the result depends only on the scene and the
        arguments, never on ``threads``.
    threads : int, optional
        Worker threads (default: all cores).
    defines : dict or list of "name=value", optional
        Overrides of the scene's ``<default>`` values (e.g. ``{"res": 64}``).
    progress : bool, tqdm-like object or callable, optional
        ``True`` shows a tqdm bar (in rendered samples) when stderr is a
        terminal; ``False``/``None`` is quiet; an object with ``update(n)`` or
        a callable ``progress(done, total)`` gets the counts.
    return_info : bool
        Also return a dict: ``realizations_done``, ``spp`` and ``media``, one
        dict per realised medium with ``shape`` ``[nx, ny, nz]``,
        ``spacing``, ``bbox``, ``sw_3d``, ``clamped_fraction`` and the
        line-average variance over ``variance_length`` measured on the grids
        (``realized_variance``) and of the model (``continuum_variance``).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        ``(mean, stderr)``, each ``(H, W, 3)`` float32 (``stderr`` is NaN for
        ``N = 1``); with ``return_info``, ``(mean, stderr, info)``.

    Raises
    ------
    fgf.SceneError
        The scene is invalid or has no ``fgf`` medium to realise.
    fgf.ParameterError
        A bad argument (``realizations = 0``, ``resolution < 2``, ...).
    KeyboardInterrupt
        On Ctrl-C, after the samples in flight finish.
    """
    from ._progress import MAX_THREADS, U32_MAX, check_int, check_seed, progress_sink
    from .render import _defines_list

    with progress_sink(progress, "ensemble") as sink:
        mean, stderr, info, interrupted = _core.ensemble_scene(
            os.fspath(scene),
            check_int("realizations", realizations, 1, U32_MAX),
            resolution=None if resolution is None else check_int("resolution", resolution, 2, MAX_RESOLUTION),
            spp=None if spp is None else check_int("spp", spp, 1, U32_MAX),
            seed=check_seed(seed),
            threads=None if threads is None else check_int("threads", threads, 1, MAX_THREADS),
            defines=_defines_list(defines),
            progress=sink,
        )
    if interrupted:
        raise KeyboardInterrupt(f"ensemble interrupted after {info['realizations_done']} realizations")
    return (mean, stderr, info) if return_info else (mean, stderr)
