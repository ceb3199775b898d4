//! Writing: one float grid, sparse over 8³ leaves, atomically (conventions in the parent module).

use super::*;

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
pub(super) fn child_slot(o: [i32; 3], log2: u32, child_total: u32) -> usize {
    let m = (1i32 << (log2 + child_total)) - 1;
    let [x, y, z] = o.map(|c| ((c & m) >> child_total) as usize);
    (x << (2 * log2)) | (y << log2) | z
}

pub(super) fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}
pub(super) fn put_str(out: &mut Vec<u8>, s: &str) {
    put_u32(out, s.len() as u32);
    out.extend_from_slice(s.as_bytes());
}
pub(super) fn put_meta_str(out: &mut Vec<u8>, name: &str, value: &str) {
    put_str(out, name);
    put_str(out, "string");
    put_str(out, value);
}
pub(super) fn put_meta_vec3i(out: &mut Vec<u8>, name: &str, v: [i32; 3]) {
    put_str(out, name);
    put_str(out, "vec3i");
    put_u32(out, 12);
    for c in v {
        out.extend_from_slice(&c.to_le_bytes());
    }
}
pub(super) fn put_mask(out: &mut Vec<u8>, words: &[u64]) {
    for w in words {
        out.extend_from_slice(&w.to_le_bytes());
    }
}
/// An internal node's topology: child mask, an empty value mask, and its
/// (all inactive, all background) tile values under active-mask
/// compression: one metadata byte and no values.
pub(super) fn put_internal_header(
    out: &mut Vec<u8>,
    log2: u32,
    children: impl Iterator<Item = usize>,
) {
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
pub(super) fn uuid(name: &str, data: &[f32], dims: [usize; 3], s: [f64; 3], o: [f64; 3]) -> String {
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
