//! `<volume>`: the 3D textures a medium takes for `sigma_t` and `albedo`
//! (see [`super::media`]) and for the `density` of a non-exponential medium
//! (see [`super::nonexp`]): `gridvolume`, a Mitsuba `.vol` grid file
//! (float32; format in `fgf_io::vol`), and `constvolume`, a constant. The
//! values are checked against the range of the parameter the volume is
//! given for: `sigma_t` and `density` ≥ 0, `albedo` in [0, 1].
//!
//! | plugin | parameter | type | units | range | default | meaning |
//! |---|---|---|---|---|---|---|
//! | `gridvolume` | `filename` | string | – | a `.vol` file of 1 or 3 channels (1 for `density`), or an OpenVDB `.vdb` file (an fgf extension, below), relative to the scene file, at most 4 GiB | required | |
//! | `gridvolume` | `grid` | string | – | the name of a float grid in the `.vdb` file (only with a `.vdb` file) | `density` | which grid of the file to use |
//! | `gridvolume` | `to_world` | transform | – | invertible | identity | volume space to world |
//! | `gridvolume` | `use_grid_bbox` | boolean | – | – | false | false: the grid spans the unit cube `[0, 1]³` of volume space; true: the bounding box in the file (which must not be empty) |
//! | `gridvolume` | `filter_type` | string | – | `trilinear`, `nearest` | `trilinear` | interpolation between voxel centres |
//! | `gridvolume` | `wrap_mode` | string | – | `clamp`, `repeat`, `mirror` | `clamp` | what a lookup reads beyond the outermost voxel centres (Dr.Jit's texture semantics, as Mitsuba 3.9.1): `repeat` interpolates across to the opposite face even inside the box, `mirror` reflects (inside the box it reads what `clamp` reads) |
//! | `constvolume` | `value` | float or rgb | that of the parameter | that of the parameter | 1 | |
//! | `constvolume` | `to_world` | transform | – | invertible | identity | places the volume's unit cube `[0, 1]³`: the bounding box of a `heterogeneous` medium with a constant `sigma_t` (see [`super::media`]); it has no effect elsewhere |
//!
//! **OpenVDB files (an fgf extension; Mitsuba 3 reads only `.vol`).** A
//! `filename` ending in `.vdb` loads the float grid named `grid` densely over
//! its active bounding box (`fgf_io::vdb`). The file's index-to-world
//! transform places it: voxel `(i, j, k)` is centred at
//! `to_world · index_to_world · (i, j, k)`, so `to_world` (default identity)
//! maps the VDB's world space into the scene, and outside the active box the
//! medium is empty (the sparse background, which must be 0). `use_grid_bbox`
//! does not apply. Fields made by `fgf field -o f.vdb` (or `fgf.write_vdb`)
//! cover the same box as `-o f.vol` with `use_grid_bbox`; conventions in
//! `docs/vdb.md`.
//!
//! ```xml
//! <volume type="gridvolume" name="sigma_t">
//!     <string name="filename" value="density64.vol"/>
//!     <string name="filter_type" value="nearest"/>
//!     <transform name="to_world"><translate value="-0.5, 0, -0.5"/></transform>
//! </volume>
//! <volume type="constvolume" name="albedo"><rgb name="value" value="0.9, 0.8, 0.7"/></volume>
//! ```
//!
//! ```python
//! import fgf
//! field = fgf.synthesize((64, 64, 64), hurst=-0.1, seed=1)
//! fgf.save_field("density.vol", field, mean=4.0, clamp_min=0.0)  # sigma_t >= 0
//! img = fgf.render("scene.xml")  # a scene whose gridvolume reads density.vol
//! ```

use super::context::{check_object_attrs, rgb, to_invertible_mat4, Ctx};
use super::document::XNode;
use super::props::{check_rgb, Entry, Props};
use crate::desc::*;
use crate::error::{SceneError, SceneErrorKind};
use crate::validate::Range;
use glam::{DMat4, Mat4};
use std::sync::Arc;

/// `.vol` files larger than this (4 GiB) are refused before reading.
const MAX_VOL_BYTES: u64 = 1 << 32;

fn take_named_volume<'a, 'p>(p: &'p Props<'a>, name: &str) -> Option<&'p Entry<'a>> {
    p.take(name).or_else(|| p.take_object_named("volume", name))
}

/// A float/rgb parameter or a nested `<volume name=...>`.
pub(crate) fn volume_of(
    ctx: &Ctx,
    p: &Props,
    name: &str,
    default: f64,
    r: Range<f64>,
) -> Result<VolumeDesc, SceneError> {
    let Some(e) = take_named_volume(p, name) else {
        return Ok(VolumeDesc::Constant([default as f32; 3]));
    };
    if e.is_property() {
        let c = check_rgb(e.node, name, e.color()?, r)?;
        return Ok(VolumeDesc::Constant(rgb(c)));
    }
    volume(ctx, e.target, name, r)
}

fn volume(ctx: &Ctx, n: &XNode, name: &str, r: Range<f64>) -> Result<VolumeDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = n.attr("type").unwrap_or("");
    match ty {
        "constvolume" => {
            let p = Props::new(n, &ctx.ids, &["value", "to_world"])?;
            let c = p.color_in("value", [1.0; 3], r)?;
            let to_world = match p.transform("to_world")? {
                Some((m, node)) => to_invertible_mat4(node, m)?,
                None => Mat4::IDENTITY,
            };
            p.finish()?;
            if to_world == Mat4::IDENTITY {
                Ok(VolumeDesc::Constant(rgb(c)))
            } else {
                Ok(VolumeDesc::Grid(constant_grid(rgb(c), to_world)))
            }
        }
        "gridvolume" => Ok(VolumeDesc::Grid(gridvolume(ctx, n, name, r)?)),
        _ => Err(n.err(format!(
            "unknown volume type '{ty}' (supported: gridvolume, constvolume)"
        ))),
    }
}

/// A constant volume over the unit cube mapped by `to_world`: a one-voxel
/// grid, which every lookup (clamped) returns.
pub(crate) fn constant_grid(c: Rgb, to_world: Mat4) -> GridVolumeDesc {
    GridVolumeDesc {
        grid: Arc::new(fgf_io::vol::VolGrid {
            shape: [1, 1, 1],
            channels: 3,
            bbox: [0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            data: c.to_vec(),
        }),
        to_world,
        use_grid_bbox: false,
        filter: GridFilter::Nearest,
        wrap: crate::WrapMode::Clamp,
    }
}

/// Half the side of the box that stands for all of space (a medium that
/// Mitsuba leaves unbounded): far beyond any scene in single precision,
/// and any ray through that much of a medium is extinguished.
const EVERYWHERE: f32 = 1.0e6;

/// A `to_world` that maps the unit cube onto `[-EVERYWHERE, EVERYWHERE]³`.
pub(crate) fn everywhere() -> Mat4 {
    Mat4::from_translation(glam::Vec3::splat(-EVERYWHERE))
        * Mat4::from_scale(glam::Vec3::splat(2.0 * EVERYWHERE))
}

/// The value of a constant volume given as a one-voxel grid (a
/// `constvolume` with a `to_world`), which is the same everywhere.
pub(crate) fn constant_value(g: &GridVolumeDesc) -> Option<Rgb> {
    let d = &g.grid;
    (d.shape == [1, 1, 1]).then(|| match d.channels {
        1 => [d.data[0]; 3],
        _ => [d.data[0], d.data[1], d.data[2]],
    })
}

pub(crate) fn gridvolume(
    ctx: &Ctx,
    n: &XNode,
    name: &str,
    r: Range<f64>,
) -> Result<GridVolumeDesc, SceneError> {
    let p = Props::new(
        n,
        &ctx.ids,
        &[
            "filename",
            "to_world",
            "filter_type",
            "use_grid_bbox",
            "wrap_mode",
            "grid",
        ],
    )?;
    let (file, fnode) = p.string("filename")?.ok_or_else(|| {
        n.err("missing required parameter 'filename' (a Mitsuba .vol file, relative to the scene file)")
    })?;
    let path = fnode.resolve(file);
    let size = fgf_io::check_regular(&path)
        .map_err(|e| {
            fnode.err_kind(
                SceneErrorKind::Io,
                format!("cannot read grid '{}': {e}", path.display()),
            )
        })?
        .len();
    if size > MAX_VOL_BYTES {
        return Err(fnode.err_kind(
            SceneErrorKind::Format,
            format!(
                "grid '{}' is {size} bytes, more than the {MAX_VOL_BYTES}-byte limit",
                path.display()
            ),
        ));
    }
    let io_err = |e: fgf_io::IoError| {
        let kind = match e {
            fgf_io::IoError::Io { .. } => SceneErrorKind::Io,
            fgf_io::IoError::Format { .. } => SceneErrorKind::Format,
        };
        fnode.err_kind(kind, format!("cannot load grid: {e}"))
    };
    let is_vdb = file.to_ascii_lowercase().ends_with(".vdb");
    let grid_name = p.string("grid")?;
    // A `.vdb` grid arrives on the unit cube with the map that places the
    // cube where the file's own index-to-world transform puts its voxels
    // (docs/vdb.md); `to_world` is composed after it.
    let (grid, vdb_to_volume) = if is_vdb {
        let name = grid_name.map_or("density", |(g, _)| g);
        let vdb = fgf_io::vdb::read_float_grid(&path, name).map_err(io_err)?;
        if vdb.background != 0.0 {
            return Err(fnode.err_kind(
                SceneErrorKind::Format,
                format!(
                    "grid '{name}' of '{}' has background {}; a medium needs background 0 (it would fill all of space)",
                    path.display(),
                    vdb.background
                ),
            ));
        }
        let (g, m) = vdb.into_unit_cube_vol();
        (g, Some(DMat4::from_cols_array_2d(&m).transpose()))
    } else {
        if let Some((_, node)) = grid_name {
            return Err(
                node.err("'grid' selects a grid of a .vdb file; this gridvolume reads a .vol file")
            );
        }
        check_vol_size(fnode, &path, size)?;
        (fgf_io::vol::read_vol(&path).map_err(io_err)?, None)
    };
    if grid.channels == 6 {
        return Err(fnode.err_kind(
            SceneErrorKind::Format,
            format!(
                "grid '{}' has 6 channels; '{name}' needs 1 (scalar) or 3 (rgb)",
                path.display()
            ),
        ));
    }
    if let Some(i) = grid.data.iter().position(|&v| !(r.ok)(v as f64)) {
        return Err(fnode.err_kind(
            SceneErrorKind::Format,
            format!(
                "grid '{}' value #{i} = {} is out of range for '{name}' (valid: {})",
                path.display(),
                grid.data[i],
                r.text
            ),
        ));
    }
    let to_world = match (p.transform("to_world")?, vdb_to_volume) {
        (Some((m, node)), None) => to_invertible_mat4(node, m)?,
        (Some((m, node)), Some(v)) => to_invertible_mat4(node, m * v)?,
        (None, Some(v)) => to_invertible_mat4(fnode, v)?,
        (None, None) => Mat4::IDENTITY,
    };
    let filter = match p
        .choice("filter_type", "trilinear", &["trilinear", "nearest"])?
        .as_str()
    {
        "nearest" => GridFilter::Nearest,
        _ => GridFilter::Trilinear,
    };
    let use_grid_bbox = p.bool_or("use_grid_bbox", false)?;
    if use_grid_bbox && is_vdb {
        return Err(fnode.err(
            "use_grid_bbox does not apply to a .vdb file: its own transform places the grid",
        ));
    }
    if use_grid_bbox {
        let b = grid.bbox;
        if !(b[3] > b[0] && b[4] > b[1] && b[5] > b[2]) {
            return Err(fnode.err_kind(
                SceneErrorKind::Format,
                format!(
                    "use_grid_bbox is true but grid '{}' has an empty bounding box [{}, {}, {}] - [{}, {}, {}]",
                    path.display(),
                    b[0], b[1], b[2], b[3], b[4], b[5]
                ),
            ));
        }
    }
    let wrap =
        crate::WrapMode::parse(&p.choice("wrap_mode", "clamp", &["clamp", "repeat", "mirror"])?)
            .unwrap_or(crate::WrapMode::Clamp);
    p.finish()?;
    Ok(GridVolumeDesc {
        grid: Arc::new(grid),
        to_world,
        use_grid_bbox,
        filter,
        wrap,
    })
}

/// Check that the resolution in a `.vol` header matches the file size with
/// overflow-checked arithmetic, before `read_vol` sees the file: a hostile
/// header (say 1e9 x 1e9 x 1e9) must be a clean error, never an overflow.
/// Headers too short or without the magic bytes are left to `read_vol`,
/// which explains them.
fn check_vol_size(fnode: &XNode, path: &std::path::Path, size: u64) -> Result<(), SceneError> {
    use std::io::Read;
    let mut head = [0u8; 24];
    let Ok(mut f) = std::fs::File::open(path) else {
        return Ok(());
    };
    if f.read_exact(&mut head).is_err() || &head[0..3] != b"VOL" {
        return Ok(());
    }
    let dim = |i: usize| i32::from_le_bytes(head[i..i + 4].try_into().expect("4 bytes"));
    let dims = [dim(8), dim(12), dim(16), dim(20)];
    if dims.iter().any(|&d| d <= 0) {
        return Ok(());
    }
    let needed = dims
        .iter()
        .try_fold(4u64, |acc, &d| acc.checked_mul(d as u64))
        .and_then(|n| n.checked_add(48));
    if needed != Some(size) {
        return Err(fnode.err_kind(
            SceneErrorKind::Format,
            format!(
                "invalid .vol file '{}': it is {size} bytes but its header declares a {}x{}x{} grid with {} channel(s), which needs {}",
                path.display(),
                dims[0],
                dims[1],
                dims[2],
                dims[3],
                needed.map(|n| format!("{n} bytes")).unwrap_or_else(|| "more than 2^64 bytes".into())
            ),
        ));
    }
    Ok(())
}
