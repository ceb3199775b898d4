//! The OBJ mesh reader on arbitrary bytes, through the scene loader (a
//! `<shape type="obj">` naming the file): `Ok` or `Err`, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = tempfile::tempdir().expect("temporary directory");
    std::fs::write(dir.path().join("mesh.obj"), data).expect("write mesh");
    let scene = r#"<scene version="3.0.0"><shape type="obj"><string name="filename" value="mesh.obj"/></shape></scene>"#;
    let _ = fgf_scene::load_str(scene, "fuzz.xml", dir.path(), &[]);
});
