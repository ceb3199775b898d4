"""Figure group 4, renders of one scene (``docs/theory.md`` §5.4).

``scenes/figures/medium_on_ground.xml``: a medium cube (side 1) on a grey
ground plane, side lighting, low density (σ_m = 2, albedo 0.8, isotropic
phase). Exponential (``homogeneous``) vs FGF media with H = -0.1 (pink),
0.2 (1-fBm) and 1.2 (2-fBm), the same σ_m, albedo and phase function.

Every FGF medium has the same white-noise strength S_w = :data:`SW_RENDER`;
the resulting gamma shape α at the cube's side length t = 1 (k-fBm: the
constant α with L = the cube's diagonal √3, the loader's default for
``length``) is reported with each image — a smaller α means a more strongly
non-exponential (more transparent, heavier-tailed) medium.

The panels share one exposure. ``results.json`` holds each image's mean
RGB and its mean relative to the exponential render.

The group also makes the side-lighting ("hero") set and the low-density
pairs on ``scenes/figures/striped_wall.xml`` (a dense cube, σ_m = 4 and
S_w = 16 for every H, in front of a striped wall): ``renders_side.png``
(exponential vs pink noise vs 1-fBm vs 2-fBm) and
``renders_low_density.png`` (σ_m = 1, the same α(1)). For each medium
``results["hero"]`` holds the model's Tr through one cube side (``tr1``),
the stripe visibility through the cube (:func:`stripe_fit`, regions from
:func:`hero_regions`) and the shadow mean relative to the exponential
cube's (``shadow_ratio``), each Monte Carlo number with its SE.
"""

from __future__ import annotations

import math
from typing import Any, Literal, overload

import numpy as np
import numpy.typing as npt

from ._common import Context, Figure, GroupResult, Unavailable, floats, need, new_figure, save_figure, srgb_preview

TITLE = "4. Renders: exponential vs pink noise vs 1-fBm vs 2-fBm"

SCENE = "medium_on_ground.xml"
SIGMA_M = 2.0
ALBEDO = 0.8
#: White-noise strength of every FGF medium of the renders (α ≈ 0.5-1.1 at
#: t = 1 for the three H: clearly non-exponential, see the module docs).
SW_RENDER = 4.0
#: k-fBm characteristic length: the diagonal of the unit cube (the
#: loader's default, the bounding-box diagonal).
CUBE_DIAGONAL = math.sqrt(3.0)
HURSTS = (-0.1, 0.2, 1.2)
#: Display exposure (stops) shared by every render panel.
EXPOSURE = 0.0


def steps(quick: bool) -> int:
    # renders.png; the hero set (reference + 4); the low-density set (3).
    return 1 + len(HURSTS) + 1 + 4 + 3


def settings(quick: bool) -> dict[str, Any]:
    """Resolution and samples per pixel of the render groups."""
    return {"res": 48, "spp": 16} if quick else {"res": 256, "spp": 256}


def alpha_at_1(hurst: float, sw: float) -> float:
    """Gamma shape α(t = 1) of the FGF medium (k-fBm: L = √3)."""
    Fgf = need("Fgf")
    m = Fgf(SIGMA_M, hurst=hurst, sw=sw, length=CUBE_DIAGONAL) if hurst > 0 else Fgf(SIGMA_M, hurst=hurst, sw=sw)
    return float(m.alpha(1.0))


def sw_for(hurst: float, alpha_ref: float) -> float:
    """S_w giving α = alpha_ref at t = 1 (k-fBm: constant α, L = √3)."""
    lav = need("line_average_variance")
    v1 = float(lav(hurst, 1.0, 1.0, length=CUBE_DIAGONAL) if hurst > 0 else lav(hurst, 1.0, 1.0))
    return SIGMA_M**2 / (alpha_ref * v1)


def defines_for(medium: str, **params: float | str) -> dict[str, Any]:
    """String defines for the figure scene (numbers with full precision)."""
    d = {"medium": medium, "sigma_t": repr(SIGMA_M), "albedo": repr(ALBEDO)}
    for k, v in params.items():
        d[k] = v if isinstance(v, str) else repr(float(v))
    return d


#: A render as float64 ``(H, W, 3)``.
Img = npt.NDArray[np.float64]


@overload
def render(
    ctx: Context, defines: dict[str, Any], seed: int, spp: int | None = None, return_variance: Literal[False] = False
) -> Img: ...
@overload
def render(ctx: Context, defines: dict[str, Any], seed: int, spp: int | None = None, *, return_variance: Literal[True]) -> tuple[Img, Img]: ...
def render(
    ctx: Context, defines: dict[str, Any], seed: int, spp: int | None = None, return_variance: bool = False
) -> Img | tuple[Img, Img]:
    """Render the figure scene with ``defines``; a failure of the renderer on
    this (valid) scene means the build lacks a feature, so it makes the
    group unavailable with the renderer's message."""
    import fgf

    render = need("render")
    s = settings(ctx.quick)
    d = dict(defines, res=str(s["res"]))
    scene = ctx.scene_dir / SCENE
    if not scene.is_file():
        raise Unavailable(f"figure scene {scene} not found")
    try:
        out = render(str(scene), spp=spp or s["spp"], seed=seed, defines=d, progress=False, return_variance=return_variance)
    except fgf.FgfError as e:
        raise Unavailable(f"fgf.render cannot render {scene.name} with {d}: {e}") from e
    except AttributeError as e:
        # The Python layer is newer than the compiled fgf._core.
        raise Unavailable(f"fgf.render is not usable in this build ({e}); rebuild with maturin develop") from e
    img = np.asarray(out[0] if return_variance else out, dtype=np.float64)
    if img.ndim != 3 or img.shape[2] < 3:
        raise Unavailable(f"fgf.render returned an array of shape {img.shape}, expected (H, W, 3)")
    if return_variance:
        # Variance of each pixel's mean (its squared standard error).
        return img[..., :3], np.asarray(out[1], dtype=np.float64)[..., :3]
    return img[..., :3]


def image_stats(img: np.ndarray) -> dict[str, Any]:
    return {
        "mean_rgb": floats(img.reshape(-1, 3).mean(axis=0)),
        "mean": float(img.mean()),
        "max": float(img.max()),
        "finite": bool(np.isfinite(img).all()),
    }


def run(ctx: Context) -> GroupResult:
    s = settings(ctx.quick)
    seed = ctx.seed + 500
    panels: list[tuple[str, Img, dict[str, float]]] = [("exponential", render(ctx, defines_for("homogeneous"), seed), {})]
    ctx.tick()
    for hurst in HURSTS:
        sw = SW_RENDER
        img = render(ctx, defines_for("fgf", hurst=hurst, sw=sw), seed)
        kind = "pink noise" if hurst < 0 else f"{int(np.ceil(hurst))}-fBm"
        panels.append((f"H = {hurst} ({kind})", img, {"hurst": hurst, "sw": sw, "alpha_at_1": alpha_at_1(hurst, sw)}))
        ctx.tick()
    res: dict[str, Any] = {"sigma_m": SIGMA_M, "albedo": ALBEDO, "sw": SW_RENDER, **s, "images": {}}
    base = panels[0][1].mean()
    fig = new_figure(3.2 * len(panels), 4.0)
    axes = fig.subplots(1, len(panels))
    for ax, (label, img, params) in zip(axes, panels):
        st = image_stats(img)
        st.update(params)
        st["mean_over_exponential"] = float(img.mean() / base) if base > 0 else 0.0
        res["images"][label] = st
        ax.imshow(srgb_preview(img, EXPOSURE))
        sub = f"\nS_w = {params['sw']:g}, α(1) = {params['alpha_at_1']:.2f}" if params else "\n(homogeneous)"
        ax.set_title(label + sub, fontsize=10)
        ax.set_axis_off()
    name = save_figure(fig, ctx.out, "renders.png")
    figures = [Figure(name, "Exponential vs FGF media", _renders_caption(s, seed))]
    hero_fig, res["hero"], ref = hero_figure(ctx, ctx.seed + 600)
    low_fig, low = low_density_figure(ctx, ctx.seed + 700, ref)
    res["low_density"] = {"sigma_m": LOW_SIGMA_M, "sw": LOW_SW, "media": low}
    return GroupResult(figures + [hero_fig, low_fig], res)


def _renders_caption(s: dict[str, Any], seed: int) -> str:
    caption = (
        f"One scene (scenes/figures/{SCENE}): a medium cube on a ground plane, side lighting, low density "
        f"(σ_m = {SIGMA_M:g}, albedo {ALBEDO:g}, isotropic phase), energy-conserving kernel, S_w = {SW_RENDER:g} "
        f"for every FGF medium (α(1): gamma shape at t = 1; k-fBm: L = √3). {s['res']}×{s['res']} pixels, "
        f"{s['spp']} spp, seed {seed}, same exposure. Correlated media let more light through: the cube "
        "gets brighter and its shadow lighter as the transmittance grows a heavy tail."
    )
    return caption


# ---------------------------------------------------------------------------
# The hero ("side lighting") set and the low-density pairs: a dense cube in
# front of a striped back wall (scenes/figures/striped_wall.xml).
# ---------------------------------------------------------------------------

HERO_SCENE = "striped_wall.xml"
#: Mean extinction and white-noise strength of every hero medium: the
#: exponential cube transmits e^-4 = 1.8 % along one side, the FGF cubes
#: 18-33 % (docs/theory.md §3: Tr = (1 + σ_m t/α)^(-α)).
HERO_SIGMA_M = 4.0
HERO_SW = 16.0
#: The low-density pairs: σ_m = 1 with S_w scaled by (σ_m / 4)² so that every
#: medium keeps the hero's α(1) (α = σ_m² / var[σ̄_t], docs/theory.md §3.1).
LOW_SIGMA_M = 1.0
LOW_SW = HERO_SW * (LOW_SIGMA_M / HERO_SIGMA_M) ** 2
#: name in results.json -> (label, Hurst parameter or None for exponential).
HERO_MEDIA: dict[str, tuple[str, float | None]] = {
    "exponential": ("exponential", None),
    "pink": ("pink noise, H = -0.1", -0.1),
    "1fbm": ("1-fBm, H = 0.2", 0.2),
    "2fbm": ("2-fBm, H = 1.2", 1.2),
}
#: Stand-in for "no cube" in the reference render: a homogeneous medium this
#: thin attenuates the wall by 1e-9 (the null boundary itself costs nothing).
NO_CUBE_SIGMA_T = 1e-9
HERO_EXPOSURE = 0.0

# Geometry of striped_wall.xml (its header comment lists the same numbers).
CAM_ORIGIN = (0.0, 1.6, 4.3)
CAM_TARGET = (0.0, 0.7, -0.2)
CAM_FOV_X = 40.0
CUBE_LO = (-0.5, 0.25, -0.5)
CUBE_HI = (0.5, 1.25, 0.5)
WALL_Z = -1.2
STRIPE_X0 = -2.2
STRIPE_PERIOD = 0.4
STRIPE_HALF_WIDTH = 0.1
LIGHT_CENTRE = (-3.0, 2.2, 0.8)
LIGHT_TARGET = (0.0, 0.75, 0.0)
LIGHT_HALF_SIZE = 0.3


def hero_settings(quick: bool) -> dict[str, Any]:
    """Resolution and samples per pixel of the hero and low-density renders."""
    return {"res": 96, "spp": 32} if quick else {"res": 384, "spp": 256}


def _frame(origin: tuple[float, ...], target: tuple[float, ...]) -> tuple[Img, Img, Img]:
    """The ``lookat`` frame (left, up, dir) of the scene loader
    (crates/fgf-scene/src/xml/transform.rs) with up = +y."""
    d = np.subtract(target, origin).astype(np.float64)
    d /= np.linalg.norm(d)
    left = np.cross([0.0, 1.0, 0.0], d)
    left /= np.linalg.norm(left)
    return left, np.cross(d, left), d


def camera_rays(res: int) -> tuple[Img, Img]:
    """Origin ``(3,)`` and unit directions ``(res, res, 3)`` of the camera rays
    through the pixel centres (the perspective sensor of
    crates/fgf-render/src/camera.rs: film x toward world +x, film y down)."""
    left, up, d = _frame(CAM_ORIGIN, CAM_TARGET)
    t = math.tan(math.radians(0.5 * CAM_FOV_X))
    n = (np.arange(res) + 0.5) * 2.0 / res - 1.0
    nx, ny = np.meshgrid(n, n)  # ny varies along rows
    v = (-nx * t)[..., None] * left + (-ny * t)[..., None] * up + d
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return np.asarray(CAM_ORIGIN, dtype=np.float64), v


def _hits_box(o: Img, d: Img, lo: Img, hi: Img, t_max: Img | float) -> npt.NDArray[np.bool_]:
    """Whether the segments ``o + s d``, 0 < s < t_max, meet the box (slab test)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t0 = (lo - o) * inv
        t1 = (hi - o) * inv
    near = np.nanmax(np.minimum(t0, t1), axis=-1)
    far = np.nanmin(np.maximum(t0, t1), axis=-1)
    return (near < far) & (far > 0.0) & (near < t_max)  # type: ignore[no-any-return]


def hero_regions(res: int) -> dict[str, npt.NDArray[np.bool_]]:
    """Pixel masks of the measured regions of ``striped_wall.xml``.

    * ``through_bright`` / ``through_dark``: camera rays that enter the cube
      through its front face (z = 0.5) and leave it through its back face
      (z = -0.5), 0.03 inside the edges, so that they cross one cube side
      (length 1.00-1.03), and then hit the wall inside a bright or a dark
      stripe, at least 0.3 of a half-stripe (or half a pixel, if larger)
      from its edges.
    * ``shadow``: ground pixels not behind the cube whose segments to the
      centre and the four corners of the light all cross the cube shrunk by
      0.05: the umbra.
    """
    o, d = camera_rays(res)
    lo, hi = np.asarray(CUBE_LO), np.asarray(CUBE_HI)
    m = 0.03

    def at_z(z: float) -> Img:
        p: Img = o + ((z - o[2]) / d[..., 2])[..., None] * d
        return p

    front, back, wall = at_z(hi[2]), at_z(lo[2]), at_z(WALL_Z)

    def inside_face(p: Img) -> npt.NDArray[np.bool_]:
        return (  # type: ignore[no-any-return]
            (p[..., 0] > lo[0] + m) & (p[..., 0] < hi[0] - m) & (p[..., 1] > lo[1] + m) & (p[..., 1] < hi[1] - m)
        )

    through = inside_face(front) & inside_face(back) & (wall[..., 1] > 0.05)
    # Distance from the nearest stripe centre, in units of the half-width.
    u = (wall[..., 0] - STRIPE_X0) / STRIPE_PERIOD
    dist = np.abs(u - np.round(u)) * STRIPE_PERIOD / STRIPE_HALF_WIDTH  # 0..2, edge at 1
    pixel_on_wall = 2.0 * (WALL_Z - o[2]) / d[..., 2] * math.tan(math.radians(0.5 * CAM_FOV_X)) / res
    margin = np.maximum(0.3, 0.5 * np.abs(pixel_on_wall) / STRIPE_HALF_WIDTH)
    bright = through & (dist < 1.0 - margin)
    dark = through & (dist > 1.0 + margin)

    # The ground: y = 0, in front of the wall.
    s_g = -o[1] / d[..., 1]
    g = o + s_g[..., None] * d
    on_ground = (d[..., 1] < 0) & (g[..., 2] > WALL_Z) & (np.abs(g[..., 0]) < 4.0) & (g[..., 2] < 4.0)
    on_ground &= ~_hits_box(o, d, lo - 0.02, hi + 0.02, s_g)
    left, up, _ = _frame(LIGHT_CENTRE, LIGHT_TARGET)
    c = np.asarray(LIGHT_CENTRE)
    h = LIGHT_HALF_SIZE
    umbra = on_ground.copy()
    for p in (c, c + h * (left + up), c + h * (left - up), c - h * (left + up), c - h * (left - up)):
        seg = p - g
        umbra &= _hits_box(g, seg, lo + 0.05, hi - 0.05, 1.0)
    masks = {"through_bright": bright, "through_dark": dark, "shadow": umbra}
    for k, v in masks.items():
        if int(v.sum()) < 4:
            raise Unavailable(f"the '{k}' region of {HERO_SCENE} at {res}x{res} pixels has {int(v.sum())} pixels")
    return masks


def _region_mean(img: Img, var: Img, mask: npt.NDArray[np.bool_]) -> tuple[float, float]:
    """Mean of the channel-averaged image over ``mask`` and its variance
    (pixels are independent estimates: var = Σ var_p / N²; the channel
    average's variance is bounded by the mean of the channel variances,
    which is exact for a grey scene whose channels share their samples)."""
    n = int(mask.sum())  # >= 4: checked by hero_regions
    lum = img.mean(axis=-1)
    v = var.mean(axis=-1)
    return float(lum[mask].mean()), float(v[mask].sum() / n**2)


def _hero_render(ctx: Context, defines: dict[str, Any], seed: int) -> tuple[Img, Img]:
    """Render striped_wall.xml at the hero settings, with the per-pixel
    variance of the mean."""
    s = hero_settings(ctx.quick)
    d = dict(defines, res=str(s["res"]))
    return _render_scene(ctx, HERO_SCENE, d, seed, s["spp"])


def _render_scene(ctx: Context, scene_name: str, defines: dict[str, Any], seed: int, spp: int) -> tuple[Img, Img]:
    import fgf

    render_fn = need("render")
    scene = ctx.scene_dir / scene_name
    if not scene.is_file():
        raise Unavailable(f"figure scene {scene} not found")
    try:
        out = render_fn(str(scene), spp=spp, seed=seed, defines=defines, progress=False, return_variance=True)
    except fgf.FgfError as e:
        raise Unavailable(f"fgf.render cannot render {scene.name} with {defines}: {e}") from e
    img = np.asarray(out[0], dtype=np.float64)[..., :3]
    var = np.asarray(out[1], dtype=np.float64)[..., :3]
    return img, var


def model_of(sigma_m: float, hurst: float | None, sw: float) -> Any:
    """The transmittance model of a hero medium (k-fBm: L = the cube's
    diagonal √3, the loader's default)."""
    if hurst is None:
        return need("Exponential")(sigma_m)
    Fgf = need("Fgf")
    return Fgf(sigma_m, hurst=hurst, sw=sw, length=CUBE_DIAGONAL) if hurst > 0 else Fgf(sigma_m, hurst=hurst, sw=sw)


def hero_defines(sigma_m: float, hurst: float | None, sw: float) -> dict[str, Any]:
    d: dict[str, Any] = {"sigma_t": repr(sigma_m), "albedo": repr(ALBEDO)}
    if hurst is None:
        d["medium"] = "homogeneous"
    else:
        d.update(medium="fgf", hurst=repr(hurst), sw=repr(sw))
    return d


def stripe_fit(img: Img, var: Img, ref: tuple[Img, Img], mask: npt.NDArray[np.bool_]) -> tuple[float, float]:
    """Stripe visibility through the cube and its standard error.

    Over the pixels of ``mask`` (rays through one cube side onto the wall),
    the channel-averaged image is fitted, by least squares weighted with each
    pixel's variance, as ``V · ref + (a quadratic in the pixel position)``,
    where ``ref`` is the same pixel of the render without the cube. ``V`` is
    the part of the wall's pattern that survives the cube; the quadratic takes
    up the smooth glow of the light the cube scatters. The SE is the fit's
    (``(XᵀWX)⁻¹``), with the reference's own noise added to each pixel's
    variance as ``V² var_ref``.
    """
    lum = img.mean(axis=-1)[mask]
    v = var.mean(axis=-1)[mask]
    r = ref[0].mean(axis=-1)[mask]
    vr = ref[1].mean(axis=-1)[mask]
    ii, jj = np.nonzero(mask)
    y = (ii - ii.mean()) / max(float(np.ptp(ii)), 1.0)
    x = (jj - jj.mean()) / max(float(np.ptp(jj)), 1.0)
    design = np.stack([r, np.ones_like(x), x, y, x * x, x * y, y * y], axis=1)
    vis = 0.0
    for _ in range(2):  # the weights depend on V through the reference's noise
        w = 1.0 / np.maximum(v + vis * vis * vr, 1e-20)
        a = design.T @ (design * w[:, None])
        coef = np.linalg.solve(a, design.T @ (w * lum))
        vis = float(coef[0])
    se = float(np.sqrt(np.linalg.inv(a)[0, 0]))
    return vis, se


def measure_hero(
    img: Img, var: Img, ref: tuple[Img, Img], masks: dict[str, npt.NDArray[np.bool_]]
) -> dict[str, float]:
    """Stripe visibility (:func:`stripe_fit`) and shadow mean of one render,
    with standard errors; also the plain stripe contrasts (bright − dark
    region means) with and without the cube."""
    through = masks["through_bright"] | masks["through_dark"]
    vis, se = stripe_fit(img, var, ref, through)
    b, _ = _region_mean(img, var, masks["through_bright"])
    k, _ = _region_mean(img, var, masks["through_dark"])
    rb, _ = _region_mean(ref[0], ref[1], masks["through_bright"])
    rk, _ = _region_mean(ref[0], ref[1], masks["through_dark"])
    sh, vsh = _region_mean(img, var, masks["shadow"])
    return {
        "stripe_visibility": vis,
        "stripe_visibility_se": se,
        "through_contrast": b - k,
        "direct_contrast": rb - rk,
        "shadow_mean": sh,
        "shadow_mean_se": math.sqrt(vsh),
    }


def _ratio(a: float, sa: float, b: float, sb: float) -> tuple[float, float]:
    r = a / b
    return r, abs(r) * math.sqrt((sa / a) ** 2 + (sb / b) ** 2)


def _hero_set(
    ctx: Context, sigma_m: float, sw: float, keys: tuple[str, ...], seed: int, ref: tuple[Img, Img]
) -> tuple[dict[str, Any], dict[str, Img]]:
    """Render and measure the media ``keys`` at (σ_m, S_w)."""
    masks = hero_regions(hero_settings(ctx.quick)["res"])
    out: dict[str, Any] = {}
    imgs: dict[str, Img] = {}
    for i, key in enumerate(keys):
        _, hurst = HERO_MEDIA[key]
        img, var = _hero_render(ctx, hero_defines(sigma_m, hurst, sw), seed + i)
        ctx.tick()
        m = model_of(sigma_m, hurst, sw)
        e: dict[str, Any] = {"tr1": float(m.tr(1.0))}
        e["alpha_at_1"] = float(m.alpha(1.0)) if hurst is not None else 0.0
        if hurst is not None:
            e.update(hurst=hurst, sw=sw)
        e.update(measure_hero(img, var, ref, masks))
        e["mean"] = float(img.mean())
        e["finite"] = bool(np.isfinite(img).all())
        out[key] = e
        imgs[key] = img
    base = out["exponential"]
    for e in out.values():
        e["shadow_ratio"], e["shadow_ratio_se"] = _ratio(
            e["shadow_mean"], e["shadow_mean_se"], base["shadow_mean"], base["shadow_mean_se"]
        )
    if keys[0] == "exponential":
        out["exponential"]["shadow_ratio_se"] = 0.0  # 1 by definition
    return out, imgs


def _reference(ctx: Context, seed: int) -> tuple[Img, Img]:
    """The striped wall without the cube (its medium made transparent)."""
    ref = _hero_render(ctx, {"medium": "homogeneous", "sigma_t": repr(NO_CUBE_SIGMA_T), "albedo": repr(ALBEDO)}, seed)
    ctx.tick()
    return ref


def _panel_title(label: str, e: dict[str, Any]) -> str:
    a = f", α(1) = {e['alpha_at_1']:.2f}" if e["alpha_at_1"] > 0 else ""
    return (
        f"{label}{a}\nTr(1) = {e['tr1']:.3f}, stripes {e['stripe_visibility']:.3f}"
        f"\nshadow / exp. = {e['shadow_ratio']:.2f}"
    )


def hero_figure(ctx: Context, seed: int) -> tuple[Figure, dict[str, Any], tuple[Img, Img]]:
    """``renders_side.png`` and the ``hero`` numbers."""
    s = hero_settings(ctx.quick)
    ref = _reference(ctx, seed + 90)
    res, imgs = _hero_set(ctx, HERO_SIGMA_M, HERO_SW, tuple(HERO_MEDIA), seed, ref)
    fig = new_figure(3.6 * len(imgs), 4.25)
    axes = fig.subplots(1, len(imgs))
    for ax, (key, img) in zip(axes, imgs.items()):
        ax.imshow(srgb_preview(img, HERO_EXPOSURE))
        ax.set_title(_panel_title(HERO_MEDIA[key][0], res[key]), fontsize=10)
        ax.set_axis_off()
        ax.set_anchor("S")  # keep the three-line titles clear of the top edge
    name = save_figure(fig, ctx.out, "renders_side.png")
    vis = ", ".join(
        f"{HERO_MEDIA[k][0].split(',')[0]} {e['stripe_visibility']:.3f} ± {e['stripe_visibility_se']:.4f}"
        for k, e in res.items()
    )
    caption = (
        f"Side lighting (scenes/figures/{HERO_SCENE}): a medium cube (side 1, σ_m = {HERO_SIGMA_M:g}, albedo "
        f"{ALBEDO:g}, isotropic phase, energy-conserving kernel) in front of a striped wall, lit from the left; "
        f"S_w = {HERO_SW:g} for every FGF medium (k-fBm: L = √3). {s['res']}×{s['res']} pixels, {s['spp']} spp, "
        f"seeds {seed}–{seed + 3}, same exposure. Tr(1): the model's transmittance through one cube side. "
        "Stripe visibility: the fraction of the wall's stripe pattern seen through the front and back faces of "
        "the cube (weighted least-squares fit of those pixels by the render without the cube plus a smooth "
        f"quadratic glow; ± 1 SE): {vis}. The exponential cube is opaque; the correlated "
        "cubes show the wall, and their shadows are lighter (shadow mean / exponential's: "
        + ", ".join(f"{HERO_MEDIA[k][0].split(',')[0]} {e['shadow_ratio']:.2f}" for k, e in res.items() if k != "exponential")
        + ")."
    )
    return Figure(name, "Side lighting: exponential vs pink noise vs 1-fBm vs 2-fBm", caption), res, ref


def low_density_figure(ctx: Context, seed: int, ref: tuple[Img, Img]) -> tuple[Figure, dict[str, Any]]:
    """``renders_low_density.png``: exponential vs pink and vs 2-fBm at
    σ_m = 1, with the hero's α(1)."""
    s = hero_settings(ctx.quick)
    res, imgs = _hero_set(ctx, LOW_SIGMA_M, LOW_SW, ("exponential", "pink", "2fbm"), seed, ref)
    fig = new_figure(7.4, 9.2)
    axes = fig.subplots(2, 2)
    for row, key in enumerate(("pink", "2fbm")):
        for col, k in enumerate(("exponential", key)):
            ax = axes[row, col]
            ax.imshow(srgb_preview(imgs[k], HERO_EXPOSURE))
            ax.set_title(_panel_title(HERO_MEDIA[k][0], res[k]), fontsize=10)
            ax.set_axis_off()
            ax.set_anchor("S")
    name = save_figure(fig, ctx.out, "renders_low_density.png")
    e, p, f = res["exponential"], res["pink"], res["2fbm"]
    caption = (
        f"Low density: the side-lighting scene with σ_m = {LOW_SIGMA_M:g} and S_w = {LOW_SW:g}, which keeps the "
        f"hero's α(1) (α = σ_m²/var[σ̄_t]); exponential vs pink noise (top) and vs 2-fBm (bottom). "
        f"{s['res']}×{s['res']} pixels, {s['spp']} spp. Even a thin cube differs: Tr(1) = {e['tr1']:.3f} "
        f"(exponential), {p['tr1']:.3f} (pink), {f['tr1']:.3f} (2-fBm); stripe visibility "
        f"{e['stripe_visibility']:.3f} ± {e['stripe_visibility_se']:.4f}, {p['stripe_visibility']:.3f} ± "
        f"{p['stripe_visibility_se']:.4f}, {f['stripe_visibility']:.3f} ± {f['stripe_visibility_se']:.4f}; "
        f"shadow mean / exponential's {p['shadow_ratio']:.2f} (pink), {f['shadow_ratio']:.2f} (2-fBm)."
    )
    return Figure(name, "Low density: exponential vs pink noise, exponential vs 2-fBm", caption), res


def hero_summary(hero: dict[str, Any]) -> dict[str, dict[str, float]]:
    """The top-level ``hero`` object of ``results.json``: per medium, ``tr1``
    (the model's Tr at one cube side), ``stripe_visibility`` and
    ``shadow_ratio`` (Monte Carlo, with ``*_se``)."""
    keys = ("tr1", "stripe_visibility", "stripe_visibility_se", "shadow_ratio", "shadow_ratio_se")
    return {name: {k: float(e[k]) for k in keys} for name, e in hero.items()}
