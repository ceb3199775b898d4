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

// ---------------------------------------------------------------- writing

/// Write `data` (`[nz][ny][nx]`, x fastest) as an OpenVDB file holding one
/// FloatGrid called `name` (class `fog volume`, background 0), atomically.
///
/// Voxel `(x, y, z)` goes to index `(x, y, z)`, centred at `origin + (idx +
/// 0.5) · voxel_size` (the transform is a `UniformScaleTranslateMap`, or a
/// `ScaleTranslateMap` when the sizes differ). Leaves (8³ blocks) whose
/// voxels are all 0 are left out, so zero regions cost nothing and read
/// back as the background; inside a written leaf every voxel of the grid is
/// active. The file is uncompressed apart from active-mask compression.
pub fn write_float_grid(
    path: &Path,
    name: &str,
    data: &[f32],
    dims: [usize; 3],
    voxel_size: [f64; 3],
    origin: [f64; 3],
) -> Result<()> {
    let bytes = encode_float_grid(name, data, dims, voxel_size, origin)
        .map_err(|m| IoError::format(path, m))?;
    atomic_write(path, |w| w.write_all(&bytes).map_err(|e| e.to_string()))
}

/// The bytes of [`write_float_grid`]'s file; errors are messages without
/// the file name.
pub fn encode_float_grid(
    name: &str,
    data: &[f32],
    dims: [usize; 3],
    voxel_size: [f64; 3],
    origin: [f64; 3],
) -> std::result::Result<Vec<u8>, String> {
    let [nx, ny, nz] = dims;
    if dims.iter().any(|&n| n == 0 || n > (1 << 30)) {
        return Err(format!(
            "cannot write a {nx}x{ny}x{nz} grid (valid: 1 to 2^30 voxels per axis)"
        ));
    }
    if nx.checked_mul(ny).and_then(|v| v.checked_mul(nz)) != Some(data.len()) {
        return Err("grid data length does not match its shape".into());
    }
    if voxel_size.iter().any(|&s| !(s.is_finite() && s > 0.0)) {
        return Err(format!(
            "voxel size {voxel_size:?} is invalid (valid: finite and > 0)"
        ));
    }
    if origin.iter().any(|o| !o.is_finite()) {
        return Err(format!("origin {origin:?} is not finite"));
    }
    if name.is_empty() || name.contains('\u{1e}') {
        return Err(format!(
            "grid name {name:?} is invalid (valid: non-empty, no ASCII RS)"
        ));
    }

    // Leaves: origin -> (value mask, 512 values in VDB order x-major).
    type Leaf = ([u64; 8], Box<[f32; 512]>);
    let mut leaves: BTreeMap<[i32; 3], Leaf> = BTreeMap::new();
    let leaf_n = |n: usize| n.div_ceil(8);
    let mut n_active: u64 = 0;
    for lx in 0..leaf_n(nx) {
        for ly in 0..leaf_n(ny) {
            for lz in 0..leaf_n(nz) {
                let mut mask = [0u64; 8];
                let mut vals = Box::new([0f32; 512]);
                let mut any_nonzero = false;
                for dx in 0..8 {
                    let x = lx * 8 + dx;
                    if x >= nx {
                        break;
                    }
                    for dy in 0..8 {
                        let y = ly * 8 + dy;
                        if y >= ny {
                            break;
                        }
                        for dz in 0..8 {
                            let z = lz * 8 + dz;
                            if z >= nz {
                                break;
                            }
                            let v = data[(z * ny + y) * nx + x];
                            let off = (dx << 6) | (dy << 3) | dz;
                            mask[off >> 6] |= 1 << (off & 63);
                            vals[off] = v;
                            any_nonzero |= v != 0.0;
                        }
                    }
                }
                if any_nonzero {
                    n_active += mask.iter().map(|w| w.count_ones() as u64).sum::<u64>();
                    let o = [(lx * 8) as i32, (ly * 8) as i32, (lz * 8) as i32];
                    leaves.insert(o, (mask, vals));
                }
            }
        }
    }

    // Group leaves by their upper (4096³) and lower (128³) internal nodes.
    // BTreeMap keys sort lexicographically (x, y, z), the order in which
    // OpenVDB's root node stores and iterates its children.
    type Lower = BTreeMap<usize, [i32; 3]>; // leaf slot -> leaf origin
    let mut uppers: BTreeMap<[i32; 3], BTreeMap<usize, Lower>> = BTreeMap::new();
    for o in leaves.keys() {
        let up = o.map(|c| c & !((1 << 12) - 1));
        let lo = o.map(|c| c & !((1 << 7) - 1));
        let slot1 = child_slot(lo, INT2_LOG2, INT1_LOG2 + LEAF_LOG2);
        let slot0 = child_slot(*o, INT1_LOG2, LEAF_LOG2);
        uppers
            .entry(up)
            .or_default()
            .entry(slot1)
            .or_default()
            .insert(slot0, *o);
    }

    let mut out = Vec::with_capacity(1024 + leaves.len() * (64 + 1 + 2048));
    // Header.
    out.extend_from_slice(&MAGIC.to_le_bytes());
    out.extend_from_slice(&FILE_VERSION.to_le_bytes());
    out.extend_from_slice(&10u32.to_le_bytes()); // library major (format of OpenVDB 10)
    out.extend_from_slice(&0u32.to_le_bytes()); // library minor
    out.push(1); // has grid offsets
    out.extend_from_slice(uuid(name, data, dims, voxel_size, origin).as_bytes());
    // File metadata.
    put_u32(&mut out, 1);
    put_str(&mut out, "creator");
    put_str(&mut out, "string");
    let creator = concat!("fgf ", env!("CARGO_PKG_VERSION"));
    put_u32(&mut out, creator.len() as u32);
    out.extend_from_slice(creator.as_bytes());
    put_u32(&mut out, 1); // grid count

    // Grid descriptor.
    put_str(&mut out, name);
    put_str(&mut out, FLOAT_TREE);
    put_str(&mut out, ""); // instance parent
    let offsets_at = out.len();
    out.extend_from_slice(&[0u8; 24]);
    let grid_pos = out.len();
    put_u32(&mut out, COMPRESS_ACTIVE_MASK);
    // Grid metadata, sorted by name like OpenVDB's MetaMap.
    // The active voxels' bounding box (written leaves clipped to the grid).
    let (mut bmin, mut bmax) = ([i32::MAX; 3], [i32::MIN; 3]);
    for o in leaves.keys() {
        for k in 0..3 {
            bmin[k] = bmin[k].min(o[k]);
            bmax[k] = bmax[k].max((o[k] + 7).min(dims[k] as i32 - 1));
        }
    }
    if leaves.is_empty() {
        (bmin, bmax) = ([0; 3], [-1; 3]);
    }
    put_u32(&mut out, 6);
    put_meta_str(&mut out, "class", "fog volume");
    put_meta_vec3i(&mut out, "file_bbox_max", bmax);
    put_meta_vec3i(&mut out, "file_bbox_min", bmin);
    put_str(&mut out, "file_voxel_count");
    put_str(&mut out, "int64");
    put_u32(&mut out, 8);
    out.extend_from_slice(&(n_active as i64).to_le_bytes());
    put_str(&mut out, "is_saved_as_half_float");
    put_str(&mut out, "bool");
    put_u32(&mut out, 1);
    out.push(0);
    put_meta_str(&mut out, "name", name);
    // Transform: index (i, j, k) -> origin + (idx + 0.5) * voxel_size.
    let translation = [0, 1, 2].map(|a| origin[a] + 0.5 * voxel_size[a]);
    let uniform = voxel_size[0] == voxel_size[1] && voxel_size[1] == voxel_size[2];
    put_str(
        &mut out,
        if uniform {
            "UniformScaleTranslateMap"
        } else {
            "ScaleTranslateMap"
        },
    );
    let s = voxel_size;
    for v in [
        translation,
        s,
        s,
        s.map(|v| 1.0 / v),
        s.map(|v| 1.0 / (v * v)),
        s.map(|v| 0.5 / v),
    ] {
        for c in v {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    // Topology.
    put_u32(&mut out, 1); // buffer count
    out.extend_from_slice(&0f32.to_le_bytes()); // background
    put_u32(&mut out, 0); // root tiles
    put_u32(&mut out, uppers.len() as u32);
    for (up_origin, lowers) in &uppers {
        for c in up_origin {
            out.extend_from_slice(&c.to_le_bytes());
        }
        put_internal_header(&mut out, INT2_LOG2, lowers.keys().copied());
        for lower in lowers.values() {
            put_internal_header(&mut out, INT1_LOG2, lower.keys().copied());
            for o in lower.values() {
                put_mask(&mut out, &leaves[o].0);
            }
        }
    }
    let block_pos = out.len();
    // Buffers, in the same order.
    for lowers in uppers.values() {
        for lower in lowers.values() {
            for o in lower.values() {
                let (mask, vals) = &leaves[o];
                put_mask(&mut out, mask);
                out.push(0); // NO_MASK_OR_INACTIVE_VALS: inactive = background
                for (i, v) in vals.iter().enumerate() {
                    if mask[i >> 6] >> (i & 63) & 1 == 1 {
                        out.extend_from_slice(&v.to_le_bytes());
                    }
                }
            }
        }
    }
    let end_pos = out.len();
    for (k, p) in [grid_pos, block_pos, end_pos].into_iter().enumerate() {
        out[offsets_at + 8 * k..offsets_at + 8 * k + 8].copy_from_slice(&(p as i64).to_le_bytes());
    }
    Ok(out)
}

/// Slot of the child containing `o` in an internal node with `log2` children
/// per axis, each `child_total` (log2 voxels) wide: x slowest, z fastest.
fn child_slot(o: [i32; 3], log2: u32, child_total: u32) -> usize {
    let m = (1i32 << (log2 + child_total)) - 1;
    let [x, y, z] = o.map(|c| ((c & m) >> child_total) as usize);
    (x << (2 * log2)) | (y << log2) | z
}

fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}
fn put_str(out: &mut Vec<u8>, s: &str) {
    put_u32(out, s.len() as u32);
    out.extend_from_slice(s.as_bytes());
}
fn put_meta_str(out: &mut Vec<u8>, name: &str, value: &str) {
    put_str(out, name);
    put_str(out, "string");
    put_str(out, value);
}
fn put_meta_vec3i(out: &mut Vec<u8>, name: &str, v: [i32; 3]) {
    put_str(out, name);
    put_str(out, "vec3i");
    put_u32(out, 12);
    for c in v {
        out.extend_from_slice(&c.to_le_bytes());
    }
}
fn put_mask(out: &mut Vec<u8>, words: &[u64]) {
    for w in words {
        out.extend_from_slice(&w.to_le_bytes());
    }
}
/// An internal node's topology: child mask, an empty value mask, and its
/// (all inactive, all background) tile values under active-mask
/// compression: one metadata byte and no values.
fn put_internal_header(out: &mut Vec<u8>, log2: u32, children: impl Iterator<Item = usize>) {
    let words = (1usize << (3 * log2)) / 64;
    let mut child = vec![0u64; words];
    for s in children {
        child[s >> 6] |= 1 << (s & 63);
    }
    put_mask(out, &child);
    put_mask(out, &vec![0u64; words]);
    out.push(0);
}

/// A deterministic RFC 4122-shaped identifier from the content (OpenVDB
/// only requires 36 characters), so equal fields give equal files.
fn uuid(name: &str, data: &[f32], dims: [usize; 3], s: [f64; 3], o: [f64; 3]) -> String {
    let mut h: [u64; 2] = [0xcbf2_9ce4_8422_2325, 0x8422_2325_cbf2_9ce4];
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h[0] = (h[0] ^ b as u64).wrapping_mul(0x100_0000_01b3);
            h[1] = (h[1] ^ b as u64)
                .wrapping_mul(0x100_0000_01b3)
                .rotate_left(5);
        }
    };
    eat(name.as_bytes());
    for d in dims {
        eat(&(d as u64).to_le_bytes());
    }
    for v in s.iter().chain(o.iter()) {
        eat(&v.to_le_bytes());
    }
    for v in data {
        eat(&v.to_le_bytes());
    }
    let hex = format!("{:016x}{:016x}", h[0], h[1]);
    format!(
        "{}-{}-4{}-a{}-{}",
        &hex[0..8],
        &hex[8..12],
        &hex[13..16],
        &hex[17..20],
        &hex[20..32]
    )
}

// ---------------------------------------------------------------- reading

/// Read the float grid `grid_name` of an OpenVDB file into a dense array
/// over its active bounding box (see the module summary for what is
/// supported). Errors name the file.
pub fn read_float_grid(path: &Path, grid_name: &str) -> Result<VdbGrid> {
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    parse_float_grid(path, &bytes, grid_name)
}

/// Names and types of the grids in an OpenVDB file's bytes.
pub fn list_grids(path: &Path, bytes: &[u8]) -> Result<Vec<(String, String)>> {
    let err = |m: String| IoError::format(path, format!("invalid .vdb file: {m}"));
    let (mut r, n) = read_header(bytes).map_err(err)?;
    let mut out = Vec::new();
    for _ in 0..n {
        let d = read_descriptor(&mut r).map_err(err)?;
        out.push((d.name.clone(), d.grid_type.clone()));
        r.seek(d.end_pos).map_err(err)?;
    }
    Ok(out)
}

/// [`read_float_grid`] on bytes; `path` is only used in error messages.
pub fn parse_float_grid(path: &Path, bytes: &[u8], grid_name: &str) -> Result<VdbGrid> {
    let err = |m: String| IoError::format(path, format!("invalid .vdb file: {m}"));
    let unsupported = |m: String| IoError::format(path, m);
    let (mut r, n_grids) = read_header(bytes).map_err(err)?;
    let mut names = Vec::new();
    for _ in 0..n_grids {
        let d = read_descriptor(&mut r).map_err(err)?;
        if d.name != grid_name {
            names.push(format!("{} ({})", d.name, d.grid_type));
            r.seek(d.end_pos).map_err(err)?;
            continue;
        }
        let half = match d.grid_type.strip_suffix(HALF_SUFFIX) {
            Some(t) if t == FLOAT_TREE => true,
            None if d.grid_type == FLOAT_TREE => false,
            _ => {
                return Err(unsupported(format!(
                    "grid '{grid_name}' has type {}; only float grids ({FLOAT_TREE}) can be read",
                    d.grid_type
                )))
            }
        };
        if !d.instance_parent.is_empty() {
            return Err(unsupported(format!(
                "grid '{grid_name}' is an instance of grid '{}'; instanced grids are not supported (re-save without instancing)",
                d.instance_parent
            )));
        }
        r.seek(d.grid_pos).map_err(err)?;
        return read_grid(&mut r, grid_name, half).map_err(|e| match e {
            GridError::Format(m) => err(m),
            GridError::Unsupported(m) => unsupported(m),
        });
    }
    Err(unsupported(format!(
        "no grid named '{grid_name}' (grids: {})",
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        }
    )))
}

enum GridError {
    /// Malformed or truncated data.
    Format(String),
    /// A valid file using a feature this reader does not handle.
    Unsupported(String),
}
impl From<String> for GridError {
    fn from(m: String) -> Self {
        GridError::Format(m)
    }
}

/// A bounds-checked cursor over the file's bytes.
struct Reader<'a> {
    b: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: u64) -> std::result::Result<&'a [u8], String> {
        let left = (self.b.len() - self.pos) as u64;
        if n > left {
            return Err(format!(
                "truncated: {n} bytes needed at offset {}, {left} left",
                self.pos
            ));
        }
        let s = &self.b[self.pos..self.pos + n as usize];
        self.pos += n as usize;
        Ok(s)
    }
    fn seek(&mut self, pos: u64) -> std::result::Result<(), String> {
        if pos > self.b.len() as u64 {
            return Err(format!(
                "offset {pos} lies past the end of the file ({} bytes)",
                self.b.len()
            ));
        }
        self.pos = pos as usize;
        Ok(())
    }
    fn u8(&mut self) -> std::result::Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> std::result::Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn i32(&mut self) -> std::result::Result<i32, String> {
        Ok(i32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn i64(&mut self) -> std::result::Result<i64, String> {
        Ok(i64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn f32(&mut self) -> std::result::Result<f32, String> {
        Ok(f32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn f64(&mut self) -> std::result::Result<f64, String> {
        Ok(f64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn vec3d(&mut self) -> std::result::Result<[f64; 3], String> {
        Ok([self.f64()?, self.f64()?, self.f64()?])
    }
    fn string(&mut self) -> std::result::Result<String, String> {
        let n = self.u32()?;
        let s = self.take(n as u64)?;
        Ok(String::from_utf8_lossy(s).into_owned())
    }
    fn mask(&mut self, words: usize, out: &mut Vec<u64>) -> std::result::Result<(), String> {
        let s = self.take(8 * words as u64)?;
        out.clear();
        out.extend(
            s.chunks_exact(8)
                .map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes"))),
        );
        Ok(())
    }
}

/// Parse the archive header and file metadata; returns the reader at the
/// first grid descriptor and the grid count.
fn read_header(b: &[u8]) -> std::result::Result<(Reader<'_>, u32), String> {
    let mut r = Reader { b, pos: 0 };
    let magic = r
        .i64()
        .map_err(|_| "too short for the OpenVDB header".to_string())?;
    if magic as u64 != MAGIC {
        return Err("does not start with the OpenVDB magic number".into());
    }
    let version = r.u32()?;
    if !(MIN_VERSION..=FILE_VERSION).contains(&version) {
        return Err(format!(
            "file format version {version} is not supported (valid: {MIN_VERSION} to {FILE_VERSION}, OpenVDB 3 to 12)"
        ));
    }
    let _lib_major = r.u32()?;
    let _lib_minor = r.u32()?;
    if r.u8()? != 1 {
        return Err(
            "has no grid offsets (an OpenVDB stream, not a file); re-save it as a file".into(),
        );
    }
    r.take(36)?; // UUID
    skip_metadata(&mut r)?;
    let n = r.u32()?;
    Ok((r, n))
}

struct Descriptor {
    name: String,
    grid_type: String,
    instance_parent: String,
    grid_pos: u64,
    end_pos: u64,
}

fn read_descriptor(r: &mut Reader<'_>) -> std::result::Result<Descriptor, String> {
    let unique = r.string()?;
    // Duplicate names are made unique with an ASCII record separator suffix.
    let name = unique.split('\u{1e}').next().unwrap_or("").to_string();
    let grid_type = r.string()?;
    let instance_parent = r.string()?;
    let grid_pos = r.i64()?;
    let _block_pos = r.i64()?;
    let end_pos = r.i64()?;
    let here = r.pos as i64;
    if grid_pos < here || end_pos < grid_pos || end_pos as u64 > r.b.len() as u64 {
        return Err(format!(
            "grid '{name}' has invalid offsets (grid {grid_pos}, end {end_pos}; file {} bytes)",
            r.b.len()
        ));
    }
    Ok(Descriptor {
        name,
        grid_type,
        instance_parent,
        grid_pos: grid_pos as u64,
        end_pos: end_pos as u64,
    })
}

/// Skip a metadata map; returns `is_saved_as_half_float` when present.
fn skip_metadata(r: &mut Reader<'_>) -> std::result::Result<Option<bool>, String> {
    let n = r.u32()?;
    let mut half = None;
    for _ in 0..n {
        let name = r.string()?;
        let ty = r.string()?;
        let size = r.u32()?;
        let v = r.take(size as u64)?;
        if name == "is_saved_as_half_float" && ty == "bool" && size == 1 {
            half = Some(v[0] != 0);
        }
    }
    Ok(half)
}

fn read_map(r: &mut Reader<'_>) -> std::result::Result<[[f64; 4]; 4], GridError> {
    let ty = r.string()?;
    let mut m = [[0.0; 4]; 4];
    m[3][3] = 1.0;
    let set_scale = |m: &mut [[f64; 4]; 4], s: [f64; 3]| (0..3).for_each(|a| m[a][a] = s[a]);
    let set_trans = |m: &mut [[f64; 4]; 4], t: [f64; 3]| (0..3).for_each(|a| m[a][3] = t[a]);
    match ty.as_str() {
        // scale, voxel size, inverse scale, 1/scale², 1/(2 scale)
        "UniformScaleMap" | "ScaleMap" => {
            let s = r.vec3d()?;
            r.take(4 * 24)?;
            set_scale(&mut m, s);
        }
        "TranslationMap" => {
            set_scale(&mut m, [1.0; 3]);
            set_trans(&mut m, r.vec3d()?);
        }
        "UniformScaleTranslateMap" | "ScaleTranslateMap" => {
            let t = r.vec3d()?;
            let s = r.vec3d()?;
            r.take(4 * 24)?;
            set_scale(&mut m, s);
            set_trans(&mut m, t);
        }
        "AffineMap" => {
            // A 4x4 matrix for row vectors (translation in the last row).
            let mut a = [[0.0; 4]; 4];
            for row in a.iter_mut() {
                for v in row.iter_mut() {
                    *v = r.f64()?;
                }
            }
            for (rr, row) in m.iter_mut().enumerate() {
                for (c, v) in row.iter_mut().enumerate() {
                    *v = a[c][rr];
                }
            }
        }
        other => {
            return Err(GridError::Unsupported(format!(
                "transform '{other}' is not supported (valid: UniformScaleMap, ScaleMap, TranslationMap, UniformScaleTranslateMap, ScaleTranslateMap, AffineMap)"
            )))
        }
    }
    if m.iter().flatten().any(|v| !v.is_finite()) {
        return Err(GridError::Format(format!(
            "transform '{ty}' holds non-finite values"
        )));
    }
    Ok(m)
}

/// How a node's values are stored; shared by internal nodes and leaves.
struct Codec {
    compression: u32,
    half: bool,
    background: f32,
}

impl Codec {
    /// Read `n` values (n = 512, 4096 or 32768) into `out`, following the
    /// node metadata byte and the value mask (`mask`, `n / 64` words).
    fn read_values(
        &self,
        r: &mut Reader<'_>,
        mask: &[u64],
        out: &mut [f32],
        scratch: &mut Vec<f32>,
    ) -> std::result::Result<(), String> {
        let n = out.len();
        let meta = r.u8()?;
        let bg = self.background;
        let (mut inactive0, mut inactive1) = (if meta == 0 { bg } else { -bg }, bg);
        match meta {
            0 | 1 | 3 | 6 => {}
            2 | 4 => inactive0 = r.f32()?,
            5 => {
                inactive0 = r.f32()?;
                inactive1 = r.f32()?;
            }
            _ => return Err(format!("invalid node metadata byte {meta} (valid: 0 to 6)")),
        }
        let mut selection = [0u64; 512];
        if matches!(meta, 3..=5) {
            let s = r.take(8 * (n / 64) as u64)?;
            for (w, c) in selection.iter_mut().zip(s.chunks_exact(8)) {
                *w = u64::from_le_bytes(c.try_into().expect("8 bytes"));
            }
        }
        let compact = self.compression & COMPRESS_ACTIVE_MASK != 0 && meta != 6;
        let count = if compact {
            mask.iter().map(|w| w.count_ones() as usize).sum()
        } else {
            n
        };
        scratch.resize(count, 0.0);
        self.read_data(r, scratch)?;
        if !compact {
            out.copy_from_slice(scratch);
            return Ok(());
        }
        let mut k = 0;
        for (i, v) in out.iter_mut().enumerate() {
            let bit = |m: &[u64]| m[i >> 6] >> (i & 63) & 1 == 1;
            *v = if bit(mask) {
                k += 1;
                scratch[k - 1]
            } else if bit(&selection) {
                inactive1
            } else {
                inactive0
            };
        }
        Ok(())
    }

    /// Read `out.len()` values, zlib-compressed or raw, f32 or f16.
    fn read_data(&self, r: &mut Reader<'_>, out: &mut [f32]) -> std::result::Result<(), String> {
        let width = if self.half { 2 } else { 4 };
        let nbytes = (out.len() * width) as u64;
        let raw: std::borrow::Cow<'_, [u8]> =
            if self.compression & (COMPRESS_ZIP | COMPRESS_BLOSC) != 0 {
                // OpenVDB stores nothing for zero half values, but the chunk
                // size (and a chunk) for zero full floats.
                if out.is_empty() && self.half {
                    return Ok(());
                }
                let stored = r.i64()?;
                if out.is_empty() {
                    r.take(stored.max(0) as u64)?;
                    return Ok(());
                }
                if stored <= 0 {
                    // Stored uncompressed: -stored bytes follow.
                    if stored.unsigned_abs() != nbytes {
                        return Err(format!(
                            "uncompressed chunk of {} bytes where {nbytes} are expected",
                            stored.unsigned_abs()
                        ));
                    }
                    r.take(nbytes)?.into()
                } else {
                    let chunk = r.take(stored as u64)?;
                    let mut buf = vec![0u8; nbytes as usize];
                    if self.compression & COMPRESS_BLOSC != 0 {
                        blosc_decompress(chunk, &mut buf).map_err(|m| {
                            format!("corrupt Blosc chunk at offset {}: {m}", r.pos - chunk.len())
                        })?;
                        decode_values(&buf, self.half, out);
                        return Ok(());
                    }
                    let mut z = flate2::Decompress::new(true);
                    match z.decompress(chunk, &mut buf, flate2::FlushDecompress::Finish) {
                        Ok(flate2::Status::StreamEnd) if z.total_out() == nbytes => {}
                        _ => {
                            return Err(format!(
                                "corrupt zlib chunk at offset {} (expected {nbytes} bytes)",
                                r.pos - chunk.len()
                            ))
                        }
                    }
                    buf.into()
                }
            } else {
                r.take(nbytes)?.into()
            };
        decode_values(&raw, self.half, out);
        Ok(())
    }
}

/// Little-endian f32 or f16 values into `out`.
fn decode_values(raw: &[u8], half: bool, out: &mut [f32]) {
    if half {
        for (v, c) in out.iter_mut().zip(raw.chunks_exact(2)) {
            *v = f16_to_f32(u16::from_le_bytes([c[0], c[1]]));
        }
    } else {
        for (v, c) in out.iter_mut().zip(raw.chunks_exact(4)) {
            *v = f32::from_le_bytes(c.try_into().expect("4 bytes"));
        }
    }
}

/// Decompress one Blosc (version 1 format) chunk into `out`, whose length
/// must be the chunk's uncompressed size. OpenVDB compresses each node
/// buffer as one chunk with byte shuffling and LZ4; this also takes zlib
/// and uncompressed (memcpy) chunks, several blocks and split streams.
/// Every offset and size is checked against the chunk, and nothing is
/// allocated beyond `out.len()`.
fn blosc_decompress(chunk: &[u8], out: &mut [u8]) -> std::result::Result<(), String> {
    const HEADER: usize = 16;
    const DOSHUFFLE: u8 = 0x1;
    const MEMCPYED: u8 = 0x2;
    const DOBITSHUFFLE: u8 = 0x4;
    const DONT_SPLIT: u8 = 0x10;
    if chunk.len() < HEADER {
        return Err(format!(
            "{} bytes, shorter than the 16-byte header",
            chunk.len()
        ));
    }
    let word = |at: usize| -> Option<usize> {
        chunk
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")) as usize)
    };
    let (version, flags, typesize) = (chunk[0], chunk[2], chunk[3] as usize);
    let nbytes = word(4).expect("header");
    let blocksize = word(8).expect("header");
    let cbytes = word(12).expect("header");
    if !(1..=2).contains(&version) || flags & 0x08 != 0 {
        return Err(format!(
            "unknown format version {version} or flags {flags:#x}"
        ));
    }
    if cbytes != chunk.len() || nbytes != out.len() {
        return Err(format!(
            "header says {cbytes} compressed / {nbytes} uncompressed bytes, expected {} / {}",
            chunk.len(),
            out.len()
        ));
    }
    if nbytes == 0 {
        return Ok(());
    }
    if flags & MEMCPYED != 0 {
        if cbytes != nbytes + HEADER {
            return Err("uncompressed chunk of the wrong size".into());
        }
        out.copy_from_slice(&chunk[HEADER..]);
        return Ok(());
    }
    if blocksize == 0 || typesize == 0 {
        return Err(format!(
            "block size {blocksize} or type size {typesize} is 0"
        ));
    }
    if flags & DOBITSHUFFLE != 0 && blocksize >= typesize {
        return Err("bit-shuffled chunks are not supported (re-save with zip compression)".into());
    }
    let codec = (flags & 0xe0) >> 5;
    if !matches!(codec, 1 | 3) {
        return Err(format!(
            "codec #{codec} is not supported (valid: LZ4 and zlib; re-save with zip compression)"
        ));
    }
    let nblocks = nbytes.div_ceil(blocksize);
    if nblocks > (cbytes - HEADER) / 4 {
        return Err(format!("{nblocks} blocks do not fit in the chunk"));
    }
    let shuffle = flags & DOSHUFFLE != 0 && typesize > 1;
    let mut tmp = vec![0u8; if shuffle { blocksize.min(nbytes) } else { 0 }];
    for j in 0..nblocks {
        let start = j * blocksize;
        let leftover = j == nblocks - 1 && nbytes % blocksize != 0;
        let bsize = if leftover { nbytes - start } else { blocksize };
        let nsplits = if flags & DONT_SPLIT == 0
            && typesize <= 16
            && blocksize / typesize >= 128
            && !leftover
        {
            typesize
        } else {
            1
        };
        let neblock = bsize / nsplits;
        let mut off = word(HEADER + 4 * j).expect("bstarts checked");
        let dest = &mut out[start..start + bsize];
        let target: &mut [u8] = if shuffle { &mut tmp[..bsize] } else { dest };
        for part in target.chunks_exact_mut(neblock).take(nsplits) {
            let cb = word(off).ok_or("stream offset past the chunk")?;
            off += 4;
            let src = chunk
                .get(off..off.saturating_add(cb))
                .ok_or("stream size past the chunk")?;
            off += cb;
            if cb == neblock {
                part.copy_from_slice(src);
                continue;
            }
            let got = if codec == 1 {
                lz4_flex::block::decompress_into(src, part).map_err(|e| format!("LZ4: {e}"))?
            } else {
                let mut z = flate2::Decompress::new(true);
                match z.decompress(src, part, flate2::FlushDecompress::Finish) {
                    Ok(flate2::Status::StreamEnd) => z.total_out() as usize,
                    _ => return Err("zlib stream is corrupt".into()),
                }
            };
            if got != neblock {
                return Err(format!(
                    "a stream decompressed to {got} bytes, expected {neblock}"
                ));
            }
        }
        if shuffle {
            // Byte j of element i was stored at j * n + i; trailing bytes
            // that do not fill an element are stored as they are.
            let n = bsize / typesize;
            let dest = &mut out[start..start + bsize];
            for i in 0..n {
                for b in 0..typesize {
                    dest[i * typesize + b] = tmp[b * n + i];
                }
            }
            dest[n * typesize..].copy_from_slice(&tmp[n * typesize..bsize]);
        }
    }
    Ok(())
}

/// IEEE 754 binary16 to binary32.
fn f16_to_f32(h: u16) -> f32 {
    let sign = ((h >> 15) as u32) << 31;
    let exp = ((h >> 10) & 0x1f) as u32;
    let frac = (h & 0x3ff) as u32;
    let bits = match (exp, frac) {
        (0, 0) => sign,
        (0, f) => {
            // Subnormal: value f * 2^-24.
            return f32::from_bits(sign)
                + (if sign != 0 { -1.0 } else { 1.0 }) * f as f32 * (-24f32).exp2();
        }
        (0x1f, 0) => sign | 0x7f80_0000,
        (0x1f, f) => sign | 0x7fc0_0000 | (f << 13),
        (e, f) => sign | ((e + 112) << 23) | (f << 13),
    };
    f32::from_bits(bits)
}

/// What the topology pass keeps: active tiles and leaf value masks, enough
/// to find the active bounding box before the dense array is allocated.
struct Topology {
    /// (origin, width in voxels, value) of every active tile.
    tiles: Vec<([i32; 3], i64, f32)>,
    /// (origin, value mask) of every leaf, in buffer order.
    leaves: Vec<([i32; 3], [u64; 8])>,
}

fn read_grid(
    r: &mut Reader<'_>,
    name: &str,
    half_type: bool,
) -> std::result::Result<VdbGrid, GridError> {
    let compression = r.u32()?;
    if compression & !(COMPRESS_ZIP | COMPRESS_ACTIVE_MASK | COMPRESS_BLOSC) != 0 {
        return Err(GridError::Format(format!(
            "unknown compression flags {compression:#x}"
        )));
    }
    let half = skip_metadata(r)?.unwrap_or(false) || half_type;
    let index_to_world = read_map(r)?;
    let buffer_count = r.u32()?;
    if buffer_count != 1 {
        return Err(GridError::Format(format!(
            "tree has {buffer_count} buffers (valid: 1)"
        )));
    }
    let background = r.f32()?;
    let codec = Codec {
        compression,
        half,
        background,
    };
    let n_tiles = r.u32()?;
    let n_children = r.u32()?;
    let mut topo = Topology {
        tiles: Vec::new(),
        leaves: Vec::new(),
    };
    let mut tile_volume = 0u64;
    for _ in 0..n_tiles {
        let o = [r.i32()?, r.i32()?, r.i32()?];
        let v = r.f32()?;
        if r.u8()? != 0 {
            // One 4096³ root tile alone exceeds any dense array.
            return Err(GridError::Unsupported(format!(
                "grid '{name}' has an active root tile at {o:?} (4096³ voxels), more than the {MAX_DENSE_VOXELS} a dense grid may hold"
            )));
        }
        let _ = v;
    }
    let mut scratch = Vec::new();
    let mut values = vec![0f32; 1 << 15];
    let (mut cmask, mut vmask) = (Vec::new(), Vec::new());
    let (mut cmask1, mut vmask1) = (Vec::new(), Vec::new());
    for _ in 0..n_children {
        let o2 = [r.i32()?, r.i32()?, r.i32()?];
        if o2.iter().any(|c| c & ((1 << 12) - 1) != 0) {
            return Err(GridError::Format(format!(
                "root child origin {o2:?} is not a multiple of 4096"
            )));
        }
        read_internal(
            r,
            &codec,
            INT2_LOG2,
            &mut cmask,
            &mut vmask,
            &mut values,
            &mut scratch,
        )?;
        collect_tiles(
            o2,
            INT2_LOG2,
            INT1_LOG2 + LEAF_LOG2,
            &cmask,
            &vmask,
            &values,
            &mut topo.tiles,
            &mut tile_volume,
        )?;
        for s2 in set_bits(&cmask) {
            let o1 = slot_origin(o2, s2, INT2_LOG2, INT1_LOG2 + LEAF_LOG2);
            read_internal(
                r,
                &codec,
                INT1_LOG2,
                &mut cmask1,
                &mut vmask1,
                &mut values,
                &mut scratch,
            )?;
            collect_tiles(
                o1,
                INT1_LOG2,
                LEAF_LOG2,
                &cmask1,
                &vmask1,
                &values,
                &mut topo.tiles,
                &mut tile_volume,
            )?;
            for s1 in set_bits(&cmask1) {
                let o0 = slot_origin(o1, s1, INT1_LOG2, LEAF_LOG2);
                let mut m = Vec::new();
                r.mask(8, &mut m)?;
                topo.leaves.push((o0, m.try_into().expect("8 words")));
            }
        }
    }

    // Active bounding box from tiles and leaf masks, in i64.
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    let mut grow = |a: [i64; 3], b: [i64; 3]| {
        for k in 0..3 {
            lo[k] = lo[k].min(a[k]);
            hi[k] = hi[k].max(b[k]);
        }
    };
    for (o, w, _) in &topo.tiles {
        let a = o.map(|c| c as i64);
        grow(a, a.map(|c| c + w - 1));
    }
    for (o, m) in &topo.leaves {
        for i in set_bits(m) {
            let p = leaf_voxel(*o, i).map(|c| c as i64);
            grow(p, p);
        }
    }
    let dims: [u64; 3] = if lo[0] == i64::MAX {
        // No active voxel: a single background voxel at the origin.
        lo = [0; 3];
        [1, 1, 1]
    } else {
        [0, 1, 2].map(|k| (hi[k] - lo[k] + 1) as u64)
    };
    let total = dims[0]
        .checked_mul(dims[1])
        .and_then(|v| v.checked_mul(dims[2]));
    if !matches!(total, Some(t) if t <= MAX_DENSE_VOXELS) {
        return Err(GridError::Unsupported(format!(
            "grid '{name}' has an active bounding box of {}x{}x{} voxels, more than the {MAX_DENSE_VOXELS} a dense grid may hold",
            dims[0], dims[1], dims[2]
        )));
    }
    let dims = dims.map(|d| d as usize);
    let index_min = lo.map(|c| c as i32);
    let mut data = vec![background; dims[0] * dims[1] * dims[2]];
    let rel = |p: [i32; 3]| -> Option<usize> {
        let d = [0, 1, 2].map(|k| p[k] as i64 - index_min[k] as i64);
        if (0..3).all(|k| d[k] >= 0 && (d[k] as usize) < dims[k]) {
            Some((d[2] as usize * dims[1] + d[1] as usize) * dims[0] + d[0] as usize)
        } else {
            None
        }
    };
    for (o, w, v) in &topo.tiles {
        // Tiles are clipped to the box (a root tile may be 4096 wide).
        let clip = |k: usize| {
            let a = (o[k] as i64).max(lo[k]);
            let b = (o[k] as i64 + w - 1).min(lo[k] + dims[k] as i64 - 1);
            a..=b
        };
        for z in clip(2) {
            for y in clip(1) {
                for x in clip(0) {
                    if let Some(i) = rel([x as i32, y as i32, z as i32]) {
                        data[i] = *v;
                    }
                }
            }
        }
    }

    // Buffers: one per leaf, in topology order.
    let mut leaf = vec![0f32; 512];
    let mut m = Vec::new();
    for (o, topo_mask) in &topo.leaves {
        r.mask(8, &mut m)?;
        if m.as_slice() != topo_mask.as_slice() {
            return Err(GridError::Format(format!(
                "leaf at {o:?}: buffer value mask differs from the topology's"
            )));
        }
        codec.read_values(r, &m, &mut leaf, &mut scratch)?;
        for i in 0..512 {
            let active = m[i >> 6] >> (i & 63) & 1 == 1;
            if let Some(j) = rel(leaf_voxel(*o, i)) {
                data[j] = if active { leaf[i] } else { background };
            }
        }
    }
    Ok(VdbGrid {
        name: name.to_string(),
        index_min,
        dims,
        data,
        background,
        index_to_world,
    })
}

#[allow(clippy::too_many_arguments)]
fn read_internal(
    r: &mut Reader<'_>,
    codec: &Codec,
    log2: u32,
    cmask: &mut Vec<u64>,
    vmask: &mut Vec<u64>,
    values: &mut [f32],
    scratch: &mut Vec<f32>,
) -> std::result::Result<(), String> {
    let n = 1usize << (3 * log2);
    r.mask(n / 64, cmask)?;
    r.mask(n / 64, vmask)?;
    codec.read_values(r, vmask, &mut values[..n], scratch)
}

/// Active tiles of an internal node (value on, child off). Tiles of a valid
/// tree are disjoint, so their total volume cannot exceed the dense array:
/// past [`MAX_DENSE_VOXELS`] the file is refused here, which bounds the tile
/// list (and the time spent filling tiles) whatever the file holds.
#[allow(clippy::too_many_arguments)]
fn collect_tiles(
    origin: [i32; 3],
    log2: u32,
    child_total: u32,
    cmask: &[u64],
    vmask: &[u64],
    values: &[f32],
    tiles: &mut Vec<([i32; 3], i64, f32)>,
    volume: &mut u64,
) -> std::result::Result<(), GridError> {
    for s in set_bits(vmask) {
        if cmask[s >> 6] >> (s & 63) & 1 == 0 {
            *volume += 1 << (3 * child_total);
            if *volume > MAX_DENSE_VOXELS {
                return Err(GridError::Unsupported(format!(
                    "active tiles hold more than the {MAX_DENSE_VOXELS} voxels a dense grid may hold"
                )));
            }
            tiles.push((
                slot_origin(origin, s, log2, child_total),
                1 << child_total,
                values[s],
            ));
        }
    }
    Ok(())
}

fn set_bits(words: &[u64]) -> impl Iterator<Item = usize> + '_ {
    words.iter().enumerate().flat_map(|(k, &w)| {
        let mut w = w;
        std::iter::from_fn(move || {
            if w == 0 {
                return None;
            }
            let b = w.trailing_zeros() as usize;
            w &= w - 1;
            Some(64 * k + b)
        })
    })
}

fn slot_origin(o: [i32; 3], s: usize, log2: u32, child_total: u32) -> [i32; 3] {
    let m = (1usize << log2) - 1;
    let (x, y, z) = (s >> (2 * log2), (s >> log2) & m, s & m);
    [
        o[0].wrapping_add((x << child_total) as i32),
        o[1].wrapping_add((y << child_total) as i32),
        o[2].wrapping_add((z << child_total) as i32),
    ]
}

fn leaf_voxel(o: [i32; 3], i: usize) -> [i32; 3] {
    [
        o[0].wrapping_add((i >> 6) as i32),
        o[1].wrapping_add(((i >> 3) & 7) as i32),
        o[2].wrapping_add((i & 7) as i32),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(dims: [usize; 3]) -> Vec<f32> {
        (0..dims[0] * dims[1] * dims[2])
            .map(|i| (i % 7) as f32 * 0.25 + 0.5)
            .collect()
    }

    #[test]
    fn round_trip_dense() {
        let dims = [13, 9, 20];
        let data = field(dims);
        let b = encode_float_grid("density", &data, dims, [0.5; 3], [1.0, -2.0, 3.0]).unwrap();
        let g = parse_float_grid(Path::new("t.vdb"), &b, "density").unwrap();
        assert_eq!(g.dims, dims);
        assert_eq!(g.index_min, [0; 3]);
        assert_eq!(g.data, data);
        assert_eq!(g.background, 0.0);
        assert_eq!(g.world_bbox().unwrap(), [1.0, -2.0, 3.0, 7.5, 2.5, 13.0]);
        assert_eq!(g.index_to_world[0][3], 1.25);
        // As a unit-cube .vol grid: voxel (x, y, z) centred at (idx + 0.5)/n
        // in the cube lands on the VDB voxel centre origin + (idx + 0.5) s.
        let (vol, m) = g.clone().into_unit_cube_vol();
        assert_eq!(vol.shape, dims);
        assert_eq!(vol.at(3, 4, 5, 0), g.at(3, 4, 5));
        let u = [3.5 / 13.0, 4.5 / 9.0, 5.5 / 20.0];
        let w: Vec<f64> = (0..3)
            .map(|r| (0..3).map(|c| m[r][c] * u[c]).sum::<f64>() + m[r][3])
            .collect();
        for (k, want) in [1.0 + 3.5 * 0.5, -2.0 + 4.5 * 0.5, 3.0 + 5.5 * 0.5]
            .into_iter()
            .enumerate()
        {
            assert!((w[k] - want).abs() < 1e-12, "{w:?}");
        }
    }

    #[test]
    fn zero_leaves_are_sparse_and_read_back_as_background() {
        // Only a 2x2x2 block far from the origin is non-zero.
        let dims = [40, 30, 20];
        let mut data = vec![0f32; 40 * 30 * 20];
        for (x, y, z) in [(33, 21, 17), (34, 22, 18)] {
            data[(z * 30 + y) * 40 + x] = 2.0;
        }
        let b = encode_float_grid("density", &data, dims, [1.0, 2.0, 3.0], [0.0; 3]).unwrap();
        // Internal-node masks are a fixed 8 KiB; the dense grid would be 96 kB.
        assert!(b.len() < 12_000, "{} bytes", b.len());
        let g = parse_float_grid(Path::new("t.vdb"), &b, "density").unwrap();
        // Active box: the written leaf [32, 40) x [16, 24) x [16, 20).
        assert_eq!(g.index_min, [32, 16, 16]);
        assert_eq!(g.dims, [8, 8, 4]);
        assert_eq!(g.at(1, 5, 1), 2.0);
        assert_eq!(g.at(2, 6, 2), 2.0);
        assert_eq!(g.data.iter().filter(|&&v| v != 0.0).count(), 2);
        assert_eq!(g.index_to_world[1][1], 2.0);
        assert_eq!(g.index_to_world[2][3], 1.5);
    }

    #[test]
    fn large_grid_spans_several_internal_nodes() {
        let dims = [130, 3, 2];
        let data = field(dims);
        let b = encode_float_grid("sigma_t", &data, dims, [0.1; 3], [0.0; 3]).unwrap();
        let g = parse_float_grid(Path::new("t.vdb"), &b, "sigma_t").unwrap();
        assert_eq!(g.data, data);
        let e = parse_float_grid(Path::new("t.vdb"), &b, "density").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.vdb: no grid named 'density' (grids: sigma_t (Tree_float_5_4_3))"
        );
    }

    #[test]
    fn deterministic_bytes() {
        let dims = [5, 6, 7];
        let a = encode_float_grid("density", &field(dims), dims, [1.0; 3], [0.0; 3]).unwrap();
        let b = encode_float_grid("density", &field(dims), dims, [1.0; 3], [0.0; 3]).unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn hostile_bytes_give_errors_not_panics() {
        let dims = [9, 9, 9];
        let good = encode_float_grid("density", &field(dims), dims, [1.0; 3], [0.0; 3]).unwrap();
        let p = Path::new("bad.vdb");
        // Every truncation.
        for n in 0..good.len() {
            let e = parse_float_grid(p, &good[..n], "density").unwrap_err();
            let m = e.to_string();
            assert!(m.starts_with("bad.vdb: "), "{m}");
            assert!(!m.contains('\n'));
        }
        // Every single-byte corruption to 0xff and 0x80 (lengths, counts,
        // masks, metadata bytes, offsets).
        for i in 0..good.len() {
            for v in [0xffu8, 0x80, 0x00] {
                let mut b = good.clone();
                b[i] = v;
                if let Err(e) = parse_float_grid(p, &b, "density") {
                    assert!(e.to_string().starts_with("bad.vdb: "));
                }
            }
        }
    }

    #[test]
    fn absurd_bounding_box_is_refused_before_allocating() {
        // Two active root tiles 2^24 voxels apart: a 2^72-voxel box.
        let tile_file = hand_made_tiles();
        let e = parse_float_grid(Path::new("big.vdb"), &tile_file, "density").unwrap_err();
        assert!(e.to_string().contains("more than the"), "{e}");
    }

    /// A file whose root holds two active tiles far apart.
    fn hand_made_tiles() -> Vec<u8> {
        let dims = [1, 1, 1];
        let good = encode_float_grid("density", &[1.0], dims, [1.0; 3], [0.0; 3]).unwrap();
        // Locate the topology: after "buffer count 1, background 0".
        let mut r = Reader { b: &good, pos: 0 };
        let (mut r2, _) = read_header(&good).unwrap();
        let d = read_descriptor(&mut r2).unwrap();
        r.pos = d.grid_pos as usize;
        r.u32().unwrap();
        skip_metadata(&mut r).unwrap();
        read_map(&mut r).ok().unwrap();
        let topo = r.pos;
        let mut b = good[..topo].to_vec();
        b.extend_from_slice(&1u32.to_le_bytes());
        b.extend_from_slice(&0f32.to_le_bytes());
        b.extend_from_slice(&2u32.to_le_bytes()); // two tiles
        b.extend_from_slice(&0u32.to_le_bytes()); // no children
        for o in [0i32, 1 << 24] {
            for _ in 0..3 {
                b.extend_from_slice(&o.to_le_bytes());
            }
            b.extend_from_slice(&1f32.to_le_bytes());
            b.push(1);
        }
        // Fix end offset.
        let end = b.len() as i64;
        let off = d.grid_pos as usize - 8;
        b[off..off + 8].copy_from_slice(&end.to_le_bytes());
        b
    }

    /// Written by the reference implementation (OpenVDB 10.0.1, Debian's
    /// python3-openvdb) with its defaults (Blosc LZ4 + byte shuffle, active
    /// mask compression), by this script under /usr/bin/python3:
    ///
    /// ```python
    /// import numpy as np, pyopenvdb as vdb
    /// g = vdb.FloatGrid(); g.name = "density"; g.gridClass = vdb.GridClass.FOG_VOLUME
    /// i, j, k = np.meshgrid(np.arange(12), np.arange(5), np.arange(9), indexing="ij")
    /// g.copyFromArray(((i + 2*j + 3*k) * 0.125 + 0.5).astype(np.float32), ijk=(-3, 4, 10), tolerance=0.0)
    /// g.fill((16, 0, 8), (23, 7, 15), 0.75, active=True)
    /// g.transform = vdb.createLinearTransform([[0, .5, 0, 0], [-.5, 0, 0, 0], [0, 0, .5, 0], [1, 2, 3, 1]])
    /// h = vdb.Vec3SGrid(); h.name = "vel"
    /// vdb.write("reference_blosc.vdb", grids=[g, h])
    /// ```
    const REFERENCE: &[u8] = include_bytes!("../tests/data/reference_blosc.vdb");

    #[test]
    fn reads_the_reference_implementations_blosc_file() {
        let p = Path::new("reference_blosc.vdb");
        let g = parse_float_grid(p, REFERENCE, "density").unwrap();
        assert_eq!(g.index_min, [-3, 0, 8]);
        assert_eq!(g.dims, [27, 9, 11]);
        let mut n_active = 0;
        for z in 0..11 {
            for y in 0..9 {
                for x in 0..27 {
                    let (i, j, k) = (x as i32 - 3, y as i32, z as i32 + 8);
                    let want = if (-3..9).contains(&i)
                        && (4..9).contains(&j)
                        && (10..19).contains(&k)
                    {
                        ((i + 3) + 2 * (j - 4) + 3 * (k - 10)) as f32 * 0.125 + 0.5
                    } else if (16..24).contains(&i) && (0..8).contains(&j) && (8..16).contains(&k) {
                        0.75 // an active tile of the lower internal node
                    } else {
                        0.0
                    };
                    assert_eq!(g.at(x, y, z), want, "voxel {:?}", (i, j, k));
                    n_active += (want != 0.0) as usize;
                }
            }
        }
        assert_eq!(n_active, 1052);
        let m = g.index_to_world;
        assert_eq!(m[0], [0.0, -0.5, 0.0, 1.0]);
        assert_eq!(m[1], [0.5, 0.0, 0.0, 2.0]);
        assert_eq!(m[2], [0.0, 0.0, 0.5, 3.0]);
        assert_eq!(g.world_bbox(), None);
        let e = parse_float_grid(p, REFERENCE, "vel")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("has type Tree_vec3s_5_4_3; only float grids"),
            "{e}"
        );
        assert_eq!(
            list_grids(p, REFERENCE).unwrap(),
            vec![
                ("density".to_string(), "Tree_float_5_4_3".to_string()),
                ("vel".to_string(), "Tree_vec3s_5_4_3".to_string())
            ]
        );
    }

    #[test]
    fn hostile_blosc_bytes_give_errors_not_panics() {
        let p = Path::new("bad.vdb");
        // The file is complete for "density" once its grid has ended.
        let (mut r, _) = read_header(REFERENCE).unwrap();
        let end = read_descriptor(&mut r).unwrap().end_pos as usize;
        assert!(end < REFERENCE.len());
        for n in (0..end).step_by(7) {
            assert!(parse_float_grid(p, &REFERENCE[..n], "density").is_err());
        }
        // Every byte of the header, descriptors, metadata and transform;
        // every 5th of the tree (masks, metadata bytes, Blosc headers).
        let positions = (0..1024).chain((1024..end).step_by(5));
        for i in positions {
            for v in [0xffu8, 0x00] {
                let mut b = REFERENCE.to_vec();
                b[i] = v;
                if let Err(e) = parse_float_grid(p, &b, "density") {
                    assert!(e.to_string().starts_with("bad.vdb: "));
                }
            }
        }
    }

    #[test]
    fn half_floats_decode() {
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert_eq!(f16_to_f32(0x0001), (-24f32).exp2());
        assert_eq!(f16_to_f32(0x7c00), f32::INFINITY);
        assert_eq!(f16_to_f32(0x3555), 0.333_251_95);
    }
}
