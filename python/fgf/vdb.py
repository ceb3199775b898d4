"""Volumes for other renderers: OpenVDB ``.vdb`` files and pbrt-v4 grid media.

* :func:`write_vdb` writes a field as an OpenVDB FloatGrid (Houdini, Blender,
  OpenVDB tools), :func:`read_vdb` reads a float grid back densely;
* :func:`pbrt_uniformgrid` writes pbrt-v4's ``uniformgrid`` medium snippet.

Conventions (``docs/vdb.md``): arrays are C order ``[z][y][x]`` like
:func:`fgf.synthesize`'s; voxel ``(x, y, z)`` is the cell ``origin +
[x, x+1] * spacing`` (and likewise along y, z), so the grid covers the box
``[origin, origin + n * spacing]``, exactly like a ``.vol`` file with that
bounding box. In the VDB file, voxel ``(x, y, z)`` has index ``(x, y, z)``
and the index-to-world transform maps it to the cell centre ``origin +
(idx + 0.5) * spacing``.

Examples
--------
>>> import numpy as np, fgf, tempfile, os
>>> d = tempfile.mkdtemp()
>>> f = np.ones((4, 5, 6), np.float32)
>>> fgf.write_vdb(os.path.join(d, "f.vdb"), f, spacing=0.5)
'f.vdb'
>>> g = fgf.read_vdb(os.path.join(d, "f.vdb"))
>>> g.data.shape, g.voxel_size, g.world_bbox
((4, 5, 6), (0.5, 0.5, 0.5), ((0.0, 0.0, 0.0), (3.0, 2.5, 2.0)))
"""

from __future__ import annotations

import os
import typing
from dataclasses import dataclass
from typing import Optional, Sequence, Tuple, Union

import numpy as np

from . import _core
from ._atomic import write_atomic

__all__ = ["write_vdb", "read_vdb", "VdbGrid", "pbrt_uniformgrid"]

Vec3 = Tuple[float, float, float]


def _vec3(name: str, v: Union[float, Sequence[float]], positive: bool) -> Vec3:
    from . import ParameterError

    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"invalid {name} = {v!r}: give one number or three (x, y, z)") from None
    t: tuple[float, ...] = (float(a),) * 3 if a.ndim == 0 else tuple(float(c) for c in a.ravel())
    if len(t) != 3:
        raise ParameterError(f"invalid {name} = {v!r}: give one number or three (x, y, z)")
    for c in t:
        if not np.isfinite(c) or (positive and c <= 0):
            raise ParameterError(f"invalid {name} = {v!r}: {'each must be finite and > 0' if positive else 'must be finite'}")
    return (t[0], t[1], t[2])


def _grid3(array: np.ndarray) -> np.ndarray:
    """A float32 C-order 3D view ``[z][y][x]``; 1D/2D get leading axes of length 1."""
    from . import ParameterError

    a = np.asarray(array)
    if a.ndim not in (1, 2, 3) or a.size == 0:
        raise ParameterError(f"a grid needs a non-empty 1D, 2D or 3D array, got shape {a.shape}")
    if not np.issubdtype(a.dtype, np.number) or np.iscomplexobj(a):
        raise ParameterError(f"a grid needs real numbers, got dtype {a.dtype}")
    a = np.ascontiguousarray(a, dtype=np.float32)
    if not np.isfinite(a).all():
        raise ParameterError("the grid holds non-finite values (NaN or infinity)")
    return a.reshape((1,) * (3 - a.ndim) + a.shape)


def write_vdb(
    path: Union[str, os.PathLike[str]],
    array: np.ndarray,
    spacing: Union[float, Sequence[float]] = 1.0,
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    name: str = "density",
) -> str:
    """Write ``array`` (``[z][y][x]``) as an OpenVDB FloatGrid ``name``; return the file name.

    ``spacing`` is the voxel size (one number, or ``(sx, sy, sz)``) and
    ``origin`` the ``(x, y, z)`` lower corner of the grid's box. The grid is
    a fog volume with background 0: 8³ blocks that are all zero are not
    stored (they read back as the background). Values are stored as float32.
    The write is atomic: a failed write leaves any old file untouched.
    """
    a = _grid3(array)
    s = _vec3("spacing", spacing, positive=True)
    o = _vec3("origin", origin, positive=False)
    _core.write_vdb(os.fspath(path), a, s, o, str(name))
    return os.path.basename(os.fspath(path))


@dataclass(frozen=True)
class VdbGrid:
    """A float grid read from a ``.vdb`` file, dense over its active bounding box."""

    #: Values, C order ``[z][y][x]``; inactive voxels hold ``background``.
    data: np.ndarray
    #: Grid name.
    name: str
    #: Index ``(i, j, k)`` of ``data[0, 0, 0]`` (x, y, z).
    index_min: Tuple[int, int, int]
    #: Row-major 4x4, column vectors: voxel centre ``(i, j, k)`` -> world.
    index_to_world: np.ndarray
    #: Value of inactive voxels.
    background: float

    @property
    def voxel_size(self) -> Vec3:
        """Lengths of the index axes in world units."""
        m = self.index_to_world[:3, :3]
        return tuple(float(v) for v in np.linalg.norm(m, axis=0))  # type: ignore[return-value]

    @property
    def world_bbox(self) -> Optional[Tuple[Vec3, Vec3]]:
        """``(lower, upper)`` corners of the grid's cells in world space for an
        axis-aligned transform, else ``None``."""
        m = self.index_to_world
        if np.count_nonzero(m[:3, :3] - np.diag(np.diag(m[:3, :3]))):
            return None
        n = np.array(self.data.shape[::-1], float)
        lo = np.array(self.index_min, float) - 0.5
        a = m[:3, :3] @ lo + m[:3, 3]
        b = m[:3, :3] @ (lo + n) + m[:3, 3]
        return tuple(float(v) for v in np.minimum(a, b)), tuple(float(v) for v in np.maximum(a, b))  # type: ignore[return-value]


def read_vdb(path: Union[str, os.PathLike[str]], grid: str = "density") -> VdbGrid:
    """Read float grid ``grid`` of an OpenVDB file densely over its active box.

    Reads uncompressed and zip-compressed files (with or without active-mask
    compression, float or half) with any scale/translate/affine transform;
    Blosc-compressed files and other grid types raise :class:`fgf.FgfError`
    with a one-line message naming the file.
    """
    data, index_min, m, bg = _core.read_vdb(os.fspath(path), str(grid))
    i0 = (int(index_min[0]), int(index_min[1]), int(index_min[2]))
    return VdbGrid(np.asarray(data), str(grid), i0, np.array(m, dtype=float), float(bg))


def pbrt_uniformgrid(
    path: Union[str, os.PathLike[str]],
    array: np.ndarray,
    spacing: Union[float, Sequence[float]] = 1.0,
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    medium_name: str = "fgf",
) -> str:
    """Write a pbrt-v4 ``MakeNamedMedium ... "uniformgrid"`` statement for ``array``.

    ``density`` lists the ``nx*ny*nz`` values with x fastest (pbrt's order,
    the same as fgf's C-order ``[z][y][x]`` array flattened); ``p0``/``p1``
    are the box ``[origin, origin + n * spacing]``, in which pbrt centres
    voxel ``i`` at ``p0 + (i + 0.5) * spacing`` like fgf and Mitsuba. With
    ``sigma_a = 0`` and ``sigma_s = 1`` pbrt's ``sigma_t`` equals the values
    (albedo 1); edit them for another albedo. Written atomically.
    """
    a = _grid3(array)
    s = _vec3("spacing", spacing, positive=True)
    o = _vec3("origin", origin, positive=False)
    nz, ny, nx = a.shape
    p1 = tuple(o[k] + n * s[k] for k, n in enumerate((nx, ny, nz)))
    head = (
        f"# fgf field {nx}x{ny}x{nz}, voxel size {s[0]:.9g} {s[1]:.9g} {s[2]:.9g}: pbrt-v4 grid medium.\n"
        "# sigma_t(p) = scale * density(p) * (sigma_a + sigma_s); use it with\n"
        f'# MediumInterface "{medium_name}" "" on a shape enclosing the box p0-p1.\n'
        f'MakeNamedMedium "{medium_name}"\n'
        '    "string type" [ "uniformgrid" ]\n'
        '    "rgb sigma_a" [ 0 0 0 ]\n'
        '    "rgb sigma_s" [ 1 1 1 ]\n'
        '    "float scale" [ 1 ]\n'
        f'    "integer nx" [ {nx} ] "integer ny" [ {ny} ] "integer nz" [ {nz} ]\n'
        f'    "point3 p0" [ {o[0]:.9g} {o[1]:.9g} {o[2]:.9g} ]\n'
        f'    "point3 p1" [ {p1[0]:.9g} {p1[1]:.9g} {p1[2]:.9g} ]\n'
        '    "float density" [\n'
    )
    flat = a.reshape(-1)

    def write(fh: typing.TextIO) -> None:
        fh.write(head)
        # Rows of nx values (x fastest); str() of a float32 is the shortest
        # decimal that reads back as the same float32.
        for row in flat.reshape(-1, nx):
            fh.write("        " + " ".join(map(str, row)) + "\n")
        fh.write("    ]\n")

    return write_atomic(path, write, mode="w")
