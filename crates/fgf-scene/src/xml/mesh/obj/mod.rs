//! OBJ meshes, read by our own parser in one pass over the file's bytes.
//!
//! It reads what the renderer uses: `v x y z [w]` (a `w` divides the
//! coordinates; three more values, vertex colours, are ignored), `vt u v`,
//! `vn x y z`, and `f` faces (`v`, `v/vt`, `v//vn`, `v/vt/vn`; indices from
//! 1, negative ones counting back from the line; n-gons fan-triangulated,
//! faces of one or two vertices skipped). `o` and `g` start a new group;
//! other statements (`l` polylines, `s`, `mtllib`, `usemtl`, ...) are
//! ignored, as Mitsuba ignores them.
//!
//! The numbering of the vertices, on which the computed smooth normals
//! depend, is the one `tobj` gave when it read our OBJ files (a test in
//! `tests.rs` compares the two on many generated files): within a group,
//! each distinct `v/vt/vn` triple is a vertex, numbered in the order the
//! faces first name it; a vertex of a later group whose position, texture
//! coordinate and normal are bitwise equal to one of an earlier group is
//! shared with it (Mitsuba merges the groups into one mesh). What it
//! accepts and refuses is `tobj`'s too, with our check of the face indices
//! before it, except for two cases where we now do as Mitsuba does: vertex
//! colours on only some vertices are no longer an error, and `l` lines are
//! ignored (`tobj` read one of three vertices or more as a face).
//!
//! We replaced `tobj` with this reader for the time and memory of large
//! files (`docs/benchmarks.md`, "Our own OBJ reader"): `tobj` makes a
//! `String` per line and keeps a 24-byte record per face corner, and the
//! indices it turns into offsets had to be checked in a pass of our own
//! before it (it wraps a hostile index instead of refusing it).

use super::{finish, open_file};
use crate::desc::TriangleMesh;
use crate::error::{SceneError, SceneErrorKind};
use crate::xml::document::XNode;
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

#[cfg(test)]
mod tests;

pub(crate) fn load_obj(fnode: &XNode, path: &Path) -> Result<TriangleMesh, SceneError> {
    let (file, _) = open_file(fnode, path, "OBJ")?;
    let fmt = |m: String| {
        fnode.err_kind(
            SceneErrorKind::Format,
            format!("invalid OBJ file '{}': {m}", path.display()),
        )
    };
    let mesh = read_obj(file).map_err(fmt)?;
    finish(mesh.positions, mesh.normals, mesh.texcoords, mesh.indices).map_err(fmt)
}

/// A mesh as the file gives it, before [`finish`] checks it.
#[derive(Debug, Default, PartialEq)]
struct ObjMesh {
    positions: Vec<Vec3>,
    /// Only if every vertex has one.
    normals: Option<Vec<Vec3>>,
    /// `(u, 1 − v)`, only if every vertex has one.
    texcoords: Option<Vec<Vec2>>,
    indices: Vec<[u32; 3]>,
}

/// The kinds of element a face's corner names, in the order of its
/// `v/vt/vn`.
const KINDS: [&str; 3] = ["vertex", "texture coordinate", "normal"];

/// A corner of a face: the indices (from 0) of its position, texture
/// coordinate and normal in the file, [`NONE`] where it has none.
type Corner = [u32; 3];

/// The index of an element a corner does not name.
const NONE: u32 = u32::MAX;

/// Elements of one kind a file may declare: [`NONE`] and the count must
/// fit in a `u32`.
const MAX_ELEMENTS: usize = u32::MAX as usize - 1;

/// The hasher of the maps from corners and vertices to their numbers:
/// `ahash` (std's SipHash made a 4M-face file's load 8 % slower when
/// `tobj` still read it). The numbering does not depend on it.
type Map<K> = HashMap<K, u32, ahash::RandomState>;

/// The file's elements declared so far.
#[derive(Default)]
struct Elements {
    positions: Vec<Vec3>,
    texcoords: Vec<[f32; 2]>,
    normals: Vec<Vec3>,
}

impl Elements {
    fn counts(&self) -> [usize; 3] {
        [
            self.positions.len(),
            self.texcoords.len(),
            self.normals.len(),
        ]
    }
}

/// The group (`o`/`g`) being read.
#[derive(Default)]
struct Group {
    /// The number of a vertex of the group by its position's index: the
    /// first of the group's vertices to have that position (unless the
    /// slot is stale: it holds a number of an earlier group). Most
    /// vertices are found here, without hashing.
    by_position: Vec<u32>,
    /// The numbers of the group's other vertices, by corner.
    numbers: Map<Corner>,
    /// Its vertices, in the order of their numbers.
    corners: Vec<Corner>,
    /// Its triangles, by its own vertex numbers.
    triangles: Vec<[u32; 3]>,
    /// Whether it has an `f` line (one that is skipped included): an `o`
    /// or `g` line then ends it.
    has_faces: bool,
    /// Indices of its triangles' corners that name an element declared
    /// later in the file: (line, kind, index from 0). Each must be
    /// declared by the end of the group.
    ahead: Vec<(usize, usize, u32)>,
}

/// The merged mesh of the groups read so far.
struct Merged {
    mesh: ObjMesh,
    normals: Vec<Vec3>,
    texcoords: Vec<Vec2>,
    all_normals: bool,
    all_texcoords: bool,
    /// The number of each vertex of the groups before the one being
    /// merged, by bitwise position, texture coordinate and normal.
    earlier: Map<([u32; 3], [u32; 2], [u32; 3])>,
}

/// Parse an OBJ file (see the module docs).
fn read_obj(src: impl Read) -> Result<ObjMesh, String> {
    let mut el = Elements::default();
    let mut group = Group::default();
    let mut merged = Merged {
        mesh: ObjMesh::default(),
        normals: Vec::new(),
        texcoords: Vec::new(),
        all_normals: true,
        all_texcoords: true,
        earlier: Map::default(),
    };
    // The greatest index of each kind that named an element not yet
    // declared, and its line: it must be declared by the end of the file.
    let mut ahead_max: [Option<(u32, usize)>; 3] = [None; 3];
    for_each_line(src, |n, line| {
        words(line, |w| -> Result<(), String> {
            let Some(first) = w.next() else {
                return Ok(());
            };
            let at = |m: String| format!("line {}: {m}", n + 1);
            match first {
                b"v" => {
                    let mut p = floats(w, "a vertex's x, y and z").map_err(at)?;
                    match (w.next(), w.next(), w.next(), w.next()) {
                        (None, ..) => {}
                        (Some(s), None, ..) => {
                            let scale = float(Some(s), "a vertex's w").map_err(at)?;
                            if scale == 0.0 {
                                return Err(at("a vertex's w is 0".into()));
                            }
                            p = p.map(|c| c / scale);
                        }
                        // x y z r g b: the colour is not used.
                        (Some(_), Some(_), Some(_), None) => {}
                        _ => {
                            return Err(at(
                                "a vertex has 3 values, 4 (with w) or 6 (with a colour)".into(),
                            ))
                        }
                    }
                    push(&mut el.positions, Vec3::from(p), 0).map_err(at)?;
                }
                b"vt" => {
                    let uv = floats(w, "a texture coordinate's u and v").map_err(at)?;
                    push(&mut el.texcoords, uv, 1).map_err(at)?;
                }
                b"vn" => {
                    let v = floats(w, "a normal's x, y and z").map_err(at)?;
                    push(&mut el.normals, Vec3::from(v), 2).map_err(at)?;
                }
                b"f" => {
                    group.has_faces = true;
                    let counts = el.counts();
                    let mut corners = 0;
                    let (mut a, mut b) = ([NONE; 3], [NONE; 3]);
                    for word in w {
                        let c = corner(word, &counts, n, &mut ahead_max).map_err(at)?;
                        corners += 1;
                        match corners {
                            1 => a = c,
                            2 => b = c,
                            _ => {
                                // Fan triangulation: (a, b, c), then (a, c, d)...
                                if [a, b, c].iter().any(|c| c[0] == NONE) {
                                    return Err(at("a face's corner has no vertex index".into()));
                                }
                                let t = [a, b, c].map(|c| group.number(c, &counts, n));
                                group.triangles.push(t);
                                b = c;
                            }
                        }
                    }
                    if corners == 0 {
                        return Err(at("a face with no vertices".into()));
                    }
                }
                b"o" | b"g" if group.has_faces => merged.add(&mut group, &el, false)?,
                b"usemtl" => {
                    // As tobj did: a material name is required.
                    let line = std::str::from_utf8(line).unwrap_or("");
                    if line.split_once(' ').map_or("", |s| s.1).trim().is_empty() {
                        return Err(at("usemtl without a material name".into()));
                    }
                }
                _ => {}
            }
            Ok(())
        })
    })?;
    merged.add(&mut group, &el, true)?;
    let counts = el.counts();
    for (k, ahead) in ahead_max.iter().enumerate() {
        if let Some((i, n)) = *ahead {
            if i as usize >= counts[k] {
                return Err(format!(
                    "line {}: face index {} names no {} (the file has {})",
                    n + 1,
                    u64::from(i) + 1,
                    KINDS[k],
                    counts[k]
                ));
            }
        }
    }
    let Merged {
        mut mesh,
        normals,
        texcoords,
        all_normals,
        all_texcoords,
        ..
    } = merged;
    let nonempty = !mesh.positions.is_empty();
    mesh.normals = (all_normals && nonempty).then_some(normals);
    mesh.texcoords = (all_texcoords && nonempty).then_some(texcoords);
    Ok(mesh)
}

/// The size of the blocks in which [`for_each_line`] reads a file.
const BLOCK: usize = 1 << 20;

/// `f(n, line)` for each line of `src`, `n` from 0, a line being what
/// `bytes.split(|&b| b == b'\n')` would give of all the bytes. They are
/// read in blocks, not held all at once (a 489 MB file took 0.5 GB more
/// memory, and the time to fill it; `docs/benchmarks.md`, "Our own OBJ
/// reader"), and must be UTF-8.
fn for_each_line(
    mut src: impl Read,
    mut f: impl FnMut(usize, &[u8]) -> Result<(), String>,
) -> Result<(), String> {
    let mut buf = vec![0u8; BLOCK];
    // Bytes in `buf`, bytes of the file before it, lines before it.
    let (mut filled, mut offset, mut n) = (0, 0, 0);
    loop {
        if filled == buf.len() {
            // A line longer than the buffer (the file's size bounds it).
            buf.resize(2 * buf.len(), 0);
        }
        let got = match src.read(&mut buf[filled..]) {
            Ok(got) => got,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(format!("cannot read it: {e}")),
        };
        filled += got;
        let end = if got == 0 {
            filled
        } else {
            match memchr::memrchr(b'\n', &buf[..filled]) {
                Some(i) => i + 1,
                None => continue,
            }
        };
        // Whole lines (all that is left at the end of the file).
        let block = &buf[..end];
        if let Err(e) = std::str::from_utf8(block) {
            let at = offset + e.valid_up_to() + 1;
            return Err(format!("not UTF-8 text (at byte {at})"));
        }
        let whole = block.strip_suffix(b"\n").unwrap_or(block);
        for line in lines(whole) {
            f(n, line)?;
            n += 1;
        }
        if got == 0 {
            return Ok(());
        }
        buf.copy_within(end..filled, 0);
        (filled, offset) = (filled - end, offset + end);
    }
}

/// The next `N` of `words` as numbers (`what` they are, for the error).
fn floats<const N: usize>(
    words: &mut dyn Iterator<Item = &[u8]>,
    what: &str,
) -> Result<[f32; N], String> {
    let mut x = [0.0; N];
    for c in &mut x {
        *c = float(words.next(), what)?;
    }
    Ok(x)
}

/// `x` pushed onto `v`, the elements of kind `k`, if there is room.
fn push<T>(v: &mut Vec<T>, x: T, k: usize) -> Result<(), String> {
    if v.len() >= MAX_ELEMENTS {
        return Err(format!("more than {MAX_ELEMENTS} {}s", KINDS[k]));
    }
    v.push(x);
    Ok(())
}

/// The number `word` gives, as `str::parse::<f32>` reads it.
fn float(word: Option<&[u8]>, what: &str) -> Result<f32, String> {
    let Some(word) = word else {
        return Err(format!("{what} are not all given"));
    };
    std::str::from_utf8(word)
        .ok()
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| {
            format!(
                "'{}' is not a number (in {what})",
                String::from_utf8_lossy(word)
            )
        })
}

/// The corner a face's `word` (`v`, `v/vt`, `v//vn`, `v/vt/vn`) names on
/// line `n`, given the `counts` of the elements declared before the line.
/// An index must name an element: from 1 to the file's count, or from
/// −(count so far) to −1. One beyond the elements declared so far is
/// checked at the end of the file, against the largest such of its kind
/// in `ahead_max`.
fn corner(
    word: &[u8],
    counts: &[usize; 3],
    n: usize,
    ahead_max: &mut [Option<(u32, usize)>; 3],
) -> Result<Corner, String> {
    let mut c = [NONE; 3];
    for (k, part) in word.split(|&b| b == b'/').enumerate() {
        if part.is_empty() {
            continue;
        }
        let Some(x) = parse_i64(part) else {
            return Err(format!(
                "'{}' is not a face index",
                String::from_utf8_lossy(part)
            ));
        };
        if k >= 3 {
            return Err(format!(
                "'{}' has more than v/vt/vn",
                String::from_utf8_lossy(word)
            ));
        }
        let so_far = counts[k] as i64;
        let i = if x > 0 && x <= MAX_ELEMENTS as i64 {
            x - 1
        } else if x < 0 && x >= -so_far {
            so_far + x
        } else {
            return Err(format!(
                "face index {x} names no {} (valid: 1 to the file's count, or -{so_far} to -1 counting back from this line)",
                KINDS[k]
            ));
        };
        let i = i as u32;
        if i as usize >= counts[k] && ahead_max[k].is_none_or(|(m, _)| i > m) {
            ahead_max[k] = Some((i, n));
        }
        c[k] = i;
    }
    Ok(c)
}

impl Group {
    /// The group's number for the vertex at corner `c` of a triangle on
    /// line `n`, a new one if the group has not met `c` before.
    ///
    /// A corner is numbered in the slot of its position if that slot is
    /// free (or stale), in the map otherwise; so a corner met before is
    /// either the one its slot names or in the map.
    fn number(&mut self, c: Corner, counts: &[usize; 3], n: usize) -> u32 {
        let v = c[0] as usize;
        if v >= self.by_position.len() && v < counts[0] {
            self.by_position.resize(counts[0], NONE);
        }
        let slot = self.by_position.get(v).copied();
        let taken = slot.filter(|&id| self.corners.get(id as usize).is_some_and(|d| d[0] == c[0]));
        if let Some(id) = taken {
            if self.corners[id as usize] == c {
                return id;
            }
        }
        if !self.numbers.is_empty() {
            if let Some(&id) = self.numbers.get(&c) {
                return id;
            }
        }
        let next = self.corners.len() as u32;
        for (k, &i) in c.iter().enumerate() {
            if i != NONE && i as usize >= counts[k] {
                self.ahead.push((n, k, i));
            }
        }
        self.corners.push(c);
        match (slot, taken) {
            (Some(_), None) => self.by_position[v] = next,
            _ => {
                self.numbers.insert(c, next);
            }
        }
        next
    }
}

impl Merged {
    /// Merge `group` into the mesh, given the file's elements declared
    /// by its end; `last` if no group follows it.
    /// The group is emptied, but for its slots.
    fn add(&mut self, group: &mut Group, el: &Elements, last: bool) -> Result<(), String> {
        // A new map rather than `clear`, which takes time in proportion to
        // the map's capacity: a large group followed by many small ones
        // would pay for the large one's map again at each.
        group.numbers = Map::default();
        group.has_faces = false;
        let ahead = std::mem::take(&mut group.ahead);
        let corners = std::mem::take(&mut group.corners);
        let triangles = std::mem::take(&mut group.triangles);
        let counts = el.counts();
        // An element named ahead must be declared by the end of the
        // group (as tobj resolved faces there). A texture coordinate or
        // normal of a group before the file's first is ignored.
        for &(n, k, i) in &ahead {
            if i as usize >= counts[k] && (k == 0 || counts[k] > 0) {
                let (x, kind) = (u64::from(i) + 1, KINDS[k]);
                return Err(if last {
                    format!(
                        "line {}: face index {x} names no {kind} (the file has {})",
                        n + 1,
                        counts[k]
                    )
                } else {
                    format!("line {}: face index {x} names a {kind} not declared by the end of its group", n + 1)
                });
            }
        }
        // Whether every vertex of the group has a texture coordinate
        // (k = 1) or normal (2): true for a group without vertices.
        let has = |k: usize| {
            let named = corners.iter().all(|c| c[k] != NONE);
            named && (counts[k] > 0 || corners.is_empty())
        };
        let (has_tc, has_n) = (has(1), has(2));
        self.all_texcoords &= has_tc;
        self.all_normals &= has_n;
        let share = !self.earlier.is_empty();
        let mut ids = Vec::with_capacity(if share { corners.len() } else { 0 });
        let mut mine = Vec::with_capacity(if last { 0 } else { corners.len() });
        // Without sharing, no earlier group has a vertex (a group that is
        // not the last puts all of its new ones in `earlier`), so the
        // group's own numbers are the mesh's.
        debug_assert!(share || self.mesh.positions.is_empty());
        for c in &corners {
            let p = el.positions[c[0] as usize];
            let tc = if has_tc {
                el.texcoords[c[1] as usize]
            } else {
                [0.0; 2]
            };
            let nrm = if has_n {
                el.normals[c[2] as usize]
            } else {
                Vec3::ZERO
            };
            let key = (
                p.to_array().map(f32::to_bits),
                tc.map(f32::to_bits),
                nrm.to_array().map(f32::to_bits),
            );
            if share {
                if let Some(&id) = self.earlier.get(&key) {
                    ids.push(id);
                    continue;
                }
            }
            let id = u32::try_from(self.mesh.positions.len())
                .ok()
                .filter(|&id| id != NONE)
                .ok_or("more than 2^32 - 1 vertices")?;
            self.mesh.positions.push(p);
            self.normals.push(nrm);
            // Mitsuba 3 flips v: an image's top row is v = 0.
            self.texcoords.push(Vec2::new(tc[0], 1.0 - tc[1]));
            if !last {
                mine.push((key, id));
            }
            if share {
                ids.push(id);
            }
        }
        for (key, id) in mine {
            self.earlier.entry(key).or_insert(id);
        }
        if share {
            let id = |i: u32| ids[i as usize];
            let tris = triangles.iter().map(|t| t.map(id));
            self.mesh.indices.extend(tris);
        } else {
            self.mesh.indices = triangles;
        }
        Ok(())
    }
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
/// them. An ASCII line is split at its bytes that `char::is_whitespace`
/// takes for spaces, without decoding (`docs/benchmarks.md`, "OBJ files").
fn words<'a, R>(line: &'a [u8], f: impl FnOnce(&mut dyn Iterator<Item = &'a [u8]>) -> R) -> R {
    if line.is_ascii() {
        let space = |b: &u8| *b == b' ' || (b'\t'..=b'\r').contains(b);
        f(&mut line.split(space).filter(|w| !w.is_empty()))
    } else {
        let line = std::str::from_utf8(line).unwrap_or("");
        f(&mut line.split_whitespace().map(str::as_bytes))
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
