"""Per-sample transmittance math in Dr.Jit (``docs/theory.md`` §3–4).

Every function works on the current Mitsuba variant's types: ``mi.Float`` or
``mi.Color3f`` lanes in the JIT variants, Python floats and
``dr.scalar.Array3f`` in ``scalar_rgb``. Divisions go through ``dr.rcp``,
which gives ``inf`` for 0 in every variant (a Python ``/`` would raise in
the scalar ones), and every singular point is resolved by ``dr.select``.

The models are the gamma closure of fgf-core (``transmittance/mod.rs``):
``ln Tr = -σ t g(x)``, ``x = k t^e``, ``g(x) = ln(1+x)/x``,
``q(x) = (1-e) g(x) + e/(1+x)``, and

* ``T_ss = Tr``, ``T_sm = σ Tr q`` (the free-flight pdf from a surface),
* ``T_ms = T_sm/σ̄`` (``σ̄ = σ`` for ``e > 0``, ``σ g(k)`` for ``e = 0``),
* ``T_mm = -dT_ms/dt = Tr (σ q² + e x (-q'(x)) / t)``.

Flights: closed forms for ``e = 0`` (exponential with ``σ̄``) and ``e = 1``
(Davis / k-fBm: ``t = expm1(y/α')/k``); pink noise and Davis–Weinstein use
the tabulated exact inverse of ``_params.flight_table`` (cubic Hermite in
``ln y``), gathered from a Dr.Jit array.
"""

from __future__ import annotations

import importlib
from typing import Any

from ._params import LN_Y_MAX, LN_Y_MIN

# Dr.Jit's types depend on the Mitsuba variant chosen at run time; its stubs
# describe none of them in particular, so it is imported as `Any` (this also
# keeps mypy from analysing the large Dr.Jit/Mitsuba stubs).
dr: Any = importlib.import_module("drjit")

# Dr.Jit values of the current variant: typed loosely on purpose (the
# concrete classes depend on the variant chosen at run time).
Value = Any


def ln_1p(x: Value) -> Value:
    """``ln(1 + x)`` with full relative accuracy for small ``x`` (Goldberg's
    correction ``ln(u)·x/(u-1)``, ``u = 1 + x`` rounded), ``x > -1``."""
    u = 1.0 + x
    d = u - 1.0
    r = dr.log(u) * (x * dr.rcp(dr.select(d == 0, 1.0, d)))
    return dr.select(d == 0, x, dr.select(dr.isinf(u), u, r))


def expm1(x: Value) -> Value:
    """``exp(x) - 1`` with full relative accuracy for small ``x`` (Kahan's
    ``(u-1)·x/ln u``, ``u = e^x`` rounded)."""
    u = dr.exp(x)
    lu = dr.log(u)
    r = (u - 1.0) * (x * dr.rcp(dr.select(lu == 0, 1.0, lu)))
    return dr.select(u == 1.0, x, dr.select(dr.isinf(u), u, r))


def g(x: Value) -> Value:
    """``g(x) = ln(1+x)/x``; ``g(0) = 1``, ``g(inf) = 0``."""
    series = 1.0 - x * (0.5 - x * (1.0 / 3.0 - x * 0.25))
    direct = ln_1p(x) * dr.rcp(dr.select(x == 0, 1.0, x))
    return dr.select(x < 1e-3, series, dr.select(dr.isinf(x), 0.0, direct))


def x_neg_dg(x: Value) -> Value:
    """``x (-g'(x)) = g(x) - 1/(1+x)``; series below 0.1 (no cancellation)."""
    # Σ_{m≥0} (-1)^m (m+1) x^(m+1) / (m+2), 10 terms: 1e-10 relative at 0.1.
    acc = 0.0 * x
    for m in range(9, -1, -1):
        acc = acc * x + (-1.0) ** m * (m + 1) / (m + 2)
    series = acc * x
    direct = g(x) - dr.rcp(1.0 + x)
    return dr.select(x < 0.1, series, dr.select(dr.isinf(x), 0.0, direct))


def x_of(k: Value, e: Value, t: Value) -> Value:
    """``x(t) = k t^e``; ``x = k`` for ``e = 0``, ``x(0) = 0`` for ``e > 0``."""
    te = dr.exp(e * dr.log(dr.select(t > 0, t, 1.0)))
    x = dr.select(t > 0, k * te, 0.0)
    return dr.select(e == 0, k, dr.select(k == 0, 0.0, x))


def tr_q(sigma: Value, k: Value, e: Value, t: Value) -> tuple[Value, Value, Value]:
    """``(Tr(t), q(x(t)), x(t))`` for ``t ≥ 0`` (``Tr(inf) = 0``)."""
    x = x_of(k, e, t)
    gx = g(x)
    fin = dr.isfinite(t)
    tr = dr.select(fin, dr.exp(-sigma * dr.select(fin, t, 0.0) * gx), 0.0)
    q = (1.0 - e) * gx + e * dr.rcp(1.0 + x)
    return tr, q, x


def tr(sigma: Value, k: Value, e: Value, t: Value) -> Value:
    """``Tr(t) = T_ss(t)``."""
    return tr_q(sigma, k, e, t)[0]


def surface_medium(sigma: Value, k: Value, e: Value, t: Value) -> Value:
    """``T_sm(t) = -dTr/dt``: the free-flight pdf from a surface."""
    t_r, q, _ = tr_q(sigma, k, e, t)
    return sigma * t_r * q


def medium_surface(sigma: Value, k: Value, e: Value, t: Value) -> Value:
    """``T_ms(t) = T_sm(t)/σ̄`` (``= Tr`` for ``e = 0``)."""
    t_r, q, _ = tr_q(sigma, k, e, t)
    return dr.select(e == 0, t_r, t_r * q)


def medium_medium(sigma: Value, k: Value, e: Value, sigma_bar: Value, t: Value) -> Value:
    """``T_mm(t) = -dT_ms/dt``: the free-flight pdf from a medium vertex;
    ``T_mm(0) = inf`` for ``0 < e < 1``, ``σ + k`` for ``e = 1``."""
    t_r, q, x = tr_q(sigma, k, e, t)
    bx = dr.select(dr.isinf(x), 0.0, x * dr.rcp(dr.square(1.0 + x)))
    x_neg_dq = (1.0 - e) * x_neg_dg(x) + e * bx
    pos = t > 0
    v = t_r * (sigma * q * q + e * x_neg_dq * dr.rcp(dr.select(pos, t, 1.0)))
    at0 = dr.select(e < 1.0, dr.inf, sigma + k)
    v = dr.select(pos, dr.select(t_r == 0, 0.0, v), at0)
    return dr.select(e == 0, sigma_bar * t_r, v)


def hermite(s0: Value, d0: Value, s1: Value, d1: Value, f: Value) -> Value:
    """Cubic Hermite interpolation on ``[0, 1]`` (slopes times the spacing)."""
    f2 = f * f
    f3 = f2 * f
    return (2.0 * f3 - 3.0 * f2 + 1.0) * s0 + (f3 - 2.0 * f2 + f) * d0 + (-2.0 * f3 + 3.0 * f2) * s1 + (f3 - f2) * d1


def table_position(ln_y: Value, n: Value) -> tuple[Value, Value, Value]:
    """For a table of ``n`` nodes: the clamped fractional node position
    ``xc ∈ [0, n-1]``, the extrapolation distance ``x - xc`` and the
    interval's fractional part ``f`` (the interval index is ``xc - f``)."""
    nf = n - 1.0
    x = (ln_y - LN_Y_MIN) * (nf * (1.0 / (LN_Y_MAX - LN_Y_MIN)))
    xc = dr.clip(x, 0.0, nf)
    i = dr.minimum(dr.floor(xc), nf - 1.0)
    return xc, x - xc, xc - i
