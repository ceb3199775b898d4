"""OpenVDB in and out, and pbrt-v4 grid media (``docs/vdb.md``).

fgf writes and reads ``.vdb`` with its own code (``fgf_io::vdb``); these
tests check its files with two independent readers, the reference OpenVDB
implementation (Debian's ``python3-openvdb`` 10.0.1, run under Debian's
``/usr/bin/python3`` in a subprocess) and ``tinyvdb``, and check fgf's
reader on files the reference implementation wrote.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import fgf
import fgf.vdb

SYSTEM_PYTHON = "/usr/bin/python3"


# The reference reader is installed by the test command (scripts/setup.sh
# --test); without it these tests fail, never skip.
def needs_reference(f):  # noqa: D103
    return f


def _reference(code: str, *args: str) -> dict:
    """Run `code` under /usr/bin/python3 with pyopenvdb; it prints one JSON object."""
    r = subprocess.run(
        [SYSTEM_PYTHON, "-c", textwrap.dedent(code), *args], capture_output=True, text=True, timeout=120
    )
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def _cli(*args, **kw):
    return subprocess.run([sys.executable, "-m", "fgf", *map(str, args)], capture_output=True, text=True, **kw)


def _field(shape=(11, 13, 19), seed=3) -> np.ndarray:
    f = fgf.synthesize(shape, hurst=-0.3, seed=seed, progress=False)
    d = np.maximum(0.0, 1.0 + f).astype(np.float32)
    d[:, :, :8] = 0.0  # an all-zero slab: leaves left out, read back as background
    return d


def test_docstring_examples_run():
    import doctest

    res = doctest.testmod(fgf.vdb, optionflags=doctest.ELLIPSIS)
    assert res.attempted >= 4 and res.failed == 0


def test_round_trip_values_transform_and_sparsity(tmp_path):
    d = _field()
    p = tmp_path / "f.vdb"
    assert fgf.write_vdb(p, d, spacing=0.25, origin=(1.0, -2.0, 0.5)) == "f.vdb"
    g = fgf.read_vdb(p)
    assert g.name == "density" and g.background == 0.0
    assert g.voxel_size == (0.25, 0.25, 0.25)
    # The zero slab x < 8 is one leaf wide: the active box starts at x = 8.
    assert g.index_min == (8, 0, 0)
    np.testing.assert_array_equal(g.data, d[:, :, 8:])
    nz, ny, nx = d.shape
    # The cells of the full grid cover [origin, origin + n * spacing]; the
    # read-back box is the active part, starting 8 cells in along x.
    assert g.world_bbox == ((1.0 + 8 * 0.25, -2.0, 0.5), (1.0 + nx * 0.25, -2.0 + ny * 0.25, 0.5 + nz * 0.25))
    # Voxel centre (x, y, z) = origin + (idx + 0.5) * spacing.
    np.testing.assert_allclose(g.index_to_world @ [8, 2, 3, 1], [1.0 + 8.5 * 0.25, -2.0 + 2.5 * 0.25, 0.5 + 3.5 * 0.25, 1])


def test_anisotropic_spacing_and_low_dims(tmp_path):
    p = tmp_path / "a.vdb"
    line = np.arange(1, 21, dtype=np.float64)
    fgf.write_vdb(p, line, spacing=(0.5, 2.0, 3.0))
    g = fgf.read_vdb(p)
    assert g.data.shape == (1, 1, 20) and g.data.dtype == np.float32
    np.testing.assert_array_equal(g.data[0, 0], line)
    assert g.voxel_size == (0.5, 2.0, 3.0)
    assert g.world_bbox == ((0.0, 0.0, 0.0), (10.0, 2.0, 3.0))


def test_bad_arguments_are_one_line_errors(tmp_path):
    p = tmp_path / "x.vdb"
    with pytest.raises(fgf.ParameterError, match="spacing"):
        fgf.write_vdb(p, np.ones((2, 2, 2)), spacing=0)
    with pytest.raises(fgf.ParameterError, match="origin"):
        fgf.write_vdb(p, np.ones((2, 2, 2)), origin=(0, 0))
    with pytest.raises(fgf.ParameterError, match="non-finite"):
        fgf.write_vdb(p, np.full((2, 2, 2), np.nan))
    with pytest.raises(fgf.ParameterError, match="1D, 2D or 3D"):
        fgf.write_vdb(p, np.ones((2, 2, 2, 2)))
    with pytest.raises(fgf.FgfError, match="output directory .* does not exist"):
        fgf.write_vdb(tmp_path / "missing" / "x.vdb", np.ones((2, 2, 2)))
    assert not p.exists()
    fgf.write_vdb(p, np.ones((2, 2, 2)))
    with pytest.raises(fgf.FgfError, match=r"x\.vdb: no grid named 'sigma_t' \(grids: density \(Tree_float_5_4_3\)\)"):
        fgf.read_vdb(p, grid="sigma_t")


def test_failed_write_keeps_the_old_file(tmp_path):
    p = tmp_path / "keep.vdb"
    fgf.write_vdb(p, np.ones((3, 3, 3)))
    before = p.read_bytes()
    with pytest.raises(fgf.ParameterError):
        fgf.write_vdb(p, np.full((3, 3, 3), np.inf))
    assert p.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["keep.vdb"]


@pytest.mark.parametrize("mutation", ["truncate", "flip", "garbage", "empty"])
def test_hostile_files_give_one_line_errors(tmp_path, mutation):
    good = tmp_path / "good.vdb"
    fgf.write_vdb(good, _field((9, 9, 9)))
    b = bytearray(good.read_bytes())
    rng = np.random.default_rng(1)
    cases = []
    if mutation == "truncate":
        cases = [bytes(b[:n]) for n in rng.integers(0, len(b), 40)]
    elif mutation == "flip":
        for _ in range(60):
            c = bytearray(b)
            for i in rng.integers(0, len(b), 3):
                c[i] = int(rng.integers(0, 256))
            cases.append(bytes(c))
    elif mutation == "garbage":
        cases = [rng.integers(0, 256, n, dtype=np.uint8).tobytes() for n in (10, 100, 5000)]
        cases.append(bytes(b[:8]) + rng.integers(0, 256, 4000, dtype=np.uint8).tobytes())
    else:
        cases = [b""]
    bad = tmp_path / "bad.vdb"
    for c in cases:
        bad.write_bytes(c)
        try:
            fgf.read_vdb(bad)
        except fgf.FgfError as e:
            msg = str(e)
            assert msg.startswith(f"{bad}: ") and "\n" not in msg, msg
    # And through the CLI-facing Python API: no crash of the interpreter.
    r = subprocess.run([sys.executable, "-c", f"import fgf; fgf.read_vdb({str(bad)!r})"], capture_output=True, text=True)
    assert r.returncode in (0, 1) and "panicked" not in r.stderr


READ_WITH_REFERENCE = """
    import json, sys
    import numpy as np
    import pyopenvdb as vdb
    path, out = sys.argv[1], sys.argv[2]
    grids, meta = vdb.readAll(path)
    g = grids[0]
    (i0, j0, k0), (i1, j1, k1) = g.evalActiveVoxelBoundingBox()
    a = np.zeros((i1 - i0 + 1, j1 - j0 + 1, k1 - k0 + 1), np.float32)
    g.copyToArray(a, ijk=(i0, j0, k0))
    np.save(out, a)
    t = g.transform
    print(json.dumps({
        "names": [h.name for h in grids], "type": g.valueTypeName, "class": g.gridClass,
        "background": g.background, "voxel_size": list(t.voxelSize()),
        "centre_000": list(t.indexToWorld((0, 0, 0))), "centre_123": list(t.indexToWorld((1, 2, 3))),
        "bbox_min": [i0, j0, k0], "active": g.activeVoxelCount(), "meta": {k: str(v) for k, v in meta.items()},
    }))
"""


@needs_reference
def test_reference_openvdb_reads_fgf_files(tmp_path):
    d = _field((21, 10, 17))
    p = tmp_path / "f.vdb"
    fgf.write_vdb(p, d, spacing=0.125, origin=(-1.0, 0.0, 2.0))
    info = _reference(READ_WITH_REFERENCE, str(p), str(tmp_path / "ref.npy"))
    assert info["names"] == ["density"]
    assert info["type"] == "float" and info["class"] == "fog volume"
    assert info["background"] == 0.0
    assert info["voxel_size"] == [0.125] * 3
    assert info["centre_000"] == [-1.0 + 0.0625, 0.0625, 2.0625]
    assert info["centre_123"] == [-1.0 + 1.5 * 0.125, 2.5 * 0.125, 2.0 + 3.5 * 0.125]
    assert info["meta"]["creator"].startswith("fgf ")
    # Active: every voxel of each written (not all-zero) 8^3 leaf inside the grid.
    assert info["bbox_min"] == [8, 0, 0]
    a = np.load(tmp_path / "ref.npy")  # index order [x][y][z]
    np.testing.assert_array_equal(a.transpose(2, 1, 0), d[:, :, 8:])
    assert info["active"] == d[:, :, 8:].size


@pytest.mark.parametrize("spacing", [0.5, (0.5, 1.0, 2.0)])
def test_tinyvdb_reads_fgf_files(tmp_path, spacing):
    import tinyvdb  # a test dependency (requirements-dev.txt)
    d = _field((10, 12, 14))
    p = tmp_path / "f.vdb"
    fgf.write_vdb(p, d, spacing=spacing, origin=(3.0, 0.0, 0.0))
    with tinyvdb.open(str(p)) as f:
        f.read_grids()
        assert f.grid_count == 1 and f.grid_name(0) == "density"
        g = f.grid(0)
        assert g.type_name.startswith("Tree_float")
        assert g.float_background() == 0.0
        s = g.to_sparse()
        ijk = np.frombuffer(s["coords"], np.int32).reshape(-1, 3)
        vals = np.frombuffer(s["values"], np.float32)
        assert s["count"] == d[:, :, 8:].size
        np.testing.assert_array_equal(vals, d[ijk[:, 2], ijk[:, 1], ijk[:, 0]])
        t = g.transform
    txt = repr(t)
    sx = spacing if np.ndim(spacing) == 0 else spacing[0]
    # The transform: translation origin + spacing/2 and scale = spacing.
    nums = [float(v) for v in re.findall(r"-?\d+(?:\.\d*)?(?:e-?\d+)?", txt)]
    assert 3.0 + 0.5 * sx in nums and sx in nums, txt


WRITE_WITH_REFERENCE = """
    import json, sys
    import numpy as np
    import pyopenvdb as vdb
    path, kind = sys.argv[1], sys.argv[2]
    rng = np.random.default_rng(5)
    g = vdb.FloatGrid()
    g.name = "smoke"
    g.gridClass = vdb.GridClass.FOG_VOLUME
    a = rng.random((20, 9, 11)).astype(np.float32)      # index order [x][y][z]
    a[a < 0.3] = 0.0
    g.copyFromArray(a, ijk=(-5, 130, 7), tolerance=0.0)
    acc = g.getAccessor()
    acc.setValueOn((40, 150, 9), 0.0)                   # an active zero far out
    g.fill((64, 0, 0), (79, 15, 15), 0.75, active=True)  # active tiles (aligned 8^3 blocks)
    if kind == "affine":
        m = [[0.0, 0.5, 0.0, 0.0], [-0.5, 0.0, 0.0, 0.0], [0.0, 0.0, 0.5, 0.0], [1.0, 2.0, 3.0, 1.0]]
        g.transform = vdb.createLinearTransform(m)
    else:
        g.transform = vdb.createLinearTransform(voxelSize=0.25)
        g.transform.translate((1.0, -1.0, 0.5))
    if kind == "half":
        g.saveFloatAsHalf = True
    other = vdb.Vec3SGrid()
    other.name = "vel"
    vdb.write(path, grids=[other, g])
    (i0, j0, k0), (i1, j1, k1) = g.evalActiveVoxelBoundingBox()
    d = np.zeros((i1 - i0 + 1, j1 - j0 + 1, k1 - k0 + 1), np.float32)
    g.copyToArray(d, ijk=(i0, j0, k0))
    np.save(path + ".npy", d)
    t = g.transform
    print(json.dumps({"bbox_min": [i0, j0, k0], "c": [list(t.indexToWorld(p)) for p in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]]}))
"""


def _grid_compression(b: bytes, name: str) -> int:
    """The compression flags of grid `name` (walks the grid descriptors)."""
    import struct

    pos = 8 + 4 + 8 + 1 + 36
    (n_meta,) = struct.unpack_from("<I", b, pos)
    pos += 4
    assert n_meta == 0
    (n_grids,) = struct.unpack_from("<I", b, pos)
    pos += 4
    for _ in range(n_grids):
        strings = []
        for _ in range(3):
            (n,) = struct.unpack_from("<I", b, pos)
            strings.append(b[pos + 4 : pos + 4 + n].decode())
            pos += 4 + n
        grid_pos, _, end_pos = struct.unpack_from("<qqq", b, pos)
        if strings[0] == name:
            return struct.unpack_from("<I", b, grid_pos)[0]
        pos = end_pos
    raise AssertionError(f"no grid {name}")


@needs_reference
@pytest.mark.parametrize("kind", ["scale_translate", "affine", "half"])
def test_fgf_reads_reference_files(tmp_path, kind):
    p = tmp_path / f"ref_{kind}.vdb"
    info = _reference(WRITE_WITH_REFERENCE, str(p), kind)
    want = np.load(str(p) + ".npy").transpose(2, 1, 0)  # -> [z][y][x]
    if kind == "half":
        # The file holds the values rounded to half precision.
        want = want.astype(np.float16).astype(np.float32)
    # OpenVDB 10 writes Blosc (LZ4, byte shuffle) with active-mask compression.
    assert _grid_compression(p.read_bytes(), "smoke") == 0x4 | 0x2
    g = fgf.read_vdb(p, grid="smoke")
    assert g.index_min == tuple(info["bbox_min"])
    np.testing.assert_array_equal(g.data, want)
    assert g.background == 0.0
    c0, cx, cy, cz = (np.array(v) for v in info["c"])
    m = g.index_to_world
    np.testing.assert_allclose(m[:3, 3], c0, atol=1e-12)
    np.testing.assert_allclose(m[:3, 0], cx - c0, atol=1e-12)
    np.testing.assert_allclose(m[:3, 1], cy - c0, atol=1e-12)
    np.testing.assert_allclose(m[:3, 2], cz - c0, atol=1e-12)
    with pytest.raises(fgf.FgfError, match="only float grids"):
        fgf.read_vdb(p, grid="vel")


def test_cli_writes_vdb_and_pbrt(tmp_path):
    common = ["field", "--shape", "6", "5", "9", "--hurst", "-0.3", "--spacing", "0.5", "--seed", "2", "--mean", "3", "--clamp-min", "0", "-q"]
    assert _cli(*common, "-o", tmp_path / "f.npy").returncode == 0
    r = _cli(*common, "-o", tmp_path / "f.vdb")
    assert r.returncode == 0, r.stderr
    r = _cli(*common, "-o", tmp_path / "f.pbrt")
    assert r.returncode == 0, r.stderr
    want = np.load(tmp_path / "f.npy")  # the .npy holds the mapped density too
    assert want.dtype == np.float32 and want.min() >= 0.0 and abs(want.mean() - 3.0) < 1.0
    g = fgf.read_vdb(tmp_path / "f.vdb")
    assert g.index_min == (0, 0, 0) and g.voxel_size == (0.5, 0.5, 0.5)
    np.testing.assert_allclose(g.data, want, rtol=1e-6)
    assert g.world_bbox == ((0.0, 0.0, 0.0), (4.5, 2.5, 3.0))
    p = _parse_pbrt((tmp_path / "f.pbrt").read_text())
    np.testing.assert_allclose(p["density"].reshape(6, 5, 9), want, rtol=1e-6)
    r = _cli(*common, "-o", tmp_path / "f.vdbx")
    assert r.returncode == 2 and ".vdb, .pbrt" in r.stderr and "Traceback" not in r.stderr


def _parse_pbrt(text: str) -> dict:
    """A minimal reader of one MakeNamedMedium statement (pbrt-v4 syntax)."""
    body = re.sub(r"#[^\n]*", "", text)
    m = re.match(r'\s*MakeNamedMedium\s+"([^"]+)"(.*)$', body, re.S)
    assert m, text[:200]
    out = {"name": m.group(1)}
    for ty, name, vals in re.findall(r'"(\w+)\s+(\w+)"\s*\[([^\]]*)\]', m.group(2)):
        toks = vals.split()
        if ty == "string":
            out[name] = toks[0].strip('"')
        elif ty == "integer":
            out[name] = [int(t) for t in toks]
        else:
            out[name] = np.array([float(t) for t in toks])
    return out


def test_pbrt_uniformgrid_structure(tmp_path):
    # Distinct values so the order is checked: value = x + 10 y + 100 z.
    nz, ny, nx = 3, 4, 5
    z, y, x = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    a = (x + 10 * y + 100 * z).astype(np.float32) + np.float32(0.1)
    p = tmp_path / "m.pbrt"
    assert fgf.pbrt_uniformgrid(p, a, spacing=(0.5, 0.25, 2.0), origin=(1, 2, 3)) == "m.pbrt"
    s = _parse_pbrt(p.read_text())
    assert s["name"] == "fgf" and s["type"] == "uniformgrid"
    assert (s["nx"], s["ny"], s["nz"]) == ([nx], [ny], [nz])
    assert s["density"].size == nx * ny * nz
    # x fastest: the first values run along x, then y, then z.
    dens = s["density"].astype(np.float32)
    np.testing.assert_array_equal(dens[:3], np.float32([0.1, 1.1, 2.1]))
    assert dens[nx] == np.float32(10.1) and dens[nx * ny] == np.float32(100.1)
    # float32 values survive the text exactly.
    np.testing.assert_array_equal(s["density"].astype(np.float32), a.reshape(-1))
    np.testing.assert_array_equal(s["p0"], [1, 2, 3])
    np.testing.assert_array_equal(s["p1"], [1 + nx * 0.5, 2 + ny * 0.25, 3 + nz * 2.0])
    np.testing.assert_array_equal(s["sigma_a"], [0, 0, 0])
    np.testing.assert_array_equal(s["sigma_s"], [1, 1, 1])


def test_scene_renders_a_vdb_field_like_the_same_vol(tmp_path):
    """``fgf field -o f.vdb`` used by a ``gridvolume`` (an fgf extension):
    the render equals that of the same field written as ``.vol`` with
    ``use_grid_bbox`` (same voxels at the same places, same seed), to within
    the images' standard error."""
    from fgf.cli import main

    for ext in ("vdb", "vol"):
        rc = main(["field", "--shape", "16", "16", "16", "--hurst", "-0.1", "--seed", "3",
                   "--mean", "4", "--clamp-min", "0", "--spacing", "0.0625",
                   "-o", str(tmp_path / f"f.{ext}"), "--quiet"])
        assert rc == 0
    images = {}
    for ext, extra in (("vdb", ""), ("vol", '<boolean name="use_grid_bbox" value="true"/>')):
        xml = textwrap.dedent(f"""\
            <scene version="3.0.0">
              <integrator type="volpath"><integer name="max_depth" value="8"/></integrator>
              <sensor type="perspective"><float name="fov" value="40"/>
                <transform name="to_world"><lookat origin="0.5,0.5,3" target="0.5,0.5,0.5" up="0,1,0"/></transform>
                <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
                <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/>
                  <rfilter type="box"/></film></sensor>
              <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
              <shape type="cube"><transform name="to_world"><scale value="0.5"/><translate value="0.5,0.5,0.5"/></transform>
                <bsdf type="null"/>
                <medium type="heterogeneous" name="interior">
                  <volume type="gridvolume" name="sigma_t"><string name="filename" value="f.{ext}"/>{extra}</volume>
                  <rgb name="albedo" value="0.5"/>
                </medium></shape>
            </scene>""")
        (tmp_path / f"{ext}.xml").write_text(xml)
        images[ext] = fgf.render(tmp_path / f"{ext}.xml", seed=1, progress=False, return_variance=True)
    (a, va), (b, vb) = images["vdb"], images["vol"]
    assert np.isfinite(a).all() and a.mean() > 0.05
    # Not trivially equal to an empty cube: the medium darkens the image.
    assert a.mean() < 0.95
    se = np.sqrt(va.sum() + vb.sum()) / a.size
    assert abs(a.mean() - b.mean()) <= 4 * se + 1e-7
