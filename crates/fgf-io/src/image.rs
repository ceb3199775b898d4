//! Image output: linear float32 EXR (scanline layout, readable by every
//! viewer and by Mitsuba's `Bitmap`) and 8-bit PNG previews
//! (exposure, then clamp, then the sRGB transfer curve). Input: EXR,
//! Radiance HDR and PNG to RGB floats, for `envmap` and `bitmap`, each
//! refusing more than [`MAX_IMAGE_PIXELS`] before allocating.
//!
//! Pixel buffers are row-major from the top-left corner, interleaved
//! channels: index `(y * width + x) * channels + c`.

use crate::{atomic_write, IoError, Result};
use std::path::Path;

fn check_buffer(
    path: &Path,
    width: usize,
    height: usize,
    channels: usize,
    len: usize,
) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(IoError::format(
            path,
            format!("cannot write a {width}x{height} image"),
        ));
    }
    if len != width * height * channels {
        return Err(IoError::format(
            path,
            format!(
                "buffer has {len} values, a {width}x{height}x{channels} image needs {}",
                width * height * channels
            ),
        ));
    }
    Ok(())
}

/// Write a linear float32 EXR with channels `R,G,B` (`channels == 3`) or a
/// single channel `Y` (`channels == 1`), atomically.
pub fn write_exr(
    path: &Path,
    width: usize,
    height: usize,
    channels: usize,
    data: &[f32],
) -> Result<()> {
    use exr::prelude::*;
    check_buffer(path, width, height, channels, data.len())?;
    let encoding = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let size = (width, height);
    atomic_write(path, |w| {
        let result = match channels {
            3 => {
                let layer = Layer::new(
                    size,
                    LayerAttributes::default(),
                    encoding,
                    SpecificChannels::rgb(|p: Vec2<usize>| {
                        let i = (p.y() * width + p.x()) * 3;
                        (data[i], data[i + 1], data[i + 2])
                    }),
                );
                Image::from_layer(layer).write().to_buffered(w)
            }
            1 => {
                let layer = Layer::new(
                    size,
                    LayerAttributes::default(),
                    encoding,
                    SpecificChannels::build()
                        .with_channel("Y")
                        .with_pixel_fn(|p: Vec2<usize>| (data[p.y() * width + p.x()],)),
                );
                Image::from_layer(layer).write().to_buffered(w)
            }
            c => return Err(format!("EXR output supports 1 or 3 channels, not {c}")),
        };
        result.map_err(|e| e.to_string())
    })
}

/// The largest image the readers accept, in pixels (2^25: 384 MiB of RGB
/// floats). A file's header declaring more is refused before any pixel
/// buffer is allocated.
pub const MAX_IMAGE_PIXELS: usize = 1 << 25;

fn check_image_size(path: &Path, width: usize, height: usize) -> Result<()> {
    match width.checked_mul(height) {
        Some(n) if n > 0 && n <= MAX_IMAGE_PIXELS => Ok(()),
        _ => Err(IoError::format(
            path,
            format!(
                "image of {width}x{height} pixels: valid sizes have 1 to {MAX_IMAGE_PIXELS} pixels"
            ),
        )),
    }
}

/// Read an RGB(A) EXR into `(width, height, rgb data)` (linear floats, rows
/// from the top); used by the `envmap` and `bitmap` plugins, by tests and
/// by users comparing images. Its declared size is checked against
/// [`MAX_IMAGE_PIXELS`] before the pixels are read.
pub fn read_exr_rgb(path: &Path) -> Result<(usize, usize, Vec<f32>)> {
    use exr::prelude::*;
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| IoError::format(path, e.to_string()))?;
    for h in meta.headers.iter() {
        check_image_size(path, h.layer_size.width(), h.layer_size.height())?;
    }
    let image = read_first_rgba_layer_from_file(
        path,
        |res: Vec2<usize>, _| (res.width(), vec![0f32; res.width() * res.height() * 3]),
        |(w, buf): &mut (usize, Vec<f32>), p: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            let i = (p.y() * *w + p.x()) * 3;
            buf[i] = r;
            buf[i + 1] = g;
            buf[i + 2] = b;
        },
    )
    .map_err(|e| IoError::format(path, e.to_string()))?;
    let size = image.layer_data.size;
    let (_, buf) = image.layer_data.channel_data.pixels;
    Ok((size.width(), size.height(), buf))
}

/// The sRGB transfer curve applied to a linear value already clamped to `[0, 1]`.
#[inline]
pub fn srgb_encode(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear values to 8-bit sRGB: `v * 2^exposure`, clamp to `[0, 1]`, encode.
/// NaN maps to 0.
pub fn to_srgb8(data: &[f32], exposure: f32) -> Vec<u8> {
    let scale = exposure.exp2();
    data.iter()
        .map(|&v| {
            let v = (v * scale).clamp(0.0, 1.0);
            let v = if v.is_nan() { 0.0 } else { v };
            (srgb_encode(v) * 255.0 + 0.5) as u8
        })
        .collect()
}

/// Write 8-bit PNG (`channels` 1 = grey, 3 = RGB) atomically; `data` is
/// already encoded.
pub fn write_png8(
    path: &Path,
    width: usize,
    height: usize,
    channels: usize,
    data: &[u8],
) -> Result<()> {
    check_buffer(path, width, height, channels, data.len())?;
    let color = match channels {
        1 => png::ColorType::Grayscale,
        3 => png::ColorType::Rgb,
        c => {
            return Err(IoError::format(
                path,
                format!("PNG output supports 1 or 3 channels, not {c}"),
            ))
        }
    };
    atomic_write(path, |w| {
        let mut enc = png::Encoder::new(w, width as u32, height as u32);
        enc.set_color(color);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(|e| e.to_string())?;
        writer.write_image_data(data).map_err(|e| e.to_string())?;
        writer.finish().map_err(|e| e.to_string())
    })
}

/// Write a linear image as an sRGB PNG preview (exposure in stops).
pub fn write_png_preview(
    path: &Path,
    width: usize,
    height: usize,
    channels: usize,
    data: &[f32],
    exposure: f32,
) -> Result<()> {
    check_buffer(path, width, height, channels, data.len())?;
    write_png8(path, width, height, channels, &to_srgb8(data, exposure))
}

/// Read a PNG (grey, grey-alpha, RGB, RGBA, palette; 1 to 16 bits) into
/// `(width, height, rgb data)` with values in [0, 1] as stored (still
/// encoded by the file's transfer curve: the caller decides whether to
/// linearise), and the file's bit depth after expansion (8 or 16: palette and
/// 1/2/4-bit grey images expand to 8). Alpha is dropped. gAMA, sRGB, cHRM and
/// iCCP chunks are not applied (as in Mitsuba, which treats every PNG as
/// sRGB-encoded). The size is checked against [`MAX_IMAGE_PIXELS`] before
/// the pixels are read.
pub fn read_png_rgb(path: &Path) -> Result<(usize, usize, Vec<f32>, u8)> {
    let fmt = |e: png::DecodingError| IoError::format(path, format!("not a readable PNG: {e}"));
    let file = crate::read_regular(path).map_err(|e| IoError::format(path, e.to_string()))?;
    let limits = png::Limits {
        bytes: MAX_IMAGE_PIXELS * 8,
    };
    let mut dec = png::Decoder::new_with_limits(std::io::Cursor::new(&file[..]), limits);
    dec.set_transformations(png::Transformations::EXPAND);
    let mut reader = dec.read_info().map_err(fmt)?;
    let (w, h) = {
        let info = reader.info();
        (info.width as usize, info.height as usize)
    };
    check_image_size(path, w, h)?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| IoError::format(path, "PNG too large"))?;
    let mut buf = vec![0u8; size];
    let out = reader.next_frame(&mut buf).map_err(fmt)?;
    let channels = out.color_type.samples();
    let sixteen = out.bit_depth == png::BitDepth::Sixteen;
    let (max, bytes) = if sixteen { (65535.0, 2) } else { (255.0, 1) };
    let line = out.line_size;
    let mut data = Vec::with_capacity(w * h * 3);
    for y in 0..h {
        let row = &buf[y * line..];
        for x in 0..w {
            let sample = |c: usize| -> f32 {
                let i = (x * channels + c) * bytes;
                let v = if sixteen {
                    u16::from_be_bytes([row[i], row[i + 1]]) as f32
                } else {
                    row[i] as f32
                };
                v / max
            };
            if channels >= 3 {
                data.extend([sample(0), sample(1), sample(2)]);
            } else {
                let g = sample(0);
                data.extend([g, g, g]);
            }
        }
    }
    Ok((w, h, data, if sixteen { 16 } else { 8 }))
}

/// The sRGB transfer curve inverted: an encoded value in [0, 1] to linear.
#[inline]
pub fn srgb_decode(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Read a Radiance `.hdr` (RGBE) image: flat or new-style run-length
/// encoded scanlines, `-Y h +X w` orientation (the common one). Returns
/// `(width, height, rgb)` with rows from the top, linear floats.
pub fn read_hdr_rgb(path: &Path) -> Result<(usize, usize, Vec<f32>)> {
    let bytes = std::fs::read(path).map_err(|e| IoError::format(path, e.to_string()))?;
    let bad = |m: &str| IoError::format(path, format!("not a Radiance RGBE image: {m}"));
    if !(bytes.starts_with(b"#?RADIANCE") || bytes.starts_with(b"#?RGBE")) {
        return Err(bad("missing '#?RADIANCE' header"));
    }
    // Header lines up to an empty line, then the resolution line.
    let mut pos = 0usize;
    let mut line = || -> Option<&[u8]> {
        let start = pos;
        let end = start + bytes[start..].iter().position(|&c| c == b'\n')?;
        pos = end + 1;
        Some(&bytes[start..end])
    };
    loop {
        let l = line().ok_or_else(|| bad("truncated header"))?;
        if l.is_empty() {
            break;
        }
        if let Some(f) = l.strip_prefix(b"FORMAT=") {
            if f != b"32-bit_rle_rgbe" {
                return Err(bad("only FORMAT=32-bit_rle_rgbe is supported"));
            }
        }
    }
    let res = line().ok_or_else(|| bad("missing resolution line"))?;
    let res = std::str::from_utf8(res).map_err(|_| bad("bad resolution line"))?;
    let f: Vec<&str> = res.split_whitespace().collect();
    if f.len() != 4 || f[0] != "-Y" || f[2] != "+X" {
        return Err(bad(
            "only the '-Y height +X width' orientation is supported",
        ));
    }
    let (h, w): (usize, usize) = match (f[1].parse(), f[3].parse()) {
        (Ok(h), Ok(w)) if h > 0 && w > 0 && h <= 1 << 15 && w <= 1 << 15 => (h, w),
        _ => return Err(bad("bad image size")),
    };
    check_image_size(path, w, h)?;
    let mut data = vec![0f32; w * h * 3];
    let mut p = pos;
    let mut scan = vec![[0u8; 4]; w];
    let byte = |i: usize| {
        bytes
            .get(i)
            .copied()
            .ok_or_else(|| bad("truncated pixel data"))
    };
    for y in 0..h {
        let rle = (8..0x8000).contains(&w)
            && byte(p)? == 2
            && byte(p + 1)? == 2
            && byte(p + 2)? & 0x80 == 0;
        if rle {
            if ((byte(p + 2)? as usize) << 8 | byte(p + 3)? as usize) != w {
                return Err(bad("scanline width mismatch"));
            }
            p += 4;
            for c in 0..4 {
                let mut x = 0usize;
                while x < w {
                    let n = byte(p)? as usize;
                    p += 1;
                    if n > 128 {
                        let run = n - 128;
                        let v = byte(p)?;
                        p += 1;
                        if x + run > w {
                            return Err(bad("run past the end of a scanline"));
                        }
                        for px in &mut scan[x..x + run] {
                            px[c] = v;
                        }
                        x += run;
                    } else {
                        if n == 0 || x + n > w {
                            return Err(bad("bad run length"));
                        }
                        for px in &mut scan[x..x + n] {
                            px[c] = byte(p)?;
                            p += 1;
                        }
                        x += n;
                    }
                }
            }
        } else {
            for px in scan.iter_mut() {
                for (c, v) in px.iter_mut().enumerate() {
                    *v = byte(p + c)?;
                }
                p += 4;
            }
        }
        for (x, px) in scan.iter().enumerate() {
            let i = (y * w + x) * 3;
            if px[3] != 0 {
                // mantissa · 2^(e - 136) (Walter's RGBE decoding, which
                // Mitsuba 3 uses; Radiance itself adds 0.5 to the mantissa).
                let f = 2f32.powi(px[3] as i32 - 136);
                for c in 0..3 {
                    data[i + c] = px[c] as f32 * f;
                }
            }
        }
    }
    Ok((w, h, data))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trip_is_exact() {
        let (w, h) = (7, 5);
        let data: Vec<f32> = (0..w * h * 3).map(|i| i as f32 * 0.125 + 1e-3).collect();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.exr");
        write_exr(&p, w, h, 3, &data).unwrap();
        let (rw, rh, back) = read_exr_rgb(&p).unwrap();
        assert_eq!((rw, rh), (w, h));
        assert_eq!(back, data);
    }

    #[test]
    fn png_writes_and_bad_size_leaves_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.png");
        write_png_preview(
            &p,
            2,
            2,
            3,
            &[0.0, 0.5, 1.0, 2.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8],
            0.0,
        )
        .unwrap();
        assert!(p.exists());
        let q = dir.path().join("b.png");
        assert!(write_png_preview(&q, 2, 2, 3, &[0.0; 5], 0.0).is_err());
        assert!(!q.exists());
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no temp file left behind"
        );
    }

    #[cfg(unix)]
    #[test]
    fn written_files_follow_the_umask_not_0600() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.png");
        write_png8(&p, 1, 1, 1, &[7]).unwrap();
        // Read the umask from /proc (Linux) to know what to expect.
        let status = std::fs::read_to_string("/proc/self/status").unwrap();
        let umask = status
            .lines()
            .find_map(|l| l.strip_prefix("Umask:"))
            .map(|v| u32::from_str_radix(v.trim(), 8).unwrap())
            .unwrap();
        let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o666 & !umask);
    }

    #[test]
    fn srgb_curve_end_points() {
        assert_eq!(
            to_srgb8(&[0.0, 1.0, 5.0, f32::NAN, -1.0], 0.0),
            vec![0, 255, 255, 0, 0]
        );
    }
}
