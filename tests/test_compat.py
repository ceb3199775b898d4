"""Mitsuba 3 features the loader accepts, each rendered by fgf and by the
``mitsuba`` package (``scalar_rgb``) and compared with the standard error
(image mean within 3 SE per channel, 8x8 blocks by Welch's t with Holm's
correction; see ``tests/test_render_mitsuba.py`` for the statistics).

One small scene per group of features: the constant-``sigma_t``
heterogeneous medium's bounding box, the ``direct`` integrator with
Mitsuba's sample-count weights, the camera's principal point offset (with
``focus_distance``, a ``stratified`` sampler and a ``moment`` wrapper), a
pre-2.0 scene with camelCase names, a ``serialized`` mesh with
``shape_index``, a grid albedo in a homogeneous medium, a referenced area
emitter with a uniform ``<spectrum>`` radiance, an area emitter on a
smooth-normal mesh, a grid's ``wrap_mode``.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

import fgf
from test_render_mitsuba import compare

pytest.importorskip("mitsuba")

SENSOR = """
<sensor type="perspective">
    <float name="fov" value="40"/>
    {extra}
    <transform name="to_world"><lookat origin="0, 0.5, 6" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="{sampler}"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm">
        <integer name="width" value="32"/><integer name="height" value="32"/>
        <rfilter type="box"/>
    </film>
</sensor>"""


def sensor(extra: str = "", sampler: str = "independent") -> str:
    return SENSOR.format(extra=extra, sampler=sampler)


def write(tmp: Path, name: str, body: str, version: str = "3.0.0") -> Path:
    p = tmp / name
    p.write_text(f'<scene version="{version}">\n{body}\n</scene>\n')
    return p


def test_heterogeneous_constant_sigma_t_exists_only_in_its_volume_box(tmp_path: Path) -> None:
    # An absorbing cube over [-1, 1]^3 under a white sky: Mitsuba fills only
    # [0, 1]^3 for a float sigma_t, and the constvolume's moved box.
    body = (
        '<integrator type="volpath"/>'
        + sensor()
        + """
<emitter type="constant"><rgb name="radiance" value="1"/></emitter>
<shape type="cube"><bsdf type="null"/>
  <medium type="heterogeneous" name="interior">
    <float name="sigma_t" value="2"/><rgb name="albedo" value="0"/>
  </medium>
</shape>
<shape type="sphere"><float name="radius" value="0.5"/>
  <transform name="to_world"><translate value="-1.6, 0, 0"/></transform>
  <bsdf type="null"/>
  <medium type="heterogeneous" name="interior">
    <volume type="constvolume" name="sigma_t"><rgb name="value" value="3, 1, 0.5"/>
      <transform name="to_world"><translate value="-2, -0.5, -0.5"/></transform>
    </volume>
    <rgb name="albedo" value="0.8"/>
  </medium>
</shape>"""
    )
    compare(write(tmp_path, "bbox.xml", body), {}, 16)


DIRECT_BODY = """
<integrator type="direct">
    <integer name="emitter_samples" value="2"/>
    <integer name="bsdf_samples" value="3"/>
</integrator>
{sensor}
<emitter type="point"><point name="position" x="1" y="2" z="2"/><rgb name="intensity" value="4"/></emitter>
<shape type="sphere" id="lamp">
    <float name="radius" value="0.4"/>
    <transform name="to_world"><translate value="-1, 1.5, 0.5"/></transform>
    <emitter type="area"><rgb name="radiance" value="6, 5, 4"/></emitter>
</shape>
<shape type="rectangle">
    <transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/><translate y="-0.8"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.5, 0.3"/></bsdf>
</shape>
<shape type="sphere">
    <float name="radius" value="0.6"/>
    <bsdf type="conductor"/>
</shape>
"""


def test_direct_integrator_matches_mitsuba_with_its_sample_weights(tmp_path: Path) -> None:
    compare(write(tmp_path, "direct.xml", DIRECT_BODY.format(sensor=sensor())), {}, 16)


def test_principal_point_focus_distance_stratified_and_moment(tmp_path: Path) -> None:
    body = (
        '<integrator type="moment"><integrator type="path" name="a"><integer name="max_depth" value="3"/></integrator></integrator>'
        + sensor(
            '<float name="principal_point_offset_x" value="0.15"/>'
            '<float name="principal_point_offset_y" value="-0.1"/>'
            '<float name="focus_distance" value="4"/>',
            sampler="stratified",
        )
        + """
<emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>
<shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.3, 0.2"/></bsdf></shape>
<shape type="cube"><transform name="to_world"><scale value="0.4"/><translate value="1.2, 0.3, 0"/></transform></shape>"""
    )
    compare(write(tmp_path, "camera.xml", body), {}, 16)


def test_pre_2_0_scene_with_camel_case_names(tmp_path: Path) -> None:
    body = (
        '<integrator type="path"><integer name="maxDepth" value="4"/></integrator>'
        + sensor()
        + """
<emitter type="constant"><rgb name="radiance" value="1"/></emitter>
<shape type="sphere"><bsdf type="dielectric"><float name="intIOR" value="1.7"/></bsdf></shape>
<shape type="cube">
  <transform name="toWorld"><scale value="0.3"/><translate x="1.3"/></transform>
  <bsdf type="diffuse"><rgb name="diffuseReflectance" value="0.2, 0.6, 0.3"/></bsdf>
</shape>"""
    )
    compare(write(tmp_path, "v06.xml", body, version="0.6.0"), {}, 16)


def serialized_mesh(pos: np.ndarray, tris: np.ndarray, version: int) -> bytes:
    """One mesh of a ``serialized`` file (single precision, no normals)."""
    body = struct.pack("<I", 0x1000)
    if version == 4:
        body += b"mesh\0"
    body += struct.pack("<QQ", len(pos), len(tris))
    body += pos.astype("<f4").tobytes() + tris.astype("<u4").tobytes()
    return struct.pack("<HH", 0x041C, version) + zlib.compress(body)


def write_serialized(path: Path, meshes: list[tuple[np.ndarray, np.ndarray]], version: int) -> None:
    out = b""
    offsets = []
    for pos, tris in meshes:
        offsets.append(len(out))
        out += serialized_mesh(pos, tris, version)
    fmt = "<Q" if version == 4 else "<I"
    out += b"".join(struct.pack(fmt, o) for o in offsets) + struct.pack("<I", len(meshes))
    path.write_bytes(out)


@pytest.mark.parametrize("version", [3, 4])
def test_serialized_meshes_by_shape_index(tmp_path: Path, version: int) -> None:
    quad = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    tri = np.array([[-0.5, -0.5, 0.5], [0.8, -0.4, 0.6], [0.0, 0.9, 0.4]], float)
    write_serialized(
        tmp_path / "m.serialized",
        [(quad, np.array([[0, 1, 2], [0, 2, 3]])), (tri, np.array([[0, 1, 2]]))],
        version,
    )
    body = (
        '<integrator type="path"/>'
        + sensor()
        + """
<emitter type="constant"><rgb name="radiance" value="1"/></emitter>
<shape type="serialized"><string name="filename" value="m.serialized"/>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.3"/></bsdf></shape>
<shape type="serialized"><string name="filename" value="m.serialized"/><integer name="shape_index" value="1"/>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.9, 0.2, 0.1"/></bsdf></shape>"""
    )
    compare(write(tmp_path, "ser.xml", body), {}, 16)


def test_grid_albedo_in_homogeneous_medium_and_referenced_area_emitter(tmp_path: Path) -> None:
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    g = np.linspace(0.1, 1.0, 4 * 4 * 4 * 3, dtype=np.float32).reshape(4, 4, 4, 3)
    mi.VolumeGrid(g).write(str(tmp_path / "albedo.vol"))
    body = (
        '<integrator type="volpath"><integer name="max_depth" value="6"/></integrator>'
        + sensor()
        + """
<emitter type="area" id="light"><spectrum name="radiance" value="3"/></emitter>
<shape type="rectangle">
  <transform name="to_world"><rotate x="1" angle="90"/><translate y="2"/></transform>
  <ref id="light"/>
</shape>
<emitter type="constant"><rgb name="radiance" value="0.2"/></emitter>
<shape type="cube"><bsdf type="null"/>
  <medium type="homogeneous" name="interior">
    <float name="sigma_t" value="2"/>
    <volume type="gridvolume" name="albedo"><string name="filename" value="albedo.vol"/>
      <transform name="to_world"><scale value="2"/><translate value="-1, -1, -1"/></transform>
    </volume>
  </medium>
</shape>"""
    )
    compare(write(tmp_path, "albedo.xml", body), {}, 16)


@pytest.mark.parametrize("wrap", ["repeat", "mirror"])
def test_grid_wrap_modes(tmp_path: Path, wrap: str) -> None:
    # A coarse sigma_t grid whose opposite faces differ tenfold: under
    # `repeat` a trilinear lookup within half a voxel of a face reads the
    # other face (the cube's rim), and an albedo grid looked up far outside
    # its box reads its wrapped or mirrored copies.
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    x = np.array([0.2, 3.0, 0.5, 6.0], dtype=np.float32)
    g = (x[None, None, :] * np.array([1.0, 0.3, 2.0], dtype=np.float32)[None, :, None])[..., None]
    mi.VolumeGrid(np.ascontiguousarray(np.broadcast_to(g, (3, 3, 4, 1)))).write(str(tmp_path / "st.vol"))
    a = np.linspace(0.1, 1.0, 2 * 2 * 2 * 3, dtype=np.float32).reshape(2, 2, 2, 3)
    mi.VolumeGrid(a).write(str(tmp_path / "albedo.vol"))
    body = (
        '<integrator type="volpath"><integer name="max_depth" value="8"/></integrator>'
        + sensor()
        + f"""
<emitter type="constant"><rgb name="radiance" value="1"/></emitter>
<shape type="cube"><bsdf type="null"/>
  <transform name="to_world"><scale value="1.2"/></transform>
  <medium type="heterogeneous" name="interior">
    <volume type="gridvolume" name="sigma_t"><string name="filename" value="st.vol"/>
      <string name="wrap_mode" value="{wrap}"/>
      <transform name="to_world"><scale value="2.4"/><translate value="-1.2, -1.2, -1.2"/></transform>
    </volume>
    <volume type="gridvolume" name="albedo"><string name="filename" value="albedo.vol"/>
      <string name="wrap_mode" value="{wrap}"/>
      <transform name="to_world"><scale value="0.7"/><translate value="-0.35, -0.35, -0.35"/></transform>
    </volume>
  </medium>
</shape>"""
    )
    compare(write(tmp_path, "wrap.xml", body), {}, 16)


def test_wavelength_value_spectra_convert_as_mitsuba_rgb_variants(tmp_path: Path) -> None:
    # A reflectance (D65-weighted, clamped to [0, 1]), an emitter's radiance
    # (unweighted) and a conductor's eta/k (D65-weighted, unclamped above).
    body = (
        '<integrator type="path"><integer name="max_depth" value="3"/></integrator>'
        + sensor()
        + """
<emitter type="constant"><spectrum name="radiance" value="380:0.5, 450:0.9, 560:1.4, 700:0.6, 780:0.3"/></emitter>
<shape type="sphere">
  <bsdf type="diffuse"><spectrum name="reflectance" value="400:0.05, 500:0.8, 600:0.3, 700:0.95"/></bsdf>
</shape>
<shape type="cube"><transform name="to_world"><scale value="0.4"/><translate value="1.3, 0.2, 0"/></transform>
  <bsdf type="conductor"><spectrum name="eta" value="400:1.6, 550:0.9, 700:0.2"/><spectrum name="k" value="400:2.0, 550:2.6, 700:3.9"/></bsdf>
</shape>"""
    )
    compare(write(tmp_path, "spec.xml", body), {}, 16)


def test_malformed_spectrum_is_refused_in_one_line(tmp_path: Path) -> None:
    body = '<shape type="sphere"><bsdf type="diffuse"><spectrum name="reflectance" value="700:0.1, 400:0.9"/></bsdf></shape>'
    with pytest.raises(fgf.SceneError) as e:
        fgf.render(write(tmp_path, "spec.xml", body), spp=1, progress=False)
    msg = str(e.value)
    assert "wavelengths must increase" in msg and "\n" not in msg


def _smooth_octahedron_obj(path: Path, levels: int = 1) -> None:
    """A coarse sphere: an octahedron subdivided `levels` times, vertices on
    the unit sphere, with vertex normals along the positions (so the shading
    normals differ from the faces' by up to ~30 degrees)."""
    v = [np.array(p, float) for p in [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]]
    f = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
    for _ in range(levels):
        mid: dict[tuple[int, int], int] = {}

        def m(a: int, b: int) -> int:
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = v[a] + v[b]
                v.append(p / np.linalg.norm(p))
                mid[key] = len(v) - 1
            return mid[key]

        f = [t for a, b, c in f for t in ((a, m(a, b), m(c, a)), (b, m(b, c), m(a, b)), (c, m(c, a), m(b, c)), (m(a, b), m(b, c), m(c, a)))]
    lines = [f"v {p[0]} {p[1]} {p[2]}" for p in v] + [f"vn {p[0]} {p[1]} {p[2]}" for p in v]
    lines += [f"f {a + 1}//{a + 1} {b + 1}//{b + 1} {c + 1}//{c + 1}" for a, b, c in f]
    path.write_text("\n".join(lines) + "\n")


def test_smooth_mesh_area_emitter_emits_by_its_shading_normal(tmp_path: Path) -> None:
    """A coarse smooth-normal mesh carrying an `area` emitter above a
    diffuse floor, in a `volpath` (light and BSDF samples combined by MIS)
    and a `direct` render. Mitsuba decides the emitting side and converts the
    light's area pdf to solid angle with the shading normal; with the
    geometric normal, fgf lit the floor 5 % more brightly than Mitsuba here
    (z ≈ 30 over 64 seeds; docs/compatibility.md, "The emitter-in-medium
    bias")."""
    _smooth_octahedron_obj(tmp_path / "ball.obj")
    for integrator in ('<integrator type="volpath"><integer name="max_depth" value="3"/></integrator>', '<integrator type="direct"/>'):
        body = (
            integrator
            + sensor()
            + """
<shape type="obj"><string name="filename" value="ball.obj"/>
    <transform name="to_world"><scale value="0.6"/><translate y="0.9"/></transform>
    <emitter type="area"><rgb name="radiance" value="3, 2, 1"/></emitter>
</shape>
<shape type="rectangle">
    <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/><translate y="-0.6"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf>
</shape>"""
        )
        compare(write(tmp_path, "smooth_emitter.xml", body), {}, 16)
