//! OBJ meshes, parsed by `tobj`.

use super::{finish, read_file};
use crate::desc::TriangleMesh;
use crate::error::{SceneError, SceneErrorKind};
use crate::xml::document::XNode;
use glam::Vec3;
use std::collections::HashMap;
use std::path::Path;

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
    check_face_indices(&bytes).map_err(fmt)?;
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

/// Refuse face indices that do not name an element of the file, before
/// `tobj` sees them: it turns an index into an array offset with unchecked
/// arithmetic (`vt * 2 + 1`, `vn * 3 + 2`), which for a hostile index wraps
/// and reads the wrong element, or panics where overflow is checked.
///
/// OBJ indices are 1-based; a negative index counts back from the elements
/// declared so far. A positive index may name an element declared later
/// in the file (tobj resolves faces at the end of each group). Lines tobj
/// would refuse anyway (unparsable numbers) are left to it.
fn check_face_indices(bytes: &[u8]) -> Result<(), String> {
    const KINDS: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    let kind_of = |w: &str| match w {
        "v" => Some(0),
        "vt" => Some(1),
        "vn" => Some(2),
        _ => None,
    };
    let lines = || {
        bytes
            .split(|&b| b == b'\n')
            .map(|l| std::str::from_utf8(l).unwrap_or(""))
    };
    let mut total = [0i64; 3];
    for line in lines() {
        if let Some(k) = line.split_whitespace().next().and_then(kind_of) {
            total[k] += 1;
        }
    }
    let mut so_far = [0i64; 3];
    for (n, line) in lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("f" | "l") => {}
            Some(w) => {
                if let Some(k) = kind_of(w) {
                    so_far[k] += 1;
                }
                continue;
            }
            None => continue,
        }
        for word in words {
            for (k, part) in word.split('/').take(3).enumerate() {
                let Ok(x) = part.parse::<i64>() else { continue };
                let ok = if x > 0 {
                    x <= total[k]
                } else {
                    x < 0 && x >= -so_far[k]
                };
                if !ok {
                    let have = if x > 0 { total[k] } else { so_far[k] };
                    return Err(format!(
                        "line {}: face index {x} names no {} (valid: 1..={have}, or -{have}..=-1 counting back)",
                        n + 1,
                        KINDS[k]
                    ));
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::check_face_indices;

    #[test]
    fn face_indices_are_checked_before_tobj() {
        let ok = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 -1/-1\n";
        assert!(check_face_indices(ok).is_ok());
        for (obj, line) in [
            (&b"v 0 0 0\nf 1 2 3\n"[..], "line 2"),
            (
                b"v 0 0 0\nv 0 0 0\nv 0 0 0\nvt 0 0\nf 1/1 2/1 3/-9223372036854775808\n",
                "line 5",
            ),
            (
                b"v 0 0 0\nv 0 0 0\nv 0 0 0\nvn 0 0 1\nf 1//1 2//1 3//6148914691236517206\n",
                "line 5",
            ),
            (b"v 0 0 0\nf 0 1 1\n", "line 2"),
            (b"f -1 -1 -1\nv 0 0 0\n", "line 1"),
        ] {
            let e = check_face_indices(obj).unwrap_err();
            assert!(e.starts_with(line), "{e}");
        }
    }
}
