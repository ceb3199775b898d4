//! Reading: the file header, grid descriptors, transforms and the tree into a dense array.

use super::*;

/// Read the float grid `grid_name` of an OpenVDB file into a dense array
/// over its active bounding box (see the module summary for what is
/// supported). Errors name the file.
pub fn read_float_grid(path: &Path, grid_name: &str) -> Result<VdbGrid> {
    let bytes = crate::read_regular(path).map_err(|e| IoError::io(path, e))?;
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

/// Parse the archive header and file metadata; returns the reader at the
/// first grid descriptor and the grid count.
pub(super) fn read_header(b: &[u8]) -> std::result::Result<(Reader<'_>, u32), String> {
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

pub(super) struct Descriptor {
    pub(super) name: String,
    pub(super) grid_type: String,
    pub(super) instance_parent: String,
    pub(super) grid_pos: u64,
    pub(super) end_pos: u64,
}

pub(super) fn read_descriptor(r: &mut Reader<'_>) -> std::result::Result<Descriptor, String> {
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
pub(super) fn skip_metadata(r: &mut Reader<'_>) -> std::result::Result<Option<bool>, String> {
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

pub(super) fn read_map(r: &mut Reader<'_>) -> std::result::Result<[[f64; 4]; 4], GridError> {
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

/// What the topology pass keeps: active tiles and leaf value masks, enough
/// to find the active bounding box before the dense array is allocated.
pub(super) struct Topology {
    /// (origin, width in voxels, value) of every active tile.
    pub(super) tiles: Vec<([i32; 3], i64, f32)>,
    /// (origin, value mask) of every leaf, in buffer order.
    pub(super) leaves: Vec<([i32; 3], [u64; 8])>,
}

pub(super) fn read_grid(
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
pub(super) fn read_internal(
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
pub(super) fn collect_tiles(
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

pub(super) fn set_bits(words: &[u64]) -> impl Iterator<Item = usize> + '_ {
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

pub(super) fn slot_origin(o: [i32; 3], s: usize, log2: u32, child_total: u32) -> [i32; 3] {
    let m = (1usize << log2) - 1;
    let (x, y, z) = (s >> (2 * log2), (s >> log2) & m, s & m);
    [
        o[0].wrapping_add((x << child_total) as i32),
        o[1].wrapping_add((y << child_total) as i32),
        o[2].wrapping_add((z << child_total) as i32),
    ]
}

pub(super) fn leaf_voxel(o: [i32; 3], i: usize) -> [i32; 3] {
    [
        o[0].wrapping_add((i >> 6) as i32),
        o[1].wrapping_add(((i >> 3) & 7) as i32),
        o[2].wrapping_add((i & 7) as i32),
    ]
}
