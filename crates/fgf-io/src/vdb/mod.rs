//! OpenVDB `.vdb` files: write one float grid, read one float grid into a
//! dense array (layout and conventions in `docs/vdb.md`).
//!
//! The subset handled is what Houdini, Blender and OpenVDB itself write for
//! a scalar fog volume:
//!
//! * file format versions 222–224 (OpenVDB 3.0 to 12), with grid offsets;
//! * grids of type `Tree_float_5_4_3` (optionally saved as half floats);
//! * uncompressed, zlib- or Blosc-compressed node data (Blosc with LZ4 or
//!   zlib and byte shuffling, OpenVDB's default), with or without
//!   active-mask compression (every inactive-value encoding);
//! * transforms `UniformScaleMap`, `ScaleMap`, `TranslationMap`,
//!   `UniformScaleTranslateMap`, `ScaleTranslateMap` and `AffineMap`.
//!
//! Voxel `(i, j, k)` of a VDB grid is centred at `index_to_world · (i, j, k)`.
//! [`write_float_grid`] places voxel `(x, y, z)` of an fgf array (C order
//! `[z][y][x]`) at index `(x, y, z)`, so that its centre is at
//! `origin + (idx + 0.5) · voxel_size`: the grid's cells tile the box
//! `[origin, origin + n · voxel_size]`, the same box a `.vol` file with that
//! bounding box covers.
//!
//! The reader works on the file's bytes: every length read from the file is
//! checked against the bytes left before anything is allocated, the dense
//! array is bounded by [`MAX_DENSE_VOXELS`] before it is allocated, and
//! every failure is an [`IoError`] naming the file (never a panic).

use crate::{atomic_write, IoError, Result};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

mod bytes;
mod codec;
mod read;
#[cfg(test)]
mod tests;
mod write;

use bytes::*;
use codec::*;

pub use read::{list_grids, parse_float_grid, read_float_grid};
pub use write::{encode_float_grid, write_float_grid};

/// The largest dense array [`read_float_grid`] materializes (4 GiB of f32).
pub const MAX_DENSE_VOXELS: u64 = 1 << 30;

const MAGIC: u64 = 0x5644_4220;
const FILE_VERSION: u32 = 224;
/// First version with per-grid compression flags and node metadata bytes.
const MIN_VERSION: u32 = 222;
const FLOAT_TREE: &str = "Tree_float_5_4_3";
const HALF_SUFFIX: &str = "_HalfFloat";

const COMPRESS_ZIP: u32 = 0x1;
const COMPRESS_ACTIVE_MASK: u32 = 0x2;
const COMPRESS_BLOSC: u32 = 0x4;

/// log2 of the node sizes in voxels along one axis: leaf 8, lower internal
/// node 16 children (128 voxels), upper internal node 32 children (4096).
const LEAF_LOG2: u32 = 3;
const INT1_LOG2: u32 = 4;
const INT2_LOG2: u32 = 5;

/// One float grid as a dense array over its active bounding box.
#[derive(Debug, Clone, PartialEq)]
pub struct VdbGrid {
    /// The grid's name (`density` for fgf's files).
    pub name: String,
    /// Index coordinates of the first voxel `data[0]`.
    pub index_min: [i32; 3],
    /// `[nx, ny, nz]`: voxels along x, y, z.
    pub dims: [usize; 3],
    /// `data[(z * ny + y) * nx + x]` = voxel `index_min + (x, y, z)`
    /// (x fastest, like `.vol` and fgf's C-order `[z][y][x]` arrays);
    /// inactive voxels hold the background.
    pub data: Vec<f32>,
    /// The tree's background value (the value of every inactive voxel).
    pub background: f32,
    /// Index space to world space, row-major, column vectors:
    /// `world = M · (i, j, k, 1)ᵀ`; voxel centres sit at integer indices.
    pub index_to_world: [[f64; 4]; 4],
}

impl VdbGrid {
    /// The affine map from the unit cube `[0,1]³` to world space that puts
    /// this grid's cells where the VDB file puts them: `u ↦ index_to_world ·
    /// (index_min - 0.5 + u · dims)`. A `.vol` grid spanning the unit cube
    /// with this as its `to_world` samples at the same world points.
    pub fn unit_cube_to_world(&self) -> [[f64; 4]; 4] {
        let mut box_map = [[0.0; 4]; 4];
        for (a, row) in box_map.iter_mut().enumerate().take(3) {
            row[a] = self.dims[a] as f64;
            row[3] = self.index_min[a] as f64 - 0.5;
        }
        box_map[3][3] = 1.0;
        mat_mul(&self.index_to_world, &box_map)
    }

    /// The world-space box covered by the grid's cells when the transform
    /// is a scale and translation (no rotation or shear): `[xmin, ymin,
    /// zmin, xmax, ymax, zmax]`; `None` otherwise.
    pub fn world_bbox(&self) -> Option<[f64; 6]> {
        let m = self.unit_cube_to_world();
        for (r, row) in m.iter().enumerate().take(3) {
            for (c, v) in row.iter().enumerate().take(3) {
                if r != c && *v != 0.0 {
                    return None;
                }
            }
        }
        let mut b = [0.0; 6];
        for a in 0..3 {
            let (lo, hi) = (m[a][3], m[a][3] + m[a][a]);
            b[a] = lo.min(hi);
            b[a + 3] = lo.max(hi);
        }
        Some(b)
    }

    /// The grid as a 1-channel `.vol` grid spanning the unit cube (bounding
    /// box `[0,1]³`, data unchanged) and the map that places that cube in
    /// world space ([`unit_cube_to_world`](Self::unit_cube_to_world)): what a
    /// `gridvolume` needs, composed after its own `to_world` (`docs/vdb.md`).
    pub fn into_unit_cube_vol(self) -> (crate::vol::VolGrid, [[f64; 4]; 4]) {
        let m = self.unit_cube_to_world();
        let grid = crate::vol::VolGrid {
            shape: self.dims,
            channels: 1,
            bbox: [0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            data: self.data,
        };
        (grid, m)
    }

    /// Value at dense voxel `(x, y, z)` (relative to `index_min`).
    #[inline]
    pub fn at(&self, x: usize, y: usize, z: usize) -> f32 {
        self.data[(z * self.dims[1] + y) * self.dims[0] + x]
    }
}

fn mat_mul(a: &[[f64; 4]; 4], b: &[[f64; 4]; 4]) -> [[f64; 4]; 4] {
    let mut m = [[0.0; 4]; 4];
    for r in 0..4 {
        for c in 0..4 {
            m[r][c] = (0..4).map(|k| a[r][k] * b[k][c]).sum();
        }
    }
    m
}
