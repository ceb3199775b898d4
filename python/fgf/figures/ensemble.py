"""Figure group 5b, uncorrelated vs correlated media: the model against
explicit realizations (``docs/theory.md`` §5.5, §1.8), on the scene of group 4.

The ``fgf`` model render beside the mean of ``fgf.ensemble``, explicit 3D
realizations rendered classically:

* pink noise, H = -0.1, σ_m = 4, S_w = 16 (α(1) = 0.52, strongly
  non-exponential): the calibrated gamma copula, σ_t = σ_m X with gamma
  marginals whose grid line-average variance follows the model's (§1.8);
* 1-fBm, H = 0.2, α = 2 (correlated): the clamped Gaussian grid
  max(0, σ_m + σ_u) with S_w3 = S_w·2π(2H+1) (§1.7).

Reported per case: the mean relative error ``Σ|model - mean| / Σ|mean|``
over all pixels and channels, the same for the exponential render of the
same σ_m, the model's own distance to that exponential render, ``Σ SE / Σ|mean|`` (the ensemble's own standard error across
realizations), the fraction of clamped voxels, the calibration (Hurst
parameter of the Gaussian field, voxel gamma shape) and the range of the
grid's exact line-average variance over the model's, and the relative
difference of the image means (model and exponential against the ensemble)
with a conservative z-score (see :func:`_mean_z`). docs/validation.md
discusses the outcome; the quantitative pink test with region standard
errors is :func:`pink_ensemble_study`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ._common import Context, Figure, GroupResult, Unavailable, need
from .comparisons import _rows_figure, mean_relative_error
from .renders import CUBE_DIAGONAL, SCENE, defines_for, image_stats, render, settings, sw_for

TITLE = "5b. Uncorrelated vs correlated media: model vs explicit realizations"

#: Media of the comparison: (label, hurst, σ_m, S_w or None for "α(1) = 2 at
#: the figure's σ_m", marginal). Pink noise uses the calibrated gamma copula
#: (non-negative by construction, so any variance is allowed: the hero
#: parameters σ_m = 4, S_w = 16); the smoother 1-fBm Gaussian field stays
#: nearly positive at α = 2.
ENSEMBLE_CASES: tuple[tuple[str, float, float, float | None, str], ...] = (
    ("pink H = -0.1, calibrated gamma copula", -0.1, 4.0, 16.0, "gamma"),
    ("1-fBm H = 0.2, clamped Gaussian", 0.2, 2.0, None, "gaussian"),
)


#: The pink scene where the model and the exponential differ most clearly
#: (σ_m = 4, S_w = 16, H = -0.1: α(1) = 0.52, Tr(1) = 0.33 against
#: e^-4 = 0.018), on ``scenes/fgf-cube-pink.xml``.
PINK_DEFINES = {"hurst": "-0.1", "sw": "16"}
#: The same scene with a white-noise strength so small that the model is
#: the exponential one (α(1) ~ 1e10).
EXPONENTIAL_DEFINES = {"hurst": "-0.1", "sw": "1e-9"}

Img = np.ndarray


def pink_ensemble_comparison(
    scene: str | Any,
    *,
    defines: dict[str, Any] | None = None,
    realizations: int = 64,
    resolution: int = 64,
    spp: int = 16,
    model_spp: int = 256,
    seed: int = 0,
    padding: float | None = None,
    return_info: bool = False,
) -> Any:
    """The fgf model render of a pink-noise scene and the calibrated
    ensemble's mean and per-pixel standard error (``fgf.ensemble`` with
    gamma marginals, ``docs/theory.md`` §1.8).

    Returns ``(model, mean, se)``, each ``(H, W, 3)`` float64; with
    ``return_info``, ``(model, model_var, mean, se, info)`` where ``info`` is
    ``fgf.ensemble``'s (with ``info["realizations"]``, every realization's
    image). ``defines`` go to both (e.g. ``{"res": 64, "sw": 16}``); the
    model uses seed ``seed``, the ensemble ``seed + 1``.
    """
    import fgf

    d = dict(defines or {})
    model, var = fgf.render(scene, spp=model_spp, seed=seed, defines=d, progress=False, return_variance=True)
    mean, se, info = fgf.ensemble(
        scene,
        realizations=realizations,
        resolution=resolution,
        spp=spp,
        seed=seed + 1,
        defines=d,
        progress=False,
        padding=padding,
        marginal="gamma",
        return_info=True,
        return_realizations=True,
    )
    out = (np.asarray(model, np.float64), np.asarray(mean, np.float64), np.asarray(se, np.float64))
    if return_info:
        return out[0], np.asarray(var, np.float64), out[1], out[2], info
    return out


def _region_stats(model: Img, var: Img, reals: Img, mask: np.ndarray) -> dict[str, float]:
    n = int(mask.sum())
    m = float(model[mask].mean())
    m_se = float(np.sqrt(var[mask].sum()) / n)
    per = reals[:, mask].reshape(len(reals), -1).mean(axis=1)
    e = float(per.mean())
    e_se = float(per.std(ddof=1) / np.sqrt(len(per))) if len(per) > 1 else float("nan")
    return {"pixels": n, "model": m, "model_se": m_se, "ensemble": e, "ensemble_se": e_se}


def pink_ensemble_study(
    scene: str | Any,
    *,
    res: int = 64,
    realizations: int = 64,
    resolution: int = 64,
    spp: int = 16,
    model_spp: int = 256,
    seed: int = 0,
    padding: float | None = None,
) -> dict[str, Any]:
    """Model vs exponential vs calibrated ensemble on the pink cube scene
    (:data:`PINK_DEFINES`), over two regions fixed by an independent pilot
    pair of renders: ``brighter`` (the model is brighter than the
    exponential by more than a quarter of the 99th percentile of the pilot
    difference: light through the cube, its shadow) and ``darker`` (the
    reverse: the cube's lit face). Region means with standard errors: the
    renders' from their per-pixel variance, the ensemble's from its
    per-realization region means. Also the grid's exact line-average
    variance against the model's (``fgf.ensemble``'s report)."""
    import fgf

    base = {"res": str(res)}
    pink = dict(base, **PINK_DEFINES)
    expo_d = dict(base, **EXPONENTIAL_DEFINES)
    # Pilot renders (independent seeds) fix the regions.
    pm = fgf.render(scene, spp=max(16, model_spp // 4), seed=seed + 7001, defines=pink, progress=False)
    pe = fgf.render(scene, spp=max(16, model_spp // 4), seed=seed + 7002, defines=expo_d, progress=False)
    dpil = (np.asarray(pm, np.float64) - np.asarray(pe, np.float64)).mean(axis=2)
    thr = 0.25 * float(np.percentile(np.abs(dpil), 99))
    masks = {"brighter": dpil > thr, "darker": dpil < -thr, "image": np.ones_like(dpil, dtype=bool)}
    model, var, mean, se, info = pink_ensemble_comparison(
        scene,
        defines=pink,
        realizations=realizations,
        resolution=resolution,
        spp=spp,
        model_spp=model_spp,
        seed=seed,
        padding=padding,
        return_info=True,
    )
    expo, expo_var = fgf.render(scene, spp=model_spp, seed=seed + 2, defines=expo_d, progress=False, return_variance=True)
    # The model under the reciprocal kernel, and with S_w scaled to the
    # smallest and largest grid/model variance ratio of the calibration
    # (how far the residual mismatch alone could move the model).
    med = info["media"][0]
    ratios = [g / t for g, t in zip(med["grid_variances"], med["model_variances"])]
    sw = float(PINK_DEFINES["sw"])
    variants = {
        "reciprocal": dict(pink, kernel="reciprocal"),
        "sw_low": dict(pink, sw=repr(sw * min(ratios))),
        "sw_high": dict(pink, sw=repr(sw * max(ratios))),
    }
    variant_imgs = {
        k: fgf.render(scene, spp=model_spp, seed=seed + 3 + i, defines=d, progress=False, return_variance=True)
        for i, (k, d) in enumerate(variants.items())
    }
    reals = np.asarray(info["realizations"], np.float64).mean(axis=3)
    model_g, var_g = model.mean(axis=2), var.mean(axis=2) / 3.0
    expo_g, expo_var_g = np.asarray(expo, np.float64).mean(axis=2), np.asarray(expo_var, np.float64).mean(axis=2) / 3.0
    out: dict[str, Any] = {
        "scene_defines": pink,
        "realizations": int(info["realizations_done"]),
        "grid_resolution": resolution,
        "spp_per_realization": spp,
        "model_spp": model_spp,
        "regions": {},
    }
    for name, mask in masks.items():
        st = _region_stats(model_g, var_g, reals, mask)
        st["exponential"] = float(expo_g[mask].mean())
        st["exponential_se"] = float(np.sqrt(expo_var_g[mask].sum()) / mask.sum())
        st["model_minus_exponential"] = st["model"] - st["exponential"]
        st["model_minus_ensemble"] = st["model"] - st["ensemble"]
        st["model_minus_ensemble_se"] = float(np.hypot(st["model_se"], st["ensemble_se"]))
        st["exponential_minus_ensemble"] = st["exponential"] - st["ensemble"]
        for k, (img, v) in variant_imgs.items():
            g, vg = np.asarray(img, np.float64).mean(axis=2), np.asarray(v, np.float64).mean(axis=2) / 3.0
            st[f"model_{k}"] = float(g[mask].mean())
            st[f"model_{k}_se"] = float(np.sqrt(vg[mask].sum()) / mask.sum())
        out["regions"][name] = st
    out["medium"] = {
        k: med[k]
        for k in ("shape", "padded_shape", "marginal", "hurst_field", "alpha_voxel", "mean_sigma_t", "model_mean_sigma_t", "lengths")
    }
    out["medium"]["variance_ratio"] = ratios
    out["images"] = {"model": model, "ensemble": mean, "ensemble_se": se, "exponential": np.asarray(expo, np.float64)}
    return out


def steps(quick: bool) -> int:
    return 2 * len(ENSEMBLE_CASES)


def _mean_z(name: str, img: np.ndarray, var: np.ndarray, mean: np.ndarray, se: np.ndarray) -> dict[str, Any]:
    """Relative difference of the image means of a render and the ensemble,
    and a conservative z-score for it.

    The render's pixel errors are independent (one random stream per
    pixel): their sum has variance Σ var. The ensemble's pixel errors are
    *not*: one realization of the field moves many pixels together. The
    standard error of their sum is at most Σ SE (perfect correlation), which
    is used here, so the reported |z| is a lower bound.
    """
    diff = float(img.sum() - mean.sum())
    sd = float(np.sqrt(var.sum() + float(se.sum()) ** 2))
    return {
        f"{name}_image_mean_rel_diff": diff / float(mean.sum()),
        f"{name}_image_mean_z_lower_bound": diff / sd if sd > 0 else 0.0,
    }


def _ensemble(ctx: Context, res: dict[str, Any]) -> Figure:
    import fgf

    ensemble = need("ensemble")
    s = settings(ctx.quick)
    realizations = 4 if ctx.quick else 16
    # 64³ grids (a 256³ synthesis domain): the resolution the pink study of
    # docs/validation.md calibrates and measures.
    grid = 32 if ctx.quick else 64
    spp_each = 8 if ctx.quick else 64
    seed = ctx.seed + 800
    rows = []
    for label, hurst, sigma_m, sw_given, marginal in ENSEMBLE_CASES:
        sw = sw_for(hurst, 2.0) if sw_given is None else sw_given
        d = defines_for("fgf", hurst=hurst, sw=sw, sigma_t=sigma_m)
        # The exponential render of the same σ_m.
        expo, expo_var = render(ctx, defines_for("homogeneous", sigma_t=sigma_m), seed, return_variance=True)
        model, model_var = render(ctx, d, seed, return_variance=True)
        Fgf = need("Fgf")
        alpha_ref = float(Fgf(sigma_m, hurst=hurst, sw=sw, length=CUBE_DIAGONAL).alpha(1.0) if hurst > 0 else Fgf(sigma_m, hurst=hurst, sw=sw).alpha(1.0))
        ctx.tick()
        try:
            mean, se, info = ensemble(
                str(ctx.scene_dir / SCENE),
                realizations=realizations,
                resolution=grid,
                spp=spp_each,
                seed=seed + 1,
                defines=dict(d, res=str(s["res"])),
                progress=False,
                return_info=True,
                marginal=marginal,
            )
        except fgf.FgfError as e:
            raise Unavailable(f"fgf.ensemble failed on the figure scene: {e}") from e
        except AttributeError as e:
            raise Unavailable(f"fgf.ensemble is not usable in this build ({e}); rebuild with maturin develop") from e
        mean = np.asarray(mean, dtype=np.float64)[..., :3]
        se = np.asarray(se, dtype=np.float64)[..., :3]
        ctx.tick()
        media = info.get("media", [])
        med = media[0] if media else {}
        ratios = [g / t for g, t in zip(med.get("grid_variances", []), med.get("model_variances", []))] or [float("nan")]
        res[f"H={hurst}"] = {
            "hurst": hurst,
            "sigma_m": sigma_m,
            "sw": sw,
            "marginal": marginal,
            "hurst_field": float(med.get("hurst_field", hurst)),
            # JSON has no NaN: None for the Gaussian grid (no gamma shape).
            "alpha_voxel": float(med["alpha_voxel"]) if marginal == "gamma" and "alpha_voxel" in med else None,
            "grid_over_model_variance_min": float(min(ratios)),
            "grid_over_model_variance_max": float(max(ratios)),
            "alpha_ref": alpha_ref,
            "realizations": realizations,
            "grid_resolution": grid,
            "spp_per_realization": spp_each,
            "model": image_stats(model),
            "ensemble": image_stats(mean),
            "exponential": image_stats(expo),
            "mean_relative_error": mean_relative_error(model, mean),
            "mean_relative_error_exponential": mean_relative_error(expo, mean),
            "model_vs_exponential": mean_relative_error(model, expo),
            **_mean_z("model", model, model_var, mean, se),
            **_mean_z("exponential", expo, expo_var, mean, se),
            "ensemble_relative_se": float(np.abs(se).sum() / np.abs(mean).sum()) if np.abs(mean).sum() > 0 else 0.0,
            "clamped_fraction": float(med.get("clamped_fraction", 0.0)),
            "realized_variance": float(med.get("realized_variance", 0.0)),
            "continuum_variance": float(med.get("continuum_variance", 0.0)),
            "variance_length": float(med.get("variance_length", 0.0)),
        }
        rows.append(("fgf model", model, f"ensemble of {realizations} realizations", mean, f"{label}\nσ_m = {sigma_m:g}, S_w = {sw:.3g}, α(1) = {alpha_ref:.2f}"))
    return _rows_figure(
        ctx,
        rows,
        "comparison_ensemble.png",
        "Model vs explicit realizations",
        f"The fgf (gamma-closure) render beside the average of {realizations} explicit realizations on grids of "
        f"{grid} voxels along the cube, synthesized on a periodic domain 4 times larger per axis and rendered "
        f"classically (fgf.ensemble, {spp_each} spp each). Top: pink noise H = −0.1, σ_m = 4, S_w = 16 "
        "(α(1) = 0.52), realized as a Gaussian copula with gamma marginals calibrated so that the grid's exact "
        "line-average variance follows the model's (docs/theory.md §1.8; its residual and the calibration are in "
        "results.json). Bottom: 1-fBm (H = 0.2, α = 2) as a clamped Gaussian grid, which carries only part of the "
        "continuum line-average variance (§1.6). Difference: model − ensemble; docs/validation.md gives the "
        "region means with their standard errors."
    )


def run(ctx: Context) -> GroupResult:
    res: dict[str, Any] = {}
    return GroupResult([_ensemble(ctx, res)], res)
