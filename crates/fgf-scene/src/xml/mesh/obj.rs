//! OBJ meshes, parsed by `tobj`.

use super::{finish, read_file};
use crate::desc::TriangleMesh;
use crate::error::{SceneError, SceneErrorKind};
use crate::xml::document::XNode;
use glam::{Vec2, Vec3};
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
    let mut texcoords = Vec::new();
    let mut all_texcoords = true;
    let mut indices = Vec::new();
    // tobj numbers the vertices of each `o`/`g` group separately, while
    // Mitsuba shares one `v/vt/vn` vertex across groups (it matters for the
    // computed smooth normals). tobj does not report the file's indices, so
    // a vertex is shared with an earlier group when its position, texture
    // coordinate and normal are bitwise equal; within one group tobj's own
    // index-based numbering is kept. (The first group has nothing to share
    // and the last none to share with: a file of one group, the common
    // case, hashes no vertex.)
    type Key = ([u32; 3], [u32; 2], [u32; 3]);
    let mut earlier: HashMap<Key, u32> = HashMap::new();
    for (g, m) in models.iter().enumerate() {
        let last = g + 1 == models.len();
        let mesh = &m.mesh;
        let nv = mesh.positions.len() / 3;
        let has_n = mesh.normals.len() == mesh.positions.len();
        let has_tc = mesh.texcoords.len() == 2 * nv;
        all_normals &= has_n;
        all_texcoords &= has_tc;
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
            let shared = if earlier.is_empty() {
                None
            } else {
                earlier.get(&key).copied()
            };
            let id = match shared {
                Some(id) => id,
                None => {
                    let id = u32::try_from(positions.len())
                        .map_err(|_| fmt("more than 2^32 vertices".into()))?;
                    positions.push(p);
                    normals.push(n);
                    // Mitsuba 3 flips v: an image's top row is v = 0.
                    texcoords.push(Vec2::new(tc[0], 1.0 - tc[1]));
                    if !last {
                        mine.push((key, id));
                    }
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
        (all_texcoords && !texcoords.is_empty()).then_some(texcoords),
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
    let mut total = [0i64; 3];
    for line in lines(bytes) {
        if let Some(k) = words(line, |w| w.next().and_then(kind_of)) {
            total[k] += 1;
        }
    }
    let mut so_far = [0i64; 3];
    for (n, line) in lines(bytes).enumerate() {
        words(line, |words| check_line(words, n, &total, &mut so_far))?;
    }
    Ok(())
}

/// The pieces of `bytes.split(|&b| b == b'\n')`, the line ends found by
/// `memchr` rather than a byte at a time.
fn lines(bytes: &[u8]) -> impl Iterator<Item = &[u8]> {
    let mut start = 0;
    let ends = memchr::memchr_iter(b'\n', bytes).chain([bytes.len()]);
    ends.map(move |end| {
        let line = &bytes[start..end];
        start = end + 1;
        line
    })
}

/// `f(words)` with the words of `line` as `str::split_whitespace` gives
/// them (none for a line that is not UTF-8, which tobj refuses anyway). An
/// ASCII line is split at its bytes that `char::is_whitespace` takes for
/// spaces, without decoding: the check with `str` methods throughout took
/// 2.1 s of a 4M-face file's 5.9 s load (`docs/benchmarks.md`, "OBJ
/// files").
fn words<'a, R>(line: &'a [u8], f: impl FnOnce(&mut dyn Iterator<Item = &'a [u8]>) -> R) -> R {
    if line.is_ascii() {
        let space = |b: &u8| *b == b' ' || (b'\t'..=b'\r').contains(b);
        f(&mut line.split(space).filter(|w| !w.is_empty()))
    } else {
        let line = std::str::from_utf8(line).unwrap_or("");
        f(&mut line.split_whitespace().map(str::as_bytes))
    }
}

/// The check of [`check_face_indices`] of line `n` (from 0), given by its
/// `words`: the counts `so_far` of each kind of element before it are
/// brought up to date, and a face's or a line's indices checked against
/// them and the file's `total`.
fn check_line(
    words: &mut dyn Iterator<Item = &[u8]>,
    n: usize,
    total: &[i64; 3],
    so_far: &mut [i64; 3],
) -> Result<(), String> {
    const KINDS: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    match words.next() {
        Some(b"f" | b"l") => {}
        Some(w) => {
            if let Some(k) = kind_of(w) {
                so_far[k] += 1;
            }
            return Ok(());
        }
        None => return Ok(()),
    }
    for word in words {
        for (k, part) in word.split(|&b| b == b'/').take(3).enumerate() {
            let Some(x) = parse_i64(part) else { continue };
            let ok = if x > 0 {
                x <= total[k]
            } else {
                x < 0 && x >= -so_far[k]
            };
            if !ok {
                return Err(format!(
                    "line {}: face index {x} names no {} (valid: 1 to {}, or -{} to -1 counting back from this line)",
                    n + 1,
                    KINDS[k],
                    total[k],
                    so_far[k]
                ));
            }
        }
    }
    Ok(())
}

/// The kind of element (0 vertex, 1 texture coordinate, 2 normal) that a
/// line starting with the word `w` declares, if any.
fn kind_of(w: &[u8]) -> Option<usize> {
    match w {
        b"v" => Some(0),
        b"vt" => Some(1),
        b"vn" => Some(2),
        _ => None,
    }
}

/// `s` as `str::parse::<i64>` reads it (an optional sign, then one or more
/// ASCII digits, within range), from bytes.
fn parse_i64(s: &[u8]) -> Option<i64> {
    let (neg, digits) = match s {
        [b'-', rest @ ..] => (true, rest),
        [b'+', rest @ ..] => (false, rest),
        _ => (false, s),
    };
    if digits.is_empty() {
        return None;
    }
    let mut x = 0i64;
    for &b in digits {
        let d = i64::from(b.wrapping_sub(b'0'));
        if d > 9 {
            return None;
        }
        // Negative numbers gather below zero, which reaches `i64::MIN`.
        x = x.checked_mul(10)?;
        x = if neg {
            x.checked_sub(d)?
        } else {
            x.checked_add(d)?
        };
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::{check_face_indices, lines, parse_i64};

    #[test]
    fn lines_are_the_pieces_between_line_feeds() {
        for b in [
            "",
            "\n",
            "\n\n",
            "a",
            "a\n",
            "a\nb",
            "\na\n\nbc\n",
            "a\r\nb",
        ] {
            let want: Vec<&[u8]> = b.as_bytes().split(|&c| c == b'\n').collect();
            assert_eq!(lines(b.as_bytes()).collect::<Vec<_>>(), want, "{b:?}");
        }
    }

    /// The bytes' parse is `str`'s, on edge cases and on every string of
    /// up to three characters from a small alphabet.
    #[test]
    fn parse_i64_is_strs() {
        let mut cases: Vec<String> = [
            "",
            "+",
            "-",
            "0",
            "-0",
            "+0",
            "007",
            "12a",
            "1 ",
            " 1",
            "--1",
            "+-1",
            "1.0",
            "1e3",
            "9223372036854775807",
            "9223372036854775808",
            "-9223372036854775808",
            "-9223372036854775809",
            "+9223372036854775807",
            "99999999999999999999",
        ]
        .map(String::from)
        .to_vec();
        let alphabet = ["", "0", "7", "9", "+", "-", "/", "a", ":", " "];
        for a in alphabet {
            for b in alphabet {
                for c in alphabet {
                    cases.push(format!("{a}{b}{c}"));
                }
            }
        }
        for s in &cases {
            assert_eq!(parse_i64(s.as_bytes()), s.parse::<i64>().ok(), "{s:?}");
        }
    }

    /// Words are split as `split_whitespace` splits them: at the ASCII
    /// spaces it knows (the vertical tab and form feed among them) and at
    /// a non-ASCII one, and a line that is not UTF-8 has none.
    #[test]
    fn face_words_split_as_str_splits_them() {
        let three = b"v 0 0 0\nv 0 0 0\nv 0 0 0\n";
        for sep in [
            " ", "\t", "\x0b", "\x0c", "\r", " \t ", "\u{a0}", "\u{2003}",
        ] {
            let mut ok = three.to_vec();
            ok.extend(format!("f{sep}1{sep}2{sep}3{sep}\n").as_bytes());
            assert!(check_face_indices(&ok).is_ok(), "{sep:?}");
            let mut bad = three.to_vec();
            bad.extend(format!("f{sep}1{sep}2{sep}4\n").as_bytes());
            let e = check_face_indices(&bad).unwrap_err();
            assert!(e.starts_with("line 4: face index 4"), "{sep:?}: {e}");
        }
        // Not UTF-8: the line is left to tobj, and counts no vertex.
        let mut b = three.to_vec();
        b.extend(b"f 1 2 9 \xff\nv 0 0 0 \xff\nf 1 2 4\n");
        let e = check_face_indices(&b).unwrap_err();
        assert!(e.starts_with("line 6: face index 4"), "{e}");
    }

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
