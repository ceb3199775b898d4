"""``fgf.mitsuba``: the fgf media and the ``fgf_volpath`` integrator inside
Mitsuba 3, against two oracles.

* Exponential media (Mitsuba's ``homogeneous``; fgf white noise, which is
  exponential with ``σ̄ = σ g(k)``) under ``fgf_volpath`` against Mitsuba's
  own ``volpath``, also with Mitsuba's ``roughplastic`` in the scene.
* Non-exponential media (pink noise, 2-fBm, Davis–Weinstein, both kernels,
  grey and RGB; the repository's reference scenes ``scenes/fgf-cube-*.xml``)
  under ``fgf_volpath`` against fgf's own renderer
  (``fgf.render(..., return_variance=True)``).
* A furnace: with albedo 1 inside a constant environment of radiance 1,
  both kernels conserve probability at every event, so the expected image is
  exactly 1 (only the split between light and phase sampling is random);
  with a ``roughplastic`` object in the medium the image stays finite and
  within ``[0, 1]``.

Statistics (as ``test_render_mitsuba.py``, whose helpers are imported):
Mitsuba renders ``K`` times with seeds ``0..K-1``; the per-seed image means
(or block means) are i.i.d., so their sample standard deviation gives the
standard error. fgf's renderer reports the per-pixel variance of the pixel
mean; pixels are independent (box filter), so a block mean's variance is
the sum of its pixels' over the block size squared. Image means per channel:
``|a - b| <= 3·SE``; with Welch's t at the degrees of freedom of these
tests (5 to several hundred) the false-alarm rate of one check is 0.3–1.2 %
for ``K = 12–16`` and up to 3 % for the small ``K = 6`` scalar renders (the
channels of a grey medium are one check, not three). Blocks: Welch's t-test per block and channel
with exact p-values and Holm's correction at a family error rate of 1 % per
scene. Seeds are fixed, so outcomes are reproducible, and none was chosen
to make a test pass.

``llvm_ad_rgb`` needs LLVM 19 (Debian's ``libllvm19``, installed by
``scripts/setup.sh --test``): Dr.Jit's default LLVM 15 aborts. The path is
set here before Dr.Jit starts its LLVM backend.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy import stats

LIBLLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
os.environ.setdefault("DRJIT_LIBLLVM_PATH", LIBLLVM)

import mitsuba as mi  # noqa: E402

import fgf  # noqa: E402
import fgf.mitsuba  # noqa: E402,F401
from test_render_mitsuba import holm_rejects, welch  # noqa: E402

Z_MEAN = 3.0
ALPHA_BLOCKS = 0.01
LIGHT = (
    '<shape type="rectangle"><transform name="to_world"><matrix value="-0.0490290338 0.107919143 '
    "0.880450906 -2.5 0 0.224471818 -0.440225453 2 -0.245145169 -0.0215838286 -0.176090181 0.5 0 0 0 1\"/>"
    '</transform><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>'
    '<emitter type="area"><rgb name="radiance" value="150"/></emitter></shape>'
)


def cube_scene(integrator: str, medium: str, res: int, inner: str = "", max_depth: int = 64) -> str:
    """The reference cube (fgf's ``scenes/fgf-cube-*.xml``): a null-bounded
    unit cube of ``medium`` over a diffuse ground, lit by a small area light;
    ``inner`` adds shapes inside the cube."""
    return f"""<scene version="3.0.0">
<integrator type="{integrator}"><integer name="max_depth" value="{max_depth}"/></integrator>
<sensor type="perspective"><float name="fov" value="40"/><string name="fov_axis" value="x"/>
<transform name="to_world"><lookat origin="0,1.6,4" target="0,0.6,0" up="0,1,0"/></transform>
<sampler type="independent"/>
<film type="hdrfilm"><integer name="width" value="{res}"/><integer name="height" value="{res}"/>
<string name="pixel_format" value="rgb"/><rfilter type="box"/></film></sensor>
<shape type="cube"><transform name="to_world"><scale value="0.5"/><translate value="0,0.75,0"/></transform>
<bsdf type="null"/>{medium}</shape>
{inner}
<shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/></transform>
<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
{LIGHT}
</scene>"""


def fgf_medium(
    hurst: float, sw: float, kernel: str, sigma: str = "4", albedo: str = "0.8", length: str = "", tag: str = "fgf"
) -> str:
    ln = f'<float name="length" value="{length}"/>' if length else ""
    return (
        f'<medium type="{tag}" name="interior"><rgb name="sigma_t" value="{sigma}"/>'
        f'<rgb name="albedo" value="{albedo}"/><float name="hurst" value="{hurst}"/>'
        f'<float name="sw" value="{sw}"/>{ln}<string name="kernel" value="{kernel}"/></medium>'
    )


def variant(name: str) -> Any:
    if name.startswith("llvm"):
        assert os.path.exists(os.environ["DRJIT_LIBLLVM_PATH"]), (
            f"llvm_ad_rgb needs {LIBLLVM} (Debian's libllvm19): run bash scripts/setup.sh --test"
        )
    mi.set_variant(name)
    assert name in fgf.mitsuba.registered_variants()
    return mi


def render_mi(xml: str, var: str, spp: int, k: int) -> np.ndarray:
    variant(var)
    scene = mi.load_string(xml)
    out = np.stack([np.array(mi.render(scene, spp=spp, seed=i))[..., :3] for i in range(k)])
    return out.astype(np.float64)


def render_fgf(xml: str, tmp_path: Path, spp: int) -> tuple[np.ndarray, np.ndarray]:
    path = tmp_path / "scene.xml"
    path.write_text(xml)
    img, var = fgf.render(path, spp=spp, seed=7, progress=False, return_variance=True)
    return np.asarray(img, np.float64), np.asarray(var, np.float64)


def blocks(a: np.ndarray, b: int) -> np.ndarray:
    """Means of ``b x b`` pixel blocks over the last three axes (h, w, c)."""
    *lead, h, w, c = a.shape
    return a.reshape(*lead, h // b, b, w // b, b, c).mean(axis=(-4, -2))


def assert_same_as_mitsuba(a: np.ndarray, b: np.ndarray, what: str, block: int) -> None:
    """``a``, ``b``: K independent renders each (K, h, w, c)."""
    assert np.isfinite(a).all() and np.isfinite(b).all(), what
    ma, mb, se, t, _ = welch(a.mean(axis=(1, 2)), b.mean(axis=(1, 2)))
    msg = f"{what}: image mean {ma} vs {mb}, SE {se}, t {t}"
    print(msg)
    assert (np.abs(ma - mb) <= Z_MEAN * se).all(), msg
    ba, bb, se, t, p = welch(blocks(a, block), blocks(b, block))
    p = np.where(np.abs(ba - bb) <= 1e-5 * np.abs(a.mean()), 1.0, p)
    rej = holm_rejects(p, ALPHA_BLOCKS)
    assert not rej.any(), f"{what}: {rej.sum()} of {rej.size} blocks differ: t = {t[rej]}"


def assert_same_as_fgf(m: np.ndarray, img: np.ndarray, var: np.ndarray, what: str, block: int) -> None:
    """``m``: K Mitsuba renders; ``img``, ``var``: fgf's image and the
    per-pixel variance of its pixel means."""
    k = len(m)
    assert np.isfinite(m).all(), what
    h, w, _ = img.shape
    # Image mean per channel.
    mm = m.mean(axis=(1, 2))
    a, va = mm.mean(0), mm.var(0, ddof=1) / k
    b, vb = img.mean(axis=(0, 1)), var.sum(axis=(0, 1)) / (h * w) ** 2
    se = np.sqrt(va + vb)
    msg = f"{what}: image mean fgf_volpath {a} vs fgf {b}, SE {se}, z {(a - b) / se}"
    print(msg)
    assert (np.abs(a - b) <= Z_MEAN * se).all(), msg
    # Blocks: Welch–Satterthwaite degrees of freedom (fgf's side has
    # thousands of samples per pixel: infinite).
    mb_ = blocks(m, block)
    a, va = mb_.mean(0), mb_.var(0, ddof=1) / k
    b = blocks(img, block)
    vb = blocks(var, block) / block**2
    se = np.sqrt(va + vb)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(se > 0, (a - b) / se, 0.0)
        dof = np.where(va > 0, (va + vb) ** 2 / (va**2 / (k - 1)), 1e9)
    p = 2 * stats.t.sf(np.abs(t), dof)
    p = np.where(np.abs(a - b) <= 1e-5 * np.abs(img.mean()), 1.0, p)
    rej = holm_rejects(p, ALPHA_BLOCKS)
    assert not rej.any(), f"{what}: {rej.sum()} of {rej.size} blocks differ: t = {t[rej]}"


# --------------------------------------------------------------------------
# Loading and parameters


def test_plugins_load_and_reject_bad_parameters() -> None:
    variant("scalar_rgb")
    xml = cube_scene("fgf_volpath", fgf_medium(-0.1, 4.0, "reciprocal"), 4)
    scene = mi.load_string(xml)
    media = [s.interior_medium() for s in scene.shapes() if s.interior_medium() is not None]
    assert len(media) == 1 and media[0].spec.hurst == -0.1 and media[0].spec.kernel == "reciprocal"
    for bad, name in [
        (fgf_medium(0.0, 4.0, "reciprocal"), "hurst"),
        (fgf_medium(-0.1, -1.0, "reciprocal"), "sw"),
        (fgf_medium(-0.1, 4.0, "both"), "kernel"),
        (fgf_medium(-0.1, 4.0, "reciprocal", albedo="1.5"), "albedo"),
        (fgf_medium(-0.1, 4.0, "reciprocal", length="2"), "length"),
        (
            '<medium type="nonexponential" name="interior"><string name="transmittance" value="davis"/></medium>',
            "alpha",
        ),
        (
            '<medium type="nonexponential" name="interior"><string name="transmittance" value="davis_weinstein"/>'
            '<float name="h" value="0.3"/><float name="c" value="1"/></medium>',
            "h",
        ),
    ]:
        with pytest.raises(RuntimeError, match=name):
            mi.load_string(cube_scene("fgf_volpath", bad, 4))
    with pytest.raises(RuntimeError, match="kernel"):
        mi.load_string(cube_scene("fgf_volpath", "", 4).replace(
            '<integrator type="fgf_volpath">', '<integrator type="fgf_volpath"><string name="kernel" value="x"/>'))


def test_heterogeneous_media_are_refused() -> None:
    variant("scalar_rgb")
    med = (
        '<medium type="heterogeneous" name="interior"><volume type="constvolume" name="sigma_t">'
        '<float name="value" value="1"/></volume></medium>'
    )
    scene = mi.load_string(cube_scene("fgf_volpath", med, 4))
    with pytest.raises(fgf.mitsuba.MediumParameterError, match="HeterogeneousMedium is not supported"):
        mi.render(scene, spp=1)


def test_volpath_sees_the_exponential_counterpart() -> None:
    """Under Mitsuba's own volpath an fgf medium is the homogeneous medium of
    the same mean sigma_t and albedo (documented): the images agree to float
    rounding (the same random numbers, the coefficients reached through Python)."""
    variant("scalar_rgb")
    fgf_xml = cube_scene("volpath", fgf_medium(-0.1, 4.0, "reciprocal", sigma="4", albedo="0.8"), 8)
    homo = '<medium type="homogeneous" name="interior"><float name="sigma_t" value="4"/><float name="albedo" value="0.8"/></medium>'
    a = np.array(mi.render(mi.load_string(fgf_xml), spp=8, seed=3))
    b = np.array(mi.render(mi.load_string(cube_scene("volpath", homo, 8)), spp=8, seed=3))
    assert np.allclose(a, b, rtol=1e-6, atol=1e-7), np.abs(a - b).max()


# --------------------------------------------------------------------------
# The per-sample Dr.Jit math against fgf's float64 models

MODELS = {
    "pink": lambda: fgf.Fgf(4.0, hurst=-0.1, sw=4.0),
    "pink-0.4": lambda: fgf.Fgf(1.0, hurst=-0.4, sw=10.0),
    "white": lambda: fgf.Fgf(4.0, hurst=-0.5, sw=4.0),
    "2fbm": lambda: fgf.Fgf(4.0, hurst=1.2, sw=34.0, length=1.0),
    "davis": lambda: fgf.Davis(4.0, alpha=0.5),
    "dw": lambda: fgf.DavisWeinstein(4.0, h=0.9, c=0.78),
    "exponential": lambda: fgf.Exponential(3.0),
}


@pytest.mark.parametrize("var", ["scalar_rgb", "llvm_ad_rgb"])
@pytest.mark.parametrize("name", list(MODELS))
def test_drjit_math_matches_fgf_models(name: str, var: str) -> None:
    """Tr, T_sm, T_ms, T_mm and both flight samplers (closed forms and the
    tabulated inverse) in float32 Dr.Jit against fgf's float64 models."""
    from fgf.mitsuba import _drmath as dm
    from fgf.mitsuba import _params, _plugins

    variant(var)
    jit = var.startswith("llvm")
    m = MODELS[name]()
    data = _params.medium_data([m] * 3, (1.0, 1.0, 1.0), True)
    tables = _plugins.SceneTables([data], {}, jit)
    g = data.gamma[0]
    n = 200 if jit else 12
    t = np.geomspace(1e-4, 30.0, n) / g.sigma
    u = np.linspace(0.0, 1.0, n, endpoint=False)[1:]
    u = np.concatenate([[1e-7, 1e-4], u, [1 - 2**-23]]).astype(np.float32).astype(np.float64)

    def run(f: Any, x: np.ndarray) -> np.ndarray:
        if jit:
            return np.array(f(mi.Float(x)), dtype=np.float64)
        return np.array([float(f(float(v))) for v in x])

    def ev(fn: Any, *extra: float) -> Any:
        return lambda x: fn(g.sigma, g.k, g.e, *extra, x)

    for what, mine, ref in [
        ("tr", ev(dm.tr), m.tr),
        ("pdf", ev(dm.surface_medium), m.pdf),
        ("T_ms", ev(dm.medium_surface), m.medium_surface),
        ("T_mm", ev(dm.medium_medium, g.sigma_bar), m.medium_medium),
    ]:
        got, want = run(mine, t), np.asarray(ref(t))
        assert np.allclose(got, want, rtol=3e-5, atol=1e-30), (what, np.max(np.abs(got / want - 1)))
    for medium, ref in [(False, m.sample_surface), (True, m.sample_medium)]:
        p = tables.params(1 if not jit else mi.UInt32(1), 0 if not jit else mi.UInt32(0), True)

        def flight(x: Any, medium: bool = medium, p: Any = p) -> Any:
            slot = mi.UInt32(1)
            return tables.sample_flight(p, slot, x, mi.Bool(medium), True)

        got, want = run(flight, u), np.asarray(ref(u))
        assert np.allclose(got, want, rtol=2e-5), (medium, np.max(np.abs(got / want - 1)))


# --------------------------------------------------------------------------
# Exponential media: fgf_volpath against Mitsuba's volpath

HOMOGENEOUS_RGB = (
    '<medium type="homogeneous" name="interior"><rgb name="sigma_t" value="0.2, 0.5, 1"/>'
    '<float name="scale" value="6"/><rgb name="albedo" value="0.9, 0.5, 0.8"/>'
    '<phase type="hg"><float name="g" value="0.4"/></phase></medium>'
)


def test_exponential_matches_volpath_llvm() -> None:
    a = render_mi(cube_scene("fgf_volpath", HOMOGENEOUS_RGB, 16), "llvm_ad_rgb", 64, 16)
    b = render_mi(cube_scene("volpath", HOMOGENEOUS_RGB, 16), "llvm_ad_rgb", 64, 16)
    assert_same_as_mitsuba(a, b, "homogeneous rgb, llvm_ad_rgb", 4)


@pytest.mark.slow
@pytest.mark.parametrize("max_depth", [1, 2, 3, 64])
def test_exponential_matches_volpath_llvm_slow(max_depth: int) -> None:
    """max_depth semantics (1: emitters seen directly, 2: single scattering)
    and a larger image."""
    inner = ROUGH_SPHERE.format(medium_ext='<ref id="h" name="exterior"/>')
    med = HOMOGENEOUS_RGB.replace('name="interior"', 'id="h" name="interior"')
    a = render_mi(cube_scene("fgf_volpath", med, 32, inner, max_depth), "llvm_ad_rgb", 128, 16)
    b = render_mi(cube_scene("volpath", med, 32, inner, max_depth), "llvm_ad_rgb", 128, 16)
    assert_same_as_mitsuba(a, b, f"homogeneous rgb + roughplastic, max_depth {max_depth}", 8)


def test_exponential_matches_volpath_scalar() -> None:
    med = '<medium type="homogeneous" name="interior"><float name="sigma_t" value="4"/><float name="albedo" value="0.8"/></medium>'
    a = render_mi(cube_scene("fgf_volpath", med, 8), "scalar_rgb", 8, 6)
    b = render_mi(cube_scene("volpath", med, 8), "scalar_rgb", 8, 6)
    assert_same_as_mitsuba(a, b, "homogeneous grey, scalar_rgb", 4)


ROUGH_SPHERE = (
    '<shape type="sphere"><point name="center" value="0.1, 0.7, 0.1"/><float name="radius" value="0.25"/>'
    '<bsdf type="roughplastic"><float name="alpha" value="0.2"/><rgb name="diffuse_reflectance" value="0.6, 0.3, 0.2"/>'
    "</bsdf>{medium_ext}</shape>"
)


def test_white_noise_with_roughplastic_matches_volpath() -> None:
    """White noise is exponential with ``σ̄ = σ g(S_w/σ)`` for either kernel;
    a roughplastic sphere (Mitsuba's own) sits inside the medium."""
    sigma, sw = 4.0, 4.0
    sigma_bar = fgf.Fgf(sigma, hurst=-0.5, sw=sw).sigma_bar
    for kernel in ("energy_conserving", "reciprocal"):
        white = fgf_medium(-0.5, sw, kernel, sigma=str(sigma), tag="fgf").replace('name="interior"', 'id="m" name="interior"')
        ext_w = '<ref id="m" name="exterior"/>'
        a = render_mi(
            cube_scene("fgf_volpath", white, 16, ROUGH_SPHERE.format(medium_ext=ext_w)), "llvm_ad_rgb", 64, 6
        )
        homo = (
            f'<medium type="homogeneous" id="m" name="interior"><float name="sigma_t" value="{sigma_bar}"/>'
            '<rgb name="albedo" value="0.8"/></medium>'
        )
        b = render_mi(cube_scene("volpath", homo, 16, ROUGH_SPHERE.format(medium_ext=ext_w)), "llvm_ad_rgb", 64, 6)
        assert_same_as_mitsuba(a, b, f"white noise + roughplastic, {kernel}", 4)


# --------------------------------------------------------------------------
# Non-exponential media: fgf_volpath against fgf's renderer

REPO = Path(__file__).resolve().parents[1]


def reference_scene(name: str, kernel: str, res: int, spp: int, k: int, max_depth: int, block: int) -> None:
    """A repository reference scene, loaded by Mitsuba as it is (its
    integrator is ``volpath``) and rendered with ``fgf_volpath``, against fgf."""
    path = REPO / "scenes" / name
    defines = {"res": str(res), "kernel": kernel, "max_depth": str(max_depth)}
    img, var = fgf.render(path, spp=16 * spp, seed=7, defines=defines, progress=False, return_variance=True)
    variant("llvm_ad_rgb")
    scene = mi.load_file(str(path), **defines)
    integ = mi.load_dict({"type": "fgf_volpath", "max_depth": max_depth})
    m = np.stack([np.array(mi.render(scene, integrator=integ, spp=spp, seed=i))[..., :3] for i in range(k)])
    img64, var64 = np.asarray(img, np.float64), np.asarray(var, np.float64)
    assert_same_as_fgf(m.astype(np.float64), img64, var64, f"{name} {kernel} {res}x{res}", block)


@pytest.mark.parametrize("kernel", ["energy_conserving", "reciprocal"])
@pytest.mark.parametrize("name", ["fgf-cube-pink.xml", "fgf-cube-2fbm.xml"])
def test_reference_scenes_match_fgf_renderer_llvm(name: str, kernel: str) -> None:
    reference_scene(name, kernel, 16, 64, 12, 64, 4)


@pytest.mark.slow
@pytest.mark.parametrize("kernel", ["energy_conserving", "reciprocal"])
@pytest.mark.parametrize("name", ["fgf-cube-pink.xml", "fgf-cube-2fbm.xml"])
def test_reference_scenes_match_fgf_renderer_llvm_slow(name: str, kernel: str) -> None:
    reference_scene(name, kernel, 32, 256, 16, 64, 8)


FGF_CASES = {
    # No 'length': the default (the cube's diagonal) must agree too.
    "2fbm-reciprocal": fgf_medium(1.2, 34.0, "reciprocal"),
    "pink-ec-hg": fgf_medium(-0.3, 10.0, "energy_conserving").replace(
        "</medium>", '<phase type="hg"><float name="g" value="-0.3"/></phase></medium>'),
    "pink-rgb-reciprocal": fgf_medium(-0.2, 4.0, "reciprocal", sigma="2, 4, 8", albedo="0.9, 0.8, 0.7"),
    "dw-reciprocal": (
        '<medium type="nonexponential" name="interior"><float name="sigma_t" value="4"/>'
        '<rgb name="albedo" value="0.9"/><string name="transmittance" value="davis_weinstein"/>'
        '<float name="h" value="0.8"/><float name="c" value="0.5"/><string name="kernel" value="reciprocal"/>'
        '<phase type="hg"><float name="g" value="0.5"/></phase></medium>'
    ),
}


@pytest.mark.parametrize("case", list(FGF_CASES))
def test_matches_fgf_renderer_llvm(case: str, tmp_path: Path) -> None:
    med = FGF_CASES[case]
    img, var = render_fgf(cube_scene("volpath", med, 16), tmp_path, 1024)
    m = render_mi(cube_scene("fgf_volpath", med, 16), "llvm_ad_rgb", 64, 12)
    assert_same_as_fgf(m, img, var, f"{case}, llvm_ad_rgb", 4)


def test_two_media_match_fgf_renderer_llvm(tmp_path: Path) -> None:
    """Nested media: a homogeneous sphere inside the pink cube (slots switch
    at each boundary; the pink segments restart on each surface)."""
    med = fgf_medium(-0.1, 4.0, "reciprocal").replace('name="interior"', 'id="pink" name="interior"')
    inner = (
        '<shape type="sphere"><point name="center" value="0, 0.75, 0"/><float name="radius" value="0.3"/>'
        '<bsdf type="null"/><medium type="homogeneous" name="interior"><float name="sigma_t" value="8"/>'
        '<rgb name="albedo" value="0.5, 0.9, 0.7"/></medium><ref id="pink" name="exterior"/></shape>'
    )
    img, var = render_fgf(cube_scene("volpath", med, 16, inner), tmp_path, 1024)
    m = render_mi(cube_scene("fgf_volpath", med, 16, inner), "llvm_ad_rgb", 64, 12)
    assert_same_as_fgf(m, img, var, "pink cube around a homogeneous sphere", 4)


def test_integrator_kernel_overrides_the_media() -> None:
    """``kernel`` on fgf_volpath: the same image as the media declaring it."""
    variant("llvm_ad_rgb")
    ec = cube_scene("fgf_volpath", fgf_medium(-0.1, 4.0, "energy_conserving"), 8)
    rec = cube_scene("fgf_volpath", fgf_medium(-0.1, 4.0, "reciprocal"), 8)
    forced = ec.replace('<integrator type="fgf_volpath">', '<integrator type="fgf_volpath"><string name="kernel" value="reciprocal"/>')
    a = np.array(mi.render(mi.load_string(forced), spp=16, seed=1))
    b = np.array(mi.render(mi.load_string(rec), spp=16, seed=1))
    c = np.array(mi.render(mi.load_string(ec), spp=16, seed=1))
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_matches_fgf_renderer_scalar(tmp_path: Path) -> None:
    med = fgf_medium(-0.1, 4.0, "reciprocal", sigma="2, 4, 6")
    img, var = render_fgf(cube_scene("volpath", med, 8), tmp_path, 2048)
    m = render_mi(cube_scene("fgf_volpath", med, 8), "scalar_rgb", 12, 6)
    assert_same_as_fgf(m, img, var, "pink rgb reciprocal, scalar_rgb", 4)


@pytest.mark.slow
@pytest.mark.parametrize("case", list(FGF_CASES))
def test_matches_fgf_renderer_llvm_slow(case: str, tmp_path: Path) -> None:
    med = FGF_CASES[case]
    img, var = render_fgf(cube_scene("volpath", med, 32, max_depth=8), tmp_path, 4096)
    m = render_mi(cube_scene("fgf_volpath", med, 32, max_depth=8), "llvm_ad_rgb", 256, 16)
    assert_same_as_fgf(m, img, var, f"{case}, llvm_ad_rgb, 32x32", 8)


@pytest.mark.slow
@pytest.mark.parametrize("case", ["pink-rgb-reciprocal", "2fbm-reciprocal", "dw-reciprocal"])
def test_matches_fgf_renderer_scalar_slow(case: str, tmp_path: Path) -> None:
    med = FGF_CASES[case]
    img, var = render_fgf(cube_scene("volpath", med, 16), tmp_path, 4096)
    m = render_mi(cube_scene("fgf_volpath", med, 16), "scalar_rgb", 16, 8)
    assert_same_as_fgf(m, img, var, f"{case}, scalar_rgb", 4)


# --------------------------------------------------------------------------
# Furnace


def furnace(medium: str, inner: str, res: int) -> str:
    return f"""<scene version="3.0.0">
<integrator type="fgf_volpath"><integer name="max_depth" value="-1"/><integer name="rr_depth" value="1000"/></integrator>
<sensor type="perspective"><float name="fov" value="30"/>
<transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
<film type="hdrfilm"><integer name="width" value="{res}"/><integer name="height" value="{res}"/>
<rfilter type="box"/></film></sensor>
<shape type="sphere"><float name="radius" value="1"/><bsdf type="null"/>{medium}</shape>
{inner}
<emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>"""


def assert_mean_is(imgs: np.ndarray, value: float, what: str, block: int) -> None:
    """One-sample t-tests of K renders against a known image value: image
    mean per channel within 3 SE, blocks by Holm at 1 %."""
    k = len(imgs)
    m = imgs.mean(axis=(1, 2))
    se = m.std(0, ddof=1) / np.sqrt(k)
    msg = f"{what}: image mean {m.mean(0)}, SE {se}, expected {value}"
    print(msg)
    assert (np.abs(m.mean(0) - value) <= Z_MEAN * se).all(), msg
    b = blocks(imgs, block)
    se_b = b.std(0, ddof=1) / np.sqrt(k)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(se_b > 0, (b.mean(0) - value) / se_b, 0.0)
    p = 2 * stats.t.sf(np.abs(t), k - 1)
    rej = holm_rejects(p, ALPHA_BLOCKS)
    assert not rej.any(), f"{what}: {rej.sum()} of {rej.size} blocks differ from {value}: t = {t[rej]}"


@pytest.mark.parametrize("var", ["scalar_rgb", "llvm_ad_rgb"])
@pytest.mark.parametrize("kernel", ["energy_conserving", "reciprocal"])
def test_furnace_is_one(var: str, kernel: str) -> None:
    """Albedo 1, RGB pink noise, constant environment 1: both kernels keep
    every path's expected contribution at 1 (only the split between light
    sampling and phase sampling is random)."""
    med = fgf_medium(-0.2, 4.0, kernel, sigma="1, 2, 3", albedo="1")
    res, spp, k = (4, 4, 6) if var == "scalar_rgb" else (16, 32, 8)
    imgs = render_mi(furnace(med, "", res), var, spp, k)
    assert np.isfinite(imgs).all()
    assert_mean_is(imgs, 1.0, f"furnace {kernel} {var}", 4)


@pytest.mark.parametrize("kernel", ["energy_conserving", "reciprocal"])
def test_furnace_camera_inside_the_medium(kernel: str) -> None:
    """The sensor's medium (a segment from the camera starts on a surface)."""
    med = fgf_medium(-0.2, 4.0, kernel, sigma="1, 2, 3", albedo="1").replace('name="interior"', 'id="m" name="interior"')
    xml = furnace(med, "", 16).replace(
        '<lookat origin="0,0,4"', '<lookat origin="0,0,0.2"').replace("</film></sensor>", '</film><ref id="m"/></sensor>')
    imgs = render_mi(xml, "llvm_ad_rgb", 32, 6)
    assert np.isfinite(imgs).all()
    assert_mean_is(imgs, 1.0, f"furnace from inside, {kernel}", 4)


def test_furnace_with_roughplastic_is_bounded() -> None:
    """A roughplastic sphere inside an albedo-1 pink medium: the medium alone
    conserves energy under both kernels and the BSDF absorbs, so the image is
    finite, non-negative, at most 1 (3 SE) and darker than 1 where the
    sphere is seen."""
    inner = (
        '<shape type="sphere"><float name="radius" value="0.4"/><bsdf type="roughplastic">'
        '<float name="alpha" value="0.3"/><rgb name="diffuse_reflectance" value="0.5"/></bsdf>'
        '<ref id="m" name="exterior"/></shape>'
    )
    for kernel in ("energy_conserving", "reciprocal"):
        med = fgf_medium(-0.2, 4.0, kernel, sigma="1", albedo="1").replace('name="interior"', 'id="m" name="interior"')
        imgs = render_mi(furnace(med, inner, 16), "llvm_ad_rgb", 32, 8)
        assert np.isfinite(imgs).all() and (imgs >= 0).all(), kernel
        b = blocks(imgs, 4)
        mean, se = b.mean(0), b.std(0, ddof=1) / np.sqrt(len(b))
        assert (mean <= 1 + Z_MEAN * se).all(), (kernel, mean.max())
        assert (mean[1:3, 1:3] < 1 - Z_MEAN * se[1:3, 1:3]).all(), (kernel, mean[1:3, 1:3])


def test_docs_xml_snippets_render() -> None:
    """The XML examples of docs/mitsuba.md load and render (finite, lit)."""
    import re

    variant("llvm_ad_rgb")
    doc = (REPO / "docs" / "mitsuba.md").read_text()
    xmls = re.findall(r"```xml\n(.*?)```", doc, re.S)
    assert len(xmls) == 2
    sensor = (
        '<sensor type="perspective"><transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/>'
        '</transform><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>'
        '</film></sensor><emitter type="constant"/>'
    )
    scene = xmls[0].replace("<!-- sensor, emitters ... -->", sensor)
    medium = re.search(r'<medium type="fgf".*?</medium>', scene, re.S)
    assert medium is not None
    for xml in (scene, scene.replace(medium.group(0), xmls[1])):
        img = np.array(mi.render(mi.load_string(xml), spp=8))
        assert np.isfinite(img).all() and img.mean() > 0.05


def test_hide_emitters_and_max_depth_zero() -> None:
    """Only the environment is in view: hide_emitters or max_depth 0 give 0."""
    variant("llvm_ad_rgb")
    base = furnace("", "", 4)
    seen = np.array(mi.render(mi.load_string(base), spp=4))
    assert np.allclose(seen, 1.0)
    hidden = base.replace('<integrator type="fgf_volpath">', '<integrator type="fgf_volpath"><boolean name="hide_emitters" value="true"/>')
    assert (np.array(mi.render(mi.load_string(hidden), spp=4)) == 0).all()
    zero = base.replace('<integer name="max_depth" value="-1"/>', '<integer name="max_depth" value="0"/>')
    assert (np.array(mi.render(mi.load_string(zero), spp=4)) == 0).all()
