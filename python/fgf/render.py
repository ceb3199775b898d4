"""Rendering Mitsuba 3 XML scenes with fgf's volumetric path tracer.

>>> import fgf                                                   # doctest: +SKIP
>>> img = fgf.render("scenes/default.xml", spp=16, seed=0)       # doctest: +SKIP
>>> img.shape, img.dtype                                         # doctest: +SKIP
((256, 256, 3), dtype('float32'))
>>> fgf.write_exr("out.exr", img); fgf.write_png("out.png", img) # doctest: +SKIP

The supported XML subset and its units are documented in the Rust crate
``fgf-scene`` (``crates/fgf-scene/src/xml/mod.rs``), and each plugin
family's parameters (units, range, default) in the table at the head of its
file there: ``integrators.rs``, ``sensors.rs``, ``shapes.rs``, ``bsdfs.rs``,
``emitters.rs``, ``media.rs``, ``nonexp.rs``, ``volumes.rs``, ``phase.rs``.
Images are linear RGB, row 0 at the top.
"""

from __future__ import annotations

import math
import os
from typing import Any, Literal, Mapping, Sequence, Union, cast, overload

import numpy as np
import numpy.typing as npt

from . import _core
from ._progress import MAX_THREADS, U32_MAX, Progress, check_int, check_seed, progress_sink

__all__ = ["render", "write_exr", "write_png"]

#: A rendered image: ``(H, W, 3)`` float32 linear RGB, row 0 at the top.
Image = npt.NDArray[np.float32]
#: ``-D``-style overrides: a mapping, or ``"name=value"`` strings, or pairs.
Defines = Union[Mapping[str, Any], Sequence[Union[str, tuple[Any, Any]]], None]


def _defines_list(defines: Defines) -> list[tuple[str, str]]:
    if defines is None:
        return []
    if isinstance(defines, Mapping):
        return [(str(k), str(v)) for k, v in defines.items()]
    out = []
    for d in defines:
        if isinstance(d, str):
            name, sep, value = d.partition("=")
            if not sep or not name:
                raise _core.ParameterError(f"define {d!r}: expected name=value")
            out.append((name, value))
        else:
            name, value = d
            out.append((str(name), str(value)))
    return out


@overload
def render(
    scene: str | os.PathLike[str],
    spp: int | None = None,
    seed: int | None = None,
    threads: int | None = None,
    defines: Defines = None,
    progress: Progress = True,
    return_variance: Literal[False] = False,
    *,
    client: Any = None,
    chunk_spp: int | None = None,
    checkpoint: str | os.PathLike[str] | None = None,
) -> Image: ...
@overload
def render(
    scene: str | os.PathLike[str],
    spp: int | None = None,
    seed: int | None = None,
    threads: int | None = None,
    defines: Defines = None,
    progress: Progress = True,
    *,
    return_variance: Literal[True],
    client: Any = None,
    chunk_spp: int | None = None,
    checkpoint: str | os.PathLike[str] | None = None,
) -> tuple[Image, Image]: ...
@overload
def render(
    scene: str | os.PathLike[str],
    spp: int | None = None,
    seed: int | None = None,
    threads: int | None = None,
    defines: Defines = None,
    progress: Progress = True,
    return_variance: bool = False,
    *,
    client: Any = None,
    chunk_spp: int | None = None,
    checkpoint: str | os.PathLike[str] | None = None,
) -> Image | tuple[Image, Image]: ...
def render(
    scene: str | os.PathLike[str],
    spp: int | None = None,
    seed: int | None = None,
    threads: int | None = None,
    defines: Defines = None,
    progress: Progress = True,
    return_variance: bool = False,
    *,
    client: Any = None,
    chunk_spp: int | None = None,
    checkpoint: str | os.PathLike[str] | None = None,
) -> Image | tuple[Image, Image]:
    """Render a Mitsuba 3 XML scene file.

    Parameters
    ----------
    scene : path
        The scene file (relative paths inside it resolve against its folder).
    spp : int, optional
        Samples per pixel (default: the scene's ``sample_count``).
    seed : int, optional
        Sampler seed (default: the scene's sampler ``seed``, else 0). The
        image depends only on the scene, ``spp`` and ``seed``, never on
        ``threads``.
    threads : int, optional
        Worker threads (default: all cores).
    defines : dict or list of "name=value", optional
        Overrides of the scene's ``<default>`` values, like ``-D`` in the CLI.
    progress : bool, tqdm-like object or callable, optional
        ``True`` shows a tqdm bar when stderr is a terminal; ``False``/``None``
        is quiet; an object with ``update(n)`` gets the samples finished; a
        callable is called as ``progress(done, total)``.
    return_variance : bool
        Also return the per-pixel variance of the pixel mean (the sample
        variance over the pixel's samples divided by their count). It needs
        at least 2 samples per pixel: with 1 it is undefined, and
        :class:`fgf.ParameterError` is raised instead of returning NaN.
    client : dask.distributed.Client, optional
        Render chunks of ``chunk_spp`` samples per pixel on the client's
        workers (``fgf.cluster``, ``docs/cluster.md``). The image has the
        same bits as without a client, for any chunk size and worker count.
    chunk_spp : int, optional
        Samples per pixel of a chunk (default: chunks sized from the times
        of those finished to take about ``fgf.cluster.CHUNK_SECONDS`` of
        rendering each).
    checkpoint : path, optional
        Save the finished chunks there as they arrive (with or without a
        client); a rerun with the same arguments resumes from them, and
        ``spp`` may be raised. A checkpoint of other arguments is refused
        with ``fgf.ParameterError``.

    Returns
    -------
    numpy.ndarray
        ``(H, W, 3)`` float32 linear RGB; with ``return_variance``, the pair
        ``(image, variance)``.

    Raises
    ------
    fgf.SceneError
        The scene is invalid or outside the supported subset (the message
        names file, line and tag).
    OSError
        A file cannot be read.
    KeyboardInterrupt
        On Ctrl-C, after the units of work in flight finish (the CLI
        instead writes the partial image; use it for long interruptible
        renders).
    fgf.cluster.ClusterError
        The client lost its scheduler (the checkpoint keeps what finished).
    """
    if client is not None or chunk_spp is not None or checkpoint is not None:
        from . import cluster

        run = cluster.render(
            scene,
            spp=spp,
            seed=None if seed is None else check_seed(seed),
            threads=threads,
            defines=_defines_list(defines),
            progress=progress,
            return_variance=return_variance,
            client=client,
            chunk_spp=chunk_spp,
            checkpoint=checkpoint,
        )
        if run.lost is not None:
            raise cluster.ClusterError(run.lost)
        if run.interrupted:
            raise KeyboardInterrupt(f"render interrupted after {run.spp_done} samples per pixel")
        return (run.image, cast(Image, run.variance)) if return_variance else run.image
    with progress_sink(progress, "render") as sink:
        img, var, done, interrupted = _core.render_scene(
            os.fspath(scene),
            spp=None if spp is None else check_int("spp", spp, 1, U32_MAX),
            seed=None if seed is None else check_seed(seed),
            threads=None if threads is None else check_int("threads", threads, 1, MAX_THREADS),
            defines=_defines_list(defines),
            progress=sink,
            return_variance=return_variance,
        )
    if interrupted:
        raise KeyboardInterrupt(f"render interrupted after {done} samples per pixel")
    if return_variance and done < 2:
        raise _core.ParameterError(
            f"spp = {done}: the per-pixel variance needs at least 2 samples per pixel (undefined for 1)"
        )
    # The native call returns a variance exactly when asked for one.
    return (img, cast(Image, var)) if return_variance else img


def _as_image(img: npt.ArrayLike) -> Image:
    a = np.ascontiguousarray(img, dtype=np.float32)
    if a.ndim != 3 or a.shape[2] != 3:
        raise _core.ParameterError(f"image has shape {a.shape}; expected (H, W, 3)")
    return a


def write_exr(path: str | os.PathLike[str], img: npt.ArrayLike) -> None:
    """Write an ``(H, W, 3)`` image as a linear float32 EXR (atomically)."""
    _core.write_exr(os.fspath(path), _as_image(img))


def write_png(path: str | os.PathLike[str], img: npt.ArrayLike, exposure: float = 0.0) -> None:
    """Write an ``(H, W, 3)`` linear image as an 8-bit sRGB PNG preview
    (exposure in stops, then clamp, then the sRGB curve), atomically."""
    stops = float(exposure)
    if not math.isfinite(stops):
        raise _core.ParameterError(f"invalid exposure = {exposure!r}: must be a finite number of stops")
    _core.write_png(os.fspath(path), _as_image(img), stops)
