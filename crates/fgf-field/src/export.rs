//! Writing fields to files, the format chosen by the extension. Every writer
//! is atomic (`fgf_io::atomic_write`): a failed write leaves no file.
//!
//! | extension | dims | content |
//! |---|---|---|
//! | `.npy` | 1–3 | numpy array, the field's dtype (`<f4`/`<f8`), C order, shape as given |
//! | `.vol` | 1–3 | Mitsuba 3 `gridvolume` (`fgf_io::vol`, layout in `formats.md`), 1 channel float32; missing axes have length 1; bbox `[0, 0, 0]`–`[nx dx, ny dx, nz dx]` |
//! | `.exr` | 2 | float32 single channel `Y`, array row 0 at the top |
//! | `.png` | 2 | 8-bit greyscale preview, array row 0 at the top |
//!
//! Before writing, values are mapped to a density
//! `v = max(clamp_min, mean + scale · f)` ([`Density`]; the identity by
//! default), so that a zero-mean field can feed a renderer's `sigma_t`.
//!
//! **PNG normalisation** is robust to outliers: the `lo` and `hi`
//! percentiles (default 0.5 and 99.5) of the mapped values map linearly to
//! grey levels 0 and 255, values beyond are clipped. Codes are linear in the
//! value (a data view, no sRGB curve). A constant field is written mid-grey.
//! A 3D field cannot be written as PNG or EXR (an error; slice it first).

use crate::synth::{Field, FieldData};
use fgf_core::ParamError;
use fgf_io::IoError;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Output formats, chosen by the file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Npy,
    Vol,
    Exr,
    Png,
}

/// Errors of [`write_field`].
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error(transparent)]
    Io(#[from] IoError),
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The request cannot be written in that format (unknown extension,
    /// a 3D field to PNG, ...).
    #[error("{path}: {msg}")]
    Unsupported { path: PathBuf, msg: String },
}

impl Format {
    /// The format of `path` from its extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Format, ExportError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("npy") => Ok(Format::Npy),
            Some("vol") => Ok(Format::Vol),
            Some("exr") => Ok(Format::Exr),
            Some("png") => Ok(Format::Png),
            other => Err(ExportError::Unsupported {
                path: path.to_path_buf(),
                msg: format!(
                    "unknown output extension {}; use .npy, .vol (Mitsuba 3 grid), .exr or .png (2D only)",
                    other.map(|e| format!("'.{e}'")).unwrap_or_else(|| "(none)".into())
                ),
            }),
        }
    }
}

/// `v = max(clamp_min, mean + scale · f)`; the default is the identity.
#[derive(Debug, Clone, PartialEq)]
pub struct Density {
    pub mean: f64,
    pub scale: f64,
    pub clamp_min: Option<f64>,
}

impl Default for Density {
    fn default() -> Self {
        Density {
            mean: 0.0,
            scale: 1.0,
            clamp_min: None,
        }
    }
}

impl Density {
    fn validate(&self) -> Result<(), ParamError> {
        if !self.mean.is_finite() {
            return Err(ParamError::new(
                "mean",
                self.mean,
                "must be finite",
                "finite",
            ));
        }
        if !self.scale.is_finite() {
            return Err(ParamError::new(
                "scale",
                self.scale,
                "must be finite",
                "finite",
            ));
        }
        if let Some(c) = self.clamp_min {
            if !c.is_finite() {
                return Err(ParamError::new("clamp_min", c, "must be finite", "finite"));
            }
        }
        Ok(())
    }

    #[inline]
    pub fn map(&self, f: f64) -> f64 {
        let v = self.mean + self.scale * f;
        match self.clamp_min {
            Some(c) => v.max(c),
            None => v,
        }
    }
}

/// Options of [`write_field`].
#[derive(Debug, Clone, PartialEq)]
pub struct ExportOptions {
    pub density: Density,
    /// Percentiles mapped to black and white in PNG output (0–100, lo < hi).
    pub png_percentiles: (f64, f64),
}

impl Default for ExportOptions {
    fn default() -> Self {
        ExportOptions {
            density: Density::default(),
            png_percentiles: (0.5, 99.5),
        }
    }
}

/// A borrowed field of either precision.
#[derive(Debug, Clone, Copy)]
pub enum FieldView<'a> {
    F32(&'a [f32]),
    F64(&'a [f64]),
}

impl<'a> From<&'a FieldData> for FieldView<'a> {
    fn from(d: &'a FieldData) -> Self {
        match d {
            FieldData::F32(v) => FieldView::F32(v),
            FieldData::F64(v) => FieldView::F64(v),
        }
    }
}

impl FieldView<'_> {
    fn len(&self) -> usize {
        match self {
            FieldView::F32(v) => v.len(),
            FieldView::F64(v) => v.len(),
        }
    }
    #[inline]
    fn get(&self, i: usize) -> f64 {
        match self {
            FieldView::F32(v) => v[i] as f64,
            FieldView::F64(v) => v[i],
        }
    }
}

/// What was written, for front ends that want to warn (e.g. about negative
/// densities in a `.vol`).
#[derive(Debug, Clone, PartialEq)]
pub struct ExportSummary {
    pub format: Format,
    /// Range of the mapped values.
    pub min: f64,
    pub max: f64,
    /// Number of mapped values below 0.
    pub n_negative: usize,
}

/// Write `field` to `path` (format from the extension, see module docs).
pub fn write(
    path: &Path,
    field: &Field,
    opts: &ExportOptions,
) -> Result<ExportSummary, ExportError> {
    write_field(
        path,
        (&field.data).into(),
        &field.shape,
        field.spacing,
        opts,
    )
}

/// Write C-order `data` of `shape` with grid `spacing` to `path`.
pub fn write_field(
    path: &Path,
    data: FieldView<'_>,
    shape: &[usize],
    spacing: f64,
    opts: &ExportOptions,
) -> Result<ExportSummary, ExportError> {
    let format = Format::from_path(path)?;
    let unsupported = |msg: String| ExportError::Unsupported {
        path: path.to_path_buf(),
        msg,
    };
    if shape.is_empty()
        || shape.len() > 3
        || shape.iter().product::<usize>() != data.len()
        || data.len() == 0
    {
        return Err(unsupported(format!(
            "shape {shape:?} does not describe {} values",
            data.len()
        )));
    }
    ParamError::check_positive("spacing", spacing)?;
    opts.density.validate()?;
    let d = shape.len();
    if matches!(format, Format::Png | Format::Exr) && d != 2 {
        return Err(unsupported(format!(
            "{} output needs a 2D field, this one is {d}D (shape {shape:?}); use .npy or .vol, or pass a 2D slice",
            if format == Format::Png { "PNG" } else { "EXR" }
        )));
    }
    let mapped: Vec<f64> = (0..data.len())
        .map(|i| opts.density.map(data.get(i)))
        .collect();
    if let Some(i) = mapped.iter().position(|v| !v.is_finite()) {
        return Err(unsupported(format!(
            "value #{i} is not finite ({})",
            mapped[i]
        )));
    }
    let summary = ExportSummary {
        format,
        min: mapped.iter().copied().fold(f64::INFINITY, f64::min),
        max: mapped.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        n_negative: mapped.iter().filter(|&&v| v < 0.0).count(),
    };
    let as_f32 = || mapped.iter().map(|&v| v as f32).collect::<Vec<f32>>();
    match format {
        Format::Npy => {
            // Keep the field's precision. The identity mapping 0 + 1·f is
            // exact, and f32 -> f64 -> f32 round-trips, so unmapped data is
            // written bit for bit.
            let f64_out = matches!(data, FieldView::F64(_));
            write_npy(path, shape, f64_out, |w| {
                for &v in &mapped {
                    if f64_out {
                        w.write_all(&v.to_le_bytes())?;
                    } else {
                        w.write_all(&(v as f32).to_le_bytes())?;
                    }
                }
                Ok(())
            })?;
        }
        Format::Vol => {
            let mut s = [1usize; 3];
            s[3 - d..].copy_from_slice(shape);
            let [nz, ny, nx] = s;
            let grid = fgf_io::vol::VolGrid {
                shape: [nx, ny, nz],
                channels: 1,
                bbox: [
                    0.0,
                    0.0,
                    0.0,
                    (nx as f64 * spacing) as f32,
                    (ny as f64 * spacing) as f32,
                    (nz as f64 * spacing) as f32,
                ],
                data: as_f32(),
            };
            fgf_io::vol::write_vol(path, &grid)?;
        }
        Format::Exr => fgf_io::image::write_exr(path, shape[1], shape[0], 1, &as_f32())?,
        Format::Png => {
            let (lo_p, hi_p) = opts.png_percentiles;
            if !(0.0..=100.0).contains(&lo_p) || !(0.0..=100.0).contains(&hi_p) || lo_p >= hi_p {
                return Err(ParamError::new(
                    "png_percentiles",
                    format!("({lo_p}, {hi_p})"),
                    "must be two percentiles lo < hi",
                    "0 <= lo < hi <= 100",
                )
                .into());
            }
            let (lo, hi) = (percentile(&mapped, lo_p), percentile(&mapped, hi_p));
            let grey: Vec<u8> = mapped
                .iter()
                .map(|&v| {
                    if hi > lo {
                        ((v - lo) / (hi - lo) * 255.0).round().clamp(0.0, 255.0) as u8
                    } else {
                        128
                    }
                })
                .collect();
            fgf_io::image::write_png8(path, shape[1], shape[0], 1, &grey)?;
        }
    }
    Ok(summary)
}

/// The `p`-th percentile (0–100) with linear interpolation between order
/// statistics (numpy's default method).
pub fn percentile(values: &[f64], p: f64) -> f64 {
    let mut v = values.to_vec();
    let pos = p / 100.0 * (v.len() - 1) as f64;
    let i = pos.floor() as usize;
    let frac = pos - i as f64;
    let (_, &mut a, rest) = v.select_nth_unstable_by(i, |x, y| x.total_cmp(y));
    if frac == 0.0 || rest.is_empty() {
        return a;
    }
    let b = rest.iter().copied().fold(f64::INFINITY, f64::min);
    a + frac * (b - a)
}

/// Write a version-1.0 `.npy` file: magic, header dict padded with spaces to
/// a multiple of 64 bytes (ending in a newline), then little-endian data.
fn write_npy<F>(path: &Path, shape: &[usize], f64_out: bool, body: F) -> Result<(), IoError>
where
    F: Fn(&mut std::io::BufWriter<&std::fs::File>) -> std::io::Result<()>,
{
    let dims = shape
        .iter()
        .map(|n| n.to_string())
        .collect::<Vec<_>>()
        .join(", ");
    let shape_str = if shape.len() == 1 {
        format!("({dims},)")
    } else {
        format!("({dims})")
    };
    let mut header = format!(
        "{{'descr': '{}', 'fortran_order': False, 'shape': {shape_str}, }}",
        if f64_out { "<f8" } else { "<f4" }
    );
    let total = 10 + header.len() + 1;
    header.push_str(&" ".repeat(total.div_ceil(64) * 64 - total));
    header.push('\n');
    fgf_io::atomic_write(path, |w| {
        w.write_all(b"\x93NUMPY\x01\x00")
            .map_err(|e| e.to_string())?;
        w.write_all(&(header.len() as u16).to_le_bytes())
            .map_err(|e| e.to_string())?;
        w.write_all(header.as_bytes()).map_err(|e| e.to_string())?;
        body(w).map_err(|e| e.to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_from_extension() {
        assert_eq!(
            Format::from_path(Path::new("a/b.VOL")).unwrap(),
            Format::Vol
        );
        let e = Format::from_path(Path::new("f.tiff"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("f.tiff") && e.contains(".tiff") && e.contains(".npy"),
            "{e}"
        );
        assert!(Format::from_path(Path::new("f")).is_err());
    }

    #[test]
    fn vol_round_trip_with_density_mapping() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.vol");
        let data: Vec<f32> = (0..24).map(|i| i as f32 - 10.0).collect();
        let opts = ExportOptions {
            density: Density {
                mean: 2.0,
                scale: 0.5,
                clamp_min: Some(0.0),
            },
            ..Default::default()
        };
        let s = write_field(&p, FieldView::F32(&data), &[2, 3, 4], 0.25, &opts).unwrap();
        assert_eq!(s.n_negative, 0);
        let g = fgf_io::vol::read_vol(&p).unwrap();
        assert_eq!(g.shape, [4, 3, 2]);
        assert_eq!(g.bbox, [0.0, 0.0, 0.0, 1.0, 0.75, 0.5]);
        for (i, v) in g.data.iter().enumerate() {
            assert_eq!(*v, (2.0 + 0.5 * data[i]).max(0.0));
        }
    }

    #[test]
    fn three_d_png_is_refused_and_leaves_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.png");
        let e = write_field(
            &p,
            FieldView::F32(&[0.0; 8]),
            &[2, 2, 2],
            1.0,
            &ExportOptions::default(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("2D"), "{e}");
        assert!(!p.exists());
    }

    #[test]
    fn npy_header_is_aligned() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.npy");
        write_field(
            &p,
            FieldView::F64(&[1.0, 2.0, 3.0]),
            &[3],
            1.0,
            &ExportOptions::default(),
        )
        .unwrap();
        let b = std::fs::read(&p).unwrap();
        let hl = u16::from_le_bytes([b[8], b[9]]) as usize;
        assert_eq!((10 + hl) % 64, 0);
        assert_eq!(b.len(), 10 + hl + 24);
        assert!(std::str::from_utf8(&b[10..10 + hl])
            .unwrap()
            .contains("'shape': (3,)"));
        assert_eq!(
            f64::from_le_bytes(b[10 + hl + 8..10 + hl + 16].try_into().unwrap()),
            2.0
        );
    }

    #[test]
    fn percentile_matches_numpy_linear() {
        let v = [3.0, 1.0, 4.0, 1.0, 5.0];
        assert_eq!(percentile(&v, 0.0), 1.0);
        assert_eq!(percentile(&v, 100.0), 5.0);
        assert_eq!(percentile(&v, 50.0), 3.0);
        assert!((percentile(&v, 90.0) - 4.6).abs() < 1e-12);
    }
}
