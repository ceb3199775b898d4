"""fgf's rough and coated BSDFs against Mitsuba 3 (``scalar_rgb``).

Each scene is a sphere of the BSDF under test on a diffuse ground, lit by a
rectangular area light (so that light sampling and BSDF sampling are
combined by MIS) and a dim constant environment, rendered at 32x32 by both
renderers ``K = 16`` times with independent seeds. The comparison is the one
of ``test_render_mitsuba``: per channel, the image means agree within 3
standard errors (Welch), and per 8x8 block Welch's t-tests with Holm's
correction at a family error rate of 1 % per scene.

A medium inside a rough dielectric sphere is checked twice: Mitsuba's
``homogeneous`` medium in both renderers, and fgf's ``nonexponential``
medium with ``transmittance="exponential"`` (the same expectation) against
Mitsuba's homogeneous one.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import fgf
from test_render_mitsuba import K, assert_agree

SPP = 16

SCENE = """<?xml version="1.0" encoding="utf-8"?>
<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="12"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="35"/>
        <transform name="to_world">
            <lookat origin="0.0, 1.3, 3.2" target="0.0, 0.55, 0.0" up="0.0, 1.0, 0.0"/>
        </transform>
        <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="32"/><integer name="height" value="32"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <shape type="sphere">
        <point name="center" x="0" y="0.6" z="0"/>
        <float name="radius" value="0.6"/>
        {bsdf}
        {medium}
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="4.0"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.5, 0.7"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="0.4"/>
            <lookat origin="1.2, 2.2, 1.0" target="0.0, 0.5, 0.0" up="0.0, 1.0, 0.0"/>
        </transform>
        <emitter type="area"><rgb name="radiance" value="25.0"/></emitter>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="0.25"/></emitter>
</scene>
"""

HOMOGENEOUS = """<medium type="homogeneous" name="interior">
            <float name="sigma_t" value="2.0"/>
            <rgb name="albedo" value="0.9"/>
        </medium>"""

NONEXP_EXPONENTIAL = """<medium type="nonexponential" name="interior">
            <string name="transmittance" value="exponential"/>
            <float name="sigma_t" value="2.0"/>
            <rgb name="albedo" value="0.9"/>
        </medium>"""

CASES = {
    "roughconductor-beckmann": '<bsdf type="roughconductor"><string name="material" value="Au"/>'
    '<float name="alpha" value="0.3"/></bsdf>',
    "roughconductor-ggx-all-normals": '<bsdf type="roughconductor"><string name="material" value="Cu"/>'
    '<string name="distribution" value="ggx"/><float name="alpha" value="0.15"/>'
    '<boolean name="sample_visible" value="false"/></bsdf>',
    "roughdielectric-beckmann": '<bsdf type="roughdielectric"><float name="alpha" value="0.2"/>'
    '<float name="int_ior" value="1.5"/></bsdf>',
    "plastic": '<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.7, 0.2, 0.2"/>'
    '<float name="int_ior" value="1.6"/></bsdf>',
    "thindielectric": '<bsdf type="thindielectric"><float name="int_ior" value="1.7"/></bsdf>',
}


def _write(tmp: Path, name: str, bsdf: str, medium: str = "") -> Path:
    p = tmp / f"{name}.xml"
    p.write_text(SCENE.format(spp=SPP, bsdf=bsdf, medium=medium))
    return p


def _mitsuba():
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    return mi


def render_fgf(scene: Path) -> np.ndarray:
    return np.stack([fgf.render(scene, spp=SPP, seed=2000 + i, progress=False) for i in range(K)]).astype(np.float64)


def render_mitsuba(scene: Path) -> np.ndarray:
    mi = _mitsuba()
    sc = mi.load_file(str(scene))
    return np.stack([np.array(mi.render(sc, seed=i, spp=SPP))[..., :3] for i in range(K)]).astype(np.float64)


def compare(fgf_scene: Path, mitsuba_scene: Path) -> None:
    assert_agree(fgf_scene.name, render_fgf(fgf_scene), render_mitsuba(mitsuba_scene))


@pytest.mark.parametrize("name", sorted(CASES))
def test_bsdf_matches_mitsuba(tmp_path, name):
    scene = _write(tmp_path, name, CASES[name])
    compare(scene, scene)


# fgf's roughplastic matches Mitsuba 3.9.1's BSDF value to 0.15 % at normal
# incidence, but its diffuse lobe is up to 7 % brighter at grazing incidence
# (cos θ_i = 0.05, against Mitsuba's BSDF.eval): the loader refuses it until
# the coating transmittance is found.
def test_roughplastic_is_refused_in_one_line(tmp_path):
    scene = _write(tmp_path, "roughplastic", '<bsdf type="roughplastic"><float name="alpha" value="0.2"/></bsdf>')
    with pytest.raises(fgf.FgfError, match="roughplastic is not supported yet") as e:
        fgf.render(scene, spp=1)
    assert "\n" not in str(e.value)


def test_homogeneous_medium_in_rough_dielectric(tmp_path):
    bsdf = '<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="0.15"/></bsdf>'
    scene = _write(tmp_path, "rough-glass-medium", bsdf, HOMOGENEOUS)
    compare(scene, scene)


def test_nonexponential_medium_in_rough_dielectric(tmp_path):
    """fgf's non-exponential medium with the exponential model has the
    homogeneous medium's expectation (docs/theory.md §4)."""
    bsdf = '<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="0.15"/></bsdf>'
    ours = _write(tmp_path, "rough-glass-nonexp", bsdf, NONEXP_EXPONENTIAL)
    theirs = _write(tmp_path, "rough-glass-homogeneous", bsdf, HOMOGENEOUS)
    compare(ours, theirs)


ENV_SCENE = """<?xml version="1.0" encoding="utf-8"?>
<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="8"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <transform name="to_world">
            <lookat origin="0.0, 1.0, 3.0" target="0.0, 0.6, 0.0" up="0.0, 1.0, 0.0"/>
        </transform>
        <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="32"/><integer name="height" value="32"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <shape type="sphere">
        <point name="center" x="-0.45" y="0.5" z="0"/>
        <float name="radius" value="0.45"/>
        <bsdf type="roughconductor"><string name="material" value="Al"/><float name="alpha" value="0.25"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="0.5" y="0.45" z="0.2"/>
        <float name="radius" value="0.4"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.6, 0.5"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3.0"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.4"/></bsdf>
    </shape>
    <emitter type="envmap">
        <string name="filename" value="{image}"/>
        <float name="scale" value="1.5"/>
        <transform name="to_world"><rotate y="1" angle="70"/></transform>
    </emitter>
</scene>
"""


def _env_image() -> np.ndarray:
    """A 48x24 sky: a bluish gradient, a warm ground band and a small bright
    sun (two orders of magnitude above the sky), so that luminance sampling
    matters."""
    h, w = 24, 48
    v = (np.arange(h) + 0.5) / h
    u = (np.arange(w) + 0.5) / w
    uu, vv = np.meshgrid(u, v)
    sky = np.stack([0.3 + 0.2 * vv, 0.4 + 0.2 * vv, 0.9 - 0.3 * vv], axis=-1) * (0.6 + 0.4 * np.cos(2 * np.pi * uu))[..., None]
    ground = vv > 0.55
    sky[ground] = [0.35, 0.25, 0.15]
    d2 = ((uu - 0.3) * 2) ** 2 + (vv - 0.25) ** 2
    sky += (60.0 * np.exp(-d2 / 0.002))[..., None] * np.array([1.0, 0.9, 0.7])
    return sky.astype(np.float32)


@pytest.mark.parametrize("ext", ["exr", "hdr"])
def test_envmap_matches_mitsuba(tmp_path, ext):
    mi = _mitsuba()
    image = tmp_path / f"sky.{ext}"
    mi.Bitmap(_env_image()).write(str(image))
    scene = tmp_path / f"envmap-{ext}.xml"
    scene.write_text(ENV_SCENE.format(spp=SPP, image=image.name))
    compare(scene, scene)


def test_envmap_refuses_other_formats(tmp_path):
    (tmp_path / "sky.png").write_bytes(b"")
    scene = tmp_path / "bad.xml"
    scene.write_text(ENV_SCENE.format(spp=SPP, image="sky.png"))
    with pytest.raises(fgf.FgfError, match="only OpenEXR"):
        fgf.render(scene, spp=1, progress=False)
