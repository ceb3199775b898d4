"""Ground truth from explicit realizations of ``fgf`` media.

Each ``fgf`` medium of the scene is replaced, realization by realization,
by an explicit 3D grid of extinction whose macro density multiplies the
whole field, ``sigma_t(x) = rho(x) * field(x)`` (as the model scales the
fluctuations with ``rho``, ``docs/theory.md`` §4.5):

* ``marginal="gamma"`` (the default for pink noise): ``field = sigma_m X``,
  ``X`` a Gaussian copula with gamma marginals of mean 1, whose Gaussian
  spectrum and voxel shape are calibrated so that the grid's exact
  line-average variance follows the model's ``var[sigma_t](t)`` from one voxel
  to the grid's side (``docs/theory.md`` §1.8; the residual is in the info);
* ``marginal="gaussian"`` (the default for k-fBm):
  ``field = max(0, sigma_m + sigma_u)``, ``sigma_u`` the fractional Gaussian
  field with the model's 1D ray statistics (``S_w3 = S_w 2pi(2H+1)``, §1.7).

Fields are synthesised on a periodic domain ``padding`` times the grid per
axis (default 4) so that large scales are not wrapped. Every realization is
rendered classically (delta/ratio tracking) and the images are averaged;
the per-pixel standard error of that average comes with it. The full
description is in the Rust module ``fgf_render::ensemble``.

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
#: The one-point law of the realized extinction.
Marginal = Literal["auto", "gamma", "gaussian"]

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
    padding: float | None = None,
    marginal: Marginal = "auto",
    return_realizations: bool = False,
    client: Any = None,
    checkpoint: str | os.PathLike[str] | None = None,
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
    padding: float | None = None,
    marginal: Marginal = "auto",
    return_realizations: bool = False,
    client: Any = None,
    checkpoint: str | os.PathLike[str] | None = None,
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
    padding: float | None = None,
    marginal: Marginal = "auto",
    return_realizations: bool = False,
    client: Any = None,
    checkpoint: str | os.PathLike[str] | None = None,
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
    padding: float | None = None,
    marginal: Marginal = "auto",
    return_realizations: bool = False,
    client: Any = None,
    checkpoint: str | os.PathLike[str] | None = None,
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
        ``padded_shape`` ``[nz, ny, nx]``, ``spacing``, ``bbox``,
        ``marginal``, ``sw_3d`` and ``hurst_field`` (of the synthesized
        Gaussian field), ``alpha_voxel`` (gamma shape of a voxel, NaN for
        Gaussian), ``clamped_fraction``, ``mean_sigma_t`` (over voxels and
        realizations) against ``model_mean_sigma_t`` (``mean(sigma_m rho)``),
        the exact line-average variance along x of the grid
        (``grid_variances``) and of the model (``model_variances``) at
        segment ``lengths`` from one voxel to the grid's side, and a Monte
        Carlo check over ``variance_length``: ``realized_variance`` measured
        on the realizations against ``continuum_variance``.
    padding : float, optional
        Size of the periodic synthesis domain per axis, in grid sides
        (``1 <= padding <= 16``, default 4; memory grows as ``padding**3``).
    marginal : {"auto", "gamma", "gaussian"}
        The one-point law of the extinction (see the module docs); ``"auto"``
        is gamma for pink noise and Gaussian for k-fBm.
    return_realizations : bool
        Also put every realization's image, ``(N, H, W, 3)`` float32 in
        realization order, in ``info["realizations"]`` (implies nothing
        about ``return_info``; use both). Region means need them for their
        standard error: one realization moves many pixels together.

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
        A bad argument (``realizations = 0``, ``resolution < 2``,
        ``padding`` outside ``[1, 16]``, an unknown ``marginal``, ...).
    fgf.cluster.ClusterError
        ``client`` lost its scheduler (the checkpoint keeps what finished).
    KeyboardInterrupt
        On Ctrl-C, after the samples in flight finish.
    """
    from ._progress import MAX_THREADS, U32_MAX, check_int, check_seed, progress_sink
    from .render import _defines_list

    if client is not None or checkpoint is not None:
        # One Dask task per realization, merged in index order (fgf.cluster).
        from . import cluster

        run = cluster.ensemble(
            scene,
            int(realizations),
            resolution=resolution,
            spp=spp,
            seed=check_seed(seed),
            threads=threads,
            defines=_defines_list(defines),
            progress=progress,
            client=client,
            checkpoint=checkpoint,
            padding=None if padding is None else float(padding),
            marginal=str(marginal),
            keep_realizations=bool(return_realizations),
        )
        if run.lost is not None:
            raise cluster.ClusterError(run.lost)
        if run.interrupted:
            raise KeyboardInterrupt(f"ensemble interrupted after {run.info['realizations_done']} realizations")
        return (run.mean, run.stderr, run.info) if return_info else (run.mean, run.stderr)
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
            padding=None if padding is None else float(padding),
            marginal=str(marginal),
            keep_realizations=bool(return_realizations),
        )
    if interrupted:
        raise KeyboardInterrupt(f"ensemble interrupted after {info['realizations_done']} realizations")
    return (mean, stderr, info) if return_info else (mean, stderr)
