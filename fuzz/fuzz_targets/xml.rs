//! The scene loader on arbitrary XML text, with `<include>`s and
//! `<default>`s: the input is split at the first 0xFF byte into the scene
//! and a file `inc.xml` it may include (also itself, for cycles). The loader
//! must return `Ok` or `Err`, never panic or abort.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let (scene, inc) = match data.iter().position(|&b| b == 0xFF) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &b""[..]),
    };
    let Ok(scene) = std::str::from_utf8(scene) else {
        return;
    };
    let dir = tempfile::tempdir().expect("temporary directory");
    std::fs::write(dir.path().join("inc.xml"), inc).expect("write include");
    let path = dir.path().join("scene.xml");
    std::fs::write(&path, scene).expect("write scene");
    let defines = [("spp".to_string(), "4".to_string())];
    let _ = fgf_scene::load_file(&path, &defines);
});
