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
    return 1 + len(HURSTS)


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
    caption = (
        f"One scene (scenes/figures/{SCENE}): a medium cube on a ground plane, side lighting, low density "
        f"(σ_m = {SIGMA_M:g}, albedo {ALBEDO:g}, isotropic phase), energy-conserving kernel, S_w = {SW_RENDER:g} "
        f"for every FGF medium (α(1): gamma shape at t = 1; k-fBm: L = √3). {s['res']}×{s['res']} pixels, "
        f"{s['spp']} spp, seed {seed}, same exposure. Correlated media let more light through: the cube "
        "gets brighter and its shadow lighter as the transmittance grows a heavy tail."
    )
    return GroupResult([Figure(name, "Exponential vs FGF media", caption)], res)
