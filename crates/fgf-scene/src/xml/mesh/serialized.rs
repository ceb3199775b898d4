//! Mitsuba's `serialized` meshes, versions 3 and 4 (the legacy format that
//! Mitsuba 0.6 and 3 export and read).
//!
//! A file is a sequence of meshes followed by a table of their offsets. Each
//! mesh starts with the identifier `0x041C` and the version (two
//! little-endian u16), followed by a zlib stream holding: the flags (u32),
//! the mesh name (version 4: a NUL-terminated string), the vertex and
//! triangle counts (u64 each), the positions (3 floats per vertex), then if
//! flagged the normals (3), texture coordinates (2) and colours (3), and
//! the triangles (3 u32 each). Floats are f32, or f64 with flag `0x2000`.
//! Flags: `0x0001` normals, `0x0002` texture coordinates, `0x0008` colours,
//! `0x0010` face normals (the mesh is flat-shaded), `0x1000` single
//! precision. The file ends with the offset of each mesh (u64 in version 4,
//! u32 in version 3) and the mesh count (u32); `shape_index` selects a mesh
//! through it.

use super::{finish, read_file};
use crate::desc::TriangleMesh;
use crate::error::{SceneError, SceneErrorKind};
use crate::xml::document::XNode;
use glam::{Vec2, Vec3};
use std::io::Read;
use std::path::Path;

const MAGIC: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const FACE_NORMALS: u32 = 0x0010;
const DOUBLE_PRECISION: u32 = 0x2000;
/// A mesh name longer than this is refused (a corrupt stream).
const MAX_NAME: usize = 1 << 16;
/// zlib's largest expansion ratio is about 1032:1; a mesh whose counts
/// need more bytes than that of the file are a hostile header.
const MAX_RATIO: u64 = 1100;

/// A `serialized` mesh: the mesh and whether the file asks for face normals.
pub(crate) struct Serialized {
    pub mesh: TriangleMesh,
    pub face_normals: bool,
}

pub(crate) fn load_serialized(
    fnode: &XNode,
    path: &Path,
    shape_index: u32,
) -> Result<Serialized, SceneError> {
    let bytes = read_file(fnode, path, "serialized")?;
    parse(&bytes, shape_index).map_err(|m| {
        fnode.err_kind(
            SceneErrorKind::Format,
            format!("invalid serialized file '{}': {m}", path.display()),
        )
    })
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}
fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}
fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

fn parse(b: &[u8], shape_index: u32) -> Result<Serialized, String> {
    let header = |at: usize| -> Result<u16, String> {
        let magic = u16_at(b, at).ok_or("the file is too short for a mesh header")?;
        if magic != MAGIC {
            return Err(format!(
                "no mesh header at byte {at} (identifier 0x{magic:04X}, expected 0x041C)"
            ));
        }
        let version = u16_at(b, at + 2).ok_or("the file is too short for a mesh header")?;
        if version != 3 && version != 4 {
            return Err(format!(
                "format version {version} is not supported (versions 3 and 4 are)"
            ));
        }
        Ok(version)
    };
    let version = header(0)?;
    let start = if shape_index == 0 {
        0usize
    } else {
        let n = b.len();
        let count = n
            .checked_sub(4)
            .and_then(|at| u32_at(b, at))
            .ok_or("the file is too short for its mesh count")?;
        if shape_index >= count {
            return Err(format!(
                "shape_index {shape_index} is out of range: the file holds {count} mesh(es) (valid: 0 ... {})",
                count.saturating_sub(1)
            ));
        }
        let back = (count - shape_index) as usize;
        let offset = if version == 4 {
            n.checked_sub(8 * back + 4).and_then(|at| u64_at(b, at))
        } else {
            n.checked_sub(4 * (back + 1))
                .and_then(|at| u32_at(b, at))
                .map(u64::from)
        }
        .ok_or("the file is too short for its offset table")?;
        let at = usize::try_from(offset)
            .ok()
            .filter(|&o| o < n)
            .ok_or(format!(
                "mesh {shape_index}'s offset {offset} is past the end of the file"
            ))?;
        if header(at)? != version {
            return Err(format!(
                "mesh {shape_index} has another format version than the file's first mesh"
            ));
        }
        at
    };
    let mut z = flate2::read::ZlibDecoder::new(&b[start + 4..]);
    let mut read = |buf: &mut [u8], what: &str| {
        z.read_exact(buf)
            .map_err(|e| format!("cannot read the {what} of mesh {shape_index}: {e}"))
    };
    let mut w4 = [0u8; 4];
    let mut w8 = [0u8; 8];
    read(&mut w4, "flags")?;
    let flags = u32::from_le_bytes(w4);
    if version == 4 {
        // The mesh name, NUL-terminated.
        let mut len = 0usize;
        loop {
            let mut c = [0u8; 1];
            read(&mut c, "name")?;
            if c[0] == 0 {
                break;
            }
            len += 1;
            if len > MAX_NAME {
                return Err(format!(
                    "mesh {shape_index}'s name is longer than {MAX_NAME} bytes"
                ));
            }
        }
    }
    read(&mut w8, "vertex count")?;
    let nv = u64::from_le_bytes(w8);
    read(&mut w8, "triangle count")?;
    let nf = u64::from_le_bytes(w8);
    let fsize: u64 = if flags & DOUBLE_PRECISION != 0 { 8 } else { 4 };
    let mut per_vertex = 3u64;
    if flags & HAS_NORMALS != 0 {
        per_vertex += 3;
    }
    if flags & HAS_TEXCOORDS != 0 {
        per_vertex += 2;
    }
    if flags & HAS_COLORS != 0 {
        per_vertex += 3;
    }
    let need = nv
        .checked_mul(per_vertex * fsize)
        .and_then(|v| nf.checked_mul(12).and_then(|f| f.checked_add(v)));
    let limit = (b.len() as u64).saturating_mul(MAX_RATIO);
    match need {
        Some(n) if n <= limit && nv <= u32::MAX as u64 => {}
        _ => {
            return Err(format!(
                "mesh {shape_index} declares {nv} vertices and {nf} triangles, more than the file can hold"
            ))
        }
    }
    let mut floats = |count: u64, what: &str| -> Result<Vec<f32>, String> {
        let mut raw = vec![0u8; (count * fsize) as usize];
        read(&mut raw, what)?;
        Ok(if fsize == 8 {
            raw.chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")) as f32)
                .collect()
        } else {
            raw.chunks_exact(4)
                .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
                .collect()
        })
    };
    let to_vec3 = |v: Vec<f32>| -> Vec<Vec3> {
        v.chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect()
    };
    let positions = to_vec3(floats(nv * 3, "positions")?);
    let normals = if flags & HAS_NORMALS != 0 {
        Some(to_vec3(floats(nv * 3, "normals")?))
    } else {
        None
    };
    let texcoords = if flags & HAS_TEXCOORDS != 0 {
        let t = floats(nv * 2, "texture coordinates")?;
        Some(t.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect())
    } else {
        None
    };
    if flags & HAS_COLORS != 0 {
        floats(nv * 3, "vertex colours")?;
    }
    let mut raw = vec![0u8; (nf * 12) as usize];
    read(&mut raw, "triangles")?;
    let indices: Vec<[u32; 3]> = raw
        .chunks_exact(12)
        .map(|c| {
            let i = |k: usize| u32::from_le_bytes(c[4 * k..4 * k + 4].try_into().expect("4 bytes"));
            [i(0), i(1), i(2)]
        })
        .collect();
    let face_normals = flags & FACE_NORMALS != 0;
    let mesh = finish(
        positions,
        if face_normals { None } else { normals },
        texcoords,
        indices,
    )?;
    Ok(Serialized { mesh, face_normals })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// One mesh of a version-4 file (single precision), uncompressed body
    /// `body` deflated after the header.
    fn mesh_bytes(
        version: u16,
        flags: u32,
        pos: &[f32],
        normals: Option<&[f32]>,
        tris: &[u32],
    ) -> Vec<u8> {
        let mut body = Vec::new();
        body.extend_from_slice(&flags.to_le_bytes());
        if version == 4 {
            body.extend_from_slice(b"mesh\0");
        }
        body.extend_from_slice(&((pos.len() / 3) as u64).to_le_bytes());
        body.extend_from_slice(&((tris.len() / 3) as u64).to_le_bytes());
        for v in pos.iter().chain(normals.unwrap_or(&[])) {
            body.extend_from_slice(&v.to_le_bytes());
        }
        for i in tris {
            body.extend_from_slice(&i.to_le_bytes());
        }
        let mut out = Vec::new();
        out.extend_from_slice(&MAGIC.to_le_bytes());
        out.extend_from_slice(&version.to_le_bytes());
        let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        e.write_all(&body).unwrap();
        out.extend_from_slice(&e.finish().unwrap());
        out
    }

    fn file(version: u16, meshes: &[Vec<u8>]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut offsets = Vec::new();
        for m in meshes {
            offsets.push(out.len() as u64);
            out.extend_from_slice(m);
        }
        for o in offsets {
            if version == 4 {
                out.extend_from_slice(&o.to_le_bytes());
            } else {
                out.extend_from_slice(&(o as u32).to_le_bytes());
            }
        }
        out.extend_from_slice(&(meshes.len() as u32).to_le_bytes());
        out
    }

    const TRI: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

    #[test]
    fn reads_shape_index_0_and_later_meshes_in_both_versions() {
        for version in [3u16, 4] {
            let a = mesh_bytes(version, 0x1000, &TRI, None, &[0, 1, 2]);
            let quad = [0.0, 0.0, 2.0, 1.0, 0.0, 2.0, 1.0, 1.0, 2.0, 0.0, 1.0, 2.0];
            let n = [0.0, 0.0, 1.0].repeat(4);
            let b = mesh_bytes(version, 0x1001, &quad, Some(&n), &[0, 1, 2, 0, 2, 3]);
            let f = file(version, &[a, b]);
            let m0 = parse(&f, 0).unwrap();
            assert_eq!(m0.mesh.indices, vec![[0, 1, 2]]);
            assert!(m0.mesh.normals.is_none());
            let m1 = parse(&f, 1).unwrap();
            assert_eq!(m1.mesh.indices.len(), 2);
            assert_eq!(m1.mesh.positions[2], Vec3::new(1.0, 1.0, 2.0));
            assert_eq!(m1.mesh.normals.as_ref().unwrap()[3], Vec3::Z);
            let e = parse(&f, 2).err().unwrap();
            assert!(e.contains("shape_index 2 is out of range"), "{e}");
        }
    }

    #[test]
    fn hostile_counts_and_truncation_are_errors() {
        let mut f = file(4, &[mesh_bytes(4, 0x1000, &TRI, None, &[0, 1, 2])]);
        assert!(parse(&f[..10], 0).is_err());
        f[0] = 0;
        assert!(parse(&f, 0).err().unwrap().contains("identifier"));
        // A header declaring 2^40 vertices.
        let mut body = Vec::new();
        body.extend_from_slice(&0x1000u32.to_le_bytes());
        body.extend_from_slice(b"\0");
        body.extend_from_slice(&(1u64 << 40).to_le_bytes());
        body.extend_from_slice(&1u64.to_le_bytes());
        let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        e.write_all(&body).unwrap();
        let mut g = vec![0x1C, 0x04, 4, 0];
        g.extend_from_slice(&e.finish().unwrap());
        assert!(parse(&g, 0)
            .err()
            .unwrap()
            .contains("more than the file can hold"));
    }
}
