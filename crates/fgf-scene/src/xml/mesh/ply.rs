//! PLY meshes: our own reader (see the parent module for why). The file is
//! read a buffer at a time, never whole: a 4M-triangle mesh's PLY is 116 MB,
//! which took as many fresh pages and a copy (`docs/benchmarks.md`, "Large
//! meshes without their `Tri`s"). In a binary file, the records of an
//! element of scalars alone (a mesh's vertices, mostly) and a face's
//! indices are taken from the buffer whole and decoded from the slice,
//! not checked against the buffer value by value (`docs/benchmarks.md`,
//! "PLY records read whole").

use super::{finish, open_file};
use crate::desc::TriangleMesh;
use crate::error::{SceneError, SceneErrorKind};
use crate::xml::document::XNode;
use glam::{Vec2, Vec3};
use std::io::Read;
use std::path::Path;

pub(crate) fn load_ply(fnode: &XNode, path: &Path) -> Result<TriangleMesh, SceneError> {
    let (file, len) = open_file(fnode, path, "PLY")?;
    parse_ply(file, len).map_err(|m| {
        fnode.err_kind(
            SceneErrorKind::Format,
            format!("invalid PLY file '{}': {m}", path.display()),
        )
    })
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Le,
    Be,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    /// The value of the `self.size()` bytes `raw`, big-endian if `be`.
    #[inline(always)]
    fn decode(self, raw: &[u8], be: bool) -> f64 {
        macro_rules! num {
            ($t:ty) => {{
                let b = raw.try_into().unwrap_or_default();
                (if be {
                    <$t>::from_be_bytes(b)
                } else {
                    <$t>::from_le_bytes(b)
                }) as f64
            }};
        }
        match self {
            Scalar::I8 => num!(i8),
            Scalar::U8 => num!(u8),
            Scalar::I16 => num!(i16),
            Scalar::U16 => num!(u16),
            Scalar::I32 => num!(i32),
            Scalar::U32 => num!(u32),
            Scalar::F32 => num!(f32),
            Scalar::F64 => num!(f64),
        }
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Debug)]
enum Prop {
    Scalar(Scalar, String),
    /// count type, item type, name
    List(Scalar, Scalar, String),
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Prop>,
}

/// The bytes [`Body`] holds at most: the longest header read (64 KiB) and
/// more, so that a refill is rare.
const CHUNK: usize = 1 << 20;

/// Reads a PLY file `src`, a buffer of [`CHUNK`] bytes at a time: its
/// header, then values from its body.
struct Body<R> {
    fmt: Format,
    src: R,
    buf: Vec<u8>,
    /// The bytes `buf[lo..hi]` are read from `src` and not yet used.
    lo: usize,
    hi: usize,
    /// The bytes of the file not yet read from `src`, by its size when
    /// opened (what bounds the counts of a hostile header).
    unread: u64,
}

impl<R: Read> Body<R> {
    /// A reader of `src`, a file of `len` bytes.
    fn new(src: R, len: u64) -> Self {
        Body {
            fmt: Format::Ascii,
            src,
            buf: vec![0; CHUNK],
            lo: 0,
            hi: 0,
            unread: len,
        }
    }

    fn remaining(&self) -> usize {
        let unread = usize::try_from(self.unread).unwrap_or(usize::MAX);
        (self.hi - self.lo).saturating_add(unread)
    }

    /// Have at least `n` (at most [`CHUNK`]) bytes at `buf[lo..]`, or all
    /// the file has left if fewer: whether there are `n`.
    #[inline(never)]
    fn fill(&mut self, n: usize) -> Result<bool, String> {
        debug_assert!(n <= CHUNK);
        self.buf.copy_within(self.lo..self.hi, 0);
        self.hi -= self.lo;
        self.lo = 0;
        while self.hi < n {
            let got = match self.src.read(&mut self.buf[self.hi..]) {
                Ok(0) => return Ok(false),
                Ok(got) => got,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(format!("read error: {e}")),
            };
            self.hi += got;
            self.unread = self.unread.saturating_sub(got as u64);
        }
        Ok(true)
    }

    /// Read the header (which must end within the first 64 KiB) and stand
    /// at the start of the body.
    fn header(&mut self) -> Result<Vec<Element>, String> {
        self.fill(1 << 16)?;
        let (fmt, elements, body) = parse_header(&self.buf[..self.hi])?;
        self.fmt = fmt;
        self.lo = body;
        Ok(elements)
    }

    fn next_token(&mut self) -> Result<&str, String> {
        loop {
            while self.lo < self.hi && self.buf[self.lo].is_ascii_whitespace() {
                self.lo += 1;
            }
            if self.lo < self.hi || !self.fill(1)? {
                break;
            }
        }
        // The token's length so far: it may run on past the buffer.
        let mut len = 0;
        loop {
            while self.lo + len < self.hi && !self.buf[self.lo + len].is_ascii_whitespace() {
                len += 1;
            }
            if self.lo + len < self.hi {
                break;
            }
            if len == CHUNK {
                return Err(format!("a token longer than {CHUNK} bytes"));
            }
            if !self.fill(len + 1)? {
                // The token ends with the file.
                break;
            }
        }
        if len == 0 {
            return Err("unexpected end of file".into());
        }
        let start = self.lo;
        self.lo += len;
        std::str::from_utf8(&self.buf[start..start + len])
            .map_err(|_| "non-ASCII data in an ascii PLY body".into())
    }

    #[inline]
    fn read(&mut self, t: Scalar) -> Result<f64, String> {
        if self.fmt == Format::Ascii {
            let tok = self.next_token()?;
            return tok
                .parse::<f64>()
                .map_err(|_| format!("cannot parse '{tok}' as a number"));
        }
        let size = t.size();
        if self.hi - self.lo < size && !self.fill(size)? {
            return Err("unexpected end of file".into());
        }
        let raw = &self.buf[self.lo..self.lo + size];
        self.lo += size;
        Ok(t.decode(raw, self.fmt == Format::Be))
    }

    /// A list length or index: a non-negative integer.
    fn read_index(&mut self, t: Scalar, what: &str) -> Result<usize, String> {
        index(self.read(t)?, what)
    }

    /// One record of an element with properties `props`, value by value:
    /// each scalar into `vals` at its property's place; lists are skipped.
    fn read_record(&mut self, props: &[Prop], vals: &mut [f64]) -> Result<(), String> {
        for (k, p) in props.iter().enumerate() {
            match p {
                Prop::Scalar(t, _) => vals[k] = self.read(*t)?,
                Prop::List(c, t, _) => {
                    let n = self.read_index(*c, "list length")?;
                    for _ in 0..n {
                        self.read(*t)?;
                    }
                }
            }
        }
        Ok(())
    }

    /// `n` list items of type `t`, as vertex indices appended to `out`; in
    /// a binary body all at once where they fit the buffer.
    fn read_indices(&mut self, t: Scalar, n: usize, out: &mut Vec<u32>) -> Result<(), String> {
        let size = t.size();
        if self.fmt != Format::Ascii && n.saturating_mul(size) <= CHUNK {
            let be = self.fmt == Format::Be;
            for raw in self.take(n * size)?.chunks_exact(size) {
                out.push(index(t.decode(raw, be), "vertex index")? as u32);
            }
            return Ok(());
        }
        for _ in 0..n {
            out.push(self.read_index(t, "vertex index")? as u32);
        }
        Ok(())
    }

    /// The next `n` bytes of a binary body (`n` at most [`CHUNK`]), as
    /// one slice: a record's values are then decoded from it without a
    /// check of the buffer each.
    #[inline]
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        debug_assert!(self.fmt != Format::Ascii && n <= CHUNK);
        if self.hi - self.lo < n && !self.fill(n)? {
            return Err("unexpected end of file".into());
        }
        let start = self.lo;
        self.lo += n;
        Ok(&self.buf[start..start + n])
    }

    /// Smallest number of bytes one value can take (to bound counts).
    fn min_size(&self, t: Scalar) -> usize {
        match self.fmt {
            // A digit and a separator.
            Format::Ascii => 2,
            _ => t.size(),
        }
    }
}

fn parse_header(b: &[u8]) -> Result<(Format, Vec<Element>, usize), String> {
    // The header is ASCII lines up to `end_header`; 64 KiB is far more than
    // any real header and bounds the search on a non-PLY file.
    let limit = b.len().min(1 << 16);
    let mut lines = Vec::new();
    let mut start = 0;
    let mut body = None;
    for i in 0..limit {
        if b[i] == b'\n' {
            let line = std::str::from_utf8(&b[start..i])
                .map_err(|_| "the header is not ASCII".to_string())?
                .trim_end_matches('\r')
                .trim();
            lines.push(line.to_string());
            start = i + 1;
            if line == "end_header" {
                body = Some(i + 1);
                break;
            }
        }
    }
    let body = body.ok_or("no 'end_header' line in the first 64 KiB (not a PLY file?)")?;
    if lines.first().map(|s| s.as_str()) != Some("ply") {
        return Err("the file does not start with 'ply'".into());
    }
    let mut fmt = None;
    let mut elements: Vec<Element> = Vec::new();
    for line in &lines[1..lines.len() - 1] {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.first().copied() {
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                fmt = Some(match w.get(1).copied() {
                    Some("ascii") => Format::Ascii,
                    Some("binary_little_endian") => Format::Le,
                    Some("binary_big_endian") => Format::Be,
                    other => {
                        return Err(format!(
                    "unknown format {:?} (valid: ascii, binary_little_endian, binary_big_endian)",
                    other.unwrap_or("")
                ))
                    }
                })
            }
            Some("element") => {
                if w.len() != 3 {
                    return Err(format!("bad header line '{line}'"));
                }
                let count = w[2]
                    .parse::<usize>()
                    .map_err(|_| format!("bad element count in '{line}'"))?;
                elements.push(Element {
                    name: w[1].to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| format!("'{line}' comes before any element"))?;
                let bad = || format!("bad property line '{line}'");
                let prop = if w.get(1) == Some(&"list") {
                    if w.len() != 5 {
                        return Err(bad());
                    }
                    Prop::List(
                        Scalar::parse(w[2]).ok_or_else(bad)?,
                        Scalar::parse(w[3]).ok_or_else(bad)?,
                        w[4].to_string(),
                    )
                } else {
                    if w.len() != 3 {
                        return Err(bad());
                    }
                    Prop::Scalar(Scalar::parse(w[1]).ok_or_else(bad)?, w[2].to_string())
                };
                el.props.push(prop);
            }
            Some(other) => return Err(format!("unknown header keyword '{other}'")),
        }
    }
    let fmt = fmt.ok_or("no 'format' line in the header")?;
    Ok((fmt, elements, body))
}

/// `v` as a list length or index: a non-negative integer that fits `u32`.
#[inline]
fn index(v: f64, what: &str) -> Result<usize, String> {
    if !(v >= 0.0 && v.fract() == 0.0 && v <= u32::MAX as f64) {
        return Err(format!("{what} {v} is not a valid non-negative integer"));
    }
    Ok(v as usize)
}

/// The byte offset of each property in a record of a binary element whose
/// properties are all scalars, and the record's size (`None` if some
/// property is a list, or the body is ascii): such records are read whole.
fn fixed_layout(el: &Element, fmt: Format) -> Option<(Vec<(usize, Scalar)>, usize)> {
    if fmt == Format::Ascii {
        return None;
    }
    let mut size = 0;
    let mut at = Vec::with_capacity(el.props.len());
    for p in &el.props {
        let Prop::Scalar(t, _) = p else { return None };
        at.push((size, *t));
        size += t.size();
    }
    (size <= CHUNK).then_some((at, size))
}

/// The mesh of the PLY file `src` of `len` bytes.
fn parse_ply(src: impl Read, len: u64) -> Result<TriangleMesh, String> {
    let mut body = Body::new(src, len);
    let elements = body.header()?;
    let mut positions: Option<Vec<Vec3>> = None;
    let mut normals: Option<Vec<Vec3>> = None;
    let mut texcoords: Option<Vec<Vec2>> = None;
    let mut indices: Option<Vec<[u32; 3]>> = None;
    for el in &elements {
        // Refuse counts the rest of the file cannot hold before allocating.
        let min_bytes: usize = el
            .props
            .iter()
            .map(|p| match p {
                Prop::Scalar(t, _) => body.min_size(*t),
                Prop::List(c, _, _) => body.min_size(*c),
            })
            .sum::<usize>()
            .max(1);
        if el.count > body.remaining() / min_bytes {
            return Err(format!(
                "element '{}' declares {} entries, more than the file's remaining {} bytes can hold",
                el.name,
                el.count,
                body.remaining()
            ));
        }
        let find = |n: &str| {
            el.props
                .iter()
                .position(|p| matches!(p, Prop::Scalar(_, name) if name == n))
        };
        match el.name.as_str() {
            "vertex" => {
                if positions.is_some() {
                    return Err("two 'vertex' elements".into());
                }
                let xyz = [find("x"), find("y"), find("z")];
                let nxyz = [find("nx"), find("ny"), find("nz")];
                if xyz.iter().any(|i| i.is_none()) {
                    return Err("the 'vertex' element lacks x, y or z".into());
                }
                let has_n = nxyz.iter().all(|i| i.is_some());
                // Mitsuba's names for texture coordinates, in its order.
                let uv = [("u", "v"), ("s", "t"), ("texture_u", "texture_v")]
                    .iter()
                    .find_map(|(a, b)| Some([find(a)?, find(b)?]));
                let mut ts = Vec::with_capacity(if uv.is_some() { el.count } else { 0 });
                let mut ps = Vec::with_capacity(el.count);
                let mut ns = Vec::with_capacity(if has_n { el.count } else { 0 });
                let mut vals = vec![0f64; el.props.len()];
                let layout = fixed_layout(el, body.fmt);
                let be = body.fmt == Format::Be;
                for _ in 0..el.count {
                    if let Some((at, size)) = &layout {
                        let rec = body.take(*size)?;
                        for (v, &(o, t)) in vals.iter_mut().zip(at) {
                            *v = t.decode(&rec[o..o + t.size()], be);
                        }
                    } else {
                        body.read_record(&el.props, &mut vals)?;
                    }
                    let g = |i: Option<usize>| vals[i.unwrap_or(0)] as f32;
                    ps.push(Vec3::new(g(xyz[0]), g(xyz[1]), g(xyz[2])));
                    if has_n {
                        ns.push(Vec3::new(g(nxyz[0]), g(nxyz[1]), g(nxyz[2])));
                    }
                    if let Some([iu, iv]) = uv {
                        ts.push(Vec2::new(vals[iu] as f32, vals[iv] as f32));
                    }
                }
                positions = Some(ps);
                normals = has_n.then_some(ns);
                texcoords = uv.map(|_| ts);
            }
            "face" => {
                if indices.is_some() {
                    return Err("two 'face' elements".into());
                }
                let li = el.props.iter().position(|p| {
                    matches!(p, Prop::List(_, _, name) if name == "vertex_indices" || name == "vertex_index")
                });
                let Some(li) = li else {
                    return Err("the 'face' element has no 'vertex_indices' list".into());
                };
                let mut tris = Vec::with_capacity(el.count);
                let mut poly = Vec::new();
                for f in 0..el.count {
                    for (k, p) in el.props.iter().enumerate() {
                        match p {
                            Prop::Scalar(t, _) => {
                                body.read(*t)?;
                            }
                            Prop::List(c, t, _) => {
                                let n = body.read_index(*c, "list length")?;
                                if n > body.remaining() / body.min_size(*t) + 1 {
                                    return Err(format!(
                                        "face #{f} list length {n} exceeds the file"
                                    ));
                                }
                                poly.clear();
                                body.read_indices(*t, n, &mut poly)?;
                                if k == li {
                                    if n < 3 {
                                        return Err(format!(
                                            "face #{f} has {n} vertices (need at least 3)"
                                        ));
                                    }
                                    // Fan triangulation, as Mitsuba does.
                                    for j in 1..n - 1 {
                                        tris.push([poly[0], poly[j], poly[j + 1]]);
                                    }
                                }
                            }
                        }
                    }
                }
                indices = Some(tris);
            }
            _ => {
                let mut vals = vec![0f64; el.props.len()];
                for _ in 0..el.count {
                    body.read_record(&el.props, &mut vals)?;
                }
            }
        }
    }
    let positions = positions.ok_or("no 'vertex' element")?;
    let indices = indices.ok_or("no 'face' element")?;
    finish(positions, normals, texcoords, indices)
}

#[cfg(test)]
mod tests {
    use super::super::Trickle;
    use super::*;

    /// The mesh of the PLY file `b`.
    fn parse(b: &[u8]) -> Result<TriangleMesh, String> {
        parse_ply(b, b.len() as u64)
    }

    /// A binary grid of `k` × `k` vertices (`z` the vertex's number, `u`
    /// its row) and its quads as triangles, large enough to take several
    /// buffers, read in big pieces and in pieces of a few bytes: every
    /// value as written.
    #[test]
    fn large_files_are_read_a_buffer_at_a_time() {
        let k = 300u32;
        let mut b = format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty double z\nproperty float u\nproperty float v\nelement face {}\nproperty uchar flags\nproperty list uchar int vertex_indices\nend_header\n",
            k * k,
            (k - 1) * (k - 1)
        )
        .into_bytes();
        for i in 0..k * k {
            for v in [(i % k) as f32, (i / k) as f32] {
                b.extend(v.to_le_bytes());
            }
            b.extend(f64::from(i).to_le_bytes());
            for v in [(i / k) as f32, 0.5] {
                b.extend(v.to_le_bytes());
            }
        }
        for r in 0..k - 1 {
            for c in 0..k - 1 {
                let v = r * k + c;
                b.extend([7, 4]);
                for i in [v, v + 1, v + k + 1, v + k] {
                    b.extend(i.to_le_bytes());
                }
            }
        }
        assert!(b.len() > 3 * CHUNK);
        let len = b.len() as u64;
        for step in [usize::MAX, 5] {
            let m = parse_ply(Trickle::new(&b, step), len).unwrap();
            assert_eq!(m.positions.len(), (k * k) as usize);
            for (i, p) in m.positions.iter().enumerate() {
                let i = i as u32;
                assert_eq!(*p, Vec3::new((i % k) as f32, (i / k) as f32, i as f32));
            }
            let t = m.texcoords.expect("texture coordinates");
            assert!(t
                .iter()
                .enumerate()
                .all(|(i, t)| *t == Vec2::new((i as u32 / k) as f32, 0.5)));
            assert_eq!(m.indices.len(), 2 * ((k - 1) * (k - 1)) as usize);
            let (r, c) = (k - 2, k - 2);
            let v = r * k + c;
            assert_eq!(
                m.indices[m.indices.len() - 2..],
                [[v, v + 1, v + k + 1], [v, v + k + 1, v + k]]
            );
        }
        // The same file cut short, read either way.
        let cut = &b[..b.len() - 3];
        for step in [usize::MAX, 5] {
            let e = parse_ply(Trickle::new(cut, step), len).unwrap_err();
            assert!(e.contains("end of file"), "{e}");
        }
    }

    /// An ascii file read a few bytes at a time: tokens cut anywhere.
    #[test]
    fn ascii_tokens_across_refills() {
        let b = SQUARE_ASCII.replace("1 1 0", "1.000 1e0   0.0");
        for step in 1..8 {
            let m = parse_ply(Trickle::new(b.as_bytes(), step), b.len() as u64).unwrap();
            assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 0.0), "step {step}");
            assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        }
        let no_newline = b.trim_end();
        assert_eq!(parse(no_newline.as_bytes()).unwrap().indices.len(), 2);
        let truncated = &b[..b.len() - 3];
        assert!(parse(truncated.as_bytes())
            .unwrap_err()
            .contains("end of file"));
    }

    const SQUARE_ASCII: &str = "ply\nformat ascii 1.0\ncomment a unit square\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

    #[test]
    fn ascii_quad_is_fan_triangulated() {
        let m = parse(SQUARE_ASCII.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert!(m.normals.is_none());
    }

    fn binary(be: bool) -> Vec<u8> {
        let mut b = format!(
            "ply\nformat {} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n",
            if be { "binary_big_endian" } else { "binary_little_endian" }
        )
        .into_bytes();
        let f =
            |b: &mut Vec<u8>, v: f32| b.extend(if be { v.to_be_bytes() } else { v.to_le_bytes() });
        for p in [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]] {
            for v in p {
                f(&mut b, v);
            }
            for v in [0.0, 0.0, 2.0] {
                f(&mut b, v);
            }
            b.push(255);
        }
        b.push(3);
        for i in [0u32, 1, 2] {
            b.extend(if be { i.to_be_bytes() } else { i.to_le_bytes() });
        }
        b
    }

    #[test]
    fn binary_both_endians_read_positions_and_unit_normals() {
        for be in [false, true] {
            let m = parse(&binary(be)).unwrap();
            assert_eq!(m.positions[1], Vec3::new(2.0, 0.0, 0.0));
            assert_eq!(m.positions[2], Vec3::new(0.0, 3.0, 0.0));
            assert_eq!(m.normals.as_ref().unwrap()[0], Vec3::Z);
            assert_eq!(m.indices, vec![[0, 1, 2]]);
        }
    }

    /// Mitsuba's three names for texture coordinates are read as written.
    #[test]
    fn texture_coordinates_under_each_name() {
        for (a, b) in [("u", "v"), ("s", "t"), ("texture_u", "texture_v")] {
            let ply = format!(
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float {a}\nproperty float {b}\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0.1 0.2\n1 0 0 0.9 0.3\n0 1 0 0.2 0.7\n3 0 1 2\n"
            );
            let m = parse(ply.as_bytes()).unwrap();
            let t = m.texcoords.expect("texture coordinates");
            assert_eq!(t[1], Vec2::new(0.9, 0.3), "{a}, {b}");
        }
        assert!(parse(SQUARE_ASCII.as_bytes()).unwrap().texcoords.is_none());
    }

    /// A binary vertex element with a list among its properties is read
    /// value by value (its records have no fixed size), and the indices of
    /// a face read at once are checked as one by one: a negative one or a
    /// fractional float is an error.
    #[test]
    fn binary_vertex_lists_and_bad_indices() {
        let ply = |index_type: &str, face: &[u8]| {
            let mut b = format!(
                "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty list uchar short extra\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar {index_type} vertex_indices\nend_header\n"
            )
            .into_bytes();
            for (i, p) in [[0f32, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]]
                .iter()
                .enumerate()
            {
                b.extend(p[0].to_le_bytes());
                b.push(i as u8);
                for k in 0..i as i16 {
                    b.extend((-k).to_le_bytes());
                }
                b.extend(p[1].to_le_bytes());
                b.extend(p[2].to_le_bytes());
            }
            b.push(3);
            b.extend(face);
            b
        };
        let ints = |v: [i32; 3]| v.iter().flat_map(|i| i.to_le_bytes()).collect::<Vec<u8>>();
        let floats = |v: [f32; 3]| v.iter().flat_map(|i| i.to_le_bytes()).collect::<Vec<u8>>();
        let m = parse(&ply("int", &ints([0, 1, 2]))).unwrap();
        assert_eq!(m.positions[2], Vec3::new(0.0, 3.0, 0.0));
        assert_eq!(m.indices, vec![[0, 1, 2]]);
        assert_eq!(
            parse(&ply("float", &floats([0.0, 1.0, 2.0])))
                .unwrap()
                .indices,
            vec![[0, 1, 2]]
        );
        for (t, face) in [
            ("int", ints([0, -1, 2])),
            ("float", floats([0.0, 1.5, 2.0])),
        ] {
            let e = parse(&ply(t, &face)).unwrap_err();
            assert!(
                e.contains("vertex index") && e.contains("not a valid"),
                "{e}"
            );
        }
    }

    #[test]
    fn hostile_counts_and_truncation_are_errors() {
        let huge = SQUARE_ASCII.replace("element vertex 4", "element vertex 4000000000000");
        assert!(parse(huge.as_bytes())
            .unwrap_err()
            .contains("more than the file"));
        let mut b = binary(false);
        b.truncate(b.len() - 2);
        assert!(parse(&b).unwrap_err().contains("end of file"));
        let bad = SQUARE_ASCII.replace("4 0 1 2 3", "4 0 1 2 9");
        assert!(parse(bad.as_bytes()).unwrap_err().contains("out of range"));
        assert!(parse(b"not a ply").is_err());
    }
}
