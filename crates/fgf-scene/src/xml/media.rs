//! Media, volumes and phase functions.
//!
//! # Classical media (as in Mitsuba 3.9)
//!
//! | type | parameters (default) |
//! |---|---|
//! | `homogeneous` | `sigma_t` (1; float or rgb, ≥ 0, in 1/length), `albedo` (0.75; float or rgb in [0, 1]), `scale` (1, ≥ 0, multiplies `sigma_t`), `sample_emitters` (true; accepted, no effect on the expected image), nested `phase` (isotropic). |
//! | `heterogeneous` | `sigma_t` and `albedo` as above or a nested `<volume>`, `scale`, `sample_emitters`, `phase`. |
//!
//! Mitsuba 3 has no `sigma_s`/`sigma_a` parameters; they are refused with
//! the conversion `sigma_t = sigma_s + sigma_a`, `albedo = sigma_s / sigma_t`.
//!
//! Volumes: `<volume type="gridvolume" name="sigma_t">` with `filename` (a
//! Mitsuba `.vol` file, 1 or 3 channels, relative to the scene file),
//! `to_world`, `filter_type` (`trilinear` | `nearest`), `use_grid_bbox`
//! (false: the grid spans `[0,1]^3` in volume space), `wrap_mode` (`clamp`
//! only); or `<volume type="constvolume">` with `value` (float or rgb).
//! `sigma_t` grids must be ≥ 0 and `albedo` grids in [0, 1].
//!
//! Phase functions: `isotropic`; `hg` with `g` (0.8, in (-1, 1)).
//!
//! # `fgf`: a fractional-Gaussian-field medium (issue 5)
//!
//! Extinction `σ_t(x) = σ_m + σ_u(x)` where `σ_u` is a zero-mean FGF of
//! Hurst parameter `H` and white-noise strength `S_w` (`theory.md` §1–2).
//! The renderer uses the ensemble-averaged, non-exponential transmittance
//! of `theory.md` §3 (gamma closure) with the kernel chosen by `kernel`
//! (`theory.md` §4).
//!
//! | parameter | meaning | units | valid range | default |
//! |---|---|---|---|---|
//! | `sigma_t` | mean extinction `σ_m` (float or rgb), times `scale` | 1/length | > 0 | 1 |
//! | `albedo` | single-scattering albedo Λ (float or rgb) | – | [0, 1] | 0.75 |
//! | `scale` | multiplies `sigma_t` | – | > 0 | 1 |
//! | `hurst` | Hurst parameter `H`: −0.5 white noise, (−0.5, 0) pink noise, (k−1, k) k-fBm | – | −0.5 ≤ H < 1000, not 0, not an integer | required |
//! | `sw` | white-noise strength `S_w` | length^(−2H−2) (so that `var[σ̄_t]` is in 1/length²) | > 0 | required |
//! | `length` | k-fBm only: characteristic length `L` of the medium (`var[σ̄_t] = S_kf L^(2H)`) | length | > 0; an error on white/pink media | diagonal of the bounding box of the shapes that have this medium as `interior` |
//! | `kernel` | `energy_conserving` (Guo 2019 / Jarabo 2018) or `reciprocal` (Bitterli 2018) | – | – | `energy_conserving` |
//! | `phase` | nested phase function | – | isotropic, hg | isotropic |
//! | `density` | optional nested `<volume type="gridvolume" name="density">` (1 channel, ≥ 0): macro-scale density `ρ(x)`, `σ_m(x) = σ_m ρ(x)` (`theory.md` §4) | – | – | none (uniform) |
//!
//! ```xml
//! <shape type="cube">
//!     <bsdf type="null"/>
//!     <medium type="fgf" name="interior">
//!         <float  name="sigma_t" value="4.0"/>
//!         <rgb    name="albedo"  value="0.8"/>
//!         <float  name="hurst"   value="-0.1"/>   <!-- pink noise -->
//!         <float  name="sw"      value="4.0"/>
//!         <string name="kernel"  value="energy_conserving"/>
//!         <phase type="isotropic"/>
//!     </medium>
//! </shape>
//! ```
//!
//! # `nonexponential`: a named transmittance model
//!
//! The same `sigma_t`, `albedo`, `scale`, `kernel`, `phase` and `density`
//! as `fgf`, and `transmittance` (required) with its own parameters, in
//! optical depth `τ = σ_m t`:
//!
//! | `transmittance` | parameters | `Tr(τ)` |
//! |---|---|---|
//! | `exponential` | – | `exp(−τ)` |
//! | `davis` | `alpha` > 0 | `(1 + τ/α)^(−α)` (Davis power law; `theory.md` §3, k-fBm) |
//! | `davis_weinstein` | `h` in [0.5, 1], `c` > 0 | Davis–Weinstein (Bitterli 2018; `theory.md` §3, pink noise with `h = H+1`) |
//!
//! ```xml
//! <medium type="nonexponential" id="cloud">
//!     <string name="transmittance" value="davis"/>
//!     <float  name="alpha"   value="2.0"/>
//!     <float  name="sigma_t" value="4.0"/>
//!     <string name="kernel"  value="reciprocal"/>
//! </medium>
//! ```
//!
//! From Python and the CLI, both render like any other scene. With
//! `<default name="hurst" value="-0.1"/>` and `value="$hurst"` in the
//! medium, a sweep needs no edit of the file
//! (`fgf render scene.xml -o out.exr -D hurst=0.2` on the command line):
//!
//! ```python
//! import fgf
//! for hurst in ["-0.1", "0.2", "1.2"]:
//!     img = fgf.render("scene.xml", spp=64, seed=0, defines={"hurst": hurst})
//!     # img: (H, W, 3) float32 numpy array, linear RGB
//! ```

use super::document::XNode;
use super::plugins::{check_object_attrs, rgb, to_invertible_mat4, Ctx};
use super::props::{check, Entry, Props};
use crate::desc::*;
use crate::error::{SceneError, SceneErrorKind};
use fgf_core::stats::{Regime, HURST_RANGE};
use fgf_core::transmittance::{Davis, DavisWeinstein, Fgf};
use glam::{DVec3, Mat4};
use std::sync::Arc;

const MEDIA: &[&str] = &["homogeneous", "heterogeneous", "fgf", "nonexponential"];

/// `.vol` files larger than this (4 GiB) are refused before reading.
const MAX_VOL_BYTES: u64 = 1 << 32;

/// A medium reference or nested medium, as an index (shared for the same id).
pub(crate) fn medium_ref<'a>(ctx: &mut Ctx<'a>, e: &Entry<'a>) -> Result<MediumId, SceneError> {
    medium_id(ctx, e.target)
}

pub(crate) fn medium_id<'a>(ctx: &mut Ctx<'a>, n: &'a XNode) -> Result<MediumId, SceneError> {
    let id = n.attr("id");
    if let Some(id) = id {
        if let Some(&i) = ctx.medium_by_id.get(id) {
            return Ok(i);
        }
    }
    let d = medium_desc(ctx, n)?;
    ctx.media.push(d);
    ctx.medium_nodes.push(n);
    let i = ctx.media.len() - 1;
    if let Some(id) = id {
        ctx.medium_by_id.insert(id.to_string(), i);
    }
    Ok(i)
}

fn medium_desc<'a>(ctx: &mut Ctx<'a>, n: &'a XNode) -> Result<MediumDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = n.attr("type").ok_or_else(|| {
        n.err(format!(
            "missing attribute 'type' (supported medium types: {})",
            MEDIA.join(", ")
        ))
    })?;
    let known: &'static [&'static str] = match ty {
        "homogeneous" | "heterogeneous" => &[
            "sigma_t",
            "albedo",
            "scale",
            "sample_emitters",
            "sigma_s",
            "sigma_a",
        ],
        "fgf" => &[
            "sigma_t", "albedo", "scale", "hurst", "sw", "length", "kernel",
        ],
        "nonexponential" => &[
            "sigma_t",
            "albedo",
            "scale",
            "transmittance",
            "alpha",
            "h",
            "c",
            "kernel",
        ],
        _ => {
            return Err(n.err(format!(
                "unknown medium type '{ty}' (supported: {})",
                MEDIA.join(", ")
            )))
        }
    };
    let p = Props::new(n, &ctx.ids, known)?;
    for k in ["sigma_s", "sigma_a"] {
        if let Some(e) = p.take(k) {
            return Err(e.node.err(format!(
                "Mitsuba 3 media take 'sigma_t' and 'albedo', not '{k}': use sigma_t = sigma_s + sigma_a and albedo = sigma_s / sigma_t"
            )));
        }
    }
    let phase = phase_of(ctx, &p)?;
    let scale = p.float_in("scale", 1.0, |v| v >= 0.0, "scale >= 0")?;
    let d = match ty {
        "homogeneous" => {
            let sigma_t = constant_of(ctx, &p, "sigma_t", 1.0, |v| v >= 0.0, ">= 0")?;
            let albedo = constant_of(ctx, &p, "albedo", 0.75, unit, "in [0, 1]")?;
            p.bool_or("sample_emitters", true)?;
            let sigma_t = sigma_t.map(|c| c * scale);
            if sigma_t.iter().any(|&c| c > f32::MAX as f64) {
                return Err(n.err(format!(
                    "sigma_t * scale = {} overflows single precision",
                    sigma_t.iter().cloned().fold(0.0, f64::max)
                )));
            }
            MediumDesc::Homogeneous {
                sigma_t: rgb(sigma_t),
                albedo: rgb(albedo),
                phase,
            }
        }
        "heterogeneous" => {
            let sigma_t = volume_of(ctx, &p, "sigma_t", 1.0, |v| v >= 0.0, ">= 0")?;
            let albedo = volume_of(ctx, &p, "albedo", 0.75, unit, "in [0, 1]")?;
            p.bool_or("sample_emitters", true)?;
            // The renderer's majorants are scale * max(sigma_t): keep them finite.
            let max = match &sigma_t {
                VolumeDesc::Constant(c) => c.iter().cloned().fold(0.0, f32::max),
                VolumeDesc::Grid(g) => g.grid.data.iter().cloned().fold(0.0, f32::max),
            } as f64;
            if max * scale > f32::MAX as f64 {
                return Err(n.err(format!(
                    "scale * max(sigma_t) = {scale} * {max} overflows single precision"
                )));
            }
            MediumDesc::Heterogeneous {
                sigma_t,
                albedo,
                scale: scale as f32,
                phase,
            }
        }
        _ => nonexponential(ctx, n, &p, ty, scale, phase)?,
    };
    p.finish()?;
    Ok(d)
}

fn unit(v: f64) -> bool {
    (0.0..=1.0).contains(&v)
}

/// A float/rgb parameter, or a `constvolume` (Mitsuba's media take volumes).
fn constant_of(
    ctx: &Ctx,
    p: &Props,
    name: &str,
    default: f64,
    ok: impl Fn(f64) -> bool + Copy,
    range: &str,
) -> Result<[f64; 3], SceneError> {
    match volume_of(ctx, p, name, default, ok, range)? {
        VolumeDesc::Constant(c) => Ok(c.map(|x| x as f64)),
        VolumeDesc::Grid(_) => Err(p.node.err(format!(
            "'{name}' of a homogeneous medium must be a constant; use a heterogeneous medium for a grid"
        ))),
    }
}

fn take_named_volume<'a, 'p>(p: &'p Props<'a>, name: &str) -> Option<&'p Entry<'a>> {
    p.take(name).or_else(|| p.take_object_named("volume", name))
}

/// A float/rgb parameter or a nested `<volume name=...>`.
fn volume_of(
    ctx: &Ctx,
    p: &Props,
    name: &str,
    default: f64,
    ok: impl Fn(f64) -> bool + Copy,
    range: &str,
) -> Result<VolumeDesc, SceneError> {
    let Some(e) = take_named_volume(p, name) else {
        return Ok(VolumeDesc::Constant([default as f32; 3]));
    };
    if e.is_property() {
        let c = e.color()?;
        if !c.iter().all(|&v| ok(v)) {
            return Err(e.node.err(format!(
                "invalid {name} = ({}, {}, {}) (valid: each channel {range})",
                c[0], c[1], c[2]
            )));
        }
        return Ok(VolumeDesc::Constant(rgb(c)));
    }
    volume(ctx, e.target, name, ok, range)
}

fn volume(
    ctx: &Ctx,
    n: &XNode,
    name: &str,
    ok: impl Fn(f64) -> bool,
    range: &str,
) -> Result<VolumeDesc, SceneError> {
    check_object_attrs(n)?;
    let ty = n.attr("type").unwrap_or("");
    match ty {
        "constvolume" => {
            let p = Props::new(n, &ctx.ids, &["value"])?;
            let c = p.color_in("value", [1.0; 3], ok, range)?;
            p.finish()?;
            Ok(VolumeDesc::Constant(rgb(c)))
        }
        "gridvolume" => Ok(VolumeDesc::Grid(gridvolume(ctx, n, name, ok, range)?)),
        _ => Err(n.err(format!(
            "unknown volume type '{ty}' (supported: gridvolume, constvolume)"
        ))),
    }
}

fn gridvolume(
    ctx: &Ctx,
    n: &XNode,
    name: &str,
    ok: impl Fn(f64) -> bool,
    range: &str,
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
        ],
    )?;
    let (file, fnode) = p.string("filename")?.ok_or_else(|| {
        n.err("missing required parameter 'filename' (a Mitsuba .vol file, relative to the scene file)")
    })?;
    let path = fnode.resolve(file);
    let size = std::fs::metadata(&path)
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
    check_vol_size(fnode, &path, size)?;
    let grid = fgf_io::vol::read_vol(&path).map_err(|e| {
        let kind = match e {
            fgf_io::IoError::Io { .. } => SceneErrorKind::Io,
            fgf_io::IoError::Format { .. } => SceneErrorKind::Format,
        };
        fnode.err_kind(kind, format!("cannot load grid: {e}"))
    })?;
    if grid.channels == 6 {
        return Err(fnode.err_kind(
            SceneErrorKind::Format,
            format!(
                "grid '{}' has 6 channels; '{name}' needs 1 (scalar) or 3 (rgb)",
                path.display()
            ),
        ));
    }
    if let Some(i) = grid.data.iter().position(|&v| !ok(v as f64)) {
        return Err(fnode.err_kind(
            SceneErrorKind::Format,
            format!(
                "grid '{}' value #{i} = {} is out of range for '{name}' (valid: {range})",
                path.display(),
                grid.data[i]
            ),
        ));
    }
    let to_world = match p.transform("to_world")? {
        Some((m, node)) => to_invertible_mat4(node, m)?,
        None => Mat4::IDENTITY,
    };
    let filter = match p
        .choice("filter_type", "trilinear", &["trilinear", "nearest"])?
        .as_str()
    {
        "nearest" => GridFilter::Nearest,
        _ => GridFilter::Trilinear,
    };
    let use_grid_bbox = p.bool_or("use_grid_bbox", false)?;
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
    if let Some((w, node)) = p.string("wrap_mode")? {
        if w != "clamp" {
            return Err(node.err(format!("wrap_mode '{w}' is not supported (valid: clamp)")));
        }
    }
    p.finish()?;
    Ok(GridVolumeDesc {
        grid: Arc::new(grid),
        to_world,
        use_grid_bbox,
        filter,
        wrap_clamp: true,
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

fn phase_of(ctx: &Ctx, p: &Props) -> Result<PhaseDesc, SceneError> {
    let phases = p.take_objects("phase");
    if phases.len() > 1 {
        return Err(phases[1].node.err("a medium takes one phase function"));
    }
    let Some(e) = phases.first() else {
        return Ok(PhaseDesc::Isotropic);
    };
    let n = e.target;
    check_object_attrs(n)?;
    let ty = n.attr("type").unwrap_or("");
    let known: &'static [&'static str] = match ty {
        "isotropic" => &[],
        "hg" => &["g"],
        _ => {
            return Err(n.err(format!(
                "unknown phase function type '{ty}' (supported: isotropic, hg)"
            )))
        }
    };
    let q = Props::new(n, &ctx.ids, known)?;
    let d = if ty == "hg" {
        PhaseDesc::Hg {
            g: q.float_in("g", 0.8, |g| g > -1.0 && g < 1.0, "-1 < g < 1")? as f32,
        }
    } else {
        PhaseDesc::Isotropic
    };
    q.finish()?;
    Ok(d)
}

fn is_kfbm(hurst: f64) -> bool {
    matches!(Regime::from_hurst(hurst), Ok(Regime::KFbm { .. }))
}

fn nonexponential<'a>(
    ctx: &Ctx<'a>,
    n: &'a XNode,
    p: &Props<'a>,
    ty: &str,
    scale: f64,
    phase: PhaseDesc,
) -> Result<MediumDesc, SceneError> {
    let pos = |v: f64| v > 0.0;
    let sigma_m = match p.color("sigma_t")? {
        None => [1.0; 3],
        Some((c, node)) => {
            if !c.iter().all(|&v| v > 0.0) {
                return Err(node.err(format!(
                    "invalid sigma_t = ({}, {}, {}) (valid: each channel > 0; it is the mean extinction σ_m)",
                    c[0], c[1], c[2]
                )));
            }
            c
        }
    };
    if scale <= 0.0 {
        return Err(n.err(format!(
            "invalid scale = {scale} (valid: scale > 0 for a non-exponential medium)"
        )));
    }
    let sigma_t = sigma_m.map(|c| c * scale);
    if !sigma_t
        .iter()
        .all(|c| (c * c).is_finite() && *c as f32 > 0.0)
    {
        return Err(n.err("sigma_t * scale is outside the representable range"));
    }
    let albedo = p.color_in("albedo", [0.75; 3], unit, "in [0, 1]")?;
    let kernel = match p
        .choice(
            "kernel",
            "energy_conserving",
            &["energy_conserving", "reciprocal"],
        )?
        .as_str()
    {
        "reciprocal" => KernelDesc::Reciprocal,
        _ => KernelDesc::EnergyConserving,
    };
    let model = if ty == "fgf" {
        let hurst = match p.float("hurst")? {
            None => {
                return Err(n.err(format!(
                    "missing required parameter 'hurst' (valid: {HURST_RANGE})"
                )))
            }
            Some((h, node)) => {
                Regime::from_hurst(h).map_err(|e| node.err(e.to_string()))?;
                h
            }
        };
        let sw = p.float_req("sw", pos, "sw > 0")?;
        let length =
            match p.float("length")? {
                None => None,
                Some((l, node)) => {
                    if !is_kfbm(hurst) {
                        return Err(node.err(format!(
                        "'length' only applies to k-fBm media (hurst > 0); hurst = {hurst} is {}",
                        if hurst == -0.5 { "white noise" } else { "pink noise" }
                    )));
                    }
                    Some(check(node, "length", l, l > 0.0, "length > 0")?)
                }
            };
        TransmittanceDesc::Fgf { hurst, sw, length }
    } else {
        let (t, tnode) = p.string("transmittance")?.ok_or_else(|| {
            n.err("missing required parameter 'transmittance' (valid: exponential, davis, davis_weinstein)")
        })?;
        let model = match t {
            "exponential" => TransmittanceDesc::Exponential,
            "davis" => TransmittanceDesc::Davis {
                alpha: p.float_req("alpha", pos, "alpha > 0")?,
            },
            "davis_weinstein" => TransmittanceDesc::DavisWeinstein {
                h: p.float_req("h", |h| (0.5..=1.0).contains(&h), "0.5 <= h <= 1")?,
                c: p.float_req("c", pos, "c > 0")?,
            },
            _ => {
                return Err(tnode.err(format!(
                    "unknown transmittance '{t}' (valid: exponential, davis, davis_weinstein)"
                )))
            }
        };
        // Parameters of the other models are errors, not silently ignored.
        for k in ["alpha", "h", "c"] {
            if let Some(e) = p.take(k) {
                return Err(e.node.err(format!(
                    "parameter '{k}' does not apply to transmittance '{t}' (davis: alpha; davis_weinstein: h, c; exponential: none)"
                )));
            }
        }
        model
    };
    let density = match p.take_object_named("volume", "density") {
        None => None,
        Some(e) => {
            let t = e.target;
            if t.attr("type") != Some("gridvolume") {
                return Err(e
                    .node
                    .err("'density' must be a <volume type=\"gridvolume\">"));
            }
            let g = gridvolume(ctx, t, "density", |v| v >= 0.0, ">= 0")?;
            if g.grid.channels != 1 {
                return Err(e.node.err(format!(
                    "'density' grid must have 1 channel (it has {})",
                    g.grid.channels
                )));
            }
            Some(g)
        }
    };
    Ok(MediumDesc::NonExponential {
        sigma_t: rgb(sigma_t),
        albedo: rgb(albedo),
        phase,
        model,
        kernel,
        density,
    })
}

/// Fill in the default `length` of k-fBm `fgf` media: the diagonal of the
/// bounding box of the shapes that have the medium as interior.
pub(crate) fn resolve_default_lengths(
    ctx: &mut Ctx,
    shapes: &[ShapeDesc],
) -> Result<(), SceneError> {
    for i in 0..ctx.media.len() {
        let MediumDesc::NonExponential {
            model: TransmittanceDesc::Fgf { hurst, length, .. },
            ..
        } = &mut ctx.media[i]
        else {
            continue;
        };
        if length.is_some() || !is_kfbm(*hurst) {
            continue;
        }
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for s in shapes.iter().filter(|s| s.interior == Some(i)) {
            let (a, b) = s.world_bbox();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        let diag = (hi - lo).length();
        if !(diag.is_finite() && diag > 0.0) {
            return Err(ctx.medium_nodes[i].err(format!(
                "this k-fBm medium (hurst = {hurst}) needs a 'length': it is the interior of no shape, so the default (the diagonal of its shapes' bounding box) is undefined"
            )));
        }
        *length = Some(diag);
    }
    // Whole-model validation by the physics crate's constructors, per colour
    // channel (each channel has its own mean extinction σ_m).
    for (m, node) in ctx.media.iter().zip(&ctx.medium_nodes) {
        let MediumDesc::NonExponential { sigma_t, model, .. } = m else {
            continue;
        };
        for &s in sigma_t {
            let s = s as f64;
            let r = match *model {
                TransmittanceDesc::Fgf { hurst, sw, length } => {
                    Fgf::new(s, hurst, sw, length).map(|_| ())
                }
                TransmittanceDesc::Davis { alpha } => Davis::new(s, alpha).map(|_| ()),
                TransmittanceDesc::DavisWeinstein { h, c } => {
                    DavisWeinstein::new(s, h, c).map(|_| ())
                }
                TransmittanceDesc::Exponential => Ok(()),
            };
            r.map_err(|e| node.err(e.to_string()))?;
        }
    }
    Ok(())
}
