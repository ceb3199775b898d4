"""Figure group 5c, the model against the exact truth (``docs/theory.md`` §6;
numbers discussed in ``docs/validation.md`` "The model against the exact
truth").

A k-fBm medium (H = 1.2, L = √3) has a constant gamma shape α, and the
random medium behind it is homogeneous along rays in each realization,
``σ = X σ_m``, ``X ~ Gamma(α, mean 1)``; :func:`fgf.truth` averages
classical renders over ``X`` by quadrature. On the scene of group 4
(``medium_on_ground.xml``: σ_m = 2, albedo 0.8) and for α = 1.14 (the 2-fBm
of figure 4, S_w = 4), 2, 4 and 8 (S_w chosen for each α), the model is
rendered under the energy-conserving and the reciprocal kernel and compared
with the truth in two regions of the image: the cube (pixels whose camera
ray crosses it) and its shadow on the ground (ground points whose segment
to the light's centre crosses the cube, not seen through the cube).

``comparison_truth.png`` shows, for α = 1.14, the two model renders, the
truth, the two differences and the standard error of a difference, and the
region differences against α with ±1 SE bars. ``results.json`` (group
``truth``, also the top-level ``"truth"``) holds, per α and kernel, each
region's relative difference ``(model - truth)/truth`` and its standard
error (from the per-pixel variances of the model render and of the
truth's node renders).

If the scene directory has the hero scene ``striped_wall.xml`` (σ_m = 4,
S_w = 16), the 2-fBm there is compared with its truth too (``"hero"``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from ._common import Context, Figure, GroupResult, Unavailable, new_figure, save_figure, srgb_preview
from .renders import EXPOSURE, SCENE, SIGMA_M, defines_for, render, settings, sw_for

TITLE = "5c. The model against the exact truth (k-fBm, constant α)"

HURST = 1.2
ALPHAS = (1.14, 2.0, 4.0, 8.0)
#: The α shown in the figure (the 2-fBm of figure 4).
SHOWN = 1.14
KERNELS = ("energy_conserving", "reciprocal")

#: Geometry of medium_on_ground.xml (keep in step with the scene file).
CUBE_LO = np.array([-0.5, 0.25, -0.5])
CUBE_HI = np.array([0.5, 1.25, 0.5])
CAMERA = {"origin": (0.0, 1.6, 4.0), "target": (0.0, 0.6, 0.0), "fov": 40.0}
LIGHT_CENTRE = np.array([-2.5, 2.0, 0.5])
GROUND_HALF = 4.0
#: The hero scene (striped_wall.xml, if present), same cube.
HERO_SCENE = "striped_wall.xml"
HERO_CAMERA = {"origin": (0.0, 1.6, 4.3), "target": (0.0, 0.7, -0.2), "fov": 40.0}
HERO_LIGHT_CENTRE = np.array([-3.0, 2.2, 0.8])
HERO_SIGMA_M = 4.0
HERO_SW = 16.0

Img = npt.NDArray[np.float64]
Mask = npt.NDArray[np.bool_]


def steps(quick: bool) -> int:
    # Three renders per α, three for the hero scene (ticked anyway when it is absent), the figure.
    return len(ALPHAS) * 3 + 3 + 1


def truth_spp(quick: bool) -> int:
    """Samples per pixel of each truth node: the truth's noise is
    ``sqrt(Σ w_i²)`` (≈ 0.4 for 12–24 nodes) times a node's, so a quarter
    of the model's spp makes both about equally noisy."""
    return 16 if quick else 64


def camera_rays(res: int, camera: dict[str, Any]) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Origin and unit directions ``(res, res, 3)`` of the pixel centres of a
    square perspective camera (fov along x), as fgf's camera makes them
    (image right = the camera's -left = world +x here, row 0 at the top)."""
    o = np.array(camera["origin"], dtype=np.float64)
    fwd = np.array(camera["target"], dtype=np.float64) - o
    fwd /= np.linalg.norm(fwd)
    left = np.cross([0.0, 1.0, 0.0], fwd)
    left /= np.linalg.norm(left)
    up = np.cross(fwd, left)
    tan = math.tan(math.radians(camera["fov"]) / 2.0)
    c = (np.arange(res) + 0.5) / res * 2.0 - 1.0
    nx, ny = np.meshgrid(c, c)
    d = -nx[..., None] * tan * left - ny[..., None] * tan * up + fwd
    return o, d / np.linalg.norm(d, axis=-1, keepdims=True)


def _slab_hit(o: npt.NDArray[np.float64], d: npt.NDArray[np.float64], t_max: npt.NDArray[np.float64] | float) -> Mask:
    """Whether the segments ``o + t d``, ``0 < t < t_max``, cross the cube."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t0 = (CUBE_LO - o) * inv
        t1 = (CUBE_HI - o) * inv
    near = np.nanmax(np.minimum(t0, t1), axis=-1)
    far = np.nanmin(np.maximum(t0, t1), axis=-1)
    hit: Mask = (far > np.maximum(near, 0.0)) & (near < t_max)
    return hit


def region_masks(res: int, camera: dict[str, Any], light: npt.NDArray[np.float64]) -> tuple[Mask, Mask]:
    """``(cube, shadow)`` pixel masks: the camera ray crosses the cube; the
    ray reaches the ground (y = 0) without crossing the cube, and the
    segment from that ground point to the light's centre crosses it."""
    o, d = camera_rays(res, camera)
    oo = np.broadcast_to(o, d.shape)
    cube = _slab_hit(oo, d, np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_ground = np.where(d[..., 1] < 0, -o[1] / d[..., 1], np.inf)
    p = o + d * t_ground[..., None]
    on_ground = np.isfinite(t_ground) & (np.abs(p[..., 0]) < GROUND_HALF) & (np.abs(p[..., 2]) < GROUND_HALF)
    to_light = light - np.where(on_ground[..., None], p, 0.0)
    shadow = on_ground & ~cube & _slab_hit(np.where(on_ground[..., None], p, 0.0), to_light, 1.0)
    return cube, shadow


def region_difference(model: Img, model_var: Img, truth: Img, truth_se: Img, mask: Mask) -> dict[str, float]:
    """Relative difference of the region means and its standard error.

    The region mean of an image is the mean over the mask's pixels of the
    RGB mean; its variance is the sum of the pixels' variances over the
    pixel count squared (pixels are independent), each pixel's variance
    taken as the mean of its channels' (exact for a grey scene, an upper
    bound otherwise).
    """
    n = int(mask.sum())
    if n == 0:
        raise Unavailable("an image region of the truth comparison is empty at this resolution")
    m = float(model[mask].mean())
    t = float(truth[mask].mean())
    var_m = float(model_var[mask].mean(axis=-1).sum()) / n**2
    var_t = float((truth_se[mask] ** 2).mean(axis=-1).sum()) / n**2
    rel = m / t - 1.0
    se = math.sqrt(var_m + (m / t) ** 2 * var_t) / t
    return {"model": m, "truth": t, "relative_difference": rel, "se": se, "pixels": n}


def _truth(ctx: Context, scene: str, defines: dict[str, Any], seed: int) -> tuple[Img, Img, dict[str, Any]]:
    import fgf

    s = settings(ctx.quick)
    path = ctx.scene_dir / scene
    if not path.is_file():
        raise Unavailable(f"figure scene {path} not found")
    d = dict(defines, res=str(s["res"]))
    try:
        plan = fgf.truth_plan(str(path), defines=d)
        img, se = fgf.truth(str(path), spp=truth_spp(ctx.quick), seed=seed, defines=d, progress=False, return_stderr=True)
    except AttributeError as e:
        raise Unavailable(f"fgf.truth is not usable in this build ({e}); rebuild with maturin develop") from e
    except fgf.FgfError as e:
        raise Unavailable(f"fgf.truth cannot compute the truth of {path.name} with {d}: {e}") from e
    info = {
        "alpha": plan.alpha,
        "nodes": plan.nodes,
        "tau_max": plan.tau_max,
        "closed_form_error": plan.closed_form_error,
        "spp_per_node": truth_spp(ctx.quick),
    }
    return np.asarray(img, dtype=np.float64), np.asarray(se, dtype=np.float64), info


def compare(
    ctx: Context, defines: dict[str, Any], seed: int, masks: tuple[Mask, Mask], scene: str = SCENE
) -> tuple[dict[str, Any], dict[str, tuple[Img, Img]], tuple[Img, Img]]:
    """Render the model under both kernels and the truth; the region numbers."""
    truth, truth_se, info = _truth(ctx, scene, defines, seed + 1)
    ctx.tick()
    images: dict[str, tuple[Img, Img]] = {}
    res: dict[str, Any] = dict(info)
    for k, kernel in enumerate(KERNELS):
        if scene == SCENE:
            img, var = render(ctx, dict(defines, kernel=kernel), seed + 10 + k, return_variance=True)
        else:
            img, var = _render_scene(ctx, scene, dict(defines, kernel=kernel), seed + 10 + k)
        ctx.tick()
        images[kernel] = (img, var)
        res[kernel] = {
            region: region_difference(img, var, truth, truth_se, mask) for region, mask in zip(("cube", "shadow"), masks)
        }
    return res, images, (truth, truth_se)


def _render_scene(ctx: Context, scene: str, defines: dict[str, Any], seed: int) -> tuple[Img, Img]:
    import fgf

    s = settings(ctx.quick)
    d = dict(defines, res=str(s["res"]))
    try:
        img, var = fgf.render(str(ctx.scene_dir / scene), spp=s["spp"], seed=seed, defines=d, progress=False, return_variance=True)
    except fgf.FgfError as e:
        raise Unavailable(f"fgf.render cannot render {scene} with {d}: {e}") from e
    return np.asarray(img, dtype=np.float64), np.asarray(var, dtype=np.float64)


def _figure(
    ctx: Context,
    images: dict[str, tuple[Img, Img]],
    truth: tuple[Img, Img],
    masks: tuple[Mask, Mask],
    per_alpha: dict[str, Any],
    sw: float,
) -> Figure:
    s = settings(ctx.quick)
    (ec, ec_var), (rc, rc_var) = images["energy_conserving"], images["reciprocal"]
    tr, tr_se = truth
    fig = new_figure(16, 7.6)
    ax = fig.subplots(2, 4)
    for a, (label, img) in zip(ax[0, :3], [("model, energy-conserving", ec), ("model, reciprocal", rc), ("truth (quadrature)", tr)]):
        a.imshow(srgb_preview(img, EXPOSURE))
        a.set_title(label, fontsize=10)
    cube, shadow = masks
    for m, colour in ((cube, "yellow"), (shadow, "cyan")):
        ax[0, 2].contour(m.astype(float), levels=[0.5], colors=colour, linewidths=0.8)
    d_ec, d_rc = (ec - tr).mean(axis=2), (rc - tr).mean(axis=2)
    lim = float(np.percentile(np.abs(np.concatenate([d_ec.ravel(), d_rc.ravel()])), 99.5)) or 1.0
    for a, (label, d) in zip(ax[1, :2], [("energy-conserving − truth", d_ec), ("reciprocal − truth", d_rc)]):
        im = a.imshow(d, cmap="RdBu_r", vmin=-lim, vmax=lim)
        a.set_title(label + " (mean of RGB)", fontsize=10)
    fig.colorbar(im, ax=ax[1, 1], shrink=0.8, label="radiance")
    se_d = np.sqrt(ec_var.mean(axis=2) + (tr_se**2).mean(axis=2))
    im2 = ax[1, 2].imshow(se_d, cmap="magma", vmin=0.0, vmax=lim)
    ax[1, 2].set_title("standard error of a difference\n(same colour range)", fontsize=10)
    fig.colorbar(im2, ax=ax[1, 2], shrink=0.8, label="radiance")
    for a in list(ax[0, :3]) + list(ax[1, :3]):
        a.set_axis_off()
    # Region differences against alpha.
    alphas = sorted(float(v["alpha"]) for v in per_alpha.values())
    for kernel, marker in zip(KERNELS, ("o", "s")):
        for region, ls in (("cube", "-"), ("shadow", "--")):
            ys = [per_alpha[_key(a)][kernel][region]["relative_difference"] * 100 for a in ALPHAS]
            es = [per_alpha[_key(a)][kernel][region]["se"] * 100 for a in ALPHAS]
            ax[0, 3].errorbar(alphas, ys, yerr=es, marker=marker, ls=ls, capsize=3, label=f"{kernel.replace('_', '-')}, {region}")
    ax[0, 3].axhline(0.0, color="k", lw=0.8)
    ax[0, 3].set_xscale("log")
    ax[0, 3].set_xticks(alphas, [f"{a:.3g}" for a in alphas])
    ax[0, 3].minorticks_off()
    ax[0, 3].set_xlabel("gamma shape α")
    ax[0, 3].set_ylabel("(model − truth) / truth  [%]")
    ax[0, 3].set_title("region means vs the truth (±1 SE)", fontsize=10)
    ax[0, 3].legend(fontsize=7)
    ax[1, 3].set_axis_off()
    shown = per_alpha[_key(SHOWN)]
    lines = [f"α = {shown['alpha']:.3g}: {shown['nodes']} nodes"]
    for kernel in KERNELS:
        for region in ("cube", "shadow"):
            r = shown[kernel][region]
            lines.append(f"{kernel.replace('_', '-')}, {region}: {100 * r['relative_difference']:+.1f} ± {100 * r['se']:.1f} %")
    ax[1, 3].text(0.0, 0.9, "\n".join(lines), fontsize=9, va="top", family="monospace")
    name = save_figure(fig, ctx.out, "comparison_truth.png")
    summary = "; ".join(
        f"α = {per_alpha[_key(a)]['alpha']:.3g}: "
        + ", ".join(
            f"{k.replace('_', '-')} {100 * per_alpha[_key(a)][k]['cube']['relative_difference']:+.1f} ± "
            f"{100 * per_alpha[_key(a)][k]['cube']['se']:.1f} %"
            for k in KERNELS
        )
        for a in ALPHAS
    )
    caption = (
        f"k-fBm media (H = {HURST}, L = √3, σ_m = {SIGMA_M:g}, albedo 0.8) on the scene of figure 4 "
        f"(scenes/figures/{SCENE}); shown: S_w = {sw:.3g}, α = {shown['alpha']:.3g}. The truth is the average of "
        "classical renders of homogeneous realizations σ = X σ_m, X ~ Gamma(α, mean 1), by generalised "
        "Gauss–Laguerre quadrature (fgf truth, docs/theory.md §6); the model is rendered under both kernels. "
        f"Cube-region differences (model − truth)/truth ± SE: {summary}. The energy-conserving kernel is "
        "above the truth and the reciprocal kernel below it: the two kernels bracket the truth. Yellow: cube "
        f"region; cyan: shadow region. {s['res']}², model {s['spp']} spp, truth {truth_spp(ctx.quick)} spp per node."
    )
    return Figure(name, "The model against the exact truth", caption)


def _key(alpha: float) -> str:
    return f"alpha={alpha:g}"


def run(ctx: Context) -> GroupResult:
    s = settings(ctx.quick)
    masks = region_masks(s["res"], CAMERA, LIGHT_CENTRE)
    seed = ctx.seed + 900
    per_alpha: dict[str, Any] = {}
    shown: tuple[dict[str, tuple[Img, Img]], tuple[Img, Img]] | None = None
    sw_shown = 0.0
    for j, alpha in enumerate(ALPHAS):
        sw = sw_for(HURST, alpha)
        defines = defines_for("fgf", hurst=HURST, sw=sw)
        res, images, truth = compare(ctx, defines, seed + 100 * j, masks)
        res["sw"] = sw
        per_alpha[_key(alpha)] = res
        if alpha == SHOWN:
            shown, sw_shown = (images, truth), sw
    assert shown is not None
    results: dict[str, Any] = {
        "scene": SCENE,
        "hurst": HURST,
        "sigma_m": SIGMA_M,
        **s,
        "truth_spp_per_node": truth_spp(ctx.quick),
        "cube": per_alpha,
    }
    hero = ctx.scene_dir / HERO_SCENE
    if hero.is_file():
        hero_masks = region_masks(s["res"], HERO_CAMERA, HERO_LIGHT_CENTRE)
        d = {"medium": "fgf", "sigma_t": repr(HERO_SIGMA_M), "albedo": "0.8", "hurst": repr(HURST), "sw": repr(HERO_SW)}
        try:
            results["hero"], _, _ = compare(ctx, d, seed + 1000, hero_masks, scene=HERO_SCENE)
        except Unavailable as e:
            results["hero_unavailable"] = str(e)
    else:
        for _ in range(3):
            ctx.tick()
    ctx.tick()
    fig = _figure(ctx, shown[0], shown[1], masks, per_alpha, sw_shown)
    return GroupResult([fig], results)
