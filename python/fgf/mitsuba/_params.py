"""Parameters of the ``fgf`` / ``nonexponential`` media, computed once per
render on the Python side with the fgf models (``docs/theory.md`` §3–4).

Nothing here runs per sample: this module validates the XML parameters (the
same names, ranges and defaults as fgf's own scene loader), builds one
:class:`fgf.TransmittanceModel` per RGB channel, reduces it to the gamma
closure ``Tr = exp(-σ t g(k t^e))`` that the Dr.Jit code in ``_drmath``
evaluates, and tabulates the flight samplers that have no closed form.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional, Sequence

import numpy as np

from .. import ParameterError
from .. import transmittance as _tr

KERNELS = ("energy_conserving", "reciprocal")
TRANSMITTANCES = ("exponential", "davis", "davis_weinstein")

#: ``ln y`` range of the flight tables, ``y = -ln(1 - u)``: a float32 variate
#: ``u ∈ [2⁻²⁴, 1 - 2⁻²⁴]`` gives ``ln y ∈ [-16.64, 2.81]`` (the same range
#: as fgf's renderer, ``medium/flight_table.rs``). Outside it the table is
#: extrapolated linearly in ``(ln y, ln t)``, which is the power-law
#: asymptote of the sampler at both ends.
LN_Y_MIN = -16.7
LN_Y_MAX = 2.9
#: Node counts tried in turn, as in fgf's renderer, plus a larger last resort.
TABLE_NODES = (1024, 4096, 16384)
#: Largest accepted error of a table on ``ln t`` at the interval midpoints
#: (a relative error of 1e-7 on the distance, below one float32 ulp).
TABLE_MAX_ERROR = 1e-7


class MediumParameterError(ParameterError):
    """An ``fgf``/``nonexponential`` medium parameter is out of range, or a
    medium ``fgf_volpath`` does not support; the message names the parameter
    and its valid range. A :class:`fgf.ParameterError` (so a ``ValueError``)."""


@dataclass(frozen=True)
class MediumSpec:
    """The validated XML parameters of one ``fgf``/``nonexponential`` medium."""

    plugin: str
    sigma_t: tuple[float, float, float]
    albedo: tuple[float, float, float]
    kernel: str
    hurst: Optional[float] = None
    sw: Optional[float] = None
    length: Optional[float] = None
    transmittance: Optional[str] = None
    alpha: Optional[float] = None
    h: Optional[float] = None
    c: Optional[float] = None

    @property
    def needs_length(self) -> bool:
        """A k-fBm medium without ``length`` (it defaults to the diagonal of
        the bounding box of the shapes it is the interior of)."""
        return self.plugin == "fgf" and self.length is None and _is_kfbm(self.hurst)


def _is_kfbm(hurst: Optional[float]) -> bool:
    return hurst is not None and hurst > 0


def _err(plugin: str, name: str, value: Any, valid: str) -> MediumParameterError:
    return MediumParameterError(f"{plugin} medium: invalid {name} = {value} (valid: {valid})")


def _rgb(plugin: str, name: str, v: Any) -> tuple[float, float, float]:
    try:
        if isinstance(v, (int, float)):
            c = [float(v)] * 3
        else:
            c = [float(v[i]) for i in range(3)]
    except (TypeError, IndexError, ValueError):
        raise _err(plugin, name, v, "a float or an rgb value") from None
    return (c[0], c[1], c[2])


def parse_spec(plugin: str, props: dict[str, Any]) -> MediumSpec:
    """Validate the parameters of an ``fgf`` or ``nonexponential`` medium.

    ``props`` maps parameter names to values (floats, strings or 3-sequences
    for rgb). Raises :class:`MediumParameterError` naming the parameter and
    its valid range, as fgf's scene loader does.
    """
    known = {"sigma_t", "albedo", "scale", "kernel"}
    known |= {"hurst", "sw", "length"} if plugin == "fgf" else {"transmittance", "alpha", "h", "c"}
    for k in props:
        if k not in known:
            raise MediumParameterError(
                f"{plugin} medium: unknown parameter '{k}' (known: {', '.join(sorted(known))})"
            )
    scale = float(props.get("scale", 1.0))
    if not scale > 0:
        raise _err(plugin, "scale", scale, "scale > 0 for a non-exponential medium")
    sigma_m = _rgb(plugin, "sigma_t", props.get("sigma_t", 1.0))
    if not all(s > 0 and math.isfinite(s) for s in sigma_m):
        raise _err(plugin, "sigma_t", sigma_m, "each channel > 0; it is the mean extinction sigma_m")
    sigma_t = (sigma_m[0] * scale, sigma_m[1] * scale, sigma_m[2] * scale)
    if not all(math.isfinite(s * s) and np.float32(s) > 0 for s in sigma_t):
        raise MediumParameterError(f"{plugin} medium: sigma_t * scale is outside the representable range")
    albedo = _rgb(plugin, "albedo", props.get("albedo", 0.75))
    if not all(0.0 <= a <= 1.0 for a in albedo):
        raise _err(plugin, "albedo", albedo, "each channel in [0, 1]")
    kernel = str(props.get("kernel", "energy_conserving"))
    if kernel not in KERNELS:
        raise _err(plugin, "kernel", kernel, " or ".join(KERNELS))
    if plugin == "fgf":
        if "hurst" not in props:
            raise MediumParameterError(
                "fgf medium: missing required parameter 'hurst' (valid: -0.5 white noise, "
                "(-0.5, 0) pink noise, (k-1, k) k-fBm)"
            )
        if "sw" not in props:
            raise MediumParameterError("fgf medium: missing required parameter 'sw' (valid: sw > 0)")
        hurst = float(props["hurst"])
        sw = float(props["sw"])
        length = None if "length" not in props else float(props["length"])
        if length is not None and not _is_kfbm(hurst):
            raise MediumParameterError(
                f"fgf medium: 'length' only applies to k-fBm media (hurst > 0); hurst = {hurst} is "
                + ("white noise" if hurst == -0.5 else "pink noise")
            )
        spec = MediumSpec(plugin, sigma_t, albedo, kernel, hurst=hurst, sw=sw, length=length)
    elif plugin == "nonexponential":
        if "transmittance" not in props:
            raise MediumParameterError(
                "nonexponential medium: missing required parameter 'transmittance' "
                f"(valid: {', '.join(TRANSMITTANCES)})"
            )
        t = str(props["transmittance"])
        if t not in TRANSMITTANCES:
            raise _err(plugin, "transmittance", t, ", ".join(TRANSMITTANCES))
        need = {"exponential": (), "davis": ("alpha",), "davis_weinstein": ("h", "c")}[t]
        for k in ("alpha", "h", "c"):
            if k in props and k not in need:
                raise MediumParameterError(f"nonexponential medium: '{k}' does not apply to transmittance '{t}'")
        for k in need:
            if k not in props:
                valid = {"alpha": "alpha > 0", "h": "0.5 <= h <= 1", "c": "c > 0"}[k]
                raise MediumParameterError(
                    f"nonexponential medium: missing required parameter '{k}' ({valid})"
                )
        spec = MediumSpec(
            plugin,
            sigma_t,
            albedo,
            kernel,
            transmittance=t,
            alpha=float(props["alpha"]) if "alpha" in props else None,
            h=float(props["h"]) if "h" in props else None,
            c=float(props["c"]) if "c" in props else None,
        )
    else:
        raise MediumParameterError(f"unknown medium plugin '{plugin}' (valid: fgf, nonexponential)")
    # Build the models once now, so that a bad value fails at scene load
    # (a k-fBm medium without 'length' is checked with L = 1).
    build_models(spec, 1.0 if spec.needs_length else None)
    return spec


def build_models(spec: MediumSpec, default_length: Optional[float]) -> list[_tr.TransmittanceModel]:
    """One fgf transmittance model per RGB channel (errors become
    :class:`MediumParameterError`)."""
    out: list[_tr.TransmittanceModel] = []
    for s in spec.sigma_t:
        try:
            m: _tr.TransmittanceModel
            if spec.plugin == "fgf":
                assert spec.hurst is not None and spec.sw is not None
                length = spec.length if spec.length is not None else (default_length if _is_kfbm(spec.hurst) else None)
                m = _tr.Fgf(s, hurst=spec.hurst, sw=spec.sw, length=length)
            elif spec.transmittance == "exponential":
                m = _tr.Exponential(s)
            elif spec.transmittance == "davis":
                assert spec.alpha is not None
                m = _tr.Davis(s, alpha=spec.alpha)
            else:
                assert spec.h is not None and spec.c is not None
                m = _tr.DavisWeinstein(s, h=spec.h, c=spec.c)
        except ValueError as e:  # fgf.ParameterError names the parameter
            raise MediumParameterError(f"{spec.plugin} medium: {e}") from None
        out.append(m)
    return out


@dataclass(frozen=True)
class Gamma:
    """The gamma-closure parameters of one channel: ``ln Tr = -σ t g(k t^e)``
    with ``g(x) = ln(1+x)/x`` (``docs/theory.md`` §3), and ``σ̄ = T_sm(0)``."""

    sigma: float
    k: float
    e: float
    sigma_bar: float


def gamma_of(model: _tr.TransmittanceModel) -> Gamma:
    """``(σ, k, e, σ̄)`` of a model, checked against the model's own ``tr``
    at a few distances (relative 1e-9 on ``-ln Tr``)."""
    s = model.sigma_t
    m: Any = model  # the models' methods take scalars or arrays
    if isinstance(model, _tr.Exponential):
        k, e = 0.0, 0.0
    elif isinstance(model, _tr.Davis):
        k, e = s / model.alpha, 1.0
    elif isinstance(model, _tr.DavisWeinstein):
        e = 2.0 * model.h - 1.0
        k = math.exp(2.0 * model.h * math.log(model.c) + e * math.log(s))
    elif isinstance(model, _tr.Fgf):
        e = {"white": 0.0, "pink": 1.0 + 2.0 * model.hurst}.get(model.regime, 1.0)
        # x(t) = t var[σ̄_t] / σ_m = k t^e, so k = var[σ̄_1] / σ_m.
        k = float(m.variance(1.0)) / s
    else:  # pragma: no cover - the four models are closed
        raise TypeError(f"unknown transmittance model {model!r}")
    g = Gamma(s, k, e, float(model.sigma_bar))
    t = np.array([1e-3, 0.1, 1.0, 10.0]) / s
    want = -np.log(np.asarray(m.tr(t), dtype=np.float64))
    got = -ln_tr_np(g, t)
    ok = np.isclose(got, want, rtol=1e-9, atol=1e-300) | (want > 700)
    if not ok.all():  # pragma: no cover - a mismatch is a bug, not bad input
        raise RuntimeError(f"gamma parameters of {model!r} do not reproduce Tr: {got} vs {want}")
    return g


def ln_tr_np(g: Gamma, t: np.ndarray) -> np.ndarray:
    """``ln Tr(t)`` in float64 numpy (the check of :func:`gamma_of`)."""
    x = np.full_like(t, g.k) if g.e == 0 else g.k * t**g.e
    gx = np.where(x > 0, np.log1p(x) / np.where(x > 0, x, 1.0), 1.0)
    return -g.sigma * t * gx


@dataclass
class FlightTable:
    """``s = ln t`` against ``ln y`` on ``n`` uniform nodes of
    ``[LN_Y_MIN, LN_Y_MAX]`` with ``h·ds/d ln y`` (``h`` the node spacing),
    for cubic Hermite interpolation; ``error`` is the worst midpoint error."""

    s: np.ndarray
    hd: np.ndarray
    error: float

    @property
    def n(self) -> int:
        return len(self.s)


def _exact(model: _tr.TransmittanceModel, medium: bool, ln_y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The exact sampler's ``(ln t, d ln t / d ln y)`` at ``ln y``."""
    m: Any = model  # the models' methods take scalars or arrays
    y = np.exp(ln_y)
    u = -np.expm1(-y)
    if medium:
        t = np.asarray(m.sample_medium(u), dtype=np.float64)
        hazard = np.asarray(m.medium_medium(t)) / np.asarray(m.medium_surface(t))
    else:
        t = np.asarray(m.sample_surface(u), dtype=np.float64)
        hazard = np.asarray(m.pdf(t)) / np.asarray(m.tr(t))
    with np.errstate(all="ignore"):
        return np.log(t), y / (t * hazard)


def hermite_np(s0: Any, d0: Any, s1: Any, d1: Any, f: Any) -> Any:
    """Cubic Hermite interpolation on ``[0, 1]`` with end slopes ``d`` (already
    multiplied by the node spacing)."""
    f2 = f * f
    f3 = f2 * f
    return (2 * f3 - 3 * f2 + 1) * s0 + (f3 - 2 * f2 + f) * d0 + (-2 * f3 + 3 * f2) * s1 + (f3 - f2) * d1


def flight_table(model: _tr.TransmittanceModel, medium: bool) -> FlightTable:
    """Tabulate the flight sampler of ``model`` (``1 - Tr`` from a surface,
    ``1 - T_ms`` from a medium vertex for the reciprocal kernel), checked at
    every interval midpoint against the exact sampler."""
    worst = math.inf
    for n in TABLE_NODES:
        h = (LN_Y_MAX - LN_Y_MIN) / (n - 1)
        ln_y = LN_Y_MIN + h * np.arange(n)
        s, d = _exact(model, medium, ln_y)
        mid = ln_y[:-1] + 0.5 * h
        want, _ = _exact(model, medium, mid)
        got = hermite_np(s[:-1], h * d[:-1], s[1:], h * d[1:], 0.5)
        with np.errstate(invalid="ignore"):
            err = np.abs(got - want)
        worst = float(np.max(err)) if np.isfinite(err).all() and np.isfinite(d).all() else math.inf
        if worst <= TABLE_MAX_ERROR:
            return FlightTable(s, h * d, worst)
    raise MediumParameterError(
        f"{model!r}: the tabulated flight sampler misses its accuracy ({worst:.3g} > {TABLE_MAX_ERROR} on ln t); "
        "the parameters are too extreme for fgf_volpath"
    )


@dataclass
class MediumData:
    """What the integrator needs of one medium: per channel the gamma
    parameters, the albedo, the kernel and (for pink noise and
    Davis–Weinstein) the flight tables ``[surface, medium]``."""

    gamma: list[Gamma]
    albedo: tuple[float, float, float]
    reciprocal: bool
    tables: list[list[Optional[FlightTable]]] = field(default_factory=list)


def iterative(g: Gamma) -> bool:
    """Models whose flights have no closed-form inverse: ``0 < e < 1``, ``k > 0``."""
    return 0.0 < g.e < 1.0 and g.k > 0.0


def medium_data(models: Sequence[_tr.TransmittanceModel], albedo: Sequence[float], reciprocal: bool) -> MediumData:
    """Reduce three channel models to :class:`MediumData` (tables shared by
    identical channels)."""
    gam = [gamma_of(m) for m in models]
    tables: list[list[Optional[FlightTable]]] = []
    for c, (m, g) in enumerate(zip(models, gam)):
        if c > 0 and g == gam[c - 1]:
            tables.append(tables[-1])
        elif iterative(g):
            tables.append([flight_table(m, False), flight_table(m, True)])
        else:
            tables.append([None, None])
    return MediumData(gam, (float(albedo[0]), float(albedo[1]), float(albedo[2])), reciprocal, tables)


def exponential_data(sigma_t: Sequence[float], albedo: Sequence[float]) -> MediumData:
    """A classical homogeneous medium (``k = 0``: ``Tr = exp(-σ t)``)."""
    gam = [Gamma(float(s), 0.0, 0.0, float(s)) for s in sigma_t]
    return MediumData(gam, (float(albedo[0]), float(albedo[1]), float(albedo[2])), False, [[None, None]] * 3)
