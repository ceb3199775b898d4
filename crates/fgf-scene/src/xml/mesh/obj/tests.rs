//! Tests of the OBJ reader, against `tobj` as we used it before (with our
//! check of the face indices and our sharing of vertices across groups)
//! on generated files, and on cases of its own.

use super::super::Trickle;
use super::{lines, parse_i64, read_obj, words, ObjMesh};
use glam::{Vec2, Vec3};
use rand::{Rng, SeedableRng};
use std::collections::HashMap;

/// The mesh that `tobj` and our checks gave for `bytes` before our own
/// reader replaced them (the reference of [`reads_as_tobj_did`]), and the
/// number of vertices of `tobj`'s groups before we shared them.
fn reference(bytes: &[u8]) -> Result<(ObjMesh, usize), String> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    check_face_indices(bytes)?;
    let mut reader = std::io::BufReader::new(bytes);
    let (models, _materials) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| e.to_string())?;
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
                    let id =
                        u32::try_from(positions.len()).map_err(|_| "more than 2^32 vertices")?;
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
                return Err(format!("object '{}' has a face index out of range", m.name));
            }
            indices.push([ids[t[0] as usize], ids[t[1] as usize], ids[t[2] as usize]]);
        }
    }
    let mesh = ObjMesh {
        positions,
        normals: (all_normals && !normals.is_empty()).then_some(normals),
        texcoords: (all_texcoords && !texcoords.is_empty()).then_some(texcoords),
        indices,
    };
    let unshared = models.iter().map(|m| m.mesh.positions.len() / 3).sum();
    Ok((mesh, unshared))
}

/// The check of the face indices that ran before `tobj`.
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

/// The check of one line, `n` (from 0), given by its `words`.
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

/// A mesh's positions, normals and texture coordinates as bits, and its
/// indices.
type Bits<'a> = (
    Vec<[u32; 3]>,
    Option<Vec<[u32; 3]>>,
    Option<Vec<[u32; 2]>>,
    &'a [[u32; 3]],
);

/// The bits of a mesh, so that meshes with NaNs compare as equal when
/// they are the same.
fn bits(m: &ObjMesh) -> Bits<'_> {
    let v3 = |v: &Vec<Vec3>| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
    let v2 = |v: &Vec<Vec2>| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
    (
        v3(&m.positions),
        m.normals.as_ref().map(v3),
        m.texcoords.as_ref().map(v2),
        &m.indices,
    )
}

/// A random OBJ file, small, of the statements that matter and their edge
/// cases: few distinct numbers (so that vertices of different groups
/// coincide), indices in range, just out of it, negative, zero, ahead of
/// their element; groups, comments, materials, CRLF ends, tabs, a
/// non-ASCII space; and now and then a malformed line.
fn random_obj(rng: &mut impl Rng) -> String {
    const NUMBERS: [&str; 12] = [
        "0", "1", "-1", "0.5", ".25", "+2", "1e-3", "-0.0", "3.", "1E2", "nan", "inf",
    ];
    let spaces = [" ", " ", " ", "\t", "  ", "\u{a0}"];
    let colours = rng.random_bool(0.1);
    let mut s = String::new();
    let (mut nv, mut nt, mut nn) = (0i64, 0i64, 0i64);
    let lines = rng.random_range(1..40);
    let end = if rng.random_bool(0.2) { "\r\n" } else { "\n" };
    let num = |rng: &mut dyn rand::RngCore| {
        // Mostly finite values, so that most files load.
        let k = if rng.random_bool(0.97) { 10 } else { 12 };
        NUMBERS[rng.random_range(0..k)]
    };
    for _ in 0..lines {
        let sp = if rng.random_bool(0.95) {
            " "
        } else {
            spaces[rng.random_range(0..spaces.len())]
        };
        let r = rng.random_range(0..1000);
        let line = if r < 300 {
            nv += 1;
            let mut l = format!("v{sp}{}{sp}{}{sp}{}", num(rng), num(rng), num(rng));
            if colours {
                l += &format!(" {} {} {}", num(rng), num(rng), num(rng));
            } else if rng.random_bool(0.05) {
                l += &format!(" {}", ["2", "0.5", "0", "-1"][rng.random_range(0..4)]);
            } else if rng.random_bool(0.01) {
                l += " 1 2";
            }
            if rng.random_bool(0.01) {
                l = format!("v {}", num(rng));
            }
            l
        } else if r < 400 {
            nt += 1;
            let extra = if rng.random_bool(0.1) { " 0" } else { "" };
            if rng.random_bool(0.02) {
                format!("vt {}", num(rng))
            } else {
                format!("vt{sp}{}{sp}{}{extra}", num(rng), num(rng))
            }
        } else if r < 480 {
            nn += 1;
            format!("vn{sp}{}{sp}{}{sp}{}", num(rng), num(rng), num(rng))
        } else if r < 850 {
            let corners = if rng.random_bool(0.01) {
                0
            } else {
                [1, 2, 3, 3, 3, 3, 4, 4, 5, 6][rng.random_range(0..10)]
            };
            let form = rng.random_range(0..4);
            let mut l = "f".to_string();
            for _ in 0..corners {
                let index = |n: i64, rng: &mut dyn rand::RngCore| -> String {
                    let x = match rng.random_range(0..1000) {
                        0 => 0,
                        1 => n + 1,
                        2 => n + 3,
                        3 => -n - 1,
                        4..=200 if n > 0 => -rng.random_range(1..=n),
                        _ => rng.random_range(1..=n.max(1)),
                    };
                    x.to_string()
                };
                let c = match form {
                    0 => index(nv, rng),
                    1 => format!("{}/{}", index(nv, rng), index(nt, rng)),
                    2 => format!("{}//{}", index(nv, rng), index(nn, rng)),
                    _ => format!("{}/{}/{}", index(nv, rng), index(nt, rng), index(nn, rng)),
                };
                let c = match rng.random_range(0..200) {
                    0 => format!("{c}/"),
                    1 => format!("{c}/1"),
                    2 => format!("/{c}"),
                    3 => "x".to_string(),
                    _ => c,
                };
                l += sp;
                l += &c;
            }
            l
        } else if r < 910 {
            let g = ["o", "g"][rng.random_range(0..2)];
            if rng.random_bool(0.5) {
                format!("{g} part{}", rng.random_range(0..5))
            } else {
                g.to_string()
            }
        } else if r < 930 {
            let m = [
                "usemtl red",
                "usemtl  red ",
                "mtllib scene.mtl",
                "usemtl",
                "usemtl\tred",
            ];
            let kinds = if rng.random_bool(0.9) { 3 } else { 5 };
            m[rng.random_range(0..kinds)].to_string()
        } else if r < 995 {
            ["# a comment", "", "s 1", "s off", "#v 1 2 3", "  "][rng.random_range(0..6)]
                .to_string()
        } else {
            ["vp 0 0", "v 1 2 x", "vn 0 0", "f 1 2 3a", "curv 0 1"][rng.random_range(0..5)]
                .to_string()
        };
        s += &line;
        s += end;
    }
    if rng.random_bool(0.2) {
        s.truncate(s.trim_end().len());
    }
    s
}

/// On thousands of generated files, our reader gives what `tobj` and our
/// checks gave: the same mesh, bit for bit (positions, normals, texture
/// coordinates and the vertex numbering), or an error where they gave one.
#[test]
fn reads_as_tobj_did() {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    let (mut ok, mut err, mut shared, mut groups) = (0, 0, 0, 0);
    for case in 0..30_000 {
        let obj = random_obj(&mut rng);
        let ours = read_obj(obj.as_bytes());
        // The same, the file read a few bytes at a time, with interruptions.
        let trickle = Trickle::new(obj.as_bytes(), 1 + case % 7).interrupted_every(2 + case % 9);
        let trickled = read_obj(trickle);
        assert_eq!(
            ours.as_ref().map(bits),
            trickled.as_ref().map(bits),
            "case {case}"
        );
        let theirs = reference(obj.as_bytes());
        match (&ours, &theirs) {
            (Ok(a), Ok((b, unshared))) => {
                assert_eq!(bits(a), bits(b), "case {case}:\n{obj}");
                ok += 1;
                let group_lines = obj.lines().filter(|l| l.starts_with(['o', 'g'])).count();
                groups += usize::from(!a.indices.is_empty() && group_lines > 0);
                shared += usize::from(*unshared > a.positions.len());
            }
            (Err(_), Err(_)) => err += 1,
            _ => panic!("case {case}: ours {ours:?}, tobj's {theirs:?}\n{obj}"),
        }
    }
    // The comparison is not vacuous: many files load, many are refused,
    // many of those that load have several groups, and in many a vertex
    // is shared between groups.
    let counts = format!("{ok} loaded, {err} refused, {groups} in groups, {shared} shared");
    assert!(
        ok > 5_000 && err > 5_000 && groups > 1_000 && shared > 1_000,
        "{counts}"
    );
}

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
        assert!(read_obj(&ok[..]).is_ok(), "{sep:?}");
        let mut bad = three.to_vec();
        bad.extend(format!("f{sep}1{sep}2{sep}4\n").as_bytes());
        let e = read_obj(&bad[..]).unwrap_err();
        assert!(e.starts_with("line 4: face index 4"), "{sep:?}: {e}");
    }
    // Not UTF-8: refused, wherever it is.
    let mut b = three.to_vec();
    b.extend(b"f 1 2 3\n# \xff\n");
    let e = read_obj(&b[..]).unwrap_err();
    assert_eq!(e, "not UTF-8 text (at byte 35)");
}

/// An index that names no element is refused with its line and what is
/// valid, however large; so is one that names an element declared after
/// the end of its group (`tobj` resolved a group's faces there), though
/// one declared later in the same group is read.
#[test]
fn face_indices_name_elements() {
    let ok = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 -1/-1\n";
    assert_eq!(read_obj(&ok[..]).unwrap().indices, [[0, 1, 2]]);
    let ahead = b"v 0 0 0\nf 1 2 3\nv 1 0 0\nv 0 1 0\n";
    assert_eq!(read_obj(&ahead[..]).unwrap().indices, [[0, 1, 2]]);
    for (obj, want) in [
        (
            &b"v 0 0 0\nf 1 2 3\n"[..],
            "line 2: face index 2 names no vertex (the file has 1)",
        ),
        (
            b"v 0 0 0\nv 0 0 0\nv 0 0 0\nvt 0 0\nf 1/1 2/1 3/-9223372036854775808\n",
            "line 5: face index -9223372036854775808 names no texture coordinate",
        ),
        (
            b"v 0 0 0\nv 0 0 0\nv 0 0 0\nvn 0 0 1\nf 1//1 2//1 3//6148914691236517206\n",
            "line 5: face index 6148914691236517206 names no normal",
        ),
        (
            b"v 0 0 0\nf 0 1 1\n",
            "line 2: face index 0 names no vertex",
        ),
        (
            b"f -1 -1 -1\nv 0 0 0\n",
            "line 1: face index -1 names no vertex",
        ),
        (
            b"v 0 0 0\nf 1 2 3\ng\nv 1 0 0\nv 0 1 0\n",
            "line 2: face index 2 names a vertex not declared by the end of its group",
        ),
        (
            b"f 1 2\nv 0 0 0\n",
            "line 1: face index 2 names no vertex (the file has 1)",
        ),
        (
            b"v 0 0 0\nf 1 /1 1\n",
            "line 2: a face's corner has no vertex index",
        ),
        (b"v 0 0 0\nf\n", "line 2: a face with no vertices"),
        (
            b"v 0 0\n",
            "line 1: a vertex's x, y and z are not all given",
        ),
        (b"v 0 0 0 0\n", "line 1: a vertex's w is 0"),
        (
            b"vt 0 x\n",
            "line 1: 'x' is not a number (in a texture coordinate's u and v)",
        ),
        (b"usemtl\n", "line 1: usemtl without a material name"),
    ] {
        let e = read_obj(obj).unwrap_err();
        assert!(e.starts_with(want), "{e}");
    }
}

/// Vertex colours are ignored, also when only some vertices have one
/// (`tobj` refused such a file), and so are polylines (`tobj` read one of
/// three vertices or more as a face), as in Mitsuba.
#[test]
fn colours_on_some_vertices_are_ignored() {
    let obj = b"v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0.5 0.5 0.5\nf 1 2 3\n";
    assert!(reference(obj).is_err());
    let m = read_obj(&obj[..]).unwrap();
    assert_eq!(m.positions, [Vec3::ZERO, Vec3::X, Vec3::Y]);
    assert_eq!(m.indices, [[0, 1, 2]]);
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\nf 3 2 1\n";
    assert_eq!(reference(obj).unwrap().0.indices.len(), 2);
    let m = read_obj(&obj[..]).unwrap();
    assert_eq!(m.positions, [Vec3::Y, Vec3::X, Vec3::ZERO]);
    assert_eq!(m.indices, [[0, 1, 2]]);
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 9 -7\nf 1 2 3\n";
    assert!(reference(obj).is_err());
    assert_eq!(read_obj(&obj[..]).unwrap().indices, [[0, 1, 2]]);
}

/// Lines are found across the blocks the file is read in, a line longer
/// than a block included, and a byte that is not UTF-8 is placed in the
/// file, not in its block.
#[test]
fn lines_cross_blocks() {
    let long = format!("# {}\n", "x".repeat(3 * super::BLOCK));
    let mut obj = String::new();
    for i in 0..200_000 {
        obj += &format!("v {i} 0 0\n");
    }
    obj += &long;
    obj += "f 1 2 3\nf 199998 -1 -2";
    let m = read_obj(obj.as_bytes()).unwrap();
    let x: Vec<f32> = m.positions.iter().map(|p| p.x).collect();
    assert_eq!(x, [0.0, 1.0, 2.0, 199_997.0, 199_999.0, 199_998.0]);
    assert_eq!(m.indices, [[0, 1, 2], [3, 4, 5]]);
    let mut bad = obj.into_bytes();
    bad.extend(b"\n\xff");
    let at = bad.len();
    assert_eq!(
        read_obj(&bad[..]).unwrap_err(),
        format!("not UTF-8 text (at byte {at})")
    );
    let e = read_obj(&b"v 0 0 0\nf 1 2 3"[..]).unwrap_err();
    assert!(e.starts_with("line 2: face index 2"), "{e}");
}
