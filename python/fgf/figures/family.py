"""Figure group 1, the FGF family (``docs/theory.md`` §1, §5.1).

* 1D covariance-matrix images of pink noise and k-fBm on [0, 1].

  - Pink noise has a point covariance ``C S_w |x-y|^(2H)`` that diverges on
    the diagonal, so the image shows the covariance of *cell averages* over
    n cells of width dx: the cell average is an increment of the optical
    depth τ_u, an fBm of Hurst h = H+1 (§1, "Exact 1D samplers"), so
    ``cov_ij = v_dx · ½(|j-i+1|^(2h) - 2|j-i|^(2h) + |j-i-1|^(2h))`` with
    ``v_dx = var[σ̄_dx]`` taken from ``fgf.line_average_variance``.
  - k-fBm (anchored at x = 0) has a finite point covariance, the Taylor
    subtraction of §1 in 1D, with ``C(H,1)`` from ``fgf.c_const``.
  - Each image is checked against the sample covariance of exact 1D
    realizations (``fgf.sample_optical_depth`` / ``fgf.sample_kfbm_1d``);
    the relative Frobenius error is reported beside its expected size for
    Gaussian paths, ``sqrt((1 + (tr Σ)²/||Σ||²_F) / n_paths)``.

* 2D realizations (``fgf.synthesize``) for H = -0.4, 0.2, 0.85, 1.2, 1.8,
  with one seed for all panels so that the same white noise is shaped by
  each H; k-fBm fields are anchored at the centre.
"""

from __future__ import annotations

from typing import Any, Union, cast

import numpy as np
import numpy.typing as npt

from ._common import Context, Figure, GroupResult, floats, need, new_figure, save_figure

TITLE = "1. The FGF family: covariance matrices and 2D realizations"

#: Hurst parameters of the 2D panels (the paper's).
HURST_2D = (-0.4, 0.2, 0.85, 1.2, 1.8)
#: Hurst parameters of the covariance images: pink noise and 1-/2-fBm.
HURST_COV = (-0.3, 0.5, 1.5)


def steps(quick: bool) -> int:
    return len(HURST_COV) + len(HURST_2D)


#: Positions or covariances: a float64 scalar or array.
Floats = Union[np.float64, npt.NDArray[np.float64]]


def kfbm_covariance(hurst: float, sw: float, x: Floats, y: Floats) -> Floats:
    """Covariance of the 1D k-fBm anchored at 0, for x, y > 0 (docs/theory.md §1:
    the covariance of M minus its Taylor polynomial of degree k-1 at 0)."""
    from scipy.special import binom

    c: float = need("c_const")(hurst, 1)
    k = int(np.ceil(hurst))
    a = 2.0 * hurst
    v = np.abs(x - y) ** a
    for j in range(k):
        v = v - binom(a, j) * ((-x) ** j * y ** (a - j) + (-y) ** j * x ** (a - j))
    return c * sw * v


def pink_cell_covariance(hurst: float, sw: float, n: int) -> npt.NDArray[np.float64]:
    """Covariance matrix of the averages of pink (or white) noise over n
    cells of [0, 1] (see the module docs)."""
    dx = 1.0 / n
    v_dx = float(need("line_average_variance")(hurst, sw, dx))
    two_h = 2.0 * (hurst + 1.0)
    j = np.abs(np.subtract.outer(np.arange(n), np.arange(n))).astype(float)
    cov: npt.NDArray[np.float64] = v_dx * 0.5 * ((j + 1) ** two_h - 2 * j**two_h + np.abs(j - 1) ** two_h)
    return cov


def _paths(samples: Any) -> npt.NDArray[np.float64]:
    """``(n_paths, n_steps+1)`` array of the paths returned by an exact 1D
    sampler (an array, or an object/tuple holding ``values``)."""
    if isinstance(samples, tuple):
        # (values, t) or (t, values): the paths are the 2D member.
        samples = next(s for s in samples if np.ndim(cast(Any, getattr(s, "values", s))) == 2)
    values = getattr(samples, "values", samples)
    return np.asarray(values, dtype=np.float64)


def _covariance_images(ctx: Context, res: dict[str, Any]) -> Figure:
    n = 48 if ctx.quick else 96
    n_paths = 2000 if ctx.quick else 20000
    sw = 1.0
    fig = new_figure(3.6 * len(HURST_COV), 6.6)
    axes = fig.subplots(2, len(HURST_COV))
    for col, hurst in enumerate(HURST_COV):
        seed = ctx.seed + 100 + col
        cov: Floats
        if hurst < 0:
            cov = pink_cell_covariance(hurst, sw, n)
            # Cell averages from the exact optical depth: (τ(x_{i+1}) - τ(x_i)) / dx.
            tau = _paths(need("sample_optical_depth")(n_paths, n, 1.0, hurst, sw, seed, progress=False))
            real = np.diff(tau, axis=1) * n
            label = f"pink noise, H = {hurst}"
        else:
            x = np.arange(1, n + 1) / n
            cov = kfbm_covariance(hurst, sw, x[:, None], x[None, :])
            real = _paths(need("sample_kfbm_1d")(n_paths, n, 1.0, hurst, sw, seed, progress=False))[:, 1:]
            label = f"{int(np.ceil(hurst))}-fBm, H = {hurst}"
        emp = real.T @ real / real.shape[0]  # the mean is 0 by construction
        rel = float(np.linalg.norm(emp - cov) / np.linalg.norm(cov))
        # Expected size of that error for Gaussian paths:
        # E||S - Σ||²_F = (||Σ||²_F + (tr Σ)²) / n  for the sample covariance S
        # of n zero-mean paths, so the relative error is about
        # sqrt((1 + (tr Σ)² / ||Σ||²_F) / n).
        expected = float(np.sqrt((1.0 + np.trace(cov) ** 2 / np.sum(cov**2)) / real.shape[0]))
        res[f"H={hurst}"] = {
            "hurst": hurst,
            "sw": sw,
            "n": n,
            "n_paths": n_paths,
            "covariance": floats(cov),
            "sample_covariance": floats(emp),
            "relative_frobenius_error_vs_realizations": rel,
            "expected_relative_frobenius_error": expected,
        }
        vmax = float(np.max(np.abs(cov)))
        for row, (mat, kind) in enumerate(((cov, "closed form"), (emp, f"{n_paths} exact realizations"))):
            ax = axes[row, col]
            im = ax.imshow(mat, cmap="viridis", origin="upper", extent=(0, 1, 1, 0), vmin=min(0.0, float(cov.min())), vmax=vmax)
            ax.set_title(f"{label}\n{kind}", fontsize=10)
            ax.set_xlabel("x")
            ax.set_ylabel("y")
            fig.colorbar(im, ax=ax, shrink=0.8, label="cov(x, y)")
        axes[1, col].text(0.02, 0.97, f"rel. error {rel:.3f}", transform=axes[1, col].transAxes, va="top", color="w", fontsize=9)
        ctx.tick()
    name = save_figure(fig, ctx.out, "family_covariance.png")
    return Figure(
        name,
        "1D covariance matrices",
        "Covariance matrices on [0, 1] with S_w = 1: pink noise (H = -0.3; covariance of cell averages, "
        "since the point covariance C S_w |x-y|^(2H) is infinite on the diagonal) and anchored k-fBm "
        "(H = 0.5, 1.5; point covariance, anchor at x = 0). Top: closed form (docs/theory.md §1); bottom: sample "
        "covariance of exact 1D realizations with the relative Frobenius error. Pink noise decorrelates "
        "quickly; k-fBm has long-range correlation that grows away from the anchor.",
    )


def _realizations_2d(ctx: Context, res: dict[str, Any]) -> Figure:
    n = 128 if ctx.quick else 512
    sw = 1.0
    synthesize = need("synthesize")
    fig = new_figure(3.0 * len(HURST_2D), 3.4)
    axes = fig.subplots(1, len(HURST_2D))
    for ax, hurst in zip(axes, HURST_2D):
        kwargs = {"anchor": "center"} if hurst > 0 else {}
        field = np.asarray(synthesize((n, n), hurst, sw, 1.0 / n, ctx.seed + 7, progress=False, **kwargs), dtype=np.float64)
        # Robust display range: the 1st-99th percentiles of each field.
        lo, hi = np.percentile(field, [1.0, 99.0])
        ax.imshow(field, cmap="gray", vmin=lo, vmax=hi, origin="lower", extent=(0, 1, 0, 1))
        kind = "pink noise" if hurst < 0 else f"{int(np.ceil(hurst))}-fBm"
        ax.set_title(f"H = {hurst} ({kind})", fontsize=10)
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        res[f"H={hurst}"] = {
            "hurst": hurst,
            "sw": sw,
            "n": n,
            "std": float(field.std()),
            "p01": float(lo),
            "p99": float(hi),
        }
        ctx.tick()
    name = save_figure(fig, ctx.out, "family_2d.png")
    return Figure(
        name,
        "2D fractional Gaussian fields",
        f"Realizations on a {n}×{n} grid over [0, 1]², S_w = 1, the same white noise (seed {ctx.seed + 7}) "
        "for every H; k-fBm fields anchored at the centre; grey levels span each field's 1st–99th "
        "percentiles. Correlation grows with H: rough pink noise (H < 0), fBm (0 < H < 1), smooth 2-fBm.",
    )


def run(ctx: Context) -> GroupResult:
    res: dict[str, Any] = {"covariance": {}, "realizations_2d": {}}
    figs = [_covariance_images(ctx, res["covariance"]), _realizations_2d(ctx, res["realizations_2d"])]
    return GroupResult(figs, res)
