"""Figure group 2, numerical verification of var[σ̄_t] (``docs/theory.md`` §2,
§5.2).

Three independent routes to the same number:

* **closed form**: ``fgf.line_average_variance`` (S_w/t, S_p t^(2H),
  S_kf L^(2H));
* **quadrature** (scipy, independent of fgf's closed forms):

  - pink noise: ``(1/t²) ∫∫_[0,t]² C S_w |x-y|^(2H)`` reduced to the exact
    1D identity ``(2/t²) ∫_0^t (t-u) C S_w u^(2H) du`` for a stationary
    covariance, integrated by ``scipy.integrate.quad`` with the algebraic
    weight ``u^(2H)`` (QAWS), which handles the integrable singularity at
    u = 0 exactly; only C(H,1) comes from fgf (``fgf.c_const``);
  - k-fBm: the point variance of the anchored field averaged over [0, L],
    ``(1/L) ∫_0^L cov(x, x) dx``, with the covariance of §1 (Taylor
    subtraction) evaluated by :func:`fgf.figures.family.kfbm_covariance`;

* **Monte Carlo** over exact 1D realizations, with standard errors:

  - pink/white noise: ``fgf.sample_optical_depth`` gives τ_u(t) on a grid;
    since E[τ_u] = 0, ``v̂ = mean((τ_u/t)²)`` is unbiased and its standard
    error is ``std((τ_u/t)²)/sqrt(n)``;
  - k-fBm: ``fgf.sample_kfbm_1d`` on [0, L]; per path
    ``y = (1/L) ∫_0^L M(x)² dx`` (trapezoid rule on the sampling grid), so
    ``E[y] = S_kf L^(2H)``; ``v̂ = mean(y)``, SE = ``std(y)/sqrt(n)``.

``results.json`` holds each estimate with its SE and its z-score
``(v̂ - closed)/SE``; the tests check ``|z| ≤ 4``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ._common import Context, Figure, GroupResult, floats, need, new_figure, save_figure
from .family import _paths, kfbm_covariance

if TYPE_CHECKING:
    from matplotlib.axes import Axes

TITLE = "2. Numerical verification of var[σ̄_t]"

#: White (-0.5) and pink noise.
HURST_PINK = (-0.5, -0.4, -0.25, -0.1)
#: 1-fBm and 2-fBm.
HURST_KFBM = (0.2, 0.85, 1.2, 1.8)
SW = 1.0


def steps(quick: bool) -> int:
    return len(HURST_PINK) + len(HURST_KFBM)


def quad_pink(hurst: float, sw: float, t: float) -> float:
    """(1/t²)∫∫ cov over [0,t]² by QAWS quadrature (see the module docs)."""
    from scipy.integrate import quad

    c: float = need("c_const")(hurst, 1)
    val, _err = quad(lambda u: t - u, 0.0, t, weight="alg", wvar=(2.0 * hurst, 0.0), epsabs=0.0, epsrel=1e-12)
    return 2.0 * c * sw * val / t**2


def quad_kfbm(hurst: float, sw: float, length: float) -> float:
    """(1/L)∫_0^L cov(x, x) dx by adaptive quadrature; the integrand behaves
    as x^(2H) at 0, integrable for H > 0 (``points`` helps QUADPACK there)."""
    from scipy.integrate import quad

    def f(x: float) -> float:
        return float(kfbm_covariance(hurst, sw, np.float64(x), np.float64(x)))

    val, _err = quad(f, 0.0, length, epsabs=0.0, epsrel=1e-10, limit=200)
    return val / length


def _pink(ctx: Context, res: dict[str, Any], ax: Axes) -> None:
    lav = need("line_average_variance")
    sod = need("sample_optical_depth")
    n_rays = 2000 if ctx.quick else 10000
    n_steps = 1000
    t_max = 10.0
    # MC at log-spaced grid indices of the exact sampler (dt = t_max/n_steps).
    idx = np.array([1, 2, 5, 10, 20, 50, 100, 200, 500, 1000])
    t_mc = idx * t_max / n_steps
    t_dense = np.logspace(-2, 1, 60)
    t_quad = np.logspace(-2, 1, 7)
    colors = ["k", "C0", "C1", "C2"]
    for color, hurst in zip(colors, HURST_PINK):
        closed = np.asarray(lav(hurst, SW, t_dense), dtype=float)
        tau = _paths(sod(n_rays, n_steps, t_max, hurst, SW, ctx.seed + 200 + int(1000 * -hurst), progress=False))
        y = (tau[:, idx] / t_mc) ** 2
        est = y.mean(axis=0)
        se = y.std(axis=0, ddof=1) / np.sqrt(n_rays)
        closed_mc = np.asarray(lav(hurst, SW, t_mc), dtype=float)
        label = "white" if hurst == -0.5 else f"pink H = {hurst}"
        ax.loglog(t_dense, closed, "-", color=color, lw=1.2, label=f"{label}: closed form")
        entry = {
            "hurst": hurst,
            "sw": SW,
            "n_rays": n_rays,
            "t_closed": floats(t_dense),
            "closed": floats(closed),
            "t_mc": floats(t_mc),
            "mc": floats(est),
            "mc_se": floats(se),
            "closed_at_mc": floats(closed_mc),
            "z": floats((est - closed_mc) / se),
        }
        if hurst > -0.5:
            # White noise has a delta covariance: there is nothing to integrate.
            q = np.array([quad_pink(hurst, SW, t) for t in t_quad])
            qc = np.asarray(lav(hurst, SW, t_quad), dtype=float)
            ax.loglog(t_quad, q, "s", mfc="none", color=color, ms=7)
            entry.update(t_quad=floats(t_quad), quad=floats(q), quad_rel_error=floats(np.abs(q / qc - 1)))
        ax.errorbar(t_mc, est, yerr=se, fmt="o", ms=3, color=color, capsize=2)
        res[f"H={hurst}"] = entry
        ctx.tick()
    ax.plot([], [], "s", mfc="none", color="gray", label="quadrature of the covariance")
    ax.plot([], [], "o", color="gray", label=f"Monte Carlo, {n_rays} exact rays (±1 SE)")
    ax.set_xlabel("segment length t")
    ax.set_ylabel("var[σ̄_t]")
    ax.set_title("white and pink noise: slope 2H against t")
    ax.legend(fontsize=7)


def _kfbm(ctx: Context, res: dict[str, Any], ax: Axes) -> None:
    lav = need("line_average_variance")
    skf = need("sample_kfbm_1d")
    n_samples = 1000 if ctx.quick else 8000
    n_steps = 128 if ctx.quick else 256
    lengths = np.array([0.25, 0.5, 1.0, 2.0, 4.0])
    l_dense = np.logspace(np.log10(0.2), np.log10(5.0), 40)
    for color, hurst in zip(["C3", "C4", "C5", "C6"], HURST_KFBM):
        # The model's var[σ̄_t] for k-fBm does not depend on t (docs/theory.md §2);
        # t = 1 is an arbitrary segment length.
        closed = np.array([float(lav(hurst, SW, 1.0, length=L)) for L in l_dense])
        closed_mc = np.array([float(lav(hurst, SW, 1.0, length=L)) for L in lengths])
        est_list: list[float] = []
        se_list: list[float] = []
        for i, L in enumerate(lengths):
            m = _paths(skf(n_samples, n_steps, float(L), hurst, SW, ctx.seed + 300 + 10 * i + int(10 * hurst), progress=False))
            m2 = m**2
            # Trapezoid rule (written out: np.trapezoid needs numpy >= 2).
            y = 0.5 * (m2[:, :-1] + m2[:, 1:]).sum(axis=1) * (L / n_steps) / L
            est_list.append(y.mean())
            se_list.append(y.std(ddof=1) / np.sqrt(n_samples))
        est, se = np.array(est_list), np.array(se_list)
        q = np.array([quad_kfbm(hurst, SW, L) for L in lengths])
        k = int(np.ceil(hurst))
        ax.loglog(l_dense, closed, "-", color=color, lw=1.2, label=f"{k}-fBm H = {hurst}: S_kf L^(2H)")
        ax.loglog(lengths, q, "s", mfc="none", color=color, ms=7)
        ax.errorbar(lengths, est, yerr=se, fmt="o", ms=3, color=color, capsize=2)
        res[f"H={hurst}"] = {
            "hurst": hurst,
            "sw": SW,
            "n_samples": n_samples,
            "n_steps": n_steps,
            "length_closed": floats(l_dense),
            "closed": floats(closed),
            "length_mc": floats(lengths),
            "mc": floats(est),
            "mc_se": floats(se),
            "closed_at_mc": floats(closed_mc),
            "z": floats((est - closed_mc) / se),
            "quad": floats(q),
            "quad_rel_error": floats(np.abs(q / closed_mc - 1)),
        }
        ctx.tick()
    ax.plot([], [], "s", mfc="none", color="gray", label="quadrature of the point variance")
    ax.plot([], [], "o", color="gray", label=f"Monte Carlo, {n_samples} exact paths (±1 SE)")
    ax.set_xlabel("characteristic length L")
    ax.set_ylabel("var[σ̄_t]")
    ax.set_title("k-fBm: slope 2H against L")
    from matplotlib.ticker import NullFormatter

    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.legend(fontsize=7)


def run(ctx: Context) -> GroupResult:
    res: dict[str, Any] = {"pink": {}, "kfbm": {}}
    fig = new_figure(12, 5)
    ax1, ax2 = fig.subplots(1, 2)
    _pink(ctx, res["pink"], ax1)
    _kfbm(ctx, res["kfbm"], ax2)
    name = save_figure(fig, ctx.out, "variance.png")
    n_rays = res["pink"]["H=-0.5"]["n_rays"]
    n_paths = res["kfbm"][f"H={HURST_KFBM[0]}"]["n_samples"]
    caption = (
        f"Variance of the line-averaged extinction, S_w = {SW}. Left: white and pink noise against the "
        "segment length t (lines: closed form S_w/t and S_p t^(2H); squares: quadrature of the covariance "
        f"C S_w |x-y|^(2H); dots: Monte Carlo over {n_rays} exact rays per H, ±1 standard error). "
        "Right: anchored k-fBm against the characteristic length L (lines: S_kf L^(2H); squares: quadrature "
        f"of the point variance over [0, L]; dots: Monte Carlo over {n_paths} exact paths). The largest "
        "|z| = |MC − closed|/SE is listed in results.json."
    )
    zmax = max(
        float(np.max(np.abs(e["z"]))) for part in ("pink", "kfbm") for e in res[part].values()
    )
    res["max_abs_z"] = zmax
    return GroupResult([Figure(name, "var[σ̄_t]: closed form, quadrature, Monte Carlo", caption + f" Here max |z| = {zmax:.2f}.")], res)
