//! Node values: the metadata byte, active-mask, zlib and Blosc decompression, half floats.

use super::*;

/// How a node's values are stored; shared by internal nodes and leaves.
pub(super) struct Codec {
    pub(super) compression: u32,
    pub(super) half: bool,
    pub(super) background: f32,
}

impl Codec {
    /// Read `n` values (n = 512, 4096 or 32768) into `out`, following the
    /// node metadata byte and the value mask (`mask`, `n / 64` words).
    pub(super) fn read_values(
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
    pub(super) fn read_data(
        &self,
        r: &mut Reader<'_>,
        out: &mut [f32],
    ) -> std::result::Result<(), String> {
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
pub(super) fn decode_values(raw: &[u8], half: bool, out: &mut [f32]) {
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
pub(super) fn blosc_decompress(chunk: &[u8], out: &mut [u8]) -> std::result::Result<(), String> {
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
pub(super) fn f16_to_f32(h: u16) -> f32 {
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
