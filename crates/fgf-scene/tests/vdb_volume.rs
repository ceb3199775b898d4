//! `gridvolume` with an OpenVDB `.vdb` file (an fgf extension): the grid is
//! placed by the file's own transform, so a field written as `.vdb` and as a
//! `.vol` with `use_grid_bbox` puts every voxel at the same world point with
//! the same value; the `grid` parameter and the refusals.

use fgf_scene::{load_str, MediumDesc, SceneDesc, VolumeDesc};
use glam::Vec3;
use std::path::Path;

const DIMS: [usize; 3] = [5, 4, 3];
const SPACING: [f64; 3] = [0.25, 0.5, 0.125];
const ORIGIN: [f64; 3] = [-1.0, 0.5, 2.0];

fn field() -> Vec<f32> {
    (0..DIMS.iter().product::<usize>())
        .map(|i| 0.25 + (i % 7) as f32)
        .collect()
}

fn scene(volume: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="volpath"/>
    <shape type="cube"><bsdf type="null"/>
        <medium type="heterogeneous" name="interior">
            <volume type="gridvolume" name="sigma_t">{volume}</volume>
        </medium>
    </shape>
</scene>"#
    )
}

fn load(dir: &Path, volume: &str) -> Result<SceneDesc, String> {
    load_str(&scene(volume), "test.xml", dir, &[]).map_err(|e| e.to_string())
}

fn grid_of(s: &SceneDesc) -> &fgf_scene::GridVolumeDesc {
    match &s.media[0] {
        MediumDesc::Heterogeneous {
            sigma_t: VolumeDesc::Grid(g),
            ..
        } => g,
        m => panic!("unexpected medium {m:?}"),
    }
}

/// World position of the centre of voxel `(x, y, z)`.
fn centre(g: &fgf_scene::GridVolumeDesc, x: usize, y: usize, z: usize) -> Vec3 {
    let n = g.grid.shape;
    let u = Vec3::new(
        (x as f32 + 0.5) / n[0] as f32,
        (y as f32 + 0.5) / n[1] as f32,
        (z as f32 + 0.5) / n[2] as f32,
    );
    let p = if g.use_grid_bbox {
        let b = g.grid.bbox;
        Vec3::new(b[0], b[1], b[2]) + u * Vec3::new(b[3] - b[0], b[4] - b[1], b[5] - b[2])
    } else {
        u
    };
    g.to_world.transform_point3(p)
}

fn write_both(dir: &Path) {
    let data = field();
    fgf_io::vdb::write_float_grid(&dir.join("f.vdb"), "density", &data, DIMS, SPACING, ORIGIN)
        .unwrap();
    let mut bbox = [0f32; 6];
    for a in 0..3 {
        bbox[a] = ORIGIN[a] as f32;
        bbox[a + 3] = (ORIGIN[a] + DIMS[a] as f64 * SPACING[a]) as f32;
    }
    let vol = fgf_io::vol::VolGrid {
        shape: DIMS,
        channels: 1,
        bbox,
        data,
    };
    fgf_io::vol::write_vol(&dir.join("f.vol"), &vol).unwrap();
}

#[test]
fn vdb_and_vol_place_every_voxel_alike() {
    let dir = tempfile::tempdir().unwrap();
    write_both(dir.path());
    let vdb = load(dir.path(), r#"<string name="filename" value="f.vdb"/>"#).unwrap();
    let vol = load(
        dir.path(),
        r#"<string name="filename" value="f.vol"/><boolean name="use_grid_bbox" value="true"/>"#,
    )
    .unwrap();
    let (a, b) = (grid_of(&vdb), grid_of(&vol));
    assert_eq!(a.grid.shape, b.grid.shape);
    assert_eq!(a.grid.data, b.grid.data);
    for z in 0..DIMS[2] {
        for y in 0..DIMS[1] {
            for x in 0..DIMS[0] {
                let (p, q) = (centre(a, x, y, z), centre(b, x, y, z));
                // Both are f32 compositions of exact binary fractions; allow
                // a few ulps of the coordinates (|p| < 4).
                assert!(
                    (p - q).abs().max_element() < 4.0 * 4.0 * f32::EPSILON,
                    "{p} vs {q}"
                );
                let want = Vec3::new(
                    (ORIGIN[0] + (x as f64 + 0.5) * SPACING[0]) as f32,
                    (ORIGIN[1] + (y as f64 + 0.5) * SPACING[1]) as f32,
                    (ORIGIN[2] + (z as f64 + 0.5) * SPACING[2]) as f32,
                );
                assert!(
                    (p - want).abs().max_element() < 16.0 * f32::EPSILON,
                    "{p} vs {want}"
                );
            }
        }
    }
}

#[test]
fn vdb_to_world_is_composed_after_the_file_transform() {
    let dir = tempfile::tempdir().unwrap();
    write_both(dir.path());
    let s = load(
        dir.path(),
        r#"<string name="filename" value="f.vdb"/><transform name="to_world"><translate value="10, 0, 0"/></transform>"#,
    )
    .unwrap();
    let p = centre(grid_of(&s), 0, 0, 0);
    let want = Vec3::new(10.0 - 1.0 + 0.125, 0.5 + 0.25, 2.0 + 0.0625);
    assert!((p - want).abs().max_element() < 1e-5, "{p} vs {want}");
}

#[test]
fn vdb_grid_parameter_and_refusals() {
    let dir = tempfile::tempdir().unwrap();
    write_both(dir.path());
    // The grid is chosen by name; a missing one is a clear error.
    let ok = load(
        dir.path(),
        r#"<string name="filename" value="f.vdb"/><string name="grid" value="density"/>"#,
    );
    assert!(ok.is_ok(), "{ok:?}");
    let e = load(
        dir.path(),
        r#"<string name="filename" value="f.vdb"/><string name="grid" value="smoke"/>"#,
    )
    .unwrap_err();
    assert!(e.contains("smoke") && e.contains("density"), "{e}");
    // `grid` on a .vol file and use_grid_bbox on a .vdb file are refused.
    let e = load(
        dir.path(),
        r#"<string name="filename" value="f.vol"/><string name="grid" value="density"/>"#,
    )
    .unwrap_err();
    assert!(e.contains("'grid'") && e.contains(".vol"), "{e}");
    let e = load(
        dir.path(),
        r#"<string name="filename" value="f.vdb"/><boolean name="use_grid_bbox" value="true"/>"#,
    )
    .unwrap_err();
    assert!(e.contains("use_grid_bbox"), "{e}");
    // A file that is not OpenVDB gives one line naming it.
    std::fs::write(dir.path().join("bad.vdb"), b"not a vdb file at all").unwrap();
    let e = load(dir.path(), r#"<string name="filename" value="bad.vdb"/>"#).unwrap_err();
    assert!(e.contains("bad.vdb") && !e.contains('\n'), "{e}");
}
