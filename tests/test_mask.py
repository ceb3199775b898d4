"""fgf's `mask` BSDF against Mitsuba 3 (``scalar_rgb``).

A leaf-like rectangle (a `mask` around a diffuse BSDF) hangs
between a diffuse floor and two lights: a rectangular area light above it
and a point light, so that the floor sees both through the leaf; a small
area light behind the leaf faces the camera, which sees it through the
leaf. The opacity is a float or a checkerboard; a `thindielectric` leaf,
the other BSDF with a null lobe, is rendered too. A small `max_depth` (3)
makes the integrators' treatment of the transparent part visible: Mitsuba's
`path` counts crossing it as a bounce and its shadow rays stop at the leaf
(so the point light casts a full shadow), `volpath` and `volpathmis` give
the crossing no depth and pass shadow rays with weight `1 - opacity`, and
`direct` blocks shadow rays but sees emitters through the leaf by BSDF
sampling. Comparison as in ``test_materials``: K = 16 images per renderer,
image means within 3 standard errors, 8x8 blocks by Welch's t with Holm's
correction.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import fgf
import test_materials as materials
from test_render_mitsuba import Z_MEAN, assert_agree, welch

SPP = 16

SCENE = """<?xml version="1.0" encoding="utf-8"?>
<scene version="3.0.0">
    {integrator}
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world">
            <lookat origin="0.0, 1.6, 3.2" target="0.0, 0.4, 0.0" up="0.0, 1.0, 0.0"/>
        </transform>
        <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="32"/><integer name="height" value="32"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world">
            <scale x="0.9" y="0.7"/><rotate x="1" angle="-70"/><translate y="0.8" z="0.6"/>
        </transform>
        {bsdf}
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="4.0"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.5, 0.7"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="0.5"/>
            <lookat origin="0.3, 2.6, 0.9" target="0.0, 0.0, 0.4" up="0.0, 1.0, 0.0"/>
        </transform>
        <emitter type="area"><rgb name="radiance" value="12.0"/></emitter>
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <scale x="0.35" y="0.2"/>
            <lookat origin="-0.2, 0.9, -0.6" target="0.0, 1.6, 3.2" up="0.0, 1.0, 0.0"/>
        </transform>
        <emitter type="area"><rgb name="radiance" value="3.0, 2.0, 1.0"/></emitter>
    </shape>
    <emitter type="point">
        <point name="position" x="-0.4" y="2.2" z="0.9"/>
        <rgb name="intensity" value="3.0"/>
    </emitter>
    <emitter type="constant"><rgb name="radiance" value="0.1"/></emitter>
</scene>
"""

DIFFUSE = '<bsdf type="diffuse"><rgb name="reflectance" value="0.3, 0.7, 0.2"/></bsdf>'
CHECKER = (
    '<texture type="checkerboard" name="opacity">'
    '<rgb name="color0" value="0.9"/><rgb name="color1" value="0.1, 0.2, 0.3"/>'
    '<transform name="to_uv"><scale x="3" y="3"/></transform></texture>'
)

BSDFS = {
    # mask(diffuse), float opacity: one-sided, so the nested part is black
    # from the back
    "float": f'<bsdf type="mask"><float name="opacity" value="0.6"/>{DIFFUSE}</bsdf>',
    # mask(twosided(diffuse)), checkerboard opacity
    "checkerboard": f'<bsdf type="mask">{CHECKER}<bsdf type="twosided">{DIFFUSE}</bsdf></bsdf>',
    # The other BSDF with a null lobe: Mitsuba's volpath passes shadow rays
    # through a thin dielectric too (with weight (1 - R')T), so the point
    # light shines through it there and not under path.
    "thindielectric": '<bsdf type="thindielectric"><float name="int_ior" value="1.7"/></bsdf>',
}


def _write(tmp: Path, name: str, integrator: str, max_depth: int = 3) -> Path:
    p = tmp / f"mask-{name}-{integrator}.xml"
    tag = f'<integrator type="{integrator}"><integer name="max_depth" value="{max_depth}"/></integrator>'
    if integrator == "direct":
        tag = '<integrator type="direct"/>'
    p.write_text(SCENE.format(spp=SPP, bsdf=BSDFS[name], integrator=tag))
    return p


def render_fgf(scene: Path) -> np.ndarray:
    return materials.render_fgf(scene, SPP, 3000)


def render_mitsuba(scene: Path) -> np.ndarray:
    return materials.render_mitsuba(scene, SPP)


@pytest.mark.parametrize("integrator", ["path", "volpath", "volpathmis", "direct"])
@pytest.mark.parametrize("name", sorted(BSDFS))
def test_mask_matches_mitsuba(tmp_path, name, integrator):
    scene = _write(tmp_path, name, integrator)
    assert_agree(scene.name, render_fgf(scene), render_mitsuba(scene))


def test_mask_depth_and_shadows_differ_between_path_and_volpath(tmp_path):
    """The comparison above can tell the integrators' treatments apart:
    Mitsuba's `path` and `volpath` images of the float-opacity scene differ
    by many standard errors in at least one channel, and `assert_agree`
    fails on any channel whose mean is off by more than Z_MEAN (3) standard
    errors, so a renderer that treated the mask the same way under both
    would fail one of them. (The red channel alone is the weakest, near 6
    standard errors at these settings; blue is near 16.)"""
    a = render_mitsuba(_write(tmp_path, "float", "path"))
    b = render_mitsuba(_write(tmp_path, "float", "volpath"))
    *_, z, _ = welch(a.mean(axis=(1, 2)), b.mean(axis=(1, 2)))
    assert np.abs(z).max() > 2 * Z_MEAN, z


def test_mask_refusals(tmp_path):
    """One line naming the problem, for a mask without a nested BSDF, with
    two, with an opacity outside [0, 1], or inside `twosided` (which
    Mitsuba refuses around a BSDF that transmits)."""
    cases = {
        "twosided": f'<bsdf type="twosided"><bsdf type="mask">{DIFFUSE}</bsdf></bsdf>',
        "none": '<bsdf type="mask"><float name="opacity" value="0.5"/></bsdf>',
        "two": f'<bsdf type="mask">{DIFFUSE}{DIFFUSE}</bsdf>',
        "range": f'<bsdf type="mask"><float name="opacity" value="1.5"/>{DIFFUSE}</bsdf>',
    }
    for name, bsdf in cases.items():
        p = tmp_path / f"{name}.xml"
        p.write_text(f'<scene version="3.0.0"><shape type="sphere">{bsdf}</shape></scene>')
        with pytest.raises(fgf.SceneError) as e:
            fgf.render(p, spp=1, progress=False)
        msg = str(e.value)
        assert "\n" not in msg and ("mask" in msg or "opacity" in msg), msg
