//! PLY meshes: our own reader (see the parent module for why).

use super::{finish, read_file};
use crate::desc::TriangleMesh;
use crate::error::{SceneError, SceneErrorKind};
use crate::xml::document::XNode;
use glam::{Vec2, Vec3};
use std::path::Path;

pub(crate) fn load_ply(fnode: &XNode, path: &Path) -> Result<TriangleMesh, SceneError> {
    let bytes = read_file(fnode, path, "PLY")?;
    parse_ply(&bytes).map_err(|m| {
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

/// Reads values from the body of a PLY file.
struct Body<'a> {
    fmt: Format,
    b: &'a [u8],
    pos: usize,
}

impl Body<'_> {
    fn remaining(&self) -> usize {
        self.b.len() - self.pos
    }

    fn next_token(&mut self) -> Result<&str, String> {
        while self.pos < self.b.len() && self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.b.len() && !self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if start == self.pos {
            return Err("unexpected end of file".into());
        }
        std::str::from_utf8(&self.b[start..self.pos])
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
        let Some(raw) = self.b.get(self.pos..self.pos + t.size()) else {
            return Err("unexpected end of file".into());
        };
        self.pos += raw.len();
        Ok(t.decode(raw, self.fmt == Format::Be))
    }

    /// A list length or index: a non-negative integer.
    fn read_index(&mut self, t: Scalar, what: &str) -> Result<usize, String> {
        let v = self.read(t)?;
        if !(v >= 0.0 && v.fract() == 0.0 && v <= u32::MAX as f64) {
            return Err(format!("{what} {v} is not a valid non-negative integer"));
        }
        Ok(v as usize)
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

fn parse_ply(b: &[u8]) -> Result<TriangleMesh, String> {
    let (fmt, elements, body_start) = parse_header(b)?;
    let mut body = Body {
        fmt,
        b,
        pos: body_start,
    };
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
                for _ in 0..el.count {
                    for (k, p) in el.props.iter().enumerate() {
                        match p {
                            Prop::Scalar(t, _) => vals[k] = body.read(*t)?,
                            Prop::List(c, t, _) => {
                                let n = body.read_index(*c, "list length")?;
                                for _ in 0..n {
                                    body.read(*t)?;
                                }
                            }
                        }
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
                                for _ in 0..n {
                                    poly.push(body.read_index(*t, "vertex index")? as u32);
                                }
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
                for _ in 0..el.count {
                    for p in &el.props {
                        match p {
                            Prop::Scalar(t, _) => {
                                body.read(*t)?;
                            }
                            Prop::List(c, t, _) => {
                                let n = body.read_index(*c, "list length")?;
                                for _ in 0..n {
                                    body.read(*t)?;
                                }
                            }
                        }
                    }
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
    use super::*;

    const SQUARE_ASCII: &str = "ply\nformat ascii 1.0\ncomment a unit square\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

    #[test]
    fn ascii_quad_is_fan_triangulated() {
        let m = parse_ply(SQUARE_ASCII.as_bytes()).unwrap();
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
            let m = parse_ply(&binary(be)).unwrap();
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
            let m = parse_ply(ply.as_bytes()).unwrap();
            let t = m.texcoords.expect("texture coordinates");
            assert_eq!(t[1], Vec2::new(0.9, 0.3), "{a}, {b}");
        }
        assert!(parse_ply(SQUARE_ASCII.as_bytes())
            .unwrap()
            .texcoords
            .is_none());
    }

    #[test]
    fn hostile_counts_and_truncation_are_errors() {
        let huge = SQUARE_ASCII.replace("element vertex 4", "element vertex 4000000000000");
        assert!(parse_ply(huge.as_bytes())
            .unwrap_err()
            .contains("more than the file"));
        let mut b = binary(false);
        b.truncate(b.len() - 2);
        assert!(parse_ply(&b).unwrap_err().contains("end of file"));
        let bad = SQUARE_ASCII.replace("4 0 1 2 3", "4 0 1 2 9");
        assert!(parse_ply(bad.as_bytes())
            .unwrap_err()
            .contains("out of range"));
        assert!(parse_ply(b"not a ply").is_err());
    }
}
