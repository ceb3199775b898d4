use super::read::*;
use super::*;

fn field(dims: [usize; 3]) -> Vec<f32> {
    (0..dims[0] * dims[1] * dims[2])
        .map(|i| (i % 7) as f32 * 0.25 + 0.5)
        .collect()
}

#[test]
fn round_trip_dense() {
    let dims = [13, 9, 20];
    let data = field(dims);
    let b = encode_float_grid("density", &data, dims, [0.5; 3], [1.0, -2.0, 3.0]).unwrap();
    let g = parse_float_grid(Path::new("t.vdb"), &b, "density").unwrap();
    assert_eq!(g.dims, dims);
    assert_eq!(g.index_min, [0; 3]);
    assert_eq!(g.data, data);
    assert_eq!(g.background, 0.0);
    assert_eq!(g.world_bbox().unwrap(), [1.0, -2.0, 3.0, 7.5, 2.5, 13.0]);
    assert_eq!(g.index_to_world[0][3], 1.25);
    // As a unit-cube .vol grid: voxel (x, y, z) centred at (idx + 0.5)/n
    // in the cube lands on the VDB voxel centre origin + (idx + 0.5) s.
    let (vol, m) = g.clone().into_unit_cube_vol();
    assert_eq!(vol.shape, dims);
    assert_eq!(vol.at(3, 4, 5, 0), g.at(3, 4, 5));
    let u = [3.5 / 13.0, 4.5 / 9.0, 5.5 / 20.0];
    let w: Vec<f64> = (0..3)
        .map(|r| (0..3).map(|c| m[r][c] * u[c]).sum::<f64>() + m[r][3])
        .collect();
    for (k, want) in [1.0 + 3.5 * 0.5, -2.0 + 4.5 * 0.5, 3.0 + 5.5 * 0.5]
        .into_iter()
        .enumerate()
    {
        assert!((w[k] - want).abs() < 1e-12, "{w:?}");
    }
}

#[test]
fn zero_leaves_are_sparse_and_read_back_as_background() {
    // Only a 2x2x2 block far from the origin is non-zero.
    let dims = [40, 30, 20];
    let mut data = vec![0f32; 40 * 30 * 20];
    for (x, y, z) in [(33, 21, 17), (34, 22, 18)] {
        data[(z * 30 + y) * 40 + x] = 2.0;
    }
    let b = encode_float_grid("density", &data, dims, [1.0, 2.0, 3.0], [0.0; 3]).unwrap();
    // Internal-node masks are a fixed 8 KiB; the dense grid would be 96 kB.
    assert!(b.len() < 12_000, "{} bytes", b.len());
    let g = parse_float_grid(Path::new("t.vdb"), &b, "density").unwrap();
    // Active box: the written leaf [32, 40) x [16, 24) x [16, 20).
    assert_eq!(g.index_min, [32, 16, 16]);
    assert_eq!(g.dims, [8, 8, 4]);
    assert_eq!(g.at(1, 5, 1), 2.0);
    assert_eq!(g.at(2, 6, 2), 2.0);
    assert_eq!(g.data.iter().filter(|&&v| v != 0.0).count(), 2);
    assert_eq!(g.index_to_world[1][1], 2.0);
    assert_eq!(g.index_to_world[2][3], 1.5);
}

#[test]
fn large_grid_spans_several_internal_nodes() {
    let dims = [130, 3, 2];
    let data = field(dims);
    let b = encode_float_grid("sigma_t", &data, dims, [0.1; 3], [0.0; 3]).unwrap();
    let g = parse_float_grid(Path::new("t.vdb"), &b, "sigma_t").unwrap();
    assert_eq!(g.data, data);
    let e = parse_float_grid(Path::new("t.vdb"), &b, "density").unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.vdb: no grid named 'density' (grids: sigma_t (Tree_float_5_4_3))"
    );
}

#[test]
fn deterministic_bytes() {
    let dims = [5, 6, 7];
    let a = encode_float_grid("density", &field(dims), dims, [1.0; 3], [0.0; 3]).unwrap();
    let b = encode_float_grid("density", &field(dims), dims, [1.0; 3], [0.0; 3]).unwrap();
    assert_eq!(a, b);
}

#[test]
fn hostile_bytes_give_errors_not_panics() {
    let dims = [9, 9, 9];
    let good = encode_float_grid("density", &field(dims), dims, [1.0; 3], [0.0; 3]).unwrap();
    let p = Path::new("bad.vdb");
    // Every truncation.
    for n in 0..good.len() {
        let e = parse_float_grid(p, &good[..n], "density").unwrap_err();
        let m = e.to_string();
        assert!(m.starts_with("bad.vdb: "), "{m}");
        assert!(!m.contains('\n'));
    }
    // Every single-byte corruption to 0xff and 0x80 (lengths, counts,
    // masks, metadata bytes, offsets).
    for i in 0..good.len() {
        for v in [0xffu8, 0x80, 0x00] {
            let mut b = good.clone();
            b[i] = v;
            if let Err(e) = parse_float_grid(p, &b, "density") {
                assert!(e.to_string().starts_with("bad.vdb: "));
            }
        }
    }
}

#[test]
fn absurd_bounding_box_is_refused_before_allocating() {
    // Two active root tiles 2^24 voxels apart: a 2^72-voxel box.
    let tile_file = hand_made_tiles();
    let e = parse_float_grid(Path::new("big.vdb"), &tile_file, "density").unwrap_err();
    assert!(e.to_string().contains("more than the"), "{e}");
}

/// A file whose root holds two active tiles far apart.
fn hand_made_tiles() -> Vec<u8> {
    let dims = [1, 1, 1];
    let good = encode_float_grid("density", &[1.0], dims, [1.0; 3], [0.0; 3]).unwrap();
    // Locate the topology: after "buffer count 1, background 0".
    let mut r = Reader { b: &good, pos: 0 };
    let (mut r2, _) = read_header(&good).unwrap();
    let d = read_descriptor(&mut r2).unwrap();
    r.pos = d.grid_pos as usize;
    r.u32().unwrap();
    skip_metadata(&mut r).unwrap();
    read_map(&mut r).ok().unwrap();
    let topo = r.pos;
    let mut b = good[..topo].to_vec();
    b.extend_from_slice(&1u32.to_le_bytes());
    b.extend_from_slice(&0f32.to_le_bytes());
    b.extend_from_slice(&2u32.to_le_bytes()); // two tiles
    b.extend_from_slice(&0u32.to_le_bytes()); // no children
    for o in [0i32, 1 << 24] {
        for _ in 0..3 {
            b.extend_from_slice(&o.to_le_bytes());
        }
        b.extend_from_slice(&1f32.to_le_bytes());
        b.push(1);
    }
    // Fix end offset.
    let end = b.len() as i64;
    let off = d.grid_pos as usize - 8;
    b[off..off + 8].copy_from_slice(&end.to_le_bytes());
    b
}

/// Written by the reference implementation (OpenVDB 10.0.1, Debian's
/// python3-openvdb) with its defaults (Blosc LZ4 + byte shuffle, active
/// mask compression), by this script under /usr/bin/python3:
///
/// ```python
/// import numpy as np, pyopenvdb as vdb
/// g = vdb.FloatGrid(); g.name = "density"; g.gridClass = vdb.GridClass.FOG_VOLUME
/// i, j, k = np.meshgrid(np.arange(12), np.arange(5), np.arange(9), indexing="ij")
/// g.copyFromArray(((i + 2*j + 3*k) * 0.125 + 0.5).astype(np.float32), ijk=(-3, 4, 10), tolerance=0.0)
/// g.fill((16, 0, 8), (23, 7, 15), 0.75, active=True)
/// g.transform = vdb.createLinearTransform([[0, .5, 0, 0], [-.5, 0, 0, 0], [0, 0, .5, 0], [1, 2, 3, 1]])
/// h = vdb.Vec3SGrid(); h.name = "vel"
/// vdb.write("reference_blosc.vdb", grids=[g, h])
/// ```
const REFERENCE: &[u8] = include_bytes!("../../tests/data/reference_blosc.vdb");

#[test]
fn reads_the_reference_implementations_blosc_file() {
    let p = Path::new("reference_blosc.vdb");
    let g = parse_float_grid(p, REFERENCE, "density").unwrap();
    assert_eq!(g.index_min, [-3, 0, 8]);
    assert_eq!(g.dims, [27, 9, 11]);
    let mut n_active = 0;
    for z in 0..11 {
        for y in 0..9 {
            for x in 0..27 {
                let (i, j, k) = (x as i32 - 3, y as i32, z as i32 + 8);
                let want = if (-3..9).contains(&i) && (4..9).contains(&j) && (10..19).contains(&k) {
                    ((i + 3) + 2 * (j - 4) + 3 * (k - 10)) as f32 * 0.125 + 0.5
                } else if (16..24).contains(&i) && (0..8).contains(&j) && (8..16).contains(&k) {
                    0.75 // an active tile of the lower internal node
                } else {
                    0.0
                };
                assert_eq!(g.at(x, y, z), want, "voxel {:?}", (i, j, k));
                n_active += (want != 0.0) as usize;
            }
        }
    }
    assert_eq!(n_active, 1052);
    let m = g.index_to_world;
    assert_eq!(m[0], [0.0, -0.5, 0.0, 1.0]);
    assert_eq!(m[1], [0.5, 0.0, 0.0, 2.0]);
    assert_eq!(m[2], [0.0, 0.0, 0.5, 3.0]);
    assert_eq!(g.world_bbox(), None);
    let e = parse_float_grid(p, REFERENCE, "vel")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("has type Tree_vec3s_5_4_3; only float grids"),
        "{e}"
    );
    assert_eq!(
        list_grids(p, REFERENCE).unwrap(),
        vec![
            ("density".to_string(), "Tree_float_5_4_3".to_string()),
            ("vel".to_string(), "Tree_vec3s_5_4_3".to_string())
        ]
    );
}

#[test]
fn hostile_blosc_bytes_give_errors_not_panics() {
    let p = Path::new("bad.vdb");
    // The file is complete for "density" once its grid has ended.
    let (mut r, _) = read_header(REFERENCE).unwrap();
    let end = read_descriptor(&mut r).unwrap().end_pos as usize;
    assert!(end < REFERENCE.len());
    for n in (0..end).step_by(7) {
        assert!(parse_float_grid(p, &REFERENCE[..n], "density").is_err());
    }
    // Every byte of the header, descriptors, metadata and transform;
    // every 5th of the tree (masks, metadata bytes, Blosc headers).
    let positions = (0..1024).chain((1024..end).step_by(5));
    for i in positions {
        for v in [0xffu8, 0x00] {
            let mut b = REFERENCE.to_vec();
            b[i] = v;
            if let Err(e) = parse_float_grid(p, &b, "density") {
                assert!(e.to_string().starts_with("bad.vdb: "));
            }
        }
    }
}

#[test]
fn half_floats_decode() {
    assert_eq!(f16_to_f32(0x3c00), 1.0);
    assert_eq!(f16_to_f32(0xc000), -2.0);
    assert_eq!(f16_to_f32(0x0001), (-24f32).exp2());
    assert_eq!(f16_to_f32(0x7c00), f32::INFINITY);
    assert_eq!(f16_to_f32(0x3555), 0.333_251_95);
}
