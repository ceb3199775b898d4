//! Property test of the scene loader: deterministic random mutations of the
//! two reference scenes (byte flips, deletions, truncation, duplicated or
//! deleted lines, swapped attribute values, hostile numbers, injected
//! elements, odd defines) must never panic. Every mutant either loads, and
//! then satisfies the description's invariants (indices in range, finite
//! transforms, bounded film), or fails with an error naming the file.
//!
//! The fast test runs 3000 mutants (well under a second of loading in
//! release mode); the `#[ignore]`d one runs 60000 for the slow step.

mod common;

use common::reference_dir;
use fgf_scene::*;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

const WEIRD_NUMBERS: &[&str] = &[
    "NaN",
    "nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "-0",
    "1e39",
    "-1e300",
    "1e-320",
    "1e9",
    "4294967296",
    "99999999999999999999",
    "-2147483649",
    "abc",
    "",
    " ",
    "0x10",
    "1,2",
    "1 2 3 4",
    "$spp",
    "$",
    "$nope",
    "0.5.5",
    "1e",
    "+",
    "2147483647",
];

const INJECTIONS: &[&str] = &[
    r#"<ref id="nope"/>"#,
    r#"<ref name="interior" id="m"/>"#,
    r#"<include filename="cube-homogeneous.xml"/>"#,
    r#"<include filename="missing.xml"/>"#,
    r#"<float name="scale" value="-1"/>"#,
    r#"<integer name="width" value="1000000000"/>"#,
    r#"<medium type="homogeneous" id="m" name="interior"/>"#,
    r#"<bsdf type="twosided" id="t"><ref id="t"/></bsdf>"#,
    r#"<emitter type="spot"/>"#,
    r#"<shape type="ply"><string name="filename" value="density64.vol"/></shape>"#,
    r#"<shape type="obj"><string name="filename" value="density64.vol"/></shape>"#,
    r#"<volume type="gridvolume" name="density"><string name="filename" value="cube-homogeneous.xml"/></volume>"#,
    r#"<default name="spp" value="$res"/>"#,
    r#"<transform name="to_world"><scale value="0"/></transform>"#,
    r#"<phase type="hg"><float name="g" value="1"/></phase>"#,
    r#"<medium type="fgf" name="interior"><float name="hurst" value="0.5"/><float name="sw" value="1"/></medium>"#,
    "<!--",
    "]]>",
    "&amp;",
    "&undefined;",
    "<",
    "\u{0}",
];

fn mutate(rng: &mut Pcg64, text: &str) -> String {
    let mut s = text.to_string();
    for _ in 0..rng.random_range(1..=3) {
        let len = s.len().max(1);
        match rng.random_range(0..9) {
            0 => {
                // flip a byte (keep the result valid UTF-8)
                let mut b = s.into_bytes();
                if !b.is_empty() {
                    let i = rng.random_range(0..b.len());
                    b[i] = rng.random_range(0x20..0x7f);
                }
                s = String::from_utf8_lossy(&b).into_owned();
            }
            1 => {
                // delete a short range
                let i = rng.random_range(0..len);
                let j = (i + rng.random_range(1..20)).min(s.len());
                s = String::from_utf8_lossy(&s.as_bytes()[..i.min(s.len())]).into_owned()
                    + &String::from_utf8_lossy(&s.as_bytes()[j..]);
            }
            2 => {
                // truncate
                let i = rng.random_range(0..len);
                s = String::from_utf8_lossy(&s.as_bytes()[..i.min(s.len())]).into_owned();
            }
            3 | 4 => {
                // duplicate or delete a line
                let mut lines: Vec<&str> = s.lines().collect();
                if !lines.is_empty() {
                    let i = rng.random_range(0..lines.len());
                    if rng.random_bool(0.5) {
                        lines.insert(i, lines[i]);
                    } else {
                        lines.remove(i);
                    }
                }
                s = lines.join("\n");
            }
            5 | 6 => {
                // swap two attribute values, or replace one by a hostile value
                let spans = attr_values(&s);
                if spans.len() >= 2 {
                    let a = spans[rng.random_range(0..spans.len())];
                    let new = if rng.random_bool(0.5) {
                        let b = spans[rng.random_range(0..spans.len())];
                        s[b.0..b.1].to_string()
                    } else {
                        WEIRD_NUMBERS[rng.random_range(0..WEIRD_NUMBERS.len())].to_string()
                    };
                    s = format!("{}{}{}", &s[..a.0], new, &s[a.1..]);
                }
            }
            7 => {
                // inject an element after a random line
                let mut lines: Vec<String> = s.lines().map(String::from).collect();
                let i = rng.random_range(0..=lines.len());
                lines.insert(
                    i,
                    INJECTIONS[rng.random_range(0..INJECTIONS.len())].to_string(),
                );
                s = lines.join("\n");
            }
            _ => {
                // a random number token replaced by a random float of any magnitude
                let spans = attr_values(&s);
                if !spans.is_empty() {
                    let a = spans[rng.random_range(0..spans.len())];
                    let v: f64 =
                        (rng.random::<f64>() - 0.5) * 10f64.powi(rng.random_range(-40..40));
                    s = format!("{}{}{}", &s[..a.0], v, &s[a.1..]);
                }
            }
        }
    }
    s
}

/// Byte ranges of every attribute value (between the quotes).
fn attr_values(s: &str) -> Vec<(usize, usize)> {
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i + 1 < b.len() {
        if b[i] == b'=' && b[i + 1] == b'"' {
            let start = i + 2;
            if let Some(len) = s[start..].find('"') {
                out.push((start, start + len));
                i = start + len + 1;
                continue;
            }
        }
        i += 1;
    }
    out
}

/// Invariants of a successfully loaded description.
fn check_invariants(d: &SceneDesc) {
    let c = &d.sensor;
    assert!(c.width >= 1 && c.height >= 1 && (c.width as u64) * (c.height as u64) <= 1 << 26);
    assert!(c.fov > 0.0 && c.fov < 180.0 && c.near_clip > 0.0 && c.far_clip > c.near_clip);
    assert!(c.to_world.is_finite() && c.spp >= 1);
    assert!(c.medium.is_none_or(|m| m < d.media.len()));
    for s in &d.shapes {
        assert!(s.bsdf < d.bsdfs.len());
        assert!(s.interior.is_none_or(|m| m < d.media.len()));
        assert!(s.exterior.is_none_or(|m| m < d.media.len()));
        assert!(s.to_world.is_finite() && s.to_world.determinant() != 0.0);
    }
    for m in &d.media {
        if let MediumDesc::Homogeneous {
            sigma_t, albedo, ..
        } = m
        {
            assert!(sigma_t.iter().all(|v| v.is_finite() && *v >= 0.0));
            assert!(albedo.iter().all(|v| (0.0..=1.0).contains(v)));
        }
    }
}

fn run(count: usize, seed: u64) {
    let dir = reference_dir();
    let sources: Vec<(PathBuf, String)> = ["cube-homogeneous.xml", "cube-heterogeneous.xml"]
        .iter()
        .map(|n| {
            let p = dir.join(n);
            let t = std::fs::read_to_string(&p).unwrap();
            (p, t)
        })
        .collect();
    let mut rng = Pcg64::seed_from_u64(seed);
    let (mut loaded, mut failed) = (0usize, 0usize);
    for case in 0..count {
        let (path, text) = &sources[case % sources.len()];
        let mutant = mutate(&mut rng, text);
        let mut defines = Vec::new();
        if rng.random_bool(0.1) {
            let v = WEIRD_NUMBERS[rng.random_range(0..WEIRD_NUMBERS.len())];
            defines.push((
                ["spp", "res", "max_depth", "x"][rng.random_range(0..4)].to_string(),
                v.to_string(),
            ));
        }
        let name = path.display().to_string();
        let r = catch_unwind(AssertUnwindSafe(|| {
            load_str(&mutant, &name, &dir, &defines)
        }));
        match r {
            Err(_) => panic!("loader panicked on mutant #{case} (defines {defines:?}):\n{mutant}"),
            Ok(Ok(d)) => {
                if catch_unwind(AssertUnwindSafe(|| check_invariants(&d))).is_err() {
                    panic!("invariant broken for mutant #{case} (defines {defines:?}):\n{mutant}");
                }
                loaded += 1;
            }
            Ok(Err(e)) => {
                let m = e.to_string();
                assert!(
                    m.contains(".xml"),
                    "error does not name a file for mutant #{case}: {m}"
                );
                failed += 1;
            }
        }
    }
    eprintln!("{count} mutants: {loaded} loaded, {failed} rejected with an error");
    // Both outcomes must occur, or the mutations are not exercising the loader.
    assert!(
        loaded > count / 50 && failed > count / 2,
        "loaded {loaded}, failed {failed}"
    );
}

/// Mutants of small OBJ and PLY files (text and binary) through the loader.
fn run_meshes(count: usize, seed: u64) {
    let dir = tempfile::tempdir().unwrap();
    let obj = "# quad\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvn 0 0 1\nvt 0 0\nf 1/1/1 2/1/1 3/1/1 4/1/1\ng second\nv 0 0 1\nf 1 2 5\n";
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n4 0 1 2 3\n";
    let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n".to_vec();
    for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        bin.extend(v.to_le_bytes());
    }
    bin.push(3);
    for i in [0u32, 1, 2] {
        bin.extend(i.to_le_bytes());
    }
    let sources: [(&str, Vec<u8>); 3] = [
        ("obj", obj.as_bytes().to_vec()),
        ("ply", ply.as_bytes().to_vec()),
        ("ply", bin),
    ];
    let mut rng = Pcg64::seed_from_u64(seed);
    let (mut loaded, mut failed) = (0usize, 0usize);
    for case in 0..count {
        let (ty, src) = &sources[case % sources.len()];
        let mut b = src.clone();
        for _ in 0..rng.random_range(1..=3) {
            if b.is_empty() {
                break;
            }
            let i = rng.random_range(0..b.len());
            match rng.random_range(0..4) {
                0 => b[i] = rng.random(),
                1 => {
                    const ALPHABET: &[u8] = b" -0123456789/\nfvle.";
                    b[i] = ALPHABET[rng.random_range(0..ALPHABET.len())]
                }
                2 => {
                    let j = (i + rng.random_range(1..8)).min(b.len());
                    b.drain(i..j);
                }
                _ => b.truncate(i),
            }
        }
        let file = dir.path().join(format!("m.{ty}"));
        std::fs::write(&file, &b).unwrap();
        let xml = format!(
            "<scene version=\"3.0.0\"><shape type=\"{ty}\"><string name=\"filename\" value=\"m.{ty}\"/></shape></scene>"
        );
        let r = catch_unwind(AssertUnwindSafe(|| {
            load_str(&xml, "mesh.xml", dir.path(), &[])
        }));
        match r {
            Err(_) => panic!(
                "loader panicked on {ty} mutant #{case}: {:?}",
                String::from_utf8_lossy(&b)
            ),
            Ok(Ok(d)) => {
                if let GeometryDesc::Mesh(m) = &d.shapes[0].geometry {
                    let n = m.positions.len() as u32;
                    assert!(m.indices.iter().all(|t| t.iter().all(|&i| i < n)));
                    assert!(m
                        .normals
                        .as_ref()
                        .is_none_or(|ns| ns.len() == m.positions.len()));
                }
                loaded += 1;
            }
            Ok(Err(e)) => {
                assert!(e.to_string().contains("mesh.xml"), "{e}");
                failed += 1;
            }
        }
    }
    eprintln!("{count} mesh mutants: {loaded} loaded, {failed} rejected with an error");
    assert!(loaded > 0 && failed > 0, "loaded {loaded}, failed {failed}");
}

#[test]
fn mutated_meshes_never_panic() {
    run_meshes(1500, 0x0b1);
}

#[test]
#[ignore = "slow: 30000 mesh mutants, run by the slow test step"]
fn mutated_meshes_never_panic_many() {
    run_meshes(30_000, 0x91e);
}

#[test]
fn mutated_reference_scenes_never_panic() {
    run(3000, 0x5ce7e);
}

#[test]
#[ignore = "slow: 60000 mutants, run by the slow test step"]
fn mutated_reference_scenes_never_panic_many() {
    run(60_000, 0xf022);
}
