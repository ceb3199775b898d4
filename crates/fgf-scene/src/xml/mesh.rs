//! Triangle meshes for the `obj` and `ply` shapes.
//!
//! * OBJ: read with `tobj` (faces fan-triangulated, one index per vertex so
//!   that positions and normals line up; every `o`/`g` group is merged into
//!   one mesh, as Mitsuba does).
//! * PLY: our own small reader for `ascii`, `binary_little_endian` and
//!   `binary_big_endian`. `ply-rs` (the only PLY crate) has had no release
//!   since 2020, and a reader this size lets us refuse hostile headers
//!   (element counts larger than the file could hold) before allocating.
//!   It reads `vertex` (`x y z`, optional `nx ny nz`) and `face`
//!   (`vertex_indices` or `vertex_index` lists; n-gons fan-triangulated);
//!   other elements and properties are skipped.
//!
//! Normals are kept only if every vertex has one; they are normalised.
//!
//! Meshes without vertex normals get Mitsuba's smooth ones from
//! [`smooth_vertex_normals`] (user docs: the `plugins` module). Mitsuba
//! (`Mesh::recompute_vertex_normals`, after Thürmer and Wüthrich 1998)
//! weights each unit face normal by the face's angle at the vertex, on the
//! world-space positions; angle weighting is not invariant under
//! non-uniform scale or shear, so we compute in world space too and store
//! `normalize(Mᵀ n_world)`, which the renderer's `M^{-T}` maps back onto
//! `n_world`.

use super::document::XNode;
use crate::desc::TriangleMesh;
use crate::error::{SceneError, SceneErrorKind};
use glam::{Mat3, Mat4, Vec3};
use std::collections::HashMap;
use std::path::Path;

fn read_file(fnode: &XNode, path: &Path, what: &str) -> Result<Vec<u8>, SceneError> {
    std::fs::read(path).map_err(|e| {
        fnode.err_kind(
            SceneErrorKind::Io,
            format!("cannot read {what} file '{}': {e}", path.display()),
        )
    })
}

/// Check and normalise a mesh; `Err` is a message about the file's content.
fn finish(
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    indices: Vec<[u32; 3]>,
) -> Result<TriangleMesh, String> {
    if indices.is_empty() {
        return Err("the mesh has no faces".into());
    }
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex #{i} position is not finite"));
    }
    let n = positions.len();
    if let Some(t) = indices.iter().find(|t| t.iter().any(|&i| i as usize >= n)) {
        return Err(format!(
            "face index {:?} is out of range (the mesh has {n} vertices)",
            t
        ));
    }
    let normals = match normals {
        Some(ns) => {
            let mut out = Vec::with_capacity(ns.len());
            for (i, v) in ns.iter().enumerate() {
                let len = v.length();
                if !(len.is_finite() && len > 0.0) {
                    return Err(format!(
                        "vertex normal #{i} is zero or not finite (use face_normals=\"true\" to ignore the file's normals)"
                    ));
                }
                out.push(*v / len);
            }
            Some(out)
        }
        None => None,
    };
    Ok(TriangleMesh {
        positions,
        normals,
        indices,
    })
}

/// Angle between two unit vectors, accurate for small and large angles
/// (`acos` of the dot product loses half the digits near 0 and π): the
/// chord `|a − b|` gives the angle through `2 asin(|a − b| / 2)`, and the
/// supplement is used past π/2, as Mitsuba's `unit_angle` does.
fn unit_angle(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) >= 0.0 {
        2.0 * (0.5 * (b - a).length()).asin()
    } else {
        std::f32::consts::PI - 2.0 * (0.5 * (a + b).length()).asin()
    }
}

/// Smooth vertex normals of a mesh that has none, computed as Mitsuba 3.9
/// does (see the module docs): angle-weighted unit face normals in world
/// space, degenerate faces skipped, `(1, 0, 0)` for a zero sum. Returns
/// local-space unit normals `normalize(Mᵀ n_world)`, which the renderer's
/// inverse-transpose maps back onto `n_world`.
pub(crate) fn smooth_vertex_normals(
    positions: &[Vec3],
    indices: &[[u32; 3]],
    to_world: &Mat4,
) -> Vec<Vec3> {
    // f32 throughout, like Mitsuba's scalar loader, so that the results
    // agree to float rounding.
    let world: Vec<Vec3> = positions
        .iter()
        .map(|&p| to_world.transform_point3(p))
        .collect();
    let mut sums = vec![Vec3::ZERO; positions.len()];
    for t in indices {
        let v = [
            world[t[0] as usize],
            world[t[1] as usize],
            world[t[2] as usize],
        ];
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let len2 = n.length_squared();
        // A zero (or non-finite) cross product: no orientation, no weight.
        if !(len2 > 0.0 && len2.is_finite()) {
            continue;
        }
        let n = n / len2.sqrt();
        for j in 0..3 {
            let d0 = (v[(j + 1) % 3] - v[j]).normalize();
            let d1 = (v[(j + 2) % 3] - v[j]).normalize();
            sums[t[j] as usize] += n * unit_angle(d0, d1);
        }
    }
    let to_local = Mat3::from_mat4(*to_world).transpose();
    sums.into_iter()
        .map(|s| {
            let len = s.length();
            // Mitsuba's placeholder for a vertex without a usable face.
            let nw = if len != 0.0 && len.is_finite() {
                s / len
            } else {
                Vec3::X
            };
            (to_local * nw).normalize_or(Vec3::X)
        })
        .collect()
}

pub(crate) fn load_obj(fnode: &XNode, path: &Path) -> Result<TriangleMesh, SceneError> {
    // Read the bytes ourselves so that a missing file is an I/O error with
    // the OS message, then let tobj parse from memory (no .mtl lookups).
    let bytes = read_file(fnode, path, "OBJ")?;
    let fmt = |m: String| {
        fnode.err_kind(
            SceneErrorKind::Format,
            format!("invalid OBJ file '{}': {m}", path.display()),
        )
    };
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut reader = std::io::BufReader::new(&bytes[..]);
    let (models, _materials) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| fmt(e.to_string()))?;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut all_normals = true;
    let mut indices = Vec::new();
    // tobj numbers the vertices of each `o`/`g` group separately, while
    // Mitsuba shares one `v/vt/vn` vertex across groups (it matters for the
    // computed smooth normals). tobj does not report the file's indices, so
    // a vertex is shared with an earlier group when its position, texture
    // coordinate and normal are bitwise equal; within one group tobj's own
    // index-based numbering is kept.
    type Key = ([u32; 3], [u32; 2], [u32; 3]);
    let mut earlier: HashMap<Key, u32> = HashMap::new();
    for m in &models {
        let mesh = &m.mesh;
        let nv = mesh.positions.len() / 3;
        let has_n = mesh.normals.len() == mesh.positions.len();
        let has_tc = mesh.texcoords.len() == 2 * nv;
        all_normals &= has_n;
        let mut ids = Vec::with_capacity(nv);
        let mut mine: Vec<(Key, u32)> = Vec::with_capacity(nv);
        for i in 0..nv {
            let p = Vec3::from_slice(&mesh.positions[3 * i..3 * i + 3]);
            let n = if has_n {
                Vec3::from_slice(&mesh.normals[3 * i..3 * i + 3])
            } else {
                Vec3::ZERO
            };
            let tc = if has_tc {
                [mesh.texcoords[2 * i], mesh.texcoords[2 * i + 1]]
            } else {
                [0.0; 2]
            };
            let key = (
                p.to_array().map(f32::to_bits),
                tc.map(f32::to_bits),
                n.to_array().map(f32::to_bits),
            );
            let id = match earlier.get(&key) {
                Some(&id) => id,
                None => {
                    let id = u32::try_from(positions.len())
                        .map_err(|_| fmt("more than 2^32 vertices".into()))?;
                    positions.push(p);
                    normals.push(n);
                    mine.push((key, id));
                    id
                }
            };
            ids.push(id);
        }
        for (key, id) in mine {
            earlier.entry(key).or_insert(id);
        }
        for t in mesh.indices.chunks_exact(3) {
            if t.iter().any(|&i| i as usize >= nv) {
                return Err(fmt(format!(
                    "object '{}' has a face index out of range",
                    m.name
                )));
            }
            indices.push([ids[t[0] as usize], ids[t[1] as usize], ids[t[2] as usize]]);
        }
    }
    finish(
        positions,
        (all_normals && !normals.is_empty()).then_some(normals),
        indices,
    )
    .map_err(fmt)
}

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

    fn read(&mut self, t: Scalar) -> Result<f64, String> {
        if self.fmt == Format::Ascii {
            let tok = self.next_token()?;
            return tok
                .parse::<f64>()
                .map_err(|_| format!("cannot parse '{tok}' as a number"));
        }
        let n = t.size();
        if self.remaining() < n {
            return Err("unexpected end of file".into());
        }
        let mut raw = [0u8; 8];
        raw[..n].copy_from_slice(&self.b[self.pos..self.pos + n]);
        self.pos += n;
        if self.fmt == Format::Be {
            raw[..n].reverse();
        }
        Ok(match t {
            Scalar::I8 => raw[0] as i8 as f64,
            Scalar::U8 => raw[0] as f64,
            Scalar::I16 => i16::from_le_bytes([raw[0], raw[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([raw[0], raw[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(raw),
        })
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
                }
                positions = Some(ps);
                normals = has_n.then_some(ns);
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
    finish(positions, normals, indices)
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
