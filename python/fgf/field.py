"""Realizations of fractional Gaussian fields (``docs/theory.md`` §1).

* :func:`synthesize`: spectral FFT synthesis on 1D/2D/3D grids (white
  noise, pink noise, k-fBm for k = 1, 2, 3), float32 or float64, C order
  ``[z][y][x]``; bit-identical for any number of threads.
* :func:`sample_optical_depth`, :func:`sample_kfbm_1d`: exact 1D samplers
  (Davies–Harte circulant embedding, Cholesky), the ground truth.
* Estimators: :func:`variogram`, :func:`covariance`,
  :func:`radial_power_spectrum`, :func:`line_average_second_moment`, and the
  expected grid variance :func:`discrete_spectral_variance`.
* :func:`save_field`: ``.npy``, ``.vol`` (Mitsuba 3 ``gridvolume``),
  ``.exr`` and ``.png`` (2D), with an optional density mapping.

Conventions: sample ``i`` along an axis sits at ``i * spacing`` from the
origin corner; the spectrum is ``P(k) = sw |k|^(-2s)``, ``s = hurst + d/2``,
with angular wavenumbers; ``k = 0`` is dropped so every field has zero mean
over its periodic domain.

Examples
--------
>>> import fgf
>>> f = fgf.synthesize((64, 64), hurst=-0.3, seed=1)
>>> f.shape, f.dtype
((64, 64), dtype('float32'))
>>> tau = fgf.sample_optical_depth(n_rays=4, n_steps=8, t_max=2.0, hurst=-0.3, sw=0.3, seed=0)
>>> tau.shape           # at t = np.linspace(0, 2.0, 9)
(4, 9)
"""

from __future__ import annotations

import os
from typing import Any, Callable, Sequence, TypeVar, Union

import numpy as np
import numpy.typing as npt

from . import _core
from ._progress import Progress, check_int, check_seed, progress_sink

__all__ = [
    "synthesize",
    "sample_optical_depth",
    "sample_kfbm_1d",
    "sw_3d_for_ray_statistics",
    "discrete_spectral_variance",
    "padded_shape",
    "variogram",
    "covariance",
    "radial_power_spectrum",
    "line_average_second_moment",
    "save_field",
]

Anchor = Union[str, None, Sequence[int]]
#: A field as returned by :func:`synthesize`: float32 or float64.
FloatField = npt.NDArray[np.floating[Any]]

_R = TypeVar("_R")


def _run(fn: Callable[..., _R], progress: Progress, desc: str, *args: Any) -> _R:
    """Call ``fn(*args, progress)`` with the public ``progress=`` translated."""
    with progress_sink(progress, desc) as sink:
        return fn(*args, sink)


def _shape(shape: int | Sequence[int]) -> list[int]:
    if isinstance(shape, (int, np.integer)):
        shape = [shape]
    return [check_int("shape", n, 1, 2**62) for n in shape]


def synthesize(
    shape: int | Sequence[int],
    hurst: float,
    sw: float = 1.0,
    spacing: float = 1.0,
    seed: int = 0,
    anchor: Anchor = "corner",
    padding: float | None = None,
    dtype: npt.DTypeLike = np.float32,
    progress: Progress = True,
) -> FloatField:
    """Synthesize one realization of a fractional Gaussian field on a grid.

    Spectral method of ``docs/theory.md`` §1: cell-averaged white noise of
    variance ``sw / spacing**d``, filtered by ``|k|^(-s)`` with ``s = hurst +
    d/2`` on a periodic domain, ``k = 0`` dropped. A k-fBm (``hurst > 0``) is
    synthesized on a padded domain and anchored: its Taylor polynomial of
    degree ``k-1`` at the anchor (derivatives taken spectrally) is subtracted.

    Parameters
    ----------
    shape : int or sequence of int
        Grid shape, 1 to 3 axes, C order: ``(nx,)``, ``(ny, nx)`` or
        ``(nz, ny, nx)``. Any sizes (not only powers of two).
    hurst : float
        Hurst parameter ``H``: ``-d/2`` is white noise, ``-d/2 < H < 0`` pink
        noise, ``k-1 < H < k`` a k-fBm, ``k = 1, 2, 3``. ``H < 3``, not 0, 1, 2.
    sw : float, default 1
        White-noise strength ``S_w > 0``, ``P(k) = S_w |k|^(-2s)``. For 3D
        fields with the 1D ray statistics of the rendering model, pass
        ``sw_3d_for_ray_statistics(hurst, sw_1d)``.
    spacing : float, default 1
        Grid spacing in scene units (the same on every axis).
    seed : int, default 0
        Seed (0 to 2**64 - 1); equal seeds give bit-identical fields for any
        thread count.
    anchor : {"corner", "center", "none", None} or sequence of int
        k-fBm only (ignored for pink/white noise). ``"corner"``: sample
        ``(0, 0, 0)``; ``"center"``: sample ``(n//2, ...)``; a sequence gives
        the sample indices; ``"none"``/``None``: no Taylor subtraction (the
        periodic field; with ``padding=1`` it tiles seamlessly).
    padding : float, optional
        Size of the periodic domain per axis relative to the grid, >= 1.
        Default 1 for pink/white noise, 2 for k-fBm (so that long-range
        correlations are not wrapped around). Padded axes are rounded up to
        sizes with prime factors 2, 3, 5, 7. Memory grows as ``padding**d``.
    dtype : numpy.float32 or numpy.float64
        Output type; the FFTs run in this precision.
    progress : bool, tqdm-like object or callable, default True
        ``True`` shows a tqdm bar when stderr is a terminal; ``False``/``None``
        is quiet; an object with ``update(n)`` is updated; a callable is
        called as ``progress(done, total)``.

    Returns
    -------
    numpy.ndarray
        The field, shape ``shape``, C order.

    Raises
    ------
    fgf.ParameterError
        For parameters out of range (the message names the valid range).
    fgf.FgfError
        If the request cannot fit in the available memory (checked before
        allocating).
    KeyboardInterrupt
        If interrupted with Ctrl-C.

    Examples
    --------
    >>> import fgf, numpy as np
    >>> f = fgf.synthesize((32, 40), hurst=1.2, seed=1, anchor="center")
    >>> bool(abs(f[16, 20]) < 1e-5 * abs(f).max())   # anchored: 0 up to float32 rounding
    True
    >>> g = fgf.synthesize((8, 8, 8), hurst=-0.1, dtype=np.float64)
    >>> g.dtype
    dtype('float64')
    """
    return _run(
        _core.synthesize,
        progress,
        "synthesize",
        _shape(shape),
        float(hurst),
        float(sw),
        float(spacing),
        check_seed(seed),
        anchor,
        None if padding is None else float(padding),
        np.dtype(dtype).name,
    )


def discrete_spectral_variance(
    shape: int | Sequence[int],
    hurst: float,
    sw: float = 1.0,
    spacing: float = 1.0,
    padding: float | None = None,
) -> float:
    """Expected variance of each sample of an unanchored synthesized field.

    The discrete spectral sum ``sw / spacing**d * (1/N) * sum_{k != 0} |k|^(-2s)``
    over the periodic domain (Nyquist modes excluded for k-fBm). Grid fields
    must be validated against this, not against the continuum variance,
    which in 3D is approached very slowly (``docs/theory.md`` §1).

    Examples
    --------
    >>> import fgf
    >>> round(fgf.discrete_spectral_variance((4096,), hurst=-0.5), 6)  # white: (N-1)/N
    0.999756
    """
    return _core.synthesis_info(_shape(shape), float(hurst), float(sw), float(spacing), padding, "float32")[0]


def padded_shape(shape: int | Sequence[int], hurst: float, padding: float | None = None) -> tuple[int, ...]:
    """Shape of the periodic domain :func:`synthesize` uses for a request."""
    return tuple(_core.synthesis_info(_shape(shape), float(hurst), 1.0, 1.0, padding, "float32")[1])


def sw_3d_for_ray_statistics(hurst: float, sw: float) -> float:
    """``S_w`` of a 3D field whose restriction to any line has the 1D model's covariance.

    ``S_w3 = S_w * 2*pi*(2H+1)`` (``docs/theory.md`` §1), for ``hurst > -1/2``.

    Examples
    --------
    >>> import fgf, math
    >>> math.isclose(fgf.sw_3d_for_ray_statistics(-0.25, 1.0), math.pi)
    True
    """
    return _core.sw_3d_for_ray_statistics(float(hurst), float(sw))


def sample_optical_depth(
    n_rays: int,
    n_steps: int,
    t_max: float,
    hurst: float,
    sw: float = 1.0,
    seed: int = 0,
    progress: Progress = True,
) -> npt.NDArray[np.float64]:
    """Exact fluctuating optical depth along rays through white or pink noise.

    ``tau_u(t) = int_0^t sigma_u`` is a fractional Brownian motion with Hurst
    ``H + 1`` and ``var tau_u(t) = S_p t^(2H+2)``; its increments are drawn
    exactly by circulant embedding (Davies–Harte).

    Parameters
    ----------
    n_rays, n_steps : int
        Number of independent rays and of uniform steps along each.
    t_max : float
        Ray length in scene units.
    hurst : float
        ``-1/2`` (white) or ``-1/2 < hurst < 0`` (pink).
    sw : float
        White-noise strength ``S_w``.
    seed : int
    progress : see :func:`synthesize`

    Returns
    -------
    tau : numpy.ndarray, shape (n_rays, n_steps + 1)
        ``tau[r, i]`` at ``t[i] = i * t_max / n_steps`` (that is
        ``t = np.linspace(0, t_max, n_steps + 1)``); ``tau[:, 0] = 0``.

    Examples
    --------
    >>> import fgf, numpy as np
    >>> tau = fgf.sample_optical_depth(n_rays=2000, n_steps=16, t_max=4.0, hurst=-0.3, sw=0.3, seed=0)
    >>> t = np.linspace(0, 4.0, 17)
    >>> line_avg = tau[:, -1] / t[-1]   # variance ~ S_p t^(2H)
    """
    return _run(
        _core.sample_optical_depth,
        progress,
        "optical depth",
        check_int("n_rays", n_rays, 1, 2**62),
        check_int("n_steps", n_steps, 1, 2**62),
        float(t_max),
        float(hurst),
        float(sw),
        check_seed(seed),
    )[0]


def sample_kfbm_1d(
    n_samples: int,
    n_steps: int,
    length: float,
    hurst: float,
    sw: float = 1.0,
    seed: int = 0,
    progress: Progress = True,
) -> npt.NDArray[np.float64]:
    """Exact anchored 1D k-fBm by Cholesky factorisation of its covariance.

    Samples at ``x[i] = i * length / n_steps``; ``x[0] = 0`` is the anchor.
    Limited to ``n_steps <= 4096`` (dense ``n^2`` matrix, ``n^3/3`` flops).

    Returns
    -------
    values : numpy.ndarray, shape (n_samples, n_steps + 1)
        At ``x = np.linspace(0, length, n_steps + 1)``; ``values[:, 0] = 0``.

    Examples
    --------
    >>> import fgf
    >>> m = fgf.sample_kfbm_1d(n_samples=3, n_steps=10, length=1.0, hurst=1.5, seed=2)
    >>> m.shape, float(m[0, 0])
    ((3, 11), 0.0)
    """
    return _run(
        _core.sample_kfbm_1d,
        progress,
        "k-fBm",
        check_int("n_samples", n_samples, 1, 2**62),
        check_int("n_steps", n_steps, 1, 2**62),
        float(length),
        float(hurst),
        float(sw),
        check_seed(seed),
    )[0]


def _array(field: npt.ArrayLike) -> FloatField:
    a = np.asarray(field)
    if a.dtype not in (np.float32, np.float64):
        a = a.astype(np.float64)
    return np.ascontiguousarray(a)


#: Most bins :func:`radial_power_spectrum` accepts (fgf-field's ``MAX_BINS``).
MAX_BINS = 1 << 20


def _axis(a: npt.NDArray[Any], axis: object) -> int:
    """``axis`` in ``[-ndim, ndim)``, as an index in ``[0, ndim)``; never wrapped."""
    return check_int("axis", axis, -a.ndim, a.ndim - 1) % a.ndim


def _max_lag(a: npt.NDArray[Any], axis: int, max_lag: object) -> int:
    n = a.shape[axis]
    return n // 2 if max_lag is None else check_int("max_lag", max_lag, 0, max(n - 1, 0))


def variogram(field: npt.ArrayLike, axis: int = -1, max_lag: int | None = None) -> npt.NDArray[np.float64]:
    """Empirical variogram ``gamma(h) = 1/2 mean (f(x + h) - f(x))^2`` along an axis.

    Lags ``h = 0 .. max_lag`` in samples (default: half the axis), pairs
    inside the grid only (not periodic).

    Examples
    --------
    >>> import fgf, numpy as np
    >>> fgf.variogram(np.arange(6.0), max_lag=2).tolist()
    [0.0, 0.5, 2.0]
    """
    a = _array(field)
    axis = _axis(a, axis)
    return np.asarray(_core.variogram(a, axis, _max_lag(a, axis, max_lag)))


def covariance(field: npt.ArrayLike, axis: int = -1, max_lag: int | None = None) -> npt.NDArray[np.float64]:
    """Empirical covariance ``mean (f(x) - mu)(f(x + h) - mu)`` along an axis.

    ``mu`` is the mean of the whole field; lags ``0 .. max_lag`` samples
    (default: half the axis), non-periodic.
    """
    a = _array(field)
    axis = _axis(a, axis)
    return np.asarray(_core.covariance(a, axis, _max_lag(a, axis, max_lag)))


def radial_power_spectrum(
    field: npt.ArrayLike, spacing: float = 1.0, n_bins: int = 32
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.int_]]:
    """Radially averaged periodogram ``|FFT(f)|^2 spacing^d / N``.

    Its expectation for a periodic synthesized field is ``P(k) = sw
    |k|^(-2s)``. Modes ``0 < |k| <= pi/spacing`` in ``n_bins`` logarithmic
    bins from the fundamental ``2 pi / (n_max spacing)``.

    Returns
    -------
    k, power, count : numpy.ndarray
        Mean ``|k|`` (rad per unit), mean periodogram and number of modes
        in each non-empty bin.
    """
    bins = check_int("n_bins", n_bins, 1, MAX_BINS)
    k, p, c = _core.radial_power_spectrum(_array(field), float(spacing), bins)
    return np.asarray(k), np.asarray(p), np.asarray(c)


def line_average_second_moment(field: npt.ArrayLike, lengths: Sequence[int], axis: int = -1) -> npt.NDArray[np.float64]:
    """Mean of ``sigma_bar^2`` over non-overlapping segments along an axis.

    ``sigma_bar`` is the mean of ``L`` consecutive samples, the line average
    over ``L * spacing``, for each ``L`` in ``lengths``. For a zero-mean
    field (synthesized fields are) this estimates ``var[sigma_bar]``.
    """
    a = _array(field)
    axis = _axis(a, axis)
    n = a.shape[axis]
    checked = [check_int("length", v, 1, max(n, 1)) for v in lengths]
    return np.asarray(_core.line_average_second_moment(a, axis, checked))


def save_field(
    path: str | os.PathLike[str],
    field: npt.ArrayLike,
    spacing: float = 1.0,
    mean: float = 0.0,
    scale: float = 1.0,
    clamp_min: float | None = None,
    png_percentiles: tuple[float, float] = (0.5, 99.5),
) -> dict[str, Any]:
    """Write a field; the format comes from the extension.

    ``.npy`` (any dims, dtype kept), ``.vol`` (Mitsuba 3 ``gridvolume``,
    float32, bbox ``[0, n*spacing]`` per axis, missing axes of length 1),
    ``.exr`` (2D, float32 channel ``Y``) or ``.png`` (2D, 8-bit grey: the
    ``png_percentiles`` of the values map linearly to 0 and 255). Values are
    first mapped to ``max(clamp_min, mean + scale * field)``. Writes are
    atomic. Unknown extensions and 3D PNG/EXR raise :class:`fgf.FgfError`.

    Returns
    -------
    dict
        ``format``, ``min``, ``max`` and ``n_negative`` of the written values.
    """
    return _core.write_field(
        str(path),
        _array(field),
        float(spacing),
        float(mean),
        float(scale),
        None if clamp_min is None else float(clamp_min),
        (float(png_percentiles[0]), float(png_percentiles[1])),
    )
