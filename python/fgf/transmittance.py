"""Transmittance models and FGF statistics (``docs/theory.md`` §2–4).

Four models share one interface, in distance units for a mean extinction
``sigma_t`` (1/length):

* :class:`Exponential` — classical media, ``Tr = exp(-sigma_t t)``;
* :class:`Fgf` — the gamma closure of Guo et al. 2019 for a fractional
  Gaussian field of Hurst parameter ``hurst`` and strength ``sw``: white noise
  (``hurst = -0.5``), pink noise (``-0.5 < hurst < 0``) and k-fBm
  (``k-1 < hurst < k``, needs ``length``);
* :class:`Davis` — Bitterli et al. 2018's power law ``(1 + sigma_t t/alpha)^-alpha``
  (equal to Fgf k-fBm);
* :class:`DavisWeinstein` — Bitterli et al. 2018's model with parameters
  ``h`` and ``c`` (equal to Fgf pink noise).

Every method takes a scalar or an array-like and returns a Python float or a
numpy array of the input's shape. Large arrays are evaluated in Rust with
the GIL released.

==================  =====================================================
method              meaning
==================  =====================================================
``tr(t)``           ``T_ss(t)``: uncollided transmittance (dimensionless)
``pdf(t)``          ``T_sm = -dTr/dt``: free-flight pdf from a surface (1/length)
``sigma_bar``       ``T_sm(0)`` (1/length)
``medium_surface``  ``T_ms = T_sm / sigma_bar``
``medium_medium``   ``T_mm = -dT_ms/dt``: free-flight pdf from a medium vertex
``sample_surface``  distance with cdf ``1 - T_ss`` from variates ``u`` in [0, 1)
``sample_medium``   distance with cdf ``1 - T_ms`` from variates ``u`` in [0, 1)
==================  =====================================================

Examples
--------
>>> import fgf, numpy as np
>>> m = fgf.Fgf(sigma_t=4.0, hurst=-0.1, sw=4.0)
>>> m.regime
'pink'
>>> round(m.tr(0.25), 6)
0.46126
>>> m.pdf(0.0) == m.sigma_bar == 4.0
True
>>> t = m.sample_surface(np.random.default_rng(0).random(5))
>>> t.shape
(5,)
"""

from __future__ import annotations

from typing import Any, Callable, Optional, Sequence, Union, cast, overload

import numpy as np
import numpy.typing as npt

from . import _core

__all__ = [
    "Exponential",
    "Fgf",
    "Davis",
    "DavisWeinstein",
    "TransmittanceModel",
    "line_average_variance",
    "c_const",
    "s_p",
    "s_kf",
    "binom",
    "kfbm_point_variance",
]

#: What the elementwise methods return for array input.
FloatArray = npt.NDArray[np.float64]
# Array input (any shape): the result is an array of that shape. A 0-d array
# gives a float, like a scalar; the overloads below cannot see ``ndim``, so a
# 0-d array is typed as giving an array.
_Array = Union[npt.NDArray[Any], Sequence[Any]]

_F = _core.ModelFunction


def _apply(fn: Callable[..., FloatArray], x: npt.ArrayLike, *args: Any) -> Union[float, FloatArray]:
    """Call a native elementwise function ``fn(*args, flat_array)`` on ``x``;
    return a float for scalar input, else an array of ``x``'s shape."""
    a = np.asarray(x, dtype=np.float64)
    flat = np.ascontiguousarray(a).reshape(-1)
    out = fn(*args, flat)
    if a.ndim == 0:
        return float(out[0])
    return out.reshape(a.shape)


class TransmittanceModel:
    """Base class of the transmittance models; see the module docs."""

    __slots__ = ("_m",)

    def __init__(self, native: _core._Model) -> None:
        self._m = native

    @classmethod
    def _wrap(cls, native: _core._Model) -> TransmittanceModel:
        kind = native.params()["kind"]
        sub: type[TransmittanceModel] = {
            "exponential": Exponential,
            "fgf": Fgf,
            "davis": Davis,
            "davis_weinstein": DavisWeinstein,
        }[kind]
        obj = object.__new__(sub)
        TransmittanceModel.__init__(obj, native)
        return obj

    def _eval(self, what: _core.ModelFunction, x: npt.ArrayLike) -> Union[float, FloatArray]:
        return _apply(self._m.eval, x, what)

    @property
    def sigma_t(self) -> float:
        """Mean extinction ``sigma_t`` (1/length)."""
        return self._m.params()["sigma_t"]

    @property
    def sigma_bar(self) -> float:
        """``sigma_bar = T_sm(0)`` (1/length): ``sigma_t`` except for white
        noise, where it is ``sigma_eff``."""
        return self._m.sigma_bar

    @property
    def params(self) -> dict[str, Any]:
        """The model's kind and constructor parameters."""
        return dict(self._m.params())

    @overload
    def tr(self, t: float) -> float: ...
    @overload
    def tr(self, t: _Array) -> FloatArray: ...
    @overload
    def tr(self, t: npt.ArrayLike) -> Union[float, FloatArray]: ...
    def tr(self, t: npt.ArrayLike) -> Union[float, FloatArray]:
        """Transmittance ``Tr(t) = T_ss(t)``.

        Parameters
        ----------
        t : float or array_like
            Distances, ``t >= 0`` (``inf`` allowed; negative gives NaN).

        Returns
        -------
        float or numpy.ndarray
            Same shape as ``t``, values in ``[0, 1]``.
        """
        return self._eval(_F.TR, t)

    @overload
    def pdf(self, t: float) -> float: ...
    @overload
    def pdf(self, t: _Array) -> FloatArray: ...
    @overload
    def pdf(self, t: npt.ArrayLike) -> Union[float, FloatArray]: ...
    def pdf(self, t: npt.ArrayLike) -> Union[float, FloatArray]:
        """Free-flight pdf from a surface, ``p(t) = -dTr/dt = T_sm(t)`` (1/length).

        Parameters
        ----------
        t : float or array_like
            Distances, ``t >= 0``.

        Returns
        -------
        float or numpy.ndarray
            Same shape as ``t``; integrates to 1 over ``[0, inf)``.
        """
        return self._eval(_F.PDF, t)

    @overload
    def surface_surface(self, t: float) -> float: ...
    @overload
    def surface_surface(self, t: _Array) -> FloatArray: ...
    @overload
    def surface_surface(self, t: npt.ArrayLike) -> Union[float, FloatArray]: ...
    def surface_surface(self, t: npt.ArrayLike) -> Union[float, FloatArray]:
        """``T_ss(t) = Tr(t)``: from a surface to a surface. See :meth:`tr`."""
        return self._eval(_F.TR, t)

    @overload
    def surface_medium(self, t: float) -> float: ...
    @overload
    def surface_medium(self, t: _Array) -> FloatArray: ...
    @overload
    def surface_medium(self, t: npt.ArrayLike) -> Union[float, FloatArray]: ...
    def surface_medium(self, t: npt.ArrayLike) -> Union[float, FloatArray]:
        """``T_sm(t) = -dTr/dt``: from a surface to a medium vertex. See :meth:`pdf`."""
        return self._eval(_F.PDF, t)

    @overload
    def medium_surface(self, t: float) -> float: ...
    @overload
    def medium_surface(self, t: _Array) -> FloatArray: ...
    @overload
    def medium_surface(self, t: npt.ArrayLike) -> Union[float, FloatArray]: ...
    def medium_surface(self, t: npt.ArrayLike) -> Union[float, FloatArray]:
        """``T_ms(t) = T_sm(t) / sigma_bar``: from a medium vertex to a surface.

        Parameters
        ----------
        t : float or array_like
            Distances, ``t >= 0``.

        Returns
        -------
        float or numpy.ndarray
            Same shape as ``t``, values in ``[0, 1]``.
        """
        return self._eval(_F.MEDIUM_SURFACE, t)

    @overload
    def medium_medium(self, t: float) -> float: ...
    @overload
    def medium_medium(self, t: _Array) -> FloatArray: ...
    @overload
    def medium_medium(self, t: npt.ArrayLike) -> Union[float, FloatArray]: ...
    def medium_medium(self, t: npt.ArrayLike) -> Union[float, FloatArray]:
        """``T_mm(t) = -dT_ms/dt`` (1/length): free-flight pdf from a medium vertex.

        For pink noise (and Davis–Weinstein with ``0.5 < h < 1``) it is
        ``+inf`` at ``t = 0`` (an integrable singularity).

        Parameters
        ----------
        t : float or array_like
            Distances, ``t >= 0``.

        Returns
        -------
        float or numpy.ndarray
            Same shape as ``t``; integrates to 1 over ``[0, inf)``.
        """
        return self._eval(_F.MEDIUM_MEDIUM, t)

    @overload
    def sample_surface(self, u: float) -> float: ...
    @overload
    def sample_surface(self, u: _Array) -> FloatArray: ...
    @overload
    def sample_surface(self, u: npt.ArrayLike) -> Union[float, FloatArray]: ...
    def sample_surface(self, u: npt.ArrayLike) -> Union[float, FloatArray]:
        """Free-flight distances from a surface: solve ``1 - T_ss(t) = u``.

        Parameters
        ----------
        u : float or array_like
            Uniform variates in ``[0, 1)``; anything else raises
            :class:`fgf.ParameterError`.

        Returns
        -------
        float or numpy.ndarray
            Distances, same shape as ``u``; ``inf`` when the distance exceeds
            the float range (extremely heavy tails).
        """
        return self._eval(_F.SAMPLE_SURFACE, u)

    @overload
    def sample_medium(self, u: float) -> float: ...
    @overload
    def sample_medium(self, u: _Array) -> FloatArray: ...
    @overload
    def sample_medium(self, u: npt.ArrayLike) -> Union[float, FloatArray]: ...
    def sample_medium(self, u: npt.ArrayLike) -> Union[float, FloatArray]:
        """Free-flight distances from a medium vertex: solve ``1 - T_ms(t) = u``.

        Parameters
        ----------
        u : float or array_like
            Uniform variates in ``[0, 1)``.

        Returns
        -------
        float or numpy.ndarray
            Distances, same shape as ``u``.
        """
        return self._eval(_F.SAMPLE_MEDIUM, u)

    def __reduce__(self) -> tuple[Callable[[dict[str, Any]], TransmittanceModel], tuple[dict[str, Any]]]:
        # Pickle by constructor parameters (the native object is rebuilt).
        return (_from_params, (self.params,))

    def __repr__(self) -> str:
        p = self.params
        p.pop("kind")
        p.pop("regime", None)
        p.pop("k", None)
        if p.get("length", 0) is None:
            p.pop("length")
        args = ", ".join(f"{k}={v!r}" for k, v in p.items())
        return f"{type(self).__name__}({args})"


def _from_params(p: dict[str, Any]) -> TransmittanceModel:
    """Rebuild a model from :attr:`TransmittanceModel.params` (for pickle)."""
    kind = p["kind"]
    if kind == "exponential":
        return Exponential(p["sigma_t"])
    if kind == "fgf":
        return Fgf(p["sigma_t"], hurst=p["hurst"], sw=p["sw"], length=p["length"])
    if kind == "davis":
        return Davis(p["sigma_t"], alpha=p["alpha"])
    return DavisWeinstein(p["sigma_t"], h=p["h"], c=p["c"])


class Exponential(TransmittanceModel):
    """Exponential transmittance ``Tr = exp(-sigma_t t)`` (classical media).

    Parameters
    ----------
    sigma_t : float
        Extinction (1/length), ``0 < sigma_t < inf``.

    Examples
    --------
    >>> import fgf, math
    >>> m = fgf.Exponential(4.0)
    >>> abs(m.sample_surface(0.5) - math.log(2) / 4) < 1e-15
    True
    """

    __slots__ = ()

    def __init__(self, sigma_t: float) -> None:
        super().__init__(_core._Model.exponential(float(sigma_t)))


class Fgf(TransmittanceModel):
    """FGF gamma-closure transmittance (Guo et al. 2019, ``docs/theory.md`` §3).

    The line-averaged extinction over a segment of length ``t`` is a gamma
    variable with mean ``sigma_t`` and variance ``variance(t)``; then
    ``alpha(t) = sigma_t**2 / variance(t)`` and
    ``Tr(t) = (1 + sigma_t t / alpha)**(-alpha)``.

    Parameters
    ----------
    sigma_t : float
        Mean extinction ``sigma_m`` (1/length), ``0 < sigma_t < inf``.
    hurst : float
        Hurst parameter: ``-0.5`` (white noise), ``(-0.5, 0)`` (pink noise),
        ``(k-1, k)`` non-integer, ``< 1000`` (k-fBm). ``0`` and integers are
        invalid.
    sw : float
        White-noise strength ``S_w > 0``.
    length : float, optional
        k-fBm only (required there, an error otherwise): the characteristic
        length ``L > 0`` of the medium; the variance is ``S_kf L**(2H)``.

    Raises
    ------
    fgf.ParameterError
        For any parameter outside its valid range; the message names it.

    Examples
    --------
    >>> import fgf
    >>> m = fgf.Fgf(sigma_t=4.0, hurst=1.2, sw=34.0, length=1.0)   # 2-fBm
    >>> d = m.to_davis()
    >>> abs(d.tr(0.3) - m.tr(0.3)) < 1e-12
    True
    """

    __slots__ = ()

    def __init__(
        self,
        sigma_t: float,
        *,
        hurst: float,
        sw: float,
        length: Optional[float] = None,
    ) -> None:
        super().__init__(
            _core._Model.fgf(
                float(sigma_t),
                float(hurst),
                float(sw),
                None if length is None else float(length),
            )
        )

    @property
    def hurst(self) -> float:
        """Hurst parameter ``H``."""
        return self._m.params()["hurst"]

    @property
    def sw(self) -> float:
        """White-noise strength ``S_w``."""
        return self._m.params()["sw"]

    @property
    def length(self) -> Optional[float]:
        """k-fBm length ``L`` (``None`` for white and pink noise)."""
        return self._m.params()["length"]

    @property
    def regime(self) -> str:
        """``"white"``, ``"pink"`` or ``"k-fbm"``."""
        return self._m.params()["regime"]

    @property
    def k(self) -> int:
        """k-fBm order ``k = ceil(H)`` (0 for white and pink noise)."""
        return self._m.params()["k"]

    @overload
    def variance(self, t: float) -> float: ...
    @overload
    def variance(self, t: _Array) -> FloatArray: ...
    @overload
    def variance(self, t: npt.ArrayLike) -> Union[float, FloatArray]: ...
    def variance(self, t: npt.ArrayLike) -> Union[float, FloatArray]:
        """Variance of the line-averaged extinction ``var[sigma_bar_t]`` (1/length²).

        Parameters
        ----------
        t : float or array_like
            Segment lengths, ``t >= 0`` (``inf`` at ``t = 0`` for white/pink).

        Returns
        -------
        float or numpy.ndarray
            Same shape as ``t``.
        """
        return self._eval(_F.VARIANCE, t)

    @overload
    def alpha(self, t: float) -> float: ...
    @overload
    def alpha(self, t: _Array) -> FloatArray: ...
    @overload
    def alpha(self, t: npt.ArrayLike) -> Union[float, FloatArray]: ...
    def alpha(self, t: npt.ArrayLike) -> Union[float, FloatArray]:
        """Gamma shape ``alpha(t) = sigma_t**2 / variance(t)`` (dimensionless).

        Parameters
        ----------
        t : float or array_like
            Segment lengths, ``t >= 0``.

        Returns
        -------
        float or numpy.ndarray
            Same shape as ``t``; constant for k-fBm, 0 at ``t = 0`` otherwise.
        """
        return self._eval(_F.ALPHA, t)

    def to_davis(self) -> "Davis":
        """The equal :class:`Davis` model, ``alpha = sigma_t**2 / (S_kf L**(2H))``
        (k-fBm only; :class:`fgf.ParameterError` otherwise)."""
        return cast(Davis, TransmittanceModel._wrap(self._m.to_davis()))

    def to_davis_weinstein(self) -> "DavisWeinstein":
        """The equal :class:`DavisWeinstein` model, ``h = H + 1``,
        ``c = S_p**(1/(2H+2)) / sigma_t`` (white or pink noise only)."""
        return cast(DavisWeinstein, TransmittanceModel._wrap(self._m.to_davis_weinstein()))


class Davis(TransmittanceModel):
    """Davis power-law transmittance ``Tr = (1 + sigma_t t / alpha)**(-alpha)``
    (Bitterli et al. 2018).

    Parameters
    ----------
    sigma_t : float
        Mean extinction (1/length), ``0 < sigma_t < inf``.
    alpha : float
        Shape, ``0 < alpha < inf``. ``alpha -> inf`` is the exponential,
        ``alpha -> 0`` fully transparent; the mean free path is finite only
        for ``alpha > 1``.

    Examples
    --------
    >>> import fgf
    >>> fgf.Davis(4.0, alpha=4.0).tr(1.0)
    0.0625
    """

    __slots__ = ()

    def __init__(self, sigma_t: float, *, alpha: float) -> None:
        super().__init__(_core._Model.davis(float(sigma_t), float(alpha)))

    @property
    def alpha(self) -> float:
        """Shape parameter ``alpha``."""
        return self._m.params()["alpha"]


class DavisWeinstein(TransmittanceModel):
    """Davis–Weinstein transmittance (Bitterli et al. 2018): in optical depth
    ``tau = sigma_t t``, ``alpha(tau) = tau**(2-2h) / c**(2h)`` and
    ``Tr = (1 + tau/alpha)**(-alpha)``.

    Parameters
    ----------
    sigma_t : float
        Mean extinction (1/length), ``0 < sigma_t < inf``.
    h : float
        ``0.5 <= h <= 1`` (``h = H + 1`` for pink noise; ``0.5`` is white
        noise, ``1`` is Davis with ``alpha = 1/c**2``).
    c : float
        ``0 < c < inf``.

    Examples
    --------
    >>> import fgf
    >>> m = fgf.DavisWeinstein(4.0, h=0.9, c=0.78)
    >>> 0 < m.tr(0.25) < 1
    True
    """

    __slots__ = ()

    def __init__(self, sigma_t: float, *, h: float, c: float) -> None:
        super().__init__(_core._Model.davis_weinstein(float(sigma_t), float(h), float(c)))

    @property
    def h(self) -> float:
        """Parameter ``h``."""
        return self._m.params()["h"]

    @property
    def c(self) -> float:
        """Parameter ``c``."""
        return self._m.params()["c"]


# --- statistics (docs/theory.md §1-2) ---


@overload
def line_average_variance(hurst: float, sw: float, t: float, length: Optional[float] = None) -> float: ...
@overload
def line_average_variance(hurst: float, sw: float, t: _Array, length: Optional[float] = None) -> FloatArray: ...
@overload
def line_average_variance(
    hurst: float, sw: float, t: npt.ArrayLike, length: Optional[float] = None
) -> Union[float, FloatArray]: ...
def line_average_variance(
    hurst: float, sw: float, t: npt.ArrayLike, length: Optional[float] = None
) -> Union[float, FloatArray]:
    """Variance of the line-averaged extinction ``var[sigma_bar_t]``.

    ``S_w / t`` (white, ``hurst = -0.5``), ``S_p t**(2H)`` (pink),
    ``S_kf L**(2H)`` (k-fBm, needs ``length``).

    Parameters
    ----------
    hurst : float
        Hurst parameter (see :class:`Fgf`).
    sw : float
        ``S_w > 0``.
    t : float or array_like
        Segment lengths, ``t > 0``.
    length : float, optional
        ``L > 0``, required for k-fBm, refused otherwise.

    Returns
    -------
    float or numpy.ndarray
        Same shape as ``t``.

    Examples
    --------
    >>> import fgf
    >>> fgf.line_average_variance(-0.5, 2.0, 4.0)
    0.5
    """
    ell = None if length is None else float(length)
    return _apply(
        lambda h, s, a: _core.line_average_variance(h, s, a, ell), t, float(hurst), float(sw)
    )


def c_const(hurst: float, d: int = 1) -> float:
    """``C(H, d) = Gamma(-H) / (2**(2H+d) pi**(d/2) Gamma(H + d/2))``, the
    constant of the covariance ``C S_w |x-y|**(2H)``.

    Examples
    --------
    >>> import fgf
    >>> fgf.c_const(0.5, 1)
    -0.5
    """
    from ._progress import check_int

    return _core.c_const(float(hurst), check_int("d", d, 1, 3))


def s_p(hurst: float, sw: float) -> float:
    """``S_p(H) = S_w / (Gamma(2H+3) |sin(pi H)|)`` for ``-0.5 <= H < 0``."""
    return _core.s_p(float(hurst), float(sw))


def s_kf(hurst: float, sw: float) -> float:
    """``S_kf(H) = S_w binom(2H-1, k-1) / (Gamma(2H+2) |sin(pi H)|)``, ``k = ceil(H)``,
    for k-fBm."""
    return _core.s_kf(float(hurst), float(sw))


def binom(a: float, k: int) -> float:
    """Generalised binomial coefficient ``a (a-1) ... (a-k+1) / k!``.

    Examples
    --------
    >>> import fgf
    >>> fgf.binom(-0.5, 3)
    -0.3125
    """
    from ._progress import U32_MAX, check_int

    return _core.binom(float(a), check_int("k", k, 0, U32_MAX))


@overload
def kfbm_point_variance(hurst: float, sw: float, x: float) -> float: ...
@overload
def kfbm_point_variance(hurst: float, sw: float, x: _Array) -> FloatArray: ...
@overload
def kfbm_point_variance(hurst: float, sw: float, x: npt.ArrayLike) -> Union[float, FloatArray]: ...
def kfbm_point_variance(hurst: float, sw: float, x: npt.ArrayLike) -> Union[float, FloatArray]:
    """Point variance of the anchored k-fBm,
    ``2 C(H,1) S_w (-1)**k binom(2H-1, k-1) |x|**(2H)``.

    Parameters
    ----------
    hurst : float
        ``1e-15 <= hurst < 1000``, not an integer.
    sw : float
        ``S_w > 0``.
    x : float or array_like
        Distances from the anchor.

    Returns
    -------
    float or numpy.ndarray
        Same shape as ``x``.
    """
    return _apply(_core.kfbm_point_variance, x, float(hurst), float(sw))
