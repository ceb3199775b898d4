"""Textures (``checkerboard``, ``bitmap``) and the texture coordinates of
every shape, rendered by fgf and by the ``mitsuba`` package (``scalar_rgb``)
and compared with the statistics of ``tests/test_render_mitsuba.py`` (image
mean within 3 SE per channel, 8x8 blocks by Welch's t with Holm's
correction, 16 seeds each).

The checks are large and strongly coloured (red against blue, one check
about a block wide), so that a texture placed wrongly — a flipped ``v``, a
cube face turned, a wrong wrap mode — moves whole blocks by many standard
errors, not only the image mean.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

import fgf
from test_render_mitsuba import K, assert_agree, compare, render_fgf, render_mitsuba

pytest.importorskip("mitsuba")

SENSOR = """
<integrator type="path"><integer name="max_depth" value="3"/></integrator>
<sensor type="perspective">
    <float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0, 0, 7" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm">
        <integer name="width" value="32"/><integer name="height" value="32"/>
        <rfilter type="box"/>
    </film>
</sensor>
<emitter type="constant"><rgb name="radiance" value="1"/></emitter>
"""

CHECKER = """
<texture type="checkerboard" id="{id}">
    <rgb name="color0" value="0.9, 0.1, 0.1"/>
    <rgb name="color1" value="0.05, 0.1, 0.8"/>
    <transform name="to_uv"><scale x="{sx}" y="{sy}"/><translate x="0.25" y="0.1"/></transform>
</texture>
"""


def write(tmp: Path, name: str, body: str) -> Path:
    p = tmp / name
    p.write_text(f'<scene version="3.0.0">\n{SENSOR}\n{body}\n</scene>\n')
    return p


SMALLER = '<scale value="0.9"/>'


def place(x: float, y: float, extra: str = "") -> str:
    return f'<transform name="to_world">{extra}<translate x="{x}" y="{y}"/></transform>'


def test_checkerboard_on_rectangle_disk_sphere_and_cube(tmp_path: Path) -> None:
    # Each shape's own parameterisation (Mitsuba's), under rotations that
    # show the cube's three front faces and the sphere's seam.
    body = CHECKER.format(id="c", sx=2, sy=3) + """
<bsdf type="twosided" id="b"><bsdf type="diffuse"><ref name="reflectance" id="c"/></bsdf></bsdf>
<shape type="rectangle">{r}<ref id="b"/></shape>
<shape type="disk">{d}<ref id="b"/></shape>
<shape type="sphere"><float name="radius" value="1.1"/>{s}<ref id="b"/></shape>
<shape type="cube">{c}<ref id="b"/></shape>
""".format(
        r=place(-1.4, 1.4, '<scale value="1.1"/><rotate z="1" angle="20"/>'),
        d=place(1.4, 1.4, '<scale value="1.1"/><rotate z="1" angle="-30"/>'),
        s=place(-1.4, -1.4, '<rotate x="1" angle="70"/><rotate y="1" angle="40"/>'),
        c=place(1.4, -1.4, '<scale value="0.75"/><rotate y="1" angle="35"/><rotate x="1" angle="30"/>'),
    )
    compare(write(tmp_path, "shapes.xml", body), {}, 16)


def png_bytes(rgb: np.ndarray) -> bytes:
    """An 8-bit RGB PNG of `rgb` (h, w, 3), uint8."""
    h, w, _ = rgb.shape
    raw = b"".join(b"\0" + rgb[y].astype(np.uint8).tobytes() for y in range(h))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


# A 4x3 image of distinct colours: its orientation, filtering and wrapping
# all show in the rendered image.
IMAGE = np.array(
    [
        [[230, 20, 20], [20, 230, 20], [20, 20, 230], [230, 230, 20]],
        [[20, 230, 230], [230, 20, 230], [128, 128, 128], [250, 250, 250]],
        [[10, 10, 10], [200, 120, 40], [40, 120, 200], [120, 40, 200]],
    ],
    np.uint8,
)


def write_images(tmp: Path) -> None:
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    (tmp / "img.png").write_bytes(png_bytes(IMAGE))
    linear = (IMAGE.astype(np.float32) / 255.0) ** 2.2
    mi.Bitmap(linear).write(str(tmp / "img.exr"))


def bitmap(name: str, file: str, extra: str = "", to_uv: str = "") -> str:
    t = f'<transform name="to_uv">{to_uv}</transform>' if to_uv else ""
    return f'<texture type="bitmap" name="{name}"><string name="filename" value="{file}"/>{extra}{t}</texture>'


def test_bitmap_filters_wrap_modes_srgb_and_raw(tmp_path: Path) -> None:
    write_images(tmp_path)
    # to_uv shows the image 1.7 times, shifted, so that every wrap mode's
    # outside matters; six rectangles, one per combination.
    uv = '<scale x="1.7" y="1.7"/><translate x="-0.35" y="-0.35"/>'
    cases = [
        ("img.png", '<string name="filter_type" value="nearest"/><string name="wrap_mode" value="repeat"/>'),
        ("img.png", '<string name="filter_type" value="bilinear"/><string name="wrap_mode" value="mirror"/>'),
        ("img.png", '<string name="wrap_mode" value="clamp"/><boolean name="raw" value="true"/>'),
        ("img.exr", '<string name="filter_type" value="nearest"/><string name="wrap_mode" value="mirror"/>'),
        ("img.exr", '<string name="wrap_mode" value="clamp"/>'),
        ("img.png", ""),
    ]
    shapes = []
    for i, (file, extra) in enumerate(cases):
        x, y = -1.9 + 1.9 * (i % 3), 1.0 - 2.0 * (i // 3)
        shapes.append(
            f'<shape type="rectangle">{place(x, y, SMALLER)}'
            f'<bsdf type="diffuse">{bitmap("reflectance", file, extra, uv)}</bsdf></shape>'
        )
    compare(write(tmp_path, "bitmaps.xml", "\n".join(shapes)), {}, 16)


def test_mesh_texture_coordinates_obj_ply_serialized_and_none(tmp_path: Path) -> None:
    write_images(tmp_path)
    quad = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    uvs = np.array([[0.1, 0.0], [0.9, 0.2], [1.0, 1.0], [0.0, 0.8]], float)
    tris = np.array([[0, 1, 2], [0, 2, 3]])
    (tmp_path / "q.obj").write_text(
        "".join(f"v {p[0]} {p[1]} {p[2]}\n" for p in quad)
        + "".join(f"vt {t[0]} {t[1]}\n" for t in uvs)
        + "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n"
    )
    header = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    for name, (a, b) in [("uv", ("u", "v")), ("st", ("s", "t")), ("tuv", ("texture_u", "texture_v"))]:
        (tmp_path / f"q_{name}.ply").write_text(
            header
            + f"property float {a}\nproperty float {b}\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
            + "".join(f"{p[0]} {p[1]} {p[2]} {t[0]} {t[1]}\n" for p, t in zip(quad, uvs))
            + "3 0 1 2\n3 0 2 3\n"
        )
    (tmp_path / "q_none.ply").write_text(
        header
        + "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
        + "".join(f"{p[0]} {p[1]} {p[2]}\n" for p in quad)
        + "3 0 1 2\n3 0 2 3\n"
    )
    body = struct.pack("<I", 0x1000 | 0x0002) + b"q\0" + struct.pack("<QQ", 4, 2)
    body += quad.astype("<f4").tobytes() + uvs.astype("<f4").tobytes() + tris.astype("<u4").tobytes()
    ser = struct.pack("<HH", 0x041C, 4) + zlib.compress(body)
    (tmp_path / "q.serialized").write_bytes(ser + struct.pack("<QI", 0, 1))
    nearest = '<string name="filter_type" value="nearest"/>'
    files = [
        ("obj", "q.obj"),
        ("ply", "q_uv.ply"),
        ("ply", "q_st.ply"),
        ("ply", "q_tuv.ply"),
        ("serialized", "q.serialized"),
    ]
    shapes = []
    for i, (kind, file) in enumerate(files):
        x, y = -1.9 + 1.9 * (i % 3), 1.0 - 2.0 * (i // 3)
        shapes.append(
            f'<shape type="{kind}"><string name="filename" value="{file}"/>'
            f"{place(x, y, SMALLER)}"
            f'<bsdf type="diffuse">{bitmap("reflectance", "img.png", nearest)}</bsdf></shape>'
        )
    # Without texture coordinates a triangle's uv is its barycentrics.
    shapes.append(
        CHECKER.format(id="c", sx=3, sy=3)
        + f'<shape type="ply"><string name="filename" value="q_none.ply"/>{place(1.9, -1.0, SMALLER)}'
        '<bsdf type="diffuse"><ref name="reflectance" id="c"/></bsdf></shape>'
    )
    compare(write(tmp_path, "meshes.xml", "\n".join(shapes)), {}, 16)


def test_textured_plastic_dielectric_conductor_and_roughness(tmp_path: Path) -> None:
    # plastic's lobe choice uses the texture's mean (as Mitsuba's); a
    # roughconductor's alpha from a checkerboard (eval_1: the channel mean);
    # a dielectric's transmittance and a conductor's reflectance.
    body = (
        CHECKER.format(id="c", sx=2, sy=2)
        + """
<texture type="checkerboard" id="alpha">
    <float name="color0" value="0.03"/><float name="color1" value="0.6"/>
    <transform name="to_uv"><scale x="3" y="2"/></transform>
</texture>
<shape type="rectangle"><transform name="to_world"><scale value="6"/><translate z="-2"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
<shape type="sphere">{a}
  <bsdf type="plastic"><ref name="diffuse_reflectance" id="c"/><float name="int_ior" value="1.7"/></bsdf></shape>
<shape type="sphere">{b}
  <bsdf type="roughconductor"><string name="material" value="Au"/><string name="distribution" value="ggx"/>
    <ref name="alpha" id="alpha"/></bsdf></shape>
<shape type="rectangle">{c}
  <bsdf type="dielectric"><ref name="specular_transmittance" id="c"/></bsdf></shape>
<shape type="rectangle">{d}
  <bsdf type="conductor"><string name="material" value="Cu"/><ref name="specular_reflectance" id="c"/></bsdf></shape>
""".format(
            a=place(-1.3, 1.3),
            b=place(1.3, 1.3, '<rotate x="1" angle="60"/>'),
            c=place(-1.3, -1.3),
            d=place(1.3, -1.3, '<rotate y="1" angle="30"/>'),
        )
    )
    compare(write(tmp_path, "materials.xml", body), {}, 16)


def test_textured_conductor_eta_and_k(tmp_path: Path) -> None:
    # A conductor's complex index from textures, as Mitsuba allows: a
    # checkerboard eta and a checkerboard k on a smooth conductor and on a
    # rough one (Fresnel per channel of the texture's value at the hit).
    # Mitsuba 3.9.1 reads a checkerboard's colours as reflectances, so
    # they stay within [0, 1] here even for eta and k.
    body = """
<texture type="checkerboard" id="eta">
    <rgb name="color0" value="0.2, 0.9, 1.0"/><rgb name="color1" value="0.95, 0.4, 0.3"/>
    <transform name="to_uv"><scale x="3" y="2"/></transform>
</texture>
<texture type="checkerboard" id="k">
    <rgb name="color0" value="0.9, 0.6, 1.0"/><rgb name="color1" value="0.3, 1.0, 0.1"/>
    <transform name="to_uv"><scale x="2" y="5"/></transform>
</texture>
<shape type="rectangle"><transform name="to_world"><scale value="6"/><translate z="-2"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
<shape type="rectangle">{a}
  <bsdf type="conductor"><ref name="eta" id="eta"/><ref name="k" id="k"/></bsdf></shape>
<shape type="sphere">{b}
  <bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/>
    <ref name="eta" id="eta"/><rgb name="k" value="2.0"/></bsdf></shape>
<shape type="rectangle">{c}
  <bsdf type="conductor"><float name="eta" value="0.3"/><ref name="k" id="k"/></bsdf></shape>
""".format(
        a=place(-1.3, 0.0, '<rotate y="1" angle="40"/>'),
        b=place(1.3, 1.3, '<rotate x="1" angle="60"/>'),
        c=place(1.3, -1.3, '<rotate x="1" angle="-35"/>'),
    )
    compare(write(tmp_path, "conductor_eta_k.xml", body), {}, 16)


def test_textured_area_emitter_radiance(tmp_path: Path) -> None:
    # A checkerboard or bitmap as an area emitter's radiance, on a rectangle,
    # a disk and a sphere: seen directly (the texture at the hit) and as the
    # light of a diffuse wall (next-event estimation: fgf samples the shape
    # by area and looks the texture up at the sampled point; Mitsuba samples
    # the texture and maps it through the shape's (u, v): the same
    # expectation). No environment, so that the emitters give all the light.
    write_images(tmp_path)
    sensor = SENSOR.replace('<emitter type="constant"><rgb name="radiance" value="1"/></emitter>', "")
    checker = """<texture type="checkerboard" name="radiance">
    <rgb name="color0" value="1.0, 0.5, 0.1"/><rgb name="color1" value="0.1, 0.3, 1.0"/>
    <transform name="to_uv"><scale x="3" y="2"/></transform></texture>"""
    body = f"""
<shape type="rectangle"><transform name="to_world"><scale value="6"/><translate z="-2"/></transform>
  <bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf></shape>
<shape type="rectangle">{place(-1.6, 1.2, '<scale value="0.8"/>')}
  <emitter type="area">{checker}</emitter></shape>
<shape type="rectangle">{place(1.5, 1.3, '<scale value="0.9"/><rotate x="1" angle="150"/>')}
  <emitter type="area">{checker}</emitter></shape>
<shape type="sphere"><float name="radius" value="0.7"/>{place(-1.2, -1.3, '<rotate x="1" angle="70"/>')}
  <emitter type="area">{bitmap("radiance", "img.exr", '<string name="wrap_mode" value="mirror"/>', '<scale x="2" y="1.5"/>')}</emitter></shape>
<shape type="disk">{place(1.4, -1.2, '<scale value="0.9"/><rotate y="1" angle="140"/>')}
  <emitter type="area">{bitmap("radiance", "img.png", '<string name="filter_type" value="nearest"/>')}</emitter></shape>
"""
    p = tmp_path / "emitters.xml"
    p.write_text(f'<scene version="3.0.0">\n{sensor}\n{body}\n</scene>\n')
    compare(p, {}, 64)


def test_fgf_medium_in_a_textured_scene(tmp_path: Path) -> None:
    # A non-exponential medium whose model is exponential renders what a
    # homogeneous medium renders in Mitsuba: the textured background seen
    # through it checks that fgf's media and textures work together.
    background = CHECKER.format(id="c", sx=4, sy=4) + """
<shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="-1.5"/></transform>
  <bsdf type="diffuse"><ref name="reflectance" id="c"/></bsdf></shape>
<shape type="sphere"><float name="radius" value="1.2"/><bsdf type="null"/>{medium}</shape>
"""
    volpath = SENSOR.replace('<integrator type="path">', '<integrator type="volpath">')
    fgf_medium = """<medium type="nonexponential" name="interior">
  <string name="transmittance" value="exponential"/>
  <float name="sigma_t" value="1.2"/><rgb name="albedo" value="0.7"/></medium>"""
    mi_medium = """<medium type="homogeneous" name="interior">
  <float name="sigma_t" value="1.2"/><rgb name="albedo" value="0.7"/></medium>"""
    scenes = {}
    for name, medium in [("fgf", fgf_medium), ("mi", mi_medium)]:
        p = tmp_path / f"medium_{name}.xml"
        p.write_text(f'<scene version="3.0.0">{volpath}{background.format(medium=medium)}</scene>')
        scenes[name] = p
    f = render_fgf(scenes["fgf"], {}, 16)
    m = render_mitsuba(scenes["mi"], {}, 16)
    assert len(f) == K
    assert_agree("textured scene with a medium", f, m)
    # An FGF (pink noise) medium in the same scene, against its exponential
    # counterpart of the same mean, both absorbing only: pink noise's
    # transmittance (1 + σt/α)^-α is above exp(-σt) at every distance
    # (docs/theory.md §2), so the checks seen through the sphere are brighter.
    absorbing = fgf_medium.replace('<rgb name="albedo" value="0.7"/>', '<rgb name="albedo" value="0"/>')
    pink = absorbing.replace('<string name="transmittance" value="exponential"/>', "").replace(
        'type="nonexponential"', 'type="fgf"'
    )
    pink = pink.replace("</medium>", '<float name="hurst" value="-0.1"/><float name="sw" value="4"/></medium>')
    centre = (slice(12, 20), slice(12, 20))
    means = {}
    for name, medium in [("exp", absorbing), ("pink", pink)]:
        p = tmp_path / f"absorbing_{name}.xml"
        p.write_text(f'<scene version="3.0.0">{volpath}{background.format(medium=medium)}</scene>')
        img = fgf.render(p, spp=64, progress=False)
        assert np.isfinite(img).all()
        means[name] = img[centre].mean()
    assert means["pink"] > 1.5 * means["exp"] > 0, means


@pytest.mark.parametrize(
    "xml, words",
    [
        (
            '<shape type="cube"><emitter type="area"><texture type="checkerboard" name="radiance"/></emitter></shape>',
            ["radiance", "cube", "not supported"],
        ),
        (
            '<shape type="rectangle"><bsdf type="roughplastic"><texture type="checkerboard" name="alpha_u"/>'
            "</bsdf></shape>",
            ["alpha_u"],
        ),
        ('<texture type="mesh_attribute" id="t"/>', ["mesh_attribute", "not supported"]),
        (
            '<shape type="rectangle"><bsdf type="diffuse"><texture type="checkerboard" name="reflectance">'
            '<rgb name="color0" value="1.5"/></texture></bsdf></shape>',
            ["reflectance", "1.5", "[0, 1]"],
        ),
        (
            '<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
            '<string name="filename" value="missing.png"/></texture></bsdf></shape>',
            ["missing.png"],
        ),
        (
            '<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
            '<string name="filename" value="x.png"/><string name="wrap_mode" value="tile"/></texture></bsdf></shape>',
            ["wrap_mode", "repeat, mirror, clamp"],
        ),
    ],
)
def test_unsupported_or_invalid_textures_are_refused_in_one_line(tmp_path: Path, xml: str, words: list[str]) -> None:
    p = tmp_path / "bad.xml"
    p.write_text(f'<scene version="3.0.0">{xml}</scene>')
    with pytest.raises((fgf.SceneError, OSError)) as e:
        fgf.render(p, spp=1, progress=False)
    msg = str(e.value)
    assert "\n" not in msg and "bad.xml:" in msg, msg
    for w in words:
        assert w in msg, msg


def test_hostile_image_size_is_refused_before_allocating(tmp_path: Path) -> None:
    # A PNG header declaring 100000 x 100000 pixels, and 16 bytes of data.
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", 100000, 100000, 8, 2, 0, 0, 0)
    idat = chunk(b"IDAT", zlib.compress(b"\0" * 16))
    (tmp_path / "huge.png").write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + idat + chunk(b"IEND", b""))
    p = tmp_path / "huge.xml"
    p.write_text(
        '<scene version="3.0.0"><shape type="rectangle"><bsdf type="diffuse">'
        '<texture type="bitmap" name="reflectance"><string name="filename" value="huge.png"/></texture>'
        "</bsdf></shape></scene>"
    )
    with pytest.raises(fgf.SceneError) as e:
        fgf.render(p, spp=1, progress=False)
    msg = str(e.value)
    assert "100000x100000" in msg and "33554432" in msg, msg


def png_file(pixels: np.ndarray, depth: int, color: int, chunks: tuple[tuple[bytes, bytes], ...] = ()) -> bytes:
    """A PNG of `pixels` (h, w, samples; integers as stored) with bit depth
    `depth`, PNG colour type `color` and the ancillary `chunks` before the
    image data."""
    h, w, _ = pixels.shape

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    rows = []
    for y in range(h):
        if depth == 16:
            row = pixels[y].astype(">u2").tobytes()
        elif depth == 8:
            row = pixels[y].astype(np.uint8).tobytes()
        else:  # 1, 2 or 4 bits, one sample per pixel
            row = np.packbits(np.unpackbits(pixels[y, :, 0].astype(np.uint8)[:, None], axis=1)[:, 8 - depth :]).tobytes()
        rows.append(b"\0" + row)
    ihdr = struct.pack(">IIBBBBB", w, h, depth, color, 0, 0, 0)
    body = b"".join(chunk(k, d) for k, d in chunks)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + body + chunk(b"IDAT", zlib.compress(b"".join(rows))) + chunk(b"IEND", b"")


# 2x2 images, one texel per quadrant of a rectangle.
RGB8 = np.array([[[230, 20, 20], [20, 230, 90]], [[40, 60, 230], [128, 200, 250]]])
# 16-bit values that no 8-bit value gives (v·257 + 100): a reader that kept
# only the high byte would be off by up to 0.4 %.
RGB16 = RGB8 * 257 + 100
# A fake ICC profile: libpng and Mitsuba ignore the chunk's content for
# decoding (no colour management), so only its presence matters.
ICCP = b"fake\0\0" + zlib.compress(b"\0" * 132)
PNG_CASES = [
    ("rgb8.png", png_file(RGB8, 8, 2), ""),
    ("rgb16.png", png_file(RGB16, 16, 2), ""),
    ("rgb16_raw.png", png_file(RGB16, 16, 2), '<boolean name="raw" value="true"/>'),
    ("grey16.png", png_file(RGB16[..., :1], 16, 0), ""),
    ("grey1.png", png_file(np.array([[[1], [0]], [[0], [1]]]), 1, 0), ""),
    ("gama_linear.png", png_file(RGB8, 8, 2, ((b"gAMA", struct.pack(">I", 100000)),)), ""),
    ("gama_raw.png", png_file(RGB8, 8, 2, ((b"gAMA", struct.pack(">I", 100000)),)), '<boolean name="raw" value="true"/>'),
    ("srgb_chunk.png", png_file(RGB8, 8, 2, ((b"sRGB", b"\0"),)), ""),
    ("iccp.png", png_file(RGB16, 16, 2, ((b"iCCP", ICCP),)), ""),
]


def test_png_bit_depths_and_colour_chunks_read_as_mitsuba(tmp_path: Path) -> None:
    """16-bit and 1-bit PNGs, and PNGs with a gAMA, sRGB or iCCP chunk, in
    `bitmap` textures. Mitsuba 3.9.1 reads 16-bit samples as v/65535 and
    treats every PNG as sRGB-encoded whatever its gAMA/sRGB/iCCP chunks say
    (its reader asks libpng for no gamma or colour transformation), so with
    `raw` false the stored values go through the sRGB curve and with `raw`
    true they are used as stored. Rendered with `direct` and BSDF samples
    only under a white sky, a diffuse rectangle's pixel is exactly its
    texel's reflectance, so the interior pixels of each texel must agree
    to float precision, not only statistically."""
    nearest = '<string name="filter_type" value="nearest"/>'
    shapes = []
    for i, (name, data, extra) in enumerate(PNG_CASES):
        (tmp_path / name).write_bytes(data)
        x, y = -1.9 + 1.9 * (i % 3), 1.9 - 1.9 * (i // 3)
        shapes.append(
            f'<shape type="rectangle">{place(x, y, SMALLER)}'
            f'<bsdf type="diffuse">{bitmap("reflectance", name, nearest + extra)}</bsdf></shape>'
        )
    body = "\n".join(shapes)
    direct = '<integrator type="direct"><integer name="emitter_samples" value="0"/><integer name="bsdf_samples" value="1"/></integrator>'
    sensor = SENSOR.replace('<integrator type="path"><integer name="max_depth" value="3"/></integrator>', direct)
    sensor = sensor.replace('value="32"', 'value="96"')
    scene = tmp_path / "pngs.xml"
    scene.write_text(f'<scene version="3.0.0">\n{sensor}\n{body}\n</scene>\n')
    mine = fgf.render(scene, spp=4, seed=1, progress=False).astype(np.float64)
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    theirs = np.array(mi.render(mi.load_file(str(scene)), seed=0, spp=4))[..., :3].astype(np.float64)
    assert mine.shape == theirs.shape == (96, 96, 3)
    # Interior pixels: Mitsuba's pixel equals its 8 neighbours, so no texel
    # or rectangle edge crosses it, whatever the sample positions.
    pad = np.pad(theirs, ((1, 1), (1, 1), (0, 0)), mode="edge")
    flat = np.ones(theirs.shape[:2], bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            flat &= (pad[1 + dy : 97 + dy, 1 + dx : 97 + dx] == theirs).all(axis=2)
    # The texels as Mitsuba's rules give them: v / (2^depth - 1), then the
    # sRGB curve unless raw, then (16 bits) rounded to half precision; every
    # one must show in interior pixels, and nothing else.
    def srgb(v: np.ndarray) -> np.ndarray:
        return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)

    def texels(name: str, extra: str) -> np.ndarray:
        if name.startswith(("rgb16", "iccp")):
            px, half = RGB16 / 65535, True
        elif name == "grey16.png":
            px, half = np.repeat(RGB16[..., :1], 3, 2) / 65535, True
        elif name == "grey1.png":
            px, half = np.repeat(np.array([[[1], [0]], [[0], [1]]]), 3, 2).astype(float), False
        else:
            px, half = RGB8 / 255, False
        px = px if "raw" in extra else srgb(px)
        return (px.astype(np.float16).astype(np.float64) if half else px).reshape(-1, 3)

    expected = np.unique(np.concatenate([texels(n, e) for n, _, e in PNG_CASES]), axis=0)
    expected = expected[(np.abs(expected - 1) > 1e-6).any(axis=1)]  # white is the sky's too
    got = mine[flat]
    got = got[(np.abs(got - 1) > 1e-6).any(axis=1)]
    dist = np.abs(got[:, None, :] - expected[None, :, :]).max(axis=2)
    assert dist.min(axis=1).max() <= 2e-6, "fgf has texel values Mitsuba's rules do not give"
    assert dist.min(axis=0).max() <= 2e-6, "some texels show in no interior pixel"
    diff = np.abs(mine - theirs)[flat]
    assert diff.max() <= 2e-6, f"max |fgf - mitsuba| {diff.max()} on {flat.sum()} interior pixels"
