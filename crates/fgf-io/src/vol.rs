//! Mitsuba 3 `.vol` grid files (little-endian), as checked against Mitsuba 3.9.1:
//!
//! | bytes | content |
//! |---|---|
//! | 0–2 | ASCII `VOL` |
//! | 3 | `u8` version = 3 |
//! | 4–7 | `i32` encoding = 1 (float32) |
//! | 8–19 | `i32` xres, yres, zres |
//! | 20–23 | `i32` channels (1, 3 or 6) |
//! | 24–47 | 6 × `f32` bounding box xmin, ymin, zmin, xmax, ymax, zmax |
//! | 48– | `f32` data, index `((z*yres + y)*xres + x)*channels + c` |
//!
//! In numpy terms the data is a C-order array of shape `(Z, Y, X, C)`.

use crate::{atomic_write, IoError, Result};
use std::io::Write;
use std::path::Path;

const HEADER: usize = 48;

/// A grid as stored in a `.vol` file.
#[derive(Debug, Clone, PartialEq)]
pub struct VolGrid {
    /// Resolution `[xres, yres, zres]`.
    pub shape: [usize; 3],
    /// Channels per voxel: 1, 3 or 6.
    pub channels: usize,
    /// `[xmin, ymin, zmin, xmax, ymax, zmax]`.
    pub bbox: [f32; 6],
    /// `((z*yres + y)*xres + x)*channels + c`.
    pub data: Vec<f32>,
}

impl VolGrid {
    /// Value at voxel `(x, y, z)`, channel `c`.
    #[inline]
    pub fn at(&self, x: usize, y: usize, z: usize, c: usize) -> f32 {
        self.data[((z * self.shape[1] + y) * self.shape[0] + x) * self.channels + c]
    }
}

fn read_i32(b: &[u8], off: usize) -> i32 {
    i32::from_le_bytes(b[off..off + 4].try_into().unwrap())
}
fn read_f32(b: &[u8], off: usize) -> f32 {
    f32::from_le_bytes(b[off..off + 4].try_into().unwrap())
}

/// Parse a `.vol` file from bytes; `path` is only used in error messages.
pub fn parse_vol(path: &Path, b: &[u8]) -> Result<VolGrid> {
    let err = |m: String| IoError::format(path, format!("invalid .vol file: {m}"));
    if b.len() < HEADER {
        return Err(err(format!(
            "file is {} bytes, shorter than the 48-byte header",
            b.len()
        )));
    }
    if &b[0..3] != b"VOL" {
        return Err(err("does not start with the magic bytes 'VOL'".into()));
    }
    if b[3] != 3 {
        return Err(err(format!(
            "version is {}, only version 3 is supported",
            b[3]
        )));
    }
    let enc = read_i32(b, 4);
    if enc != 1 {
        return Err(err(format!(
            "encoding is {enc}, only 1 (float32) is supported"
        )));
    }
    let (nx, ny, nz, nc) = (
        read_i32(b, 8),
        read_i32(b, 12),
        read_i32(b, 16),
        read_i32(b, 20),
    );
    for (n, v) in [("xres", nx), ("yres", ny), ("zres", nz)] {
        if v <= 0 {
            return Err(err(format!("{n} = {v}, must be >= 1")));
        }
    }
    if !matches!(nc, 1 | 3 | 6) {
        return Err(err(format!("channels = {nc}, must be 1, 3 or 6")));
    }
    // Checked products: a hostile header (e.g. 1e9^3 voxels) must give an
    // error, not an overflow.
    let expect = [ny, nz, nc, 4]
        .iter()
        .try_fold(nx as u64, |acc, &v| acc.checked_mul(v as u64))
        .and_then(|n| n.checked_add(HEADER as u64));
    if expect != Some(b.len() as u64) {
        let expect = expect.map_or("more than 2^64".to_string(), |n| n.to_string());
        return Err(err(format!(
            "file is {} bytes but a {nx}x{ny}x{nz} grid with {nc} channel(s) needs {expect}",
            b.len()
        )));
    }
    let mut bbox = [0f32; 6];
    for (i, v) in bbox.iter_mut().enumerate() {
        *v = read_f32(b, 24 + 4 * i);
    }
    // An infinite or NaN box would make the medium vanish without a word.
    if let Some(i) = bbox.iter().position(|v| !v.is_finite()) {
        let name = ["xmin", "ymin", "zmin", "xmax", "ymax", "zmax"][i];
        return Err(err(format!(
            "bounding box {name} = {} is not finite (the box must be finite, min <= max)",
            bbox[i]
        )));
    }
    if let Some(a) = (0..3).find(|&a| bbox[a] > bbox[a + 3]) {
        return Err(err(format!(
            "bounding box has {}min = {} > {}max = {} (need min <= max)",
            ["x", "y", "z"][a],
            bbox[a],
            ["x", "y", "z"][a],
            bbox[a + 3]
        )));
    }
    let data: Vec<f32> = b[HEADER..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        return Err(err(format!("value #{i} is not finite ({})", data[i])));
    }
    Ok(VolGrid {
        shape: [nx as usize, ny as usize, nz as usize],
        channels: nc as usize,
        bbox,
        data,
    })
}

/// Read a `.vol` file.
pub fn read_vol(path: &Path) -> Result<VolGrid> {
    let b = crate::read_regular(path).map_err(|e| IoError::io(path, e))?;
    parse_vol(path, &b)
}

/// Serialise a grid to `.vol` bytes (the exact inverse of [`parse_vol`]).
pub fn encode_vol(grid: &VolGrid, w: &mut impl Write) -> std::io::Result<()> {
    let [nx, ny, nz] = grid.shape;
    assert_eq!(
        grid.data.len(),
        nx * ny * nz * grid.channels,
        "grid data size"
    );
    w.write_all(b"VOL")?;
    w.write_all(&[3u8])?;
    w.write_all(&1i32.to_le_bytes())?;
    for v in [nx, ny, nz, grid.channels] {
        w.write_all(&(v as i32).to_le_bytes())?;
    }
    for v in grid.bbox {
        w.write_all(&v.to_le_bytes())?;
    }
    for v in &grid.data {
        w.write_all(&v.to_le_bytes())?;
    }
    Ok(())
}

/// Write a `.vol` file atomically. Rejects grids whose size does not match
/// their shape or that hold non-finite values.
pub fn write_vol(path: &Path, grid: &VolGrid) -> Result<()> {
    let [nx, ny, nz] = grid.shape;
    if nx == 0 || ny == 0 || nz == 0 || !matches!(grid.channels, 1 | 3 | 6) {
        return Err(IoError::format(
            path,
            format!(
                "cannot write a {nx}x{ny}x{nz} grid with {} channels (need sizes >= 1, channels 1, 3 or 6)",
                grid.channels
            ),
        ));
    }
    if grid.data.len() != nx * ny * nz * grid.channels {
        return Err(IoError::format(
            path,
            "grid data length does not match its shape",
        ));
    }
    if nx > i32::MAX as usize || ny > i32::MAX as usize || nz > i32::MAX as usize {
        return Err(IoError::format(path, "grid resolution does not fit in i32"));
    }
    if grid.data.iter().any(|v| !v.is_finite()) {
        return Err(IoError::format(path, "grid holds non-finite values"));
    }
    atomic_write(path, |w| encode_vol(grid, w).map_err(|e| e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vol_round_trip_preserves_everything() {
        let grid = VolGrid {
            shape: [3, 2, 4],
            channels: 3,
            bbox: [0.0, -1.0, 0.5, 1.0, 2.0, 3.5],
            data: (0..72).map(|i| i as f32 * 0.25 - 3.0).collect(),
        };
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("g.vol");
        write_vol(&p, &grid).unwrap();
        assert_eq!(std::fs::metadata(&p).unwrap().len(), 48 + 4 * 72);
        assert_eq!(read_vol(&p).unwrap(), grid);
        assert_eq!(
            grid.at(2, 1, 3, 1),
            grid.data[((3 * 2 + 1) * 3 + 2) * 3 + 1]
        );
    }

    #[test]
    fn huge_header_is_an_error_not_an_overflow() {
        let mut b = vec![0u8; 48];
        b[0..3].copy_from_slice(b"VOL");
        b[3] = 3;
        b[4..8].copy_from_slice(&1i32.to_le_bytes());
        for off in [8, 12, 16] {
            b[off..off + 4].copy_from_slice(&i32::MAX.to_le_bytes());
        }
        b[20..24].copy_from_slice(&6i32.to_le_bytes());
        let e = parse_vol(Path::new("h.vol"), &b).unwrap_err().to_string();
        assert!(e.contains("2^64"), "{e}");
    }

    #[test]
    fn bad_headers_are_named() {
        let p = Path::new("x.vol");
        let e = parse_vol(p, b"VOL").unwrap_err().to_string();
        assert!(e.contains("x.vol") && e.contains("header"), "{e}");
        let mut b = vec![0u8; 48];
        b[0..3].copy_from_slice(b"VOX");
        assert!(parse_vol(p, &b).unwrap_err().to_string().contains("magic"));
        b[0..3].copy_from_slice(b"VOL");
        b[3] = 3;
        b[4..8].copy_from_slice(&1i32.to_le_bytes());
        b[8..12].copy_from_slice(&(-2i32).to_le_bytes());
        assert!(parse_vol(p, &b)
            .unwrap_err()
            .to_string()
            .contains("xres = -2"));
    }

    #[test]
    fn reference_example_grid_reads() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/reference/density64.vol");
        let g = read_vol(&p).expect("scenes/reference/density64.vol is part of the repository");
        assert_eq!(g.shape, [64, 64, 64]);
        let mean: f64 = g.data.iter().map(|&v| v as f64).sum::<f64>() / g.data.len() as f64;
        assert!((mean - 1.0).abs() < 1e-3, "mean {mean}");
    }
}
