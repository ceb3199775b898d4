"""Figure group 5a, comparisons (``docs/theory.md`` §4, §5.5), on the scene of
group 4 (:mod:`fgf.figures.renders`).

* **Kernels**: the same FGF medium (pink H = -0.1 and 2-fBm H = 1.2) under
  the energy-conserving kernel (Guo 2019) and the reciprocal kernel
  (Bitterli 2018).
* **Bitterli**: Bitterli et al.'s Davis medium (α = σ_m²/(S_kf L^(2H)) of
  the 2-fBm) under the energy-conserving kernel, under the reciprocal
  kernel, and the exact truth (:func:`fgf.truth`, §6), with the difference
  images and the cube- and shadow-region differences. That the Bitterli
  models equal FGF media (Davis–Weinstein with h = H+1, c =
  S_p^(1/(2H+2))/σ_m ≡ pink noise, Davis ≡ k-fBm; §3.5) is checked in
  numbers only (``results.json`` ``bitterli.davis*``).

The third comparison of §5.5 (model vs explicit realizations) is the group
:mod:`fgf.figures.ensemble`.

Each row shows the two images and their difference (same exposure; the
difference in a diverging colour map). The number reported is the mean
relative error ``Σ|a - b| / Σ|b|`` over all pixels and channels (b the
reference: the reciprocal kernel, the FGF medium, the truth); also the level
Monte Carlo noise alone would give (:func:`noise_level`).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import numpy.typing as npt

from ._common import Context, Figure, GroupResult, Unavailable, need, new_figure, save_figure, srgb_preview
from .renders import CUBE_DIAGONAL, EXPOSURE, SCENE, SIGMA_M, SW_RENDER, defines_for, image_stats, render, settings

TITLE = "5a. Comparisons: energy-conserving vs reciprocal kernel; Bitterli's model under both kernels vs the truth"


def steps(quick: bool) -> int:
    return 4 + 2 + 3


def mean_relative_error(a: np.ndarray, b: np.ndarray) -> float:
    """Σ|a - b| / Σ|b| over all pixels and channels: normalising by the
    image total, not per pixel, keeps dark pixels from dominating."""
    den = float(np.abs(b).sum())
    return float(np.abs(a - b).sum() / den) if den > 0 else 0.0


def noise_level(var_a: np.ndarray, var_b: np.ndarray, b: np.ndarray) -> float:
    """The mean relative error two renders of the *same* expected image
    would show from Monte Carlo noise alone: E|a - b| = sqrt(2/π) ·
    sqrt(var_a + var_b) per pixel for Gaussian pixel errors, summed and
    divided by Σ|b| like :func:`mean_relative_error`."""
    den = float(np.abs(b).sum())
    return float(np.sqrt(2.0 / np.pi) * np.sqrt(var_a + var_b).sum() / den) if den > 0 else 0.0


#: One row of a comparison figure: (label_a, img_a, label_b, img_b, row_title).
Row = tuple[str, npt.NDArray[np.float64], str, npt.NDArray[np.float64], str]


def _rows_figure(ctx: Context, rows: Sequence[Row], name: str, title: str, caption: str) -> Figure:
    """rows: (label_a, img_a, label_b, img_b, row_title) -> a 3-column grid."""
    fig = new_figure(10, 3.3 * len(rows))
    axes = np.atleast_2d(fig.subplots(len(rows), 3))
    for r, (la, a, lb, b, rt) in enumerate(rows):
        axes[r, 0].imshow(srgb_preview(a, EXPOSURE))
        axes[r, 0].set_title(f"{rt}\n{la}", fontsize=9)
        axes[r, 1].imshow(srgb_preview(b, EXPOSURE))
        axes[r, 1].set_title(lb, fontsize=9)
        d = (a - b).mean(axis=2)
        lim = float(np.percentile(np.abs(d), 99.5)) or 1.0
        im = axes[r, 2].imshow(d, cmap="RdBu_r", vmin=-lim, vmax=lim)
        axes[r, 2].set_title(f"difference (mean of RGB)\nmean rel. error {mean_relative_error(a, b):.3f}", fontsize=9)
        fig.colorbar(im, ax=axes[r, 2], shrink=0.8, label="radiance")
        for ax in axes[r]:
            ax.set_axis_off()
    return Figure(save_figure(fig, ctx.out, name), title, caption)


def _kernels(ctx: Context, res: dict[str, Any]) -> Figure:
    seed = ctx.seed + 600
    rows = []
    for hurst in (-0.1, 1.2):
        sw = SW_RENDER
        imgs = {}
        for kernel in ("energy_conserving", "reciprocal"):
            imgs[kernel] = render(ctx, defines_for("fgf", hurst=hurst, sw=sw, kernel=kernel), seed, return_variance=True)
            ctx.tick()
        (ec, ec_var), (rc, rc_var) = imgs["energy_conserving"], imgs["reciprocal"]
        res[f"H={hurst}"] = {
            "hurst": hurst,
            "sw": sw,
            "energy_conserving": image_stats(ec),
            "reciprocal": image_stats(rc),
            "mean_relative_difference": mean_relative_error(ec, rc),
            "noise_level": noise_level(ec_var, rc_var, rc),
        }
        rows.append(("energy-conserving", ec, "reciprocal", rc, f"H = {hurst}, S_w = {sw:.3g}"))
    s = settings(ctx.quick)
    return _rows_figure(
        ctx,
        rows,
        "comparison_kernels.png",
        "Energy-conserving vs reciprocal kernel",
        f"The FGF media of figure 4 (pink H = −0.1, 2-fBm H = 1.2; σ_m = {SIGMA_M:g}) under the energy-conserving "
        "kernel (Guo 2019: free flights from −dTr/dt whatever the segment start) and the reciprocal kernel "
        "(Bitterli 2018: T_sm from surfaces, T_mm from medium vertices). The kernels differ by design "
        "(docs/theory.md §4); the difference is largest where light scatters many times. The mean relative "
        "error expected from Monte Carlo noise alone is in results.json (noise_level). "
        f"{s['res']}², {s['spp']} spp, seed {seed}.",
    )


def _identity_checks(ctx: Context, res: dict[str, Any]) -> None:
    """The Bitterli models with the parameters that make them equal to FGF
    media (docs/theory.md §3.5), same seed, reciprocal kernel: the images
    must agree to the rounding of the parameters (the random streams are
    shared). Numbers only (``results.json``), at 16 spp: an image of two
    identical renders would show nothing."""
    seed = ctx.seed + 700
    Fgf = need("Fgf")
    # Pink noise = Davis–Weinstein with h = H+1, c = S_p^(1/(2H+2))/σ_m.
    hurst = -0.1
    sw = SW_RENDER
    mapped = Fgf(SIGMA_M, hurst=hurst, sw=sw).to_davis_weinstein()
    h, c = float(mapped.h), float(mapped.c)
    dw = render(ctx, defines_for("davis_weinstein", h=h, c=c, kernel="reciprocal"), seed, spp=16)
    fp = render(ctx, defines_for("fgf", hurst=hurst, sw=sw, kernel="reciprocal"), seed, spp=16)
    ctx.tick()
    res["davis_weinstein"] = {
        "hurst": hurst,
        "sw": sw,
        "h": h,
        "c": c,
        "davis_weinstein": image_stats(dw),
        "fgf": image_stats(fp),
        "mean_relative_error": mean_relative_error(dw, fp),
    }
    # k-fBm = Davis with α = σ_m²/(S_kf L^(2H)), L = √3.
    hurst = 1.2
    alpha = float(Fgf(SIGMA_M, hurst=hurst, sw=sw, length=CUBE_DIAGONAL).to_davis().alpha)
    dv = render(ctx, defines_for("davis", alpha=alpha, kernel="reciprocal"), seed, spp=16)
    fk = render(ctx, defines_for("fgf", hurst=hurst, sw=sw, kernel="reciprocal"), seed, spp=16)
    ctx.tick()
    res["davis"] = {
        "hurst": hurst,
        "sw": sw,
        "alpha": alpha,
        "davis": image_stats(dv),
        "fgf": image_stats(fk),
        "mean_relative_error": mean_relative_error(dv, fk),
    }


def _bitterli(ctx: Context, res: dict[str, Any]) -> Figure:
    """Bitterli's Davis medium under the energy-conserving kernel, the
    reciprocal kernel and the exact truth (docs/theory.md §6.3)."""
    import fgf

    from .truth import region_difference, region_masks, truth_spp, CAMERA, LIGHT_CENTRE

    _identity_checks(ctx, res)
    seed = ctx.seed + 750
    Fgf = need("Fgf")
    need("truth")
    hurst, sw = 1.2, SW_RENDER
    alpha = float(Fgf(SIGMA_M, hurst=hurst, sw=sw, length=CUBE_DIAGONAL).to_davis().alpha)
    imgs = {}
    for k, kernel in enumerate(("energy_conserving", "reciprocal")):
        imgs[kernel] = render(ctx, defines_for("davis", alpha=alpha, kernel=kernel), seed + k, return_variance=True)
        ctx.tick()
    s = settings(ctx.quick)
    scene = ctx.scene_dir / SCENE
    d = dict(defines_for("davis", alpha=alpha), res=str(s["res"]))
    try:
        tr32, se32 = fgf.truth(str(scene), spp=truth_spp(ctx.quick), seed=seed + 2, defines=d, progress=False, return_stderr=True)
        nodes = fgf.truth_plan(str(scene), defines=d).nodes
    except fgf.FgfError as e:
        raise Unavailable(f"fgf.truth cannot compute the truth of {scene.name} with {d}: {e}") from e
    ctx.tick()
    tr, tr_se = np.asarray(tr32, dtype=np.float64), np.asarray(se32, dtype=np.float64)
    masks = region_masks(s["res"], CAMERA, LIGHT_CENTRE)
    (ec, ec_var), (rc, rc_var) = imgs["energy_conserving"], imgs["reciprocal"]
    res["truth"] = {"alpha": alpha, "nodes": nodes, "truth_spp_per_node": truth_spp(ctx.quick), "truth": image_stats(tr)}
    for kernel, (img, var) in imgs.items():
        res["truth"][kernel] = {
            "image": image_stats(img),
            "mean_relative_error": mean_relative_error(img, tr),
            "noise_level": noise_level(var, tr_se**2, tr),
            **{region: region_difference(img, var, tr, tr_se, m) for region, m in zip(("cube", "shadow"), masks)},
        }
    ecr, rcr = res["truth"]["energy_conserving"], res["truth"]["reciprocal"]
    rows: list[Row] = [
        ("energy-conserving kernel", ec, "truth", tr, f"Davis α = {alpha:.3g}"),
        ("reciprocal kernel", rc, "truth", tr, f"Davis α = {alpha:.3g}"),
    ]
    return _rows_figure(
        ctx,
        rows,
        "comparison_bitterli.png",
        "Bitterli's Davis medium: both kernels against the truth",
        f"Bitterli et al.'s Davis power law, α = {alpha:.3g} (≡ the 2-fBm of figure 4, H = 1.2, S_w = {sw:g}, "
        f"L = √3; σ_m = {SIGMA_M:g}), under the energy-conserving kernel (Guo 2019) and the reciprocal kernel "
        "(Bitterli 2018), each against the exact truth: classical renders of σ = X σ_m, X ~ Gamma(α, mean 1), "
        f"averaged by {nodes}-node generalised Gauss–Laguerre quadrature (docs/theory.md §6). Cube region: "
        f"energy-conserving {100 * ecr['cube']['relative_difference']:+.1f} ± {100 * ecr['cube']['se']:.1f} %, reciprocal "
        f"{100 * rcr['cube']['relative_difference']:+.1f} ± {100 * rcr['cube']['se']:.1f} %; shadow region: "
        f"{100 * ecr['shadow']['relative_difference']:+.1f} ± {100 * ecr['shadow']['se']:.1f} % and "
        f"{100 * rcr['shadow']['relative_difference']:+.1f} ± {100 * rcr['shadow']['se']:.1f} %. The Bitterli models "
        "equal FGF media exactly (Davis ≡ k-fBm, Davis–Weinstein ≡ pink noise; mean relative errors in "
        f"results.json). {s['res']}², {s['spp']} spp, truth {truth_spp(ctx.quick)} spp per node.",
    )


def run(ctx: Context) -> GroupResult:
    res: dict[str, Any] = {"kernels": {}, "bitterli": {}}
    figs = [_kernels(ctx, res["kernels"]), _bitterli(ctx, res["bitterli"])]
    return GroupResult(figs, res)
